//! vocc: virtual occluders for city models, baked per view cell, and the runtime that culls with
//! them.
//!
//! Input: city models (GeoJSON, CityJSON and CityJSONSeq, CityGML, OBJ, OpenStreetMap PBF,
//! GeoPackage, FlatGeobuf, Shapefile; terrain as DEM or TIN). Output: a store file
//! (`docs/FORMAT.md`) holding, per view cell, at most 10 conservative virtual occluders of 6
//! bytes each, and a culler that builds a cell's potentially visible set (PVS) from them.
//!
//! ## Where to start
//! - **Bake** a store: [`BakeJob`] (`vocc::bake::job::BakeJob`), over a scene from
//!   [`scene::load()`] and [`bake::params::BakeParams`]; it returns the store's bytes, its
//!   `.hashes` bytes and a summary, and does no file I/O. Shards of one bake merge with
//!   [`bake::merge::merge`].
//! - **Read** a store: [`runtime::Store`] borrows the file's bytes, [`runtime::OwnedStore`] keeps
//!   them; both check the whole file once and then answer per cell.
//! - **Cull**: [`runtime::BoxTree`] over the engine's object boxes, built once, then
//!   [`runtime::pvs`] on every cell entry (module [`runtime::culler`]).
//!
//! ```no_run
//! # #[cfg(feature = "bake")]
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use vocc::bake::params::BakeParams;
//! use vocc::runtime::{pvs, BoxTree, Store};
//! use vocc::scene::{self, ReadOptions};
//! use vocc::BakeJob;
//!
//! let read = ReadOptions { height_attr: Some("HAUTEUR".into()), ..ReadOptions::default() };
//! let scene = scene::load(&["data/lyon1/buildings_lyon1.geojson".into()], &read)?;
//! let out = BakeJob::new(&scene, BakeParams::default())?.run(&|_| {})?;
//! let store = Store::parse(&out.store)?;
//! let boxes: Vec<[f64; 6]> = scene.objects.iter().map(|o| {
//!     let (a, b) = (o.bbox.min, o.bbox.max);
//!     [a.x, a.y, a.z, b.x, b.y, b.z]
//! }).collect();
//! let tree = BoxTree::new(&boxes);
//! let mut visible = Vec::new();
//! pvs(store.frame(), 0, &store.cell(0)?, &tree, &mut visible);
//! # Ok(())
//! # }
//! # #[cfg(not(feature = "bake"))]
//! # fn main() {}
//! ```
//!
//! Module wings:
//! - [`scene`]: readers and the 2.5D blocker model (feature `bake`);
//! - [`geom`]: the exact predicates and the verifier (feature `bake`);
//! - [`bake`]: the bake, one file per stage (feature `bake`);
//! - [`eval`]: the ground truth (a ray caster that reads no VO code) and the reports (feature
//!   `bake`);
//! - [`view`]: the viewer page, the scene's geometry as binary buffers (feature `bake`);
//! - [`runtime`]: the store format and culler core, which builds without the geometry stack
//!   (`--no-default-features`, depending on thiserror alone) so an engine can embed it.
//!
//! The `vocc` command line tool is the workspace member `vocc-cli` (`cli/`); this library
//! compiles no argument parser or progress bar. The C ABI is `capi/`, the Python package
//! `python/`.
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
/// The bake as one library call (re-exported from [`bake::job`]).
#[cfg(feature = "bake")]
pub use bake::job::BakeJob;
#[cfg(feature = "bake")]
pub mod eval;
#[cfg(feature = "bake")]
pub mod geom;
#[cfg(feature = "bake")]
pub mod scene;
/// The viewer page of `vocc view`: a scene's geometry as typed arrays, and the HTML page.
#[cfg(feature = "bake")]
pub mod view;
