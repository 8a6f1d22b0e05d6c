//! The C ABI of the vocc runtime: the store format and culler of `vocc` built with no default
//! features (no geometry stack), as `libvocc.so` / `libvocc.a` with the header
//! `include/vocc.h`, which cbindgen generates from this file (its doc comments become the
//! header's). The ownership and thread rules are in the header's preamble (`cbindgen.toml`).
//!
//! Input: caller memory through raw pointers: store, frame and blob bytes, object boxes, cell
//! records, output buffers. Output: status codes (`VOCC_OK` or a `VOCC_ERR_*`), an optional
//! [`VoccError`] with the library's message, values written to caller memory, and opaque
//! objects ([`VoccStore`], [`VoccTree`], [`VoccQuery`]) the caller frees.
//! Invariants:
//! - no panic crosses the boundary: every entry point runs inside `catch_unwind`, and a panic
//!   (a bug) is reported as `VOCC_ERR_PANIC`;
//! - every pointer is checked for NULL before use and every length or count for range before a
//!   slice is made of it; a required output is written only on success (out-pointers of
//!   constructors are set to NULL on failure);
//! - a frame or cell coming from the caller is checked (frame rules F1..F12 as a frame on its
//!   own follows them, VO fields in range, canonical endpoints, no degenerate VO) before the
//!   culler sees it, so the culler only runs on what a decoder would have accepted;
//! - the culling path allocates nothing: [`vocc_pvs`] and [`vocc_pvs_bitmap`] run the Rust
//!   culler into the [`VoccQuery`]'s vector, reserved for the tree when the query is made, and
//!   copy the result into the caller's buffer;
//! - this file wraps `vocc::runtime` and decides nothing about occlusion itself.

#![deny(clippy::undocumented_unsafe_blocks, unsafe_op_in_unsafe_fn)]

use std::ffi::c_char;
use std::panic::catch_unwind;
use std::ptr;

use vocc::runtime::culler::MAX_BOXES;
use vocc::runtime::format::{decode_blob, decode_frame};
use vocc::runtime::{pvs, BoxTree, OwnedStore, MAX_VOS_PER_CELL};

/// Success.
pub const VOCC_OK: i32 = 0;
/// A required pointer was NULL.
pub const VOCC_ERR_NULL: i32 = 1;
/// An argument is out of range: a length or count, a cell record field, a query made for a
/// smaller tree.
pub const VOCC_ERR_ARGUMENT: i32 = 2;
/// The output buffer is too small; the count written tells the size needed.
pub const VOCC_ERR_BUFFER_TOO_SMALL: i32 = 3;
/// A position or cell id outside the frame's grid.
pub const VOCC_ERR_OUTSIDE_GRID: i32 = 4;
/// Bytes refused by a decoder (docs/FORMAT.md section 8); the message names the rule and the
/// offset.
pub const VOCC_ERR_FORMAT: i32 = 5;
/// A store or blob of a major version this library does not read.
pub const VOCC_ERR_VERSION: i32 = 6;
/// A checksum mismatch: the bytes were damaged.
pub const VOCC_ERR_CHECKSUM: i32 = 7;
/// A frame that breaks a rule F1..F12 of docs/FORMAT.md section 4.1.
pub const VOCC_ERR_FRAME: i32 = 8;
/// An internal error caught at the boundary (a bug in vocc: please report it).
pub const VOCC_ERR_PANIC: i32 = 9;

/// At most this many VOs per cell.
pub const VOCC_MAX_VOS: usize = 10;
/// Bytes of a `VoccError` message, with its terminating NUL.
pub const VOCC_MESSAGE_LEN: usize = 256;
/// Length of an encoded frame (the `.frame` file beside a store's blobs).
pub const VOCC_FRAME_BYTES: usize = 112;

const _: () = assert!(VOCC_MAX_VOS == MAX_VOS_PER_CELL);
const _: () = assert!(VOCC_FRAME_BYTES == vocc::runtime::format::FRAME_LEN);

