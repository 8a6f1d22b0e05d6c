//! The boundary of the C ABI: status codes and messages, panics caught, raw pointers turned
//! into references and slices, and the checked conversions between the C structs and the
//! runtime's types.
//!
//! Input: raw pointers and lengths from the entry points of `lib.rs`, under the contracts their
//! `# Safety` sections state. Output: references, slices, checked frames and records, or a
//! [`Fail`] (status code and message). Invariants: every helper that dereferences a raw pointer
//! is an `unsafe fn` whose `# Safety` section says what the caller guarantees; NULL is always
//! checked before use and lengths before a slice is made; nothing here decides about occlusion.

use std::ffi::c_char;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::ptr;

use vocc::runtime::format::{validate_frame, CellRecord, FormatError};
use vocc::runtime::frame::QPoint;
use vocc::runtime::{CellId, Frame, GridDescriptor, QVo};

use crate::*;

// ---------------------------------------------------------------------------------------------
// The boundary: status codes, messages, panics.

pub(crate) struct Fail {
    pub(crate) code: i32,
    pub(crate) message: String,
}

pub(crate) fn fail(code: i32, message: impl Into<String>) -> Fail {
    Fail {
        code,
        message: message.into(),
    }
}

impl From<FormatError> for Fail {
    fn from(e: FormatError) -> Fail {
        let code = match e {
            FormatError::UnsupportedVersion { .. } => VOCC_ERR_VERSION,
            FormatError::Checksum { .. } => VOCC_ERR_CHECKSUM,
            FormatError::BadFrame(_) => VOCC_ERR_FRAME,
            FormatError::CellOutOfGrid { .. } => VOCC_ERR_OUTSIDE_GRID,
            _ => VOCC_ERR_FORMAT,
        };
        fail(code, e.to_string())
    }
}

/// Writes the code and message into `err` when it is not NULL.
///
/// # Safety
/// `err` is NULL or points to a writable `VoccError` that nothing else accesses during the call.
pub(crate) unsafe fn report(err: *mut VoccError, code: i32, message: &str) {
    // SAFETY: NULL or writable and unaliased, as this function's contract requires.
    let Some(e) = (unsafe { err.as_mut() }) else {
        return;
    };
    e.code = code;
    let mut n = message.len().min(VOCC_MESSAGE_LEN - 1);
    while !message.is_char_boundary(n) {
        n -= 1;
    }
    for (dst, &src) in e.message.iter_mut().zip(&message.as_bytes()[..n]) {
        *dst = src as c_char;
    }
    e.message[n] = 0;
}

/// Runs `f` at the boundary: a panic becomes `VOCC_ERR_PANIC`. The entry point then gives the
/// result to [`finish`] (with its `err`) or [`status`].
pub(crate) fn guard(f: impl FnOnce() -> Result<(), Fail>) -> Result<(), Fail> {
    let r = catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|p| {
        let what = p
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Err(fail(VOCC_ERR_PANIC, format!("internal error: {what}")))
    });
    r
}

/// The status code of a result, written with its message into `err` too.
///
/// # Safety
/// As [`report`]: `err` is NULL or writable and unaliased during the call.
pub(crate) unsafe fn finish(err: *mut VoccError, r: Result<(), Fail>) -> i32 {
    let (code, message) = match &r {
        Ok(()) => (VOCC_OK, ""),
        Err(Fail { code, message }) => (*code, message.as_str()),
    };
    // SAFETY: forwarded from this function's contract.
    unsafe { report(err, code, message) };
    code
}

/// The status code of a result, for entry points without an error out-parameter.
pub(crate) fn status(r: Result<(), Fail>) -> i32 {
    r.err().map_or(VOCC_OK, |f| f.code)
}

/// A shared reference from a pointer that may be NULL.
///
/// # Safety
/// `p` is NULL or points to a live, properly aligned `T` that nothing mutates for `'a` (the
/// caller picks `'a`: at most the entry point's call).
pub(crate) unsafe fn get<'a, T>(p: *const T, what: &str) -> Result<&'a T, Fail> {
    // SAFETY: NULL or live, aligned and unmutated for 'a, as this function's contract requires.
    unsafe { p.as_ref() }.ok_or_else(|| fail(VOCC_ERR_NULL, format!("{what} is NULL")))
}

