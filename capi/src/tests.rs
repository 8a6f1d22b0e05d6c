//! The C ABI called as C would call it: results equal the Rust runtime's, every bad pointer,
//! length, frame, cell and byte string gives its status and message without a panic, panics are
//! caught, and the culling path allocates nothing (a counting allocator, per thread).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::ffi::CStr;

use vocc::runtime::format::{
    encode_blob, encode_store, encode_store_with, CellRecord, SceneSection,
};
use vocc::runtime::frame::QPoint;
use vocc::runtime::{Frame, GridDescriptor, QVo};

use super::boundary::report;
use super::*;

struct Counting;

thread_local! {
    static ALLOCS: Cell<u64> = const { Cell::new(0) };
}

// SAFETY: every method forwards to the system allocator with its own arguments, so the GlobalAlloc contract holds as it does for `System`.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        // SAFETY: the caller's arguments, under GlobalAlloc's contract, passed on unchanged.
        unsafe { System.alloc(l) }
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        // SAFETY: the caller's arguments, under GlobalAlloc's contract, passed on unchanged.
        unsafe { System.alloc_zeroed(l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        // SAFETY: the caller's arguments, under GlobalAlloc's contract, passed on unchanged.
        unsafe { System.realloc(p, l, n) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        // SAFETY: the caller's arguments, under GlobalAlloc's contract, passed on unchanged.
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
        // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
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
            // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
            unsafe { vocc_store_cell(self.store, id, &mut c, ptr::null_mut()) },
            VOCC_OK
        );
        c
    }
}

impl Drop for Fixture {
    fn drop(&mut self) {
        // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
        unsafe {
            vocc_query_free(self.query);
            vocc_tree_free(self.tree);
            vocc_store_free(self.store);
        }
    }
}

#[test]
fn pvs_equals_the_rust_culler_for_every_cell_as_ids_and_bitmap() {
    let fx = Fixture::new();
    let f = frame();
    assert_eq!(fx.frame, VoccFrame::from(&f));
    // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
    assert_eq!(unsafe { vocc_store_cell_count(fx.store) }, 25);
    // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
    assert_eq!(unsafe { vocc_tree_len(fx.tree) }, fx.boxes.len());
    let tree = BoxTree::new(&fx.boxes);
    let recs = records();
    let mut ids = vec![0u32; fx.boxes.len()];
    let mut bits = vec![0u8; fx.boxes.len().div_ceil(8)];
    let mut some_culled = false;
    for id in 0..25u32 {
        let cell = fx.cell(id);
        assert_eq!(cell, VoccCell::from(&recs[id as usize]), "cell {id}");
        let mut want = Vec::new();
        pvs(&f, id, &recs[id as usize], &tree, &mut want);
        some_culled |= want.len() < fx.boxes.len();
        let mut n = 0;
        let mut e = blank_error();
        // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
        let st = unsafe {
            vocc_pvs(
                fx.query,
                fx.tree,
                &fx.frame,
                id,
                &cell,
                ids.as_mut_ptr(),
                ids.len(),
                &mut n,
                &mut e,
            )
        };
        assert_eq!((st, e.code), (VOCC_OK, VOCC_OK));
        assert_eq!(&ids[..n], &want[..], "cell {id}");
        let mut m = 0;
        // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
        let (p, got) = unsafe {
            let p = vocc_query_ids(fx.query, &mut m);
            (p, std::slice::from_raw_parts(p, m))
        };
        assert!(!p.is_null());
        assert_eq!(got, &want[..]);
        // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
        let st = unsafe {
            vocc_pvs_bitmap(
                fx.query,
                fx.tree,
                &fx.frame,
                id,
                &cell,
                bits.as_mut_ptr(),
                bits.len(),
                &mut m,
                ptr::null_mut(),
            )
        };
        assert_eq!(st, VOCC_OK);
        assert_eq!(m, want.len());
        let from_bits: Vec<u32> = (0..fx.boxes.len() as u32)
            .filter(|&i| bits[i as usize / 8] >> (i % 8) & 1 == 1)
            .collect();
        assert_eq!(from_bits, want, "cell {id}");
    }
    assert!(some_culled, "the fixture must cull something");
    // The two invalid boxes are in every PVS.
    let cell = fx.cell(12);
    let mut n = 0;
    // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
    unsafe {
        vocc_pvs(
            fx.query,
            fx.tree,
            &fx.frame,
            12,
            &cell,
            ids.as_mut_ptr(),
            ids.len(),
            &mut n,
            ptr::null_mut(),
        );
    }
    assert!(ids[..n].ends_with(&[3000, 3001]));
}

