//! Runtime core: what an engine embeds. Builds with `--no-default-features`.
//!
//! Input: a store or a per-cell blob, positions and the engine's object boxes, in the store's
//! local frame. Output: cell ids, a cell's virtual occluders, and the cell's PVS.
//! Invariants: no dependency on the geometry stack; no panics on any input (NaN and out-of-grid
//! positions give `None`, malformed bytes give an error); every culling decision is conservative
//! (rule 3, [`occlusion`]).

pub mod crc;
pub mod culler;
pub mod format;
pub mod frame;
pub mod grid;
pub mod occlusion;

pub use culler::{pvs, BoxTree};
pub use format::{
    decode_blob, decode_frame, encode_blob, encode_frame, encode_store, validate_frame, CellRecord,
    FormatError, Store, VoList,
};
pub use frame::{CellView, Frame, QVo, VoGeom, MAX_VOS_PER_CELL};
pub use grid::{CellId, GridDescriptor};
pub use occlusion::{Cover, PreparedVo};