/// An exclusive reference from a pointer that may be NULL.
///
/// # Safety
/// `p` is NULL or points to a live, properly aligned, writable `T` that nothing else reads or
/// writes for `'a` (at most the entry point's call).
pub(crate) unsafe fn get_mut<'a, T>(p: *mut T, what: &str) -> Result<&'a mut T, Fail> {
    // SAFETY: NULL or live, aligned, writable and unaliased for 'a (this function's contract).
    unsafe { p.as_mut() }.ok_or_else(|| fail(VOCC_ERR_NULL, format!("{what} is NULL")))
}

/// `len` elements at `p`; NULL is allowed for an empty slice.
///
/// # Safety
/// When `len > 0` and `p` is not NULL, `p` points to `len` readable, initialized, properly
/// aligned `T` in one allocation that nothing mutates for `'a` (at most the entry point's call).
pub(crate) unsafe fn slice<'a, T>(p: *const T, len: usize, what: &str) -> Result<&'a [T], Fail> {
    if len == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err(fail(VOCC_ERR_NULL, format!("{what} is NULL")));
    }
    if len
        .checked_mul(size_of::<T>())
        .is_none_or(|b| b > isize::MAX as usize)
    {
        return Err(fail(
            VOCC_ERR_ARGUMENT,
            format!("{what}: length {len} too large"),
        ));
    }
    // SAFETY: non-NULL and `len * size_of::<T>()` fits an isize (checked above); `len` readable
    // elements unmutated for 'a (this function's contract).
    Ok(unsafe { std::slice::from_raw_parts(p, len) })
}

/// `len` writable elements at `p`; NULL is allowed for an empty slice.
///
/// # Safety
/// When `len > 0` and `p` is not NULL, `p` points to `len` writable, properly aligned `T` in
/// one allocation that nothing else reads or writes for `'a` (at most the entry point's call).
pub(crate) unsafe fn slice_mut<'a, T>(
    p: *mut T,
    len: usize,
    what: &str,
) -> Result<&'a mut [T], Fail> {
    if len == 0 {
        return Ok(&mut []);
    }
    if p.is_null() {
        return Err(fail(VOCC_ERR_NULL, format!("{what} is NULL")));
    }
    if len
        .checked_mul(size_of::<T>())
        .is_none_or(|b| b > isize::MAX as usize)
    {
        return Err(fail(
            VOCC_ERR_ARGUMENT,
            format!("{what}: length {len} too large"),
        ));
    }
    // SAFETY: non-NULL and `len * size_of::<T>()` fits an isize (checked above); `len` writable,
    // unaliased elements for 'a (this function's contract).
    Ok(unsafe { std::slice::from_raw_parts_mut(p, len) })
}

/// Sets a constructor's out-pointer to NULL up front, so it is NULL on every failure.
///
/// # Safety
/// `out` is NULL or points to a writable, aligned pointer slot.
pub(crate) unsafe fn clear_out<T>(out: *mut *mut T) {
    // SAFETY: NULL or a writable, aligned slot (this function's contract).
    if let Some(o) = unsafe { out.as_mut() } {
        *o = ptr::null_mut();
    }
}

// ---------------------------------------------------------------------------------------------
// Conversions, checked.

impl From<&Frame> for VoccFrame {
    fn from(f: &Frame) -> VoccFrame {
        VoccFrame {
            origin: f.origin,
            min_x: f.grid.min_x,
            min_y: f.grid.min_y,
            cell_size: f.grid.cell_size,
            nx: f.grid.nx,
            ny: f.grid.ny,
            quantum: f.quantum,
            eye_lo: f.eye_lo,
            eye_hi: f.eye_hi,
            ground_z0: f.ground_z0,
            ground_step: f.ground_step,
            h0: f.h0,
            h_ratio: f.h_ratio,
        }
    }
}