/// What went wrong: the status code again, and a NUL-terminated UTF-8 message (empty on
/// success), truncated to fit.
#[repr(C)]
pub struct VoccError {
    pub code: i32,
    pub message: [c_char; VOCC_MESSAGE_LEN],
}

/// What a decoder needs beside a cell's bytes (docs/FORMAT.md section 4): the scene origin,
/// the cell grid, the VO quantization and the vertical frame. Cell (i, j) has id `j * nx + i`
/// and covers `[min_x + i * cell_size, min_x + (i + 1) * cell_size)` and likewise in y.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoccFrame {
    /// World position of the local origin: world = local + origin.
    pub origin: [f64; 3],
    /// Local x and y of the grid's minimum corner, metres.
    pub min_x: f64,
    pub min_y: f64,
    /// Side of a square cell, metres.
    pub cell_size: f64,
    /// Columns and rows.
    pub nx: u32,
    pub ny: u32,
    /// Step of the VO endpoint grid, metres.
    pub quantum: f64,
    /// Eye heights above a cell's ground, metres.
    pub eye_lo: f64,
    pub eye_hi: f64,
    /// Local height of ground level 0 and the step between levels, metres.
    pub ground_z0: f64,
    pub ground_step: f64,
    /// VO top of level k: e1 + h0 * (h_ratio^k - 1), with e1 the cell's top eye.
    pub h0: f64,
    pub h_ratio: f64,
}

/// One stored VO (docs/FORMAT.md section 3): endpoint 1 is
/// `centre + (x1 - 256, y1 - 256) * quantum * 2^exp1` of its cell, endpoint 2 likewise with
/// `x2, y2, exp2`; grid indices 0..512, exponents 0..8 (0 in a 1.0 store), height level 0..32
/// (0..16 in a 1.0 store). A cell given to the library must hold canonical endpoints: `exp == 0`,
/// or `x - 256` or `y - 256` outside -128..128 (what every decoded cell holds).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VoccVo {
    pub x1: u16,
    pub y1: u16,
    pub x2: u16,
    pub y2: u16,
    pub exp1: u8,
    pub exp2: u8,
    pub level: u8,
}

/// Bytes of a `VoccStoreInfo` CRS name, with its terminating NUL.
pub const VOCC_CRS_LEN: usize = 256;

const _: () = assert!(VOCC_CRS_LEN == vocc::runtime::format::MAX_CRS_LEN + 1);

/// What a store says about itself (docs/FORMAT.md sections 2 and 5.2): its version, and the
/// scene it was baked from. A 1.0 store records no scene: objects 0, scene 0, empty CRS.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VoccStoreInfo {
    /// The store's major (2, or 1 for a store written before 2.0) and minor version.
    pub major: u16,
    pub minor: u16,
    /// How many objects the store was baked for; 0: not recorded.
    pub objects: u32,
    /// A fingerprint of the scene it was baked from (opaque); 0: not recorded.
    pub scene: u64,
    /// Bytes of the CRS name, 0..=255 (0: unknown).
    pub crs_len: u32,
    /// The CRS name (e.g. "EPSG:3946"), UTF-8, NUL-terminated after `crs_len` bytes.
    pub crs: [c_char; VOCC_CRS_LEN],
}

/// One cell's record. `skipped` is 1 for a cell inside a building (no VOs: everything is
/// potentially visible), else 0; `ground` is the cell's ground level; `vos[0..count]` are its
/// VOs, most effective first.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VoccCell {
    pub skipped: u8,
    pub ground: u8,
    pub count: u8,
    pub vos: [VoccVo; VOCC_MAX_VOS],
}

/// A VO as geometry, local frame: the segment a-b standing from height g to height h.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VoccVoGeom {
    pub a: [f64; 2],
    pub b: [f64; 2],
    pub g: f64,
    pub h: f64,
}

/// A parsed store; owns a copy of the bytes given to `vocc_store_open`.
pub struct VoccStore {
    store: OwnedStore<Box<[u8]>>,
}