#[test]
fn world_boxes_with_the_origin_give_the_local_result() {
    let fx = Fixture::new();
    let o = frame().origin;
    let world: Vec<[f64; 6]> = fx
        .boxes
        .iter()
        .map(|b| {
            [
                b[0] + o[0],
                b[1] + o[1],
                b[2] + o[2],
                b[3] + o[0],
                b[4] + o[1],
                b[5] + o[2],
            ]
        })
        .collect();
    let mut t = ptr::null_mut();
    let mut e = blank_error();
    let rust = BoxTree::from_world(&world, o);
    assert_eq!(
        // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
        unsafe {
            vocc_tree_new(
                world.as_ptr().cast(),
                world.len(),
                o.as_ptr(),
                &mut t,
                &mut e,
            )
        },
        VOCC_OK
    );
    let cell = fx.cell(12);
    let mut want = Vec::new();
    pvs(&frame(), 12, &records()[12], &rust, &mut want);
    let mut n = 0;
    let mut ids = vec![0u32; world.len()];
    // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
    let st = unsafe {
        vocc_pvs(
            fx.query,
            t,
            &fx.frame,
            12,
            &cell,
            ids.as_mut_ptr(),
            ids.len(),
            &mut n,
            &mut e,
        )
    };
    assert_eq!(st, VOCC_OK);
    assert_eq!(&ids[..n], &want[..]);
    assert!(n < world.len());
    // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
    unsafe { vocc_tree_free(t) };
}

#[test]
fn cell_at_and_rect_follow_the_grid() {
    let fx = Fixture::new();
    let mut id = 99;
    // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
    unsafe {
        assert_eq!(vocc_cell_at(&fx.frame, 250.0, 250.0, &mut id), VOCC_OK);
        assert_eq!(id, 12);
        assert_eq!(
            vocc_cell_at_world(&fx.frame, 843000.0 + 499.9, 6518000.0 + 0.5, &mut id),
            VOCC_OK
        );
        assert_eq!(id, 4);
        id = 99;
        assert_eq!(
            vocc_cell_at(&fx.frame, 500.0, 10.0, &mut id),
            VOCC_ERR_OUTSIDE_GRID
        );
        assert_eq!(
            vocc_cell_at(&fx.frame, f64::NAN, 10.0, &mut id),
            VOCC_ERR_OUTSIDE_GRID
        );
        assert_eq!(id, 99, "no output on failure");
        let mut r = [0.0; 4];
        assert_eq!(vocc_cell_rect(&fx.frame, 7, r.as_mut_ptr()), VOCC_OK);
        assert_eq!(r, [200.0, 100.0, 300.0, 200.0]);
        assert_eq!(
            vocc_cell_rect(&fx.frame, 25, r.as_mut_ptr()),
            VOCC_ERR_OUTSIDE_GRID
        );
        let cell = fx.cell(12);
        let mut g = VoccVoGeom::default();
        assert_eq!(vocc_vo_geometry(&fx.frame, 12, &cell, 0, &mut g), VOCC_OK);
        let want = frame().dequantize(12, 0, &records()[12].vos()[0]).unwrap();
        assert_eq!((g.a, g.b, g.g, g.h), (want.a, want.b, want.g, want.h));
        assert_eq!(
            vocc_vo_geometry(&fx.frame, 12, &cell, 2, &mut g),
            VOCC_ERR_ARGUMENT
        );
        let s = CStr::from_ptr(vocc_version()).to_str().unwrap();
        assert_eq!(s, env!("CARGO_PKG_VERSION"));
    }
}

#[test]
fn blobs_and_frames_decode_like_the_store() {
    let fx = Fixture::new();
    let f = frame();
    let frame_bytes = vocc::runtime::format::encode_frame(&f);
    let mut fr = VoccFrame::from(&Frame {
        quantum: 3.0,
        ..frame()
    });
    let mut e = blank_error();
    // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
    unsafe {
        assert_eq!(
            vocc_frame_decode(frame_bytes.as_ptr(), frame_bytes.len(), &mut fr, &mut e),
            VOCC_OK
        );
        assert_eq!(fr, fx.frame);
        assert_eq!(
            vocc_frame_decode(frame_bytes.as_ptr(), 111, &mut fr, &mut e),
            VOCC_ERR_FORMAT
        );
        assert_eq!(msg(&e), "truncated: 112 bytes needed, 111 given");
    }
    for (id, rec) in records().iter().enumerate() {
        let blob = encode_blob(&f, id as u32, rec).unwrap();
        let (mut got_id, mut cell) = (0u32, VoccCell::default());
        // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
        let st = unsafe {
            vocc_blob_decode(
                &fr,
                blob.as_ptr(),
                blob.len(),
                &mut got_id,
                &mut cell,
                &mut e,
            )
        };
        assert_eq!(st, VOCC_OK);
        assert_eq!((got_id, cell), (id as u32, fx.cell(id as u32)));
    }
    let mut blob = encode_blob(&f, 12, &records()[12]).unwrap();
    blob[12] ^= 1;
    let (mut got_id, mut cell) = (0u32, VoccCell::default());
    // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
    let st = unsafe {
        vocc_blob_decode(
            &fr,
            blob.as_ptr(),
            blob.len(),
            &mut got_id,
            &mut cell,
            &mut e,
        )
    };
    assert_eq!((st, e.code), (VOCC_ERR_CHECKSUM, VOCC_ERR_CHECKSUM));
    assert!(msg(&e).starts_with("checksum mismatch"), "{}", msg(&e));
}

