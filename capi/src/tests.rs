//! The C ABI called as C would call it: results equal the Rust runtime's, every bad pointer,
//! length, frame, cell and byte string gives its status and message without a panic, panics are
//! caught, and the culling path allocates nothing (a counting allocator, per thread).
//!
//! This file holds what the tests share: the counting allocator, the fixture frame, records,
//! store and boxes, the 1.0 example bytes. The tests are in [`pvs`] (results against the Rust
//! culler), [`decode`] (stores, blobs, frames, refusals), [`arguments`] (bad arguments give
//! statuses) and [`boundary`] (no allocation, panics caught, messages cut).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::ffi::CStr;

use vocc::runtime::format::{encode_blob, encode_store, encode_store_with, SceneSection};

use super::*;

struct Counting;

thread_local! {
    static ALLOCS: Cell<u64> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.alloc(l) }
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.alloc_zeroed(l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.realloc(p, l, n) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

fn allocations<T>(f: impl FnOnce() -> T) -> (T, u64) {
    let before = ALLOCS.with(|c| c.get());
    let r = f();
    (r, ALLOCS.with(|c| c.get()) - before)
}

/// A 5×5 grid of 100 m cells with per-cell ground (the culler tests' frame).
fn frame() -> Frame {
    Frame {
        origin: [843000.0, 6518000.0, 0.0],
        grid: GridDescriptor {
            min_x: 0.0,
            min_y: 0.0,
            cell_size: 100.0,
            nx: 5,
            ny: 5,
        },
        quantum: 0.5,
        eye_lo: 1.5,
        eye_hi: 2.0,
        ground_z0: 160.0,
        ground_step: 0.5,
        h0: 4.0,
        h_ratio: 1.25,
    }
}

fn q(x1: u16, y1: u16, x2: u16, y2: u16, level: u8) -> QVo {
    QVo {
        a: QPoint::fine(x1, y1),
        b: QPoint::fine(x2, y2),
        level,
        deep: false,
    }
}

/// Cell 12 (centre (250, 250)) has two long walls north and east of it; cell 3 is skipped;
/// cell 18 a far wall (exponents 2 and 3) of level 20.
fn records() -> Vec<CellRecord> {
    let mut cells = vec![CellRecord::EMPTY; 25];
    // North: y = 250 + 60 from x = 150 to 350; east: x = 250 + 70 from y = 170 to 330.
    cells[12] = CellRecord::new(0, &[q(56, 376, 456, 376, 6), q(396, 96, 396, 416, 4)]).unwrap();
    cells[3] = CellRecord::Skipped;
    cells[7] = CellRecord::new(2, &[q(10, 400, 500, 400, 15)]).unwrap();
    // Cell 18, centre (350, 350): from (350 - 300, 350 + 600) (steps of 4 m) to
    // (350 + 300, 350 + 300) (steps of 2 m).
    let far = QVo {
        a: QPoint {
            e: 3,
            x: 256 - 75,
            y: 256 + 150,
        },
        b: QPoint {
            e: 2,
            x: 256 + 150,
            y: 256 + 150,
        },
        level: 20,
        deep: false,
    };
    cells[18] = CellRecord::new(1, &[far]).unwrap();
    cells
}

/// The 1.0 store of docs/FORMAT.md section 12 (3 cells; cell 0 has two VOs on ground level 4,
/// cell 1 is skipped).
const STORE_V1: &str =
    "89564f43430d0a1a010000000000000000000000f0b92941000000003cdd58410000000000000000\
    0000000000000000000000000000000000000000000059400300000001000000000000000000e03f\
    000000000000f83f00000000000000400000000000006440000000000000e03f0000000000001040\
    000000000000f43f0b0000009ac7b08202ff000000000004c4f042c55b7861e1d53a";

/// Cell 0 of that store as a 1.0 blob.
const BLOB_V1: &str = "564f434201000000000204c4f042c55b7861e1d53a85913567";

fn unhex(s: &str) -> Vec<u8> {
    let s: String = s.split_whitespace().collect();
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap())
        .collect()
}

/// A deterministic scatter of boxes over the grid, some behind the walls, a few invalid.
fn boxes() -> Vec<[f64; 6]> {
    let mut s: u64 = 12345;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut v = Vec::new();
    for _ in 0..3000 {
        let (x, y) = (next() * 500.0, next() * 500.0);
        let (w, d, h) = (1.0 + next() * 20.0, 1.0 + next() * 20.0, next() * 30.0);
        v.push([x, y, 160.0, x + w, y + d, 160.0 + h]);
    }
    v.push([f64::NAN, 0.0, 0.0, 1.0, 1.0, 1.0]);
    v.push([5.0, 5.0, 5.0, 1.0, 1.0, 1.0]);
    v
}

fn msg(e: &VoccError) -> String {
    // SAFETY: report() always NUL-terminates within the buffer.
    unsafe { CStr::from_ptr(e.message.as_ptr()) }
        .to_str()
        .unwrap()
        .to_string()
}

fn blank_error() -> VoccError {
    VoccError {
        code: -1,
        message: [b'x' as c_char; VOCC_MESSAGE_LEN],
    }
}

struct Fixture {
    bytes: Vec<u8>,
    store: *mut VoccStore,
    tree: *mut VoccTree,
    query: *mut VoccQuery,
    frame: VoccFrame,
    boxes: Vec<[f64; 6]>,
}

impl Fixture {
    fn new() -> Fixture {
        let bytes = encode_store(&frame(), &records()).unwrap();
        let boxes = boxes();
        let mut f = Fixture {
            bytes,
            store: ptr::null_mut(),
            tree: ptr::null_mut(),
            query: ptr::null_mut(),
            frame: VoccFrame::from(&frame()),
            boxes,
        };
        let mut e = blank_error();
        unsafe {
            assert_eq!(
                vocc_store_open(f.bytes.as_ptr(), f.bytes.len(), &mut f.store, &mut e),
                VOCC_OK
            );
            assert_eq!((e.code, msg(&e).as_str()), (0, ""));
            assert_eq!(vocc_store_frame(f.store, &mut f.frame), VOCC_OK);
            assert_eq!(
                vocc_tree_new(
                    f.boxes.as_ptr().cast(),
                    f.boxes.len(),
                    ptr::null(),
                    &mut f.tree,
                    &mut e
                ),
                VOCC_OK
            );
            assert_eq!(vocc_query_new(f.tree, &mut f.query, &mut e), VOCC_OK);
        }
        f
    }

    fn cell(&self, id: u32) -> VoccCell {
        let mut c = VoccCell::default();
        assert_eq!(
            unsafe { vocc_store_cell(self.store, id, &mut c, ptr::null_mut()) },
            VOCC_OK
        );
        c
    }
}

impl Drop for Fixture {
    fn drop(&mut self) {
        unsafe {
            vocc_query_free(self.query);
            vocc_tree_free(self.tree);
            vocc_store_free(self.store);
        }
    }
}

mod arguments;
mod boundary;
mod decode;
mod pvs;