/// The bounding volume hierarchy over a scene's object boxes, built once per scene.
pub struct VoccTree {
    tree: BoxTree,
}

/// Scratch memory for PVS queries over trees of up to a given size; one thread at a time.
pub struct VoccQuery {
    out: Vec<u32>,
    objects: usize,
}

// ---------------------------------------------------------------------------------------------
// Stores, frames, blobs.

/// The library's version, a static NUL-terminated string such as "0.1.0".
#[no_mangle]
pub extern "C" fn vocc_version() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr() as *const c_char
}

/// Opens a store of version 2.0 or 1.0 from the `len` bytes at `bytes`, checking all of it
/// once (docs/FORMAT.md section 8.1). The bytes are copied (once, here): the caller may free or
/// reuse them as soon as this returns. On success `*out` is the store; on failure NULL.
///
/// # Safety
/// `bytes` points to `len` readable bytes (or `len` is 0); `out` is NULL or writable; `err` is
/// NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vocc_store_open(
    bytes: *const u8,
    len: usize,
    out: *mut *mut VoccStore,
    err: *mut VoccError,
) -> i32 {
    // SAFETY: `out` is NULL or writable (this function's `# Safety`).
    unsafe { clear_out(out) };
    let r = guard(|| {
        // SAFETY: `out` is NULL or writable (this function's `# Safety`).
        let out = unsafe { get_mut(out, "out") }?;
        // SAFETY: `bytes` points to `len` readable bytes (or `len` is 0) (this function's `# Safety`).
        let bytes = unsafe { slice(bytes, len, "bytes") }?;
        // Copied: the store owns its bytes, so the caller may free theirs when this returns.
        let store = OwnedStore::parse(Box::<[u8]>::from(bytes))?;
        *out = Box::into_raw(Box::new(VoccStore { store }));
        Ok(())
    });
    // SAFETY: `err` is NULL or writable (this function's `# Safety`).
    unsafe { finish(err, r) }
}

/// Frees a store and its copy of the bytes (NULL is ignored).
///
/// # Safety
/// `store` is NULL or came from `vocc_store_open` and was not freed yet.
#[no_mangle]
pub unsafe extern "C" fn vocc_store_free(store: *mut VoccStore) {
    if !store.is_null() {
        let _ = catch_unwind(|| {
            // SAFETY: made by Box::into_raw in vocc_store_open, freed once.
            drop(unsafe { Box::from_raw(store) })
        });
    }
}

/// The store's frame.
///
/// # Safety
/// `store` is NULL or a live store; `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vocc_store_frame(store: *const VoccStore, out: *mut VoccFrame) -> i32 {
    let r = guard(|| {
        // SAFETY: `store` is NULL or a live store (this function's `# Safety`).
        let s = unsafe { get(store, "store") }?;
        // SAFETY: `out` is NULL or writable (this function's `# Safety`).
        *unsafe { get_mut(out, "out") }? = VoccFrame::from(s.store.store().frame());
        Ok(())
    });
    status(r)
}

/// The store's version and scene section.
///
/// # Safety
/// `store` is NULL or a live store; `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vocc_store_info(store: *const VoccStore, out: *mut VoccStoreInfo) -> i32 {
    let r = guard(|| {
        // SAFETY: `store` is NULL or a live store (this function's `# Safety`).
        let s = unsafe { get(store, "store") }?.store.store();
        // SAFETY: `out` is NULL or writable (this function's `# Safety`).
        let out = unsafe { get_mut(out, "out") }?;
        let (major, minor) = s.version();
        let crs = s.crs().as_bytes();
        let mut info = VoccStoreInfo {
            major,
            minor,
            objects: s.objects(),
            scene: s.scene(),
            crs_len: crs.len() as u32,
            crs: [0; VOCC_CRS_LEN],
        };
        // At most 255 bytes (the format's limit), so the NUL always fits.
        for (dst, &src) in info.crs.iter_mut().zip(crs) {
            *dst = src as c_char;
        }
        *out = info;
        Ok(())
    });
    status(r)
}