/// The caller's frame, checked against rules F1..F12 as a frame on its own follows them (2.0:
/// F12 at level 31).
///
/// # Safety
/// `f` is NULL or points to a readable `VoccFrame`.
pub(crate) unsafe fn frame_of(f: *const VoccFrame) -> Result<Frame, Fail> {
    // SAFETY: NULL or readable (this function's contract); the reference ends here.
    let f = unsafe { get(f, "frame") }?;
    let frame = Frame {
        origin: f.origin,
        grid: GridDescriptor {
            min_x: f.min_x,
            min_y: f.min_y,
            cell_size: f.cell_size,
            nx: f.nx,
            ny: f.ny,
        },
        quantum: f.quantum,
        eye_lo: f.eye_lo,
        eye_hi: f.eye_hi,
        ground_z0: f.ground_z0,
        ground_step: f.ground_step,
        h0: f.h0,
        h_ratio: f.h_ratio,
    };
    validate_frame(&frame)?;
    Ok(frame)
}

impl From<&CellRecord> for VoccCell {
    fn from(r: &CellRecord) -> VoccCell {
        let mut c = VoccCell {
            skipped: matches!(r, CellRecord::Skipped) as u8,
            ground: r.ground(),
            count: r.vos().len() as u8,
            ..VoccCell::default()
        };
        for (dst, q) in c.vos.iter_mut().zip(r.vos()) {
            *dst = VoccVo {
                x1: q.a.x,
                y1: q.a.y,
                x2: q.b.x,
                y2: q.b.y,
                exp1: q.a.e,
                exp2: q.b.e,
                level: q.level,
            };
        }
        c
    }
}

/// The caller's cell, checked as a decoder checks a record: at most 10 VOs, fields in range,
/// canonical endpoints, no degenerate VO.
///
/// # Safety
/// `c` is NULL or points to a readable `VoccCell`.
pub(crate) unsafe fn record_of(c: *const VoccCell) -> Result<CellRecord, Fail> {
    // SAFETY: NULL or readable (this function's contract); the reference ends here.
    let c = unsafe { get(c, "cell") }?;
    if c.skipped != 0 {
        return Ok(CellRecord::Skipped);
    }
    let vos = c.vos.get(..c.count as usize).ok_or_else(|| {
        fail(
            VOCC_ERR_ARGUMENT,
            format!("cell: count {} is over {VOCC_MAX_VOS}", c.count),
        )
    })?;
    let mut qs = [QVo {
        a: QPoint::fine(0, 0),
        b: QPoint::fine(0, 0),
        level: 0,
        deep: false,
    }; VOCC_MAX_VOS];
    for (k, (v, q)) in vos.iter().zip(qs.iter_mut()).enumerate() {
        *q = QVo {
            a: QPoint {
                e: v.exp1,
                x: v.x1,
                y: v.y1,
            },
            b: QPoint {
                e: v.exp2,
                x: v.x2,
                y: v.y2,
            },
            level: v.level,
            deep: false,
        };
        if !q.in_range() {
            return Err(fail(
                VOCC_ERR_ARGUMENT,
                format!("cell: VO {k} has a field out of range (exponents 0..8, coordinates 0..512, level 0..32)"),
            ));
        }
        if !q.is_canonical() {
            return Err(fail(
                VOCC_ERR_ARGUMENT,
                format!("cell: VO {k} has an endpoint that is not canonical (a smaller exponent holds it)"),
            ));
        }
        if q.is_degenerate() {
            return Err(fail(
                VOCC_ERR_ARGUMENT,
                format!("cell: VO {k} is degenerate (one grid point)"),
            ));
        }
    }
    Ok(CellRecord::new(c.ground, &qs[..vos.len()])?)
}

pub(crate) fn in_grid(frame: &Frame, id: CellId) -> Result<(), Fail> {
    let cells = frame.grid.cell_count();
    if id as u64 >= cells {
        return Err(FormatError::CellOutOfGrid { id, cells }.into());
    }
    Ok(())
}
