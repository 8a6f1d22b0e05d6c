//! Geometry: the exact predicates and the checks built only from them.
//!
//! All exact tests live in [`predicates`]; nothing else in the crate computes a sign from
//! floating-point arithmetic to decide topology or occlusion.

pub mod predicates;
pub mod verify;

pub use predicates::{Containment, Orientation, SegmentIntersection};