/// Number of cells of the store's grid (nx * ny); 0 for NULL.
///
/// # Safety
/// `store` is NULL or a live store.
#[no_mangle]
pub unsafe extern "C" fn vocc_store_cell_count(store: *const VoccStore) -> u32 {
    // SAFETY: NULL or a live store.
    unsafe { store.as_ref() }.map_or(0, |s| s.store.store().cell_count())
}

/// The record of cell `id` of the store. Reads at most 63 index bytes and one record;
/// allocates nothing.
///
/// # Safety
/// `store` is NULL or a live store; `out` and `err` are NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vocc_store_cell(
    store: *const VoccStore,
    id: u32,
    out: *mut VoccCell,
    err: *mut VoccError,
) -> i32 {
    let r = guard(|| {
        // SAFETY: `store` is NULL or a live store (this function's `# Safety`).
        let s = unsafe { get(store, "store") }?;
        // SAFETY: `out` is NULL or writable (this function's `# Safety`).
        let out = unsafe { get_mut(out, "out") }?;
        *out = VoccCell::from(&s.store.store().cell(id)?);
        Ok(())
    });
    // SAFETY: `err` is NULL or writable (this function's `# Safety`).
    unsafe { finish(err, r) }
}

/// Decodes and checks a frame from exactly 112 bytes (the `.frame` file `vocc export --blob`
/// writes beside a blob).
///
/// # Safety
/// `bytes` points to `len` readable bytes (or `len` is 0); `out` and `err` are NULL or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn vocc_frame_decode(
    bytes: *const u8,
    len: usize,
    out: *mut VoccFrame,
    err: *mut VoccError,
) -> i32 {
    let r = guard(|| {
        // SAFETY: `out` is NULL or writable (this function's `# Safety`).
        let out = unsafe { get_mut(out, "out") }?;
        // SAFETY: `bytes` points to `len` readable bytes (or `len` is 0) (this function's `# Safety`).
        let f = decode_frame(unsafe { slice(bytes, len, "bytes") }?)?;
        *out = VoccFrame::from(&f);
        Ok(())
    });
    // SAFETY: `err` is NULL or writable (this function's `# Safety`).
    unsafe { finish(err, r) }
}

/// Decodes and checks one cell's blob of version 2.0 or 1.0 (docs/FORMAT.md section 6) against
/// `frame`: `*id` is the cell's id, `*out` its record. Allocates nothing.
///
/// # Safety
/// `frame` is NULL or readable; `bytes` points to `len` readable bytes (or `len` is 0); `id`,
/// `out` and `err` are NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vocc_blob_decode(
    frame: *const VoccFrame,
    bytes: *const u8,
    len: usize,
    id: *mut u32,
    out: *mut VoccCell,
    err: *mut VoccError,
) -> i32 {
    let r = guard(|| {
        // SAFETY: `frame` is NULL or readable (this function's `# Safety`).
        let f = unsafe { frame_of(frame) }?;
        // SAFETY: `id` is NULL or writable (this function's `# Safety`).
        let id = unsafe { get_mut(id, "id") }?;
        // SAFETY: `out` is NULL or writable (this function's `# Safety`).
        let out = unsafe { get_mut(out, "out") }?;
        // SAFETY: `bytes` points to `len` readable bytes (or `len` is 0) (this function's `# Safety`).
        let (cell, rec) = decode_blob(&f, unsafe { slice(bytes, len, "bytes") }?)?;
        *id = cell;
        *out = VoccCell::from(&rec);
        Ok(())
    });
    // SAFETY: `err` is NULL or writable (this function's `# Safety`).
    unsafe { finish(err, r) }
}

