//! vocc: virtual occluders for city models.
//!
//! Input: city models (GeoJSON footprints with heights, OBJ meshes, CityJSON). Output, in later
//! stages: per view cell, at most 10 conservative virtual occluders packed at 5 bytes each, and a
//! runtime culler that builds the cell's potentially visible set from them.
//!
//! Module wings:
//! - [`scene`]: readers and the 2.5D blocker model (feature `bake`);
//! - [`geom`]: the exact predicates (feature `bake`);
//! - [`view`]: the viewer page, the scene's geometry as binary buffers (feature `bake`);
//! - [`runtime`]: the store format and culler core, which builds without the geometry stack
//!   (`--no-default-features`) so an engine can embed it.
//!
//! Invariant: every occlusion decision is conservative; see `ARCHITECTURE.md`.

#![forbid(unsafe_code)]
// `!(x > 0.0)` is how this crate says "not positive, or NaN": NaN must fail every test.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod runtime;
#[cfg(test)]
mod testutil;

/// The fuzz targets' bodies, shared with the corpus replay test; not a public API.
#[doc(hidden)]
pub mod fuzzing;

#[cfg(feature = "bake")]
pub mod bake;
#[cfg(feature = "bake")]
pub mod eval;
#[cfg(feature = "bake")]
pub mod geom;
#[cfg(feature = "bake")]
pub mod scene;
/// The viewer page of `vocc view`: a scene's geometry as typed arrays, and the HTML page.
#[cfg(feature = "bake")]
pub mod view;
