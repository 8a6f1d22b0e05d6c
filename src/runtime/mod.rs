//! Runtime core: what an engine embeds. Builds with `--no-default-features`.
//!
//! Input: a grid descriptor and positions in the store's local frame. Output: cell ids.
//! Invariants: no dependency on the geometry stack; no panics on any input (NaN and out-of-grid
//! positions give `None`).

pub mod grid;

pub use grid::{CellId, GridDescriptor};