/// The cell holding local position (x, y): `VOCC_OK` and `*id`, or `VOCC_ERR_OUTSIDE_GRID`
/// (also for NaN). For world coordinates, subtract `frame->origin` or use
/// `vocc_cell_at_world`.
///
/// # Safety
/// `frame` is NULL or readable; `id` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vocc_cell_at(
    frame: *const VoccFrame,
    x: f64,
    y: f64,
    id: *mut u32,
) -> i32 {
    let r = guard(|| {
        // SAFETY: `frame` is NULL or readable (this function's `# Safety`).
        let f = unsafe { frame_of(frame) }?;
        // SAFETY: `id` is NULL or writable (this function's `# Safety`).
        let id = unsafe { get_mut(id, "id") }?;
        *id = f.grid.cell_at(x, y).ok_or_else(|| {
            fail(
                VOCC_ERR_OUTSIDE_GRID,
                format!("({x}, {y}) is outside the grid"),
            )
        })?;
        Ok(())
    });
    status(r)
}

/// `vocc_cell_at` for a world position: (x - origin[0], y - origin[1]).
///
/// # Safety
/// As `vocc_cell_at`.
#[no_mangle]
pub unsafe extern "C" fn vocc_cell_at_world(
    frame: *const VoccFrame,
    x: f64,
    y: f64,
    id: *mut u32,
) -> i32 {
    // SAFETY: NULL or readable, as the caller guarantees.
    let o = unsafe { frame.as_ref() }.map_or([0.0; 3], |f| f.origin);
    // SAFETY: forwarded.
    unsafe { vocc_cell_at(frame, x - o[0], y - o[1], id) }
}

/// The local rectangle of cell `id`: `rect[0..4] = x0, y0, x1, y1`.
///
/// # Safety
/// `frame` is NULL or readable; `rect` is NULL or points to 4 writable doubles.
#[no_mangle]
pub unsafe extern "C" fn vocc_cell_rect(frame: *const VoccFrame, id: u32, rect: *mut f64) -> i32 {
    let r = guard(|| {
        // SAFETY: `frame` is NULL or readable (this function's `# Safety`).
        let f = unsafe { frame_of(frame) }?;
        in_grid(&f, id)?;
        let r = f
            .grid
            .cell_rect(id)
            .ok_or_else(|| fail(VOCC_ERR_OUTSIDE_GRID, format!("cell {id}")))?;
        // SAFETY: `rect` is NULL or points to 4 writable doubles (this function's `# Safety`).
        unsafe { slice_mut(rect, 4, "rect") }?.copy_from_slice(&r);
        Ok(())
    });
    status(r)
}

/// The geometry of VO `k` of cell `id` with record `cell`, local frame.
///
/// # Safety
/// `frame` and `cell` are NULL or readable; `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vocc_vo_geometry(
    frame: *const VoccFrame,
    id: u32,
    cell: *const VoccCell,
    k: u32,
    out: *mut VoccVoGeom,
) -> i32 {
    let r = guard(|| {
        // SAFETY: `frame` is NULL or readable (this function's `# Safety`).
        let f = unsafe { frame_of(frame) }?;
        in_grid(&f, id)?;
        // SAFETY: `cell` is NULL or readable (this function's `# Safety`).
        let rec = unsafe { record_of(cell) }?;
        let q = rec.vos().get(k as usize).ok_or_else(|| {
            fail(
                VOCC_ERR_ARGUMENT,
                format!("VO {k}: the cell has {}", rec.vos().len()),
            )
        })?;
        let g = f
            .dequantize(id, rec.stand(), q)
            .ok_or_else(|| fail(VOCC_ERR_OUTSIDE_GRID, format!("cell {id}")))?;
        // SAFETY: `out` is NULL or writable (this function's `# Safety`).
        *unsafe { get_mut(out, "out") }? = VoccVoGeom {
            a: g.a,
            b: g.b,
            g: g.g,
            h: g.h,
        };
        Ok(())
    });
    status(r)
}

// ---------------------------------------------------------------------------------------------
// Trees, queries, the PVS.

