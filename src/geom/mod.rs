//! Geometry: the exact predicates and the checks built only from them.
//!
//! All exact tests live in [`predicates`]; nothing else in the crate computes a sign from
//! floating-point arithmetic to decide topology or occlusion.

pub mod predicates;
pub mod verify;

pub use predicates::{Containment, Orientation, SegmentIntersection};

use glam::DVec2;

/// A pseudo-angle of direction `d`, monotone in the true angle, in `[0, 4)`: floating point, for
/// ordering and bucketing directions only (the hidden map's bins, the verifier's choice of
/// what to try); it decides nothing.
#[inline]
pub fn pseudo_angle(d: DVec2) -> f64 {
    let s = d.x.abs() + d.y.abs();
    if s == 0.0 {
        return 0.0;
    }
    let t = d.y / s;
    if d.x >= 0.0 {
        if t >= 0.0 {
            t
        } else {
            4.0 + t
        }
    } else {
        2.0 - t
    }
}