#[test]
fn a_1_0_store_and_blob_read_as_2_0_ones_and_the_store_info() {
    // The 1.0 store of FORMAT.md: its frame, the records of its cells.
    let v1 = unhex(STORE_V1);
    let mut s: *mut VoccStore = ptr::null_mut();
    let mut e = blank_error();
    let f = Frame {
        grid: GridDescriptor {
            nx: 3,
            ny: 1,
            ..frame().grid
        },
        ..frame()
    };
    let mut info = VoccStoreInfo {
        major: 0,
        minor: 0,
        objects: 9,
        scene: 9,
        crs_len: 9,
        crs: [b'x' as c_char; VOCC_CRS_LEN],
    };
    // SAFETY: every pointer passed is NULL where the function allows it, a live object of this test (made by the library, not yet freed), or a buffer of this test of the length passed.
    unsafe {
        assert_eq!(
            vocc_store_open(v1.as_ptr(), v1.len(), &mut s, &mut e),
            VOCC_OK
        );
        let mut fr = VoccFrame::from(&frame());
        assert_eq!(vocc_store_frame(s, &mut fr), VOCC_OK);
        assert_eq!(fr, VoccFrame::from(&f));
        let mut c = VoccCell::default();
        assert_eq!(vocc_store_cell(s, 0, &mut c, &mut e), VOCC_OK);
        assert_eq!((c.skipped, c.ground, c.count), (0, 4, 2));
        assert_eq!(
            c.vos[0],
            VoccVo {
                x1: 196,
                y1: 376,
                x2: 336,
                y2: 376,
                exp1: 0,
                exp2: 0,
                level: 5
            }
        );
        assert_eq!(vocc_store_info(s, &mut info), VOCC_OK);
        assert_eq!(
            (
                info.major,
                info.minor,
                info.objects,
                info.scene,
                info.crs_len
            ),
            (1, 0, 0, 0, 0)
        );
        assert_eq!(info.crs[0], 0);
        // The same cell from its 1.0 blob.
        let blob = unhex(BLOB_V1);
        let (mut id, mut b) = (9u32, VoccCell::default());
        assert_eq!(
            vocc_blob_decode(&fr, blob.as_ptr(), blob.len(), &mut id, &mut b, &mut e),
            VOCC_OK
        );
        assert_eq!((id, b), (0, c));
        vocc_store_free(s);
        // A 2.0 store with a scene section.
        let v2 = encode_store_with(
            &frame(),
            &records(),
            &SceneSection {
                objects: 3002,
                scene: 0x0123_4567_89ab_cdef,
                crs: "EPSG:2154",
            },
        )
        .unwrap();
        assert_eq!(
            vocc_store_open(v2.as_ptr(), v2.len(), &mut s, &mut e),
            VOCC_OK
        );
        assert_eq!(vocc_store_info(s, &mut info), VOCC_OK);
        assert_eq!(
            (
                info.major,
                info.minor,
                info.objects,
                info.scene,
                info.crs_len
            ),
            (2, 0, 3002, 0x0123_4567_89ab_cdef, 9)
        );
        assert_eq!(
            CStr::from_ptr(info.crs.as_ptr()).to_str().unwrap(),
            "EPSG:2154"
        );
        // Cell 18's far VO: exponents and a level above 15 come through.
        assert_eq!(vocc_store_cell(s, 18, &mut c, &mut e), VOCC_OK);
        assert_eq!(
            c.vos[0],
            VoccVo {
                x1: 181,
                y1: 406,
                x2: 406,
                y2: 406,
                exp1: 3,
                exp2: 2,
                level: 20
            }
        );
        let mut g = VoccVoGeom::default();
        let fr = VoccFrame::from(&frame());
        assert_eq!(vocc_vo_geometry(&fr, 18, &c, 0, &mut g), VOCC_OK);
        assert_eq!((g.a, g.b), ([50.0, 950.0], [650.0, 650.0]));
        assert_eq!(vocc_store_info(ptr::null(), &mut info), VOCC_ERR_NULL);
        assert_eq!(vocc_store_info(s, ptr::null_mut()), VOCC_ERR_NULL);
        vocc_store_free(s);
    }
}

mod refusals;