/// Builds the box hierarchy over `count` object boxes, `6 * count` doubles (xmin, ymin, zmin,
/// xmax, ymax, zmax per object; object i is boxes[6i .. 6i + 6]). With `origin` NULL the boxes
/// are in the store's local frame; otherwise they are world coordinates and `origin` points to
/// the frame's 3 origin doubles. The boxes are copied. A box with a NaN or infinite coordinate,
/// or min > max, is kept in every PVS. More than 268,435,455 boxes are refused
/// (`VOCC_ERR_ARGUMENT`). On success `*out` is the tree; on failure NULL.
///
/// # Safety
/// `boxes` points to `6 * count` readable doubles (or `count` is 0); `origin` is NULL or
/// points to 3 readable doubles; `out` and `err` are NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vocc_tree_new(
    boxes: *const f64,
    count: usize,
    origin: *const f64,
    out: *mut *mut VoccTree,
    err: *mut VoccError,
) -> i32 {
    // SAFETY: `out` is NULL or writable (this function's `# Safety`).
    unsafe { clear_out(out) };
    let r = guard(|| {
        // SAFETY: `out` is NULL or writable (this function's `# Safety`).
        let out = unsafe { get_mut(out, "out") }?;
        if count > MAX_BOXES {
            return Err(fail(
                VOCC_ERR_ARGUMENT,
                format!("{count} boxes: at most {MAX_BOXES}"),
            ));
        }
        let n = count
            .checked_mul(6)
            .ok_or_else(|| fail(VOCC_ERR_ARGUMENT, format!("{count} boxes: too many")))?;
        // SAFETY: `boxes` points to `6 * count` readable doubles (or `count` is 0) (this function's `# Safety`).
        let flat = unsafe { slice(boxes, n, "boxes") }?;
        let mut local: Vec<[f64; 6]> = flat
            .chunks_exact(6)
            .map(|c| [c[0], c[1], c[2], c[3], c[4], c[5]])
            .collect();
        if !origin.is_null() {
            // SAFETY: `origin` points to 3 readable doubles (not NULL here) (this function's `# Safety`).
            let o = unsafe { slice(origin, 3, "origin") }?;
            // As `BoxTree::from_world`: local = world - origin.
            for b in &mut local {
                for k in 0..6 {
                    b[k] -= o[k % 3];
                }
            }
        }
        let tree = BoxTree::new(&local);
        *out = Box::into_raw(Box::new(VoccTree { tree }));
        Ok(())
    });
    // SAFETY: `err` is NULL or writable (this function's `# Safety`).
    unsafe { finish(err, r) }
}

/// Frees a tree (NULL is ignored).
///
/// # Safety
/// `tree` is NULL or came from `vocc_tree_new` and was not freed yet.
#[no_mangle]
pub unsafe extern "C" fn vocc_tree_free(tree: *mut VoccTree) {
    if !tree.is_null() {
        let _ = catch_unwind(|| {
            // SAFETY: made by Box::into_raw in vocc_tree_new, freed once.
            drop(unsafe { Box::from_raw(tree) })
        });
    }
}

/// Number of objects of the tree (the `count` it was built with); 0 for NULL.
///
/// # Safety
/// `tree` is NULL or a live tree.
#[no_mangle]
pub unsafe extern "C" fn vocc_tree_len(tree: *const VoccTree) -> usize {
    // SAFETY: NULL or a live tree.
    unsafe { tree.as_ref() }.map_or(0, |t| t.tree.len())
}

/// Makes the scratch memory for PVS queries over `tree` or any tree with as many objects or
/// fewer (about 4.1 bytes per object). One thread at a time may use a query.
///
/// # Safety
/// `tree` is NULL or a live tree; `out` and `err` are NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vocc_query_new(
    tree: *const VoccTree,
    out: *mut *mut VoccQuery,
    err: *mut VoccError,
) -> i32 {
    // SAFETY: `out` is NULL or writable (this function's `# Safety`).
    unsafe { clear_out(out) };
    let r = guard(|| {
        // SAFETY: `tree` is NULL or a live tree (this function's `# Safety`).
        let t = unsafe { get(tree, "tree") }?;
        // SAFETY: `out` is NULL or writable (this function's `# Safety`).
        let out = unsafe { get_mut(out, "out") }?;
        let objects = t.tree.len();
        // The culler holds a bitmap of the culled objects (one u32 per 32) before the ids.
        let out_vec = Vec::with_capacity(objects + objects.div_ceil(32));
        *out = Box::into_raw(Box::new(VoccQuery {
            out: out_vec,
            objects,
        }));
        Ok(())
    });
    // SAFETY: `err` is NULL or writable (this function's `# Safety`).
    unsafe { finish(err, r) }
}

