//! Runtime core: what an engine embeds. Builds with `--no-default-features`.
//!
//! Input: a store or a per-cell blob, positions and the engine's object boxes, in the store's
//! local frame. Output: cell ids, a cell's virtual occluders, and the cell's PVS.
//! Invariants: no dependency on the geometry stack; no panics on any input (NaN and out-of-grid
//! positions give `None`, malformed bytes give an error); every culling decision is conservative
//! (rule 3, [`PreparedVo::cover`]). The one exception: [`BoxTree::new`] refuses more than `MAX_BOXES`
//! = 268,435,455 object boxes with a panic (`runtime/culler/tree.rs`: a node's link keeps 29 bits for
//! the index of its first child, and a tree over `n` boxes has at most `2n - 1` nodes).
//!
//! Modules: [`grid`] (cell ids), [`frame`] (what the bytes mean as geometry), [`format`] (the
//! store file, cell blobs and the frame's bytes, specified in `docs/FORMAT.md`: 2.0 written,
//! 1.0 still read), [`crc`],
//! `occlusion` (rule 3, crate-private: [`PreparedVo`] and [`Cover`] are its public face) and
//! [`culler`] (the PVS).
//!
//! ## Use
//! ```
//! use vocc::runtime::{encode_store, pvs, BoxTree, CellRecord, Frame, GridDescriptor, QPoint, QVo, Store};
//!
//! # fn main() -> Result<(), vocc::runtime::FormatError> {
//! let frame = Frame {
//!     origin: [843000.0, 6518000.0, 0.0],
//!     grid: GridDescriptor { min_x: 0.0, min_y: 0.0, cell_size: 100.0, nx: 2, ny: 1 },
//!     quantum: 0.5,
//!     eye_lo: 1.5,
//!     eye_hi: 2.0,
//!     ground_z0: 160.0,
//!     ground_step: 0.0,
//!     h0: 4.0,
//!     h_ratio: 1.25,
//! };
//! // The bake writes the store: cell 0 has a 70 m wall 60 m north of its centre.
//! let wall = QVo { a: QPoint::fine(196, 376), b: QPoint::fine(336, 376), level: 5, deep: false };
//! let bytes = encode_store(&frame, &[CellRecord::new(0, &[wall])?, CellRecord::EMPTY])?;
//!
//! // The engine: parse once, build the tree once (boxes in the local frame, or
//! // `BoxTree::from_world` with `frame.origin`), query on every cell entry.
//! let store = Store::parse(&bytes)?;
//! let tree = BoxTree::new(&[
//!     [48.0, 115.0, 160.0, 56.0, 118.0, 162.5], // low, right behind the wall
//!     [48.0, 115.0, 160.0, 56.0, 118.0, 200.0], // taller than the wall can hide
//! ]);
//! let mut visible = Vec::new();
//! if let Some(id) = store.cell_at(50.0, 20.0) {
//!     pvs(store.frame(), id, &store.cell(id)?, &tree, &mut visible);
//! }
//! assert_eq!(visible, [1]);
//! # Ok(())
//! # }
//! ```

pub mod crc;
pub mod culler;
pub mod format;
pub mod frame;
pub mod grid;
pub(crate) mod occlusion;

pub use culler::{pvs, BoxTree};
pub use format::{
    decode_blob, decode_frame, encode_blob, encode_frame, encode_store, encode_store_with,
    validate_frame, CellRecord, FormatError, OwnedStore, SceneSection, Store, VoList,
};
pub use frame::{CellView, Frame, QPoint, QVo, VoGeom, MAX_VOS_PER_CELL};
pub use grid::{CellId, GridDescriptor};
pub use occlusion::{hides, Cover, PreparedVo, MARGIN_M};