/// Frees a query (NULL is ignored).
///
/// # Safety
/// `query` is NULL or came from `vocc_query_new` and was not freed yet.
#[no_mangle]
pub unsafe extern "C" fn vocc_query_free(query: *mut VoccQuery) {
    if !query.is_null() {
        let _ = catch_unwind(|| {
            // SAFETY: made by Box::into_raw in vocc_query_new, freed once.
            drop(unsafe { Box::from_raw(query) })
        });
    }
}

/// The visible ids, ascending, of the query's last `vocc_pvs` or `vocc_pvs_bitmap` that ran the
/// culler (returned `VOCC_OK`, or `VOCC_ERR_BUFFER_TOO_SMALL` from `vocc_pvs`), without copying: `*count` ids at the returned pointer, valid until the query's
/// next call or its free. NULL (and `*count = 0`) for a NULL query.
///
/// # Safety
/// `query` is NULL or a live query; `count` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vocc_query_ids(query: *const VoccQuery, count: *mut usize) -> *const u32 {
    // SAFETY: NULL or a live query; NULL or writable.
    let (q, c) = unsafe { (query.as_ref(), count.as_mut()) };
    if let Some(c) = c {
        *c = q.map_or(0, |q| q.out.len());
    }
    q.map_or(ptr::null(), |q| q.out.as_ptr())
}

/// Runs the culler for cell `id` with record `cell` into the query's scratch memory; returns
/// the query and the number of visible objects.
///
/// # Safety
/// `query` is NULL or a live query that nothing else uses for `'a`; `tree` is NULL or a live
/// tree not freed for the call; `frame` and `cell` are NULL or readable.
unsafe fn run_pvs<'a>(
    query: *mut VoccQuery,
    tree: *const VoccTree,
    frame: *const VoccFrame,
    id: u32,
    cell: *const VoccCell,
) -> Result<(&'a mut VoccQuery, usize), Fail> {
    // SAFETY: NULL or a live query, unaliased for 'a (this function's contract).
    let q = unsafe { get_mut(query, "query") }?;
    // SAFETY: NULL or a live tree for the call (this function's contract).
    let t = unsafe { get(tree, "tree") }?;
    // SAFETY: NULL or readable (this function's contract).
    let f = unsafe { frame_of(frame) }?;
    in_grid(&f, id)?;
    // SAFETY: NULL or readable (this function's contract).
    let rec = unsafe { record_of(cell) }?;
    if t.tree.len() > q.objects {
        return Err(fail(
            VOCC_ERR_ARGUMENT,
            format!(
                "the query was made for {} objects, the tree has {}",
                q.objects,
                t.tree.len()
            ),
        ));
    }
    pvs(&f, id, &rec, &t.tree, &mut q.out);
    let n = q.out.len();
    Ok((q, n))
}

/// The PVS of cell `id` (record `cell`, from `vocc_store_cell` or `vocc_blob_decode`):
/// the ascending indices of the objects of `tree` that no VO of the cell hides. `*count` is
/// their number. When `ids` is not NULL they are copied there; `capacity` (in ids) must be at
/// least `*count`, which `vocc_tree_len(tree)` always is, else nothing is copied and the
/// status is `VOCC_ERR_BUFFER_TOO_SMALL`. With `ids` NULL, read them with
/// `vocc_query_ids`. A skipped cell or a cell without VOs keeps every object. Allocates
/// nothing.
///
/// # Safety
/// `query`, `tree`, `frame`, `cell` are NULL or live and readable (`query` used by this thread
/// alone); `ids` is NULL or points to `capacity` writable u32; `count` and `err` are NULL or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn vocc_pvs(
    query: *mut VoccQuery,
    tree: *const VoccTree,
    frame: *const VoccFrame,
    id: u32,
    cell: *const VoccCell,
    ids: *mut u32,
    capacity: usize,
    count: *mut usize,
    err: *mut VoccError,
) -> i32 {
    let r = guard(|| {
        // SAFETY: `count` is NULL or writable (this function's `# Safety`).
        let count = unsafe { get_mut(count, "count") }?;
        // SAFETY: the pointers are as `run_pvs` requires (this function's `# Safety`).
        let (q, n) = unsafe { run_pvs(query, tree, frame, id, cell) }?;
        *count = n;
        if ids.is_null() {
            return Ok(());
        }
        if capacity < n {
            return Err(fail(
                VOCC_ERR_BUFFER_TOO_SMALL,
                format!("{n} ids do not fit a buffer of {capacity}"),
            ));
        }
        // SAFETY: `ids` points to `capacity >= n` writable u32 (not NULL here) (this function's `# Safety`).
        unsafe { slice_mut(ids, n, "ids") }?.copy_from_slice(&q.out);
        Ok(())
    });
    // SAFETY: `err` is NULL or writable (this function's `# Safety`).
    unsafe { finish(err, r) }
}

/// `vocc_pvs` as a bitmap: bit `i % 8` of byte `i / 8` (least significant first) is set when
/// object i may be visible, for the `vocc_tree_len(tree)` objects; `bitmap_len` (bytes) must
/// be at least `(vocc_tree_len(tree) + 7) / 8`, else `VOCC_ERR_BUFFER_TOO_SMALL`. Bytes past
/// that are left alone. `*count` is the number of bits set. Allocates nothing.
///
/// # Safety
/// As `vocc_pvs`, with `bitmap` NULL or pointing to `bitmap_len` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn vocc_pvs_bitmap(
    query: *mut VoccQuery,
    tree: *const VoccTree,
    frame: *const VoccFrame,
    id: u32,
    cell: *const VoccCell,
    bitmap: *mut u8,
    bitmap_len: usize,
    count: *mut usize,
    err: *mut VoccError,
) -> i32 {
    let r = guard(|| {
        // SAFETY: `count` is NULL or writable (this function's `# Safety`).
        let count = unsafe { get_mut(count, "count") }?;
        // SAFETY: `tree` is NULL or a live tree (this function's `# Safety`).
        let objects = unsafe { get(tree, "tree") }?.tree.len();
        let need = objects.div_ceil(8);
        if bitmap_len < need {
            return Err(fail(
                VOCC_ERR_BUFFER_TOO_SMALL,
                format!("{objects} objects need a bitmap of {need} bytes, {bitmap_len} given"),
            ));
        }
        // SAFETY: `bitmap` is NULL or points to `bitmap_len >= need` writable bytes (this function's `# Safety`).
        let bits = unsafe { slice_mut(bitmap, need, "bitmap") }?;
        // SAFETY: the pointers are as `run_pvs` requires (this function's `# Safety`).
        let (q, n) = unsafe { run_pvs(query, tree, frame, id, cell) }?;
        bits.fill(0);
        for &i in &q.out {
            // Ids are below the tree's length, so the index is in range; `get_mut` keeps it
            // checked anyway.
            if let Some(b) = bits.get_mut(i as usize >> 3) {
                *b |= 1 << (i & 7);
            }
        }
        *count = n;
        Ok(())
    });
    // SAFETY: `err` is NULL or writable (this function's `# Safety`).
    unsafe { finish(err, r) }
}

mod boundary;
#[cfg(test)]
mod tests;

use boundary::{
    clear_out, fail, finish, frame_of, get, get_mut, guard, in_grid, record_of, slice, slice_mut,
    status, Fail,
};
