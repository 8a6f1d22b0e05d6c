//! The store format against its specification, `docs/FORMAT.md` (2.0, and 1.0 still read): the
//! worked hex examples of both versions read from the document and compared byte for byte with
//! the encoder (2.0) and with a 1.0 writer kept here from the document's 1.0 section (vocc writes
//! 2.0 only), one test per row of the "accepted?" tables (named after the row, and run on both
//! versions where the row applies to both), round trips, a no-allocation check, and property
//! tests with fixed seeds (random bytes and mutations of valid stores and blobs of both versions
//! never panic; accepted mutations re-encode to the same bytes). Builds and runs with
//! `--no-default-features`.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use vocc::runtime::crc::crc32;
use vocc::runtime::format::{
    decode_blob, decode_frame, encode_blob, encode_frame, encode_store, encode_store_with,
    CellRecord, FormatError, SceneSection, Store, VoList, BLOB_MIN_LEN, FRAME_LEN, HEADER_LEN,
};
use vocc::runtime::{pvs, BoxTree, Frame, GridDescriptor, QPoint, QVo};

// ---------------------------------------------------------------------------------------------
// Allocation counting, per thread (tests run in parallel).

struct Counting;

thread_local! {
    static ALLOCS: Cell<u64> = const { Cell::new(0) };
}

fn count_alloc() {
    let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        count_alloc();
        unsafe { System.alloc(l) }
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        count_alloc();
        unsafe { System.alloc_zeroed(l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        count_alloc();
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

// ---------------------------------------------------------------------------------------------
// The document's examples.

const DOC: &str = include_str!("../docs/FORMAT.md");

/// The bytes of the fenced block "```hex example:NAME" of FORMAT.md. Each line is
/// `OFFSET: hex bytes # comment`; the offset must be the number of bytes before the line.
fn doc_hex(name: &str) -> Vec<u8> {
    let fence = format!("```hex example:{name}\n");
    let start = DOC
        .find(&fence)
        .unwrap_or_else(|| panic!("FORMAT.md has no block {name}"))
        + fence.len();
    let len = DOC[start..].find("```").expect("unclosed block");
    let mut out = Vec::new();
    for line in DOC[start..start + len].lines() {
        let data = line.split('#').next().unwrap();
        let (off, hex) = data
            .split_once(':')
            .unwrap_or_else(|| panic!("no offset: {line}"));
        let off = usize::from_str_radix(off.trim(), 16).unwrap();
        assert_eq!(off, out.len(), "{name}: offset of line {line:?}");
        for tok in hex.split_whitespace() {
            assert_eq!(tok.len(), 2, "{name}: token {tok:?}");
            out.push(u8::from_str_radix(tok, 16).unwrap());
        }
    }
    out
}

/// The frame of FORMAT.md section 9 (both versions' examples).
fn doc_frame() -> Frame {
    Frame {
        origin: [843000.0, 6518000.0, 0.0],
        grid: GridDescriptor {
            min_x: 0.0,
            min_y: 0.0,
            cell_size: 100.0,
            nx: 3,
            ny: 1,
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

/// A VO of two endpoints of exponent 0 (the only kind 1.0 holds).
fn q(x1: u16, y1: u16, x2: u16, y2: u16, level: u8) -> QVo {
    QVo {
        a: QPoint::fine(x1, y1),
        b: QPoint::fine(x2, y2),
        level,
        deep: false,
    }
}

fn p(e: u8, x: u16, y: u16) -> QPoint {
    QPoint { e, x, y }
}

/// The records of FORMAT.md section 9 (2.0): cell 0 has a near wall, a far wall of exponent 3
/// and level 20, and a wall from near to far (exponents 0 and 2) of level 16.
fn doc_cells() -> Vec<CellRecord> {
    let far = QVo {
        a: p(3, 194, 406),
        b: p(3, 344, 406),
        level: 20,
        deep: false,
    };
    let north = QVo {
        a: p(0, 376, 346),
        b: p(2, 286, 456),
        level: 16,
        deep: false,
    };
    vec![
        CellRecord::new(4, &[q(196, 376, 336, 376, 5), far, north]).unwrap(),
        CellRecord::Skipped,
        CellRecord::EMPTY,
    ]
}

/// The scene section of FORMAT.md section 9.1.
fn doc_scene() -> SceneSection<'static> {
    SceneSection {
        objects: 2576,
        scene: 0x9e37_79b9_7f4a_7c15,
        crs: "EPSG:2154",
    }
}

/// The records of FORMAT.md section 12 (1.0).
fn doc_cells_v1() -> Vec<CellRecord> {
    vec![
        CellRecord::new(4, &[q(196, 376, 336, 376, 5), q(376, 176, 376, 346, 3)]).unwrap(),
        CellRecord::Skipped,
        CellRecord::EMPTY,
    ]
}

// ---------------------------------------------------------------------------------------------
// A 1.0 writer, as FORMAT.md section 12 describes the 1.0 layout (vocc itself writes 2.0 only):
// the tests build 1.0 stores and blobs with it, and the document's 1.0 examples pin it.

fn v1_record(out: &mut Vec<u8>, f: &Frame, rec: &CellRecord) {
    if let CellRecord::Vos { ground, vos, .. } = rec {
        if !vos.is_empty() {
            if f.per_cell_ground() {
                out.push(*ground);
            }
            for v in vos.iter() {
                assert!(v.fits_v1(), "1.0 cannot hold {v:?}");
                out.extend_from_slice(&v.to_bytes_v1());
            }
        }
    }
}

fn encode_v1(f: &Frame, cells: &[CellRecord]) -> Vec<u8> {
    let mut index = Vec::new();
    let mut table = Vec::new();
    let mut payload = Vec::new();
    for (i, r) in cells.iter().enumerate() {
        if i % 64 == 0 {
            table.extend_from_slice(&(payload.len() as u32).to_le_bytes());
        }
        index.push(r.index_byte());
        v1_record(&mut payload, f, r);
    }
    let mut out = b"\x89VOCC\r\n\x1a".to_vec();
    out.extend_from_slice(&1u16.to_le_bytes());
    out.extend_from_slice(&[0; 6]);
    out.extend_from_slice(&encode_frame(f));
    out.extend_from_slice(&(payload.len() as u32).to_le_bytes());
    out.extend_from_slice(&[0; 4]);
    out.extend(index);
    out.extend(table);
    out.extend(payload);
    fix_store_crc(&mut out);
    out
}

fn encode_v1_blob(f: &Frame, id: u32, rec: &CellRecord) -> Vec<u8> {
    let mut out = b"VOCB\x01".to_vec();
    out.extend_from_slice(&id.to_le_bytes());
    out.push(rec.index_byte());
    v1_record(&mut out, f, rec);
    out.extend_from_slice(&crc32(&out).to_le_bytes());
    out
}

fn fix_store_crc(b: &mut [u8]) {
    if b.len() >= HEADER_LEN {
        b[132..136].fill(0);
        let c = crc32(b);
        b[132..136].copy_from_slice(&c.to_le_bytes());
    }
}

fn fix_blob_crc(b: &mut [u8]) {
    if b.len() >= 4 {
        let n = b.len() - 4;
        let c = crc32(&b[..n]);
        b[n..].copy_from_slice(&c.to_le_bytes());
    }
}

fn frame_rule(e: Result<impl std::fmt::Debug, FormatError>) -> &'static str {
    match e {
        Err(FormatError::BadFrame(rule)) => rule.split(':').next().unwrap(),
        other => panic!("expected BadFrame, got {other:?}"),
    }
}

/// One of the document's two example stores, with where its parts lie.
struct Doc {
    major: u16,
    bytes: Vec<u8>,
    cells: Vec<CellRecord>,
    /// Offsets of the index, the block table, cell 0's ground byte and its VO `k`.
    index: usize,
    table: usize,
    ground: usize,
    vo0: usize,
    vo_bytes: usize,
    payload_len: u32,
    crc: u32,
}

impl Doc {
    fn vo(&self, k: usize) -> usize {
        self.vo0 + k * self.vo_bytes
    }
}

/// The 2.0 store of section 9.1 and the 1.0 store of section 12.
fn docs() -> [Doc; 2] {
    [
        Doc {
            major: 2,
            bytes: doc_hex("store"),
            cells: doc_cells(),
            index: 0x9e,
            table: 0xa1,
            ground: 0xa5,
            vo0: 0xa6,
            vo_bytes: 6,
            payload_len: 19,
            crc: 0xe700_4571,
        },
        Doc {
            major: 1,
            bytes: doc_hex("store-1.0"),
            cells: doc_cells_v1(),
            index: 0x88,
            table: 0x8b,
            ground: 0x8f,
            vo0: 0x90,
            vo_bytes: 5,
            payload_len: 11,
            crc: 0x82b0_c79a,
        },
    ]
}

/// The cell-0 blobs of sections 9.2 (2.0) and 12 (1.0), with where cell 0's VO 0 lies and how
/// long a VO is.
fn doc_blobs() -> [(u16, Vec<u8>, Vec<CellRecord>, usize); 2] {
    [
        (2, doc_hex("blob-cell0"), doc_cells(), 6),
        (1, doc_hex("blob-1.0-cell0"), doc_cells_v1(), 5),
    ]
}

fn doc_store() -> Vec<u8> {
    doc_hex("store")
}

#[test]
fn doc_store_example_is_the_encoder_output() {
    let doc = doc_store();
    assert_eq!(doc.len(), 184);
    let bytes = encode_store_with(&doc_frame(), &doc_cells(), &doc_scene()).unwrap();
    assert_eq!(bytes, doc);
    let s = Store::parse(&doc).unwrap();
    assert_eq!(*s.frame(), doc_frame());
    assert_eq!((s.version(), s.major(), s.vo_bytes()), ((2, 0), 2, 6));
    assert_eq!(s.scene_section(), doc_scene());
    assert_eq!(
        (s.objects(), s.scene(), s.crs()),
        (2576, 0x9e3779b97f4a7c15, "EPSG:2154")
    );
    assert_eq!(s.cell_count(), 3);
    for (i, rec) in doc_cells().iter().enumerate() {
        assert_eq!(s.cell(i as u32).unwrap(), *rec);
    }
    assert_eq!(
        (
            s.cell_bytes(0),
            s.cell_bytes(1),
            s.cell_bytes(2),
            s.cell_bytes(3)
        ),
        (20, 1, 1, 0)
    );
    assert_eq!(s.cell_at(150.0, 99.0), Some(1));
    assert_eq!(s.cell_at(300.0, 0.0), None);
    // The frame's 112 bytes sit at offset 16.
    assert_eq!(&doc[16..128], &encode_frame(&doc_frame())[..]);
    // With an empty scene section: the 9 bytes of the CRS name fewer, the rest of it zero.
    let plain = encode_store(&doc_frame(), &doc_cells()).unwrap();
    assert_eq!(plain.len(), 184 - 9);
    assert_eq!(&plain[136..149], &[0; 13]);
    assert_eq!(
        Store::parse(&plain).unwrap().scene_section(),
        SceneSection::NONE
    );
}

#[test]
fn doc_blob_examples_are_the_encoder_output() {
    let f = doc_frame();
    let cells = doc_cells();
    let b0 = doc_hex("blob-cell0");
    assert_eq!(encode_blob(&f, 0, &cells[0]).unwrap(), b0);
    assert_eq!(decode_blob(&f, &b0).unwrap(), (0, cells[0]));
    let b1 = doc_hex("blob-cell1");
    assert_eq!(encode_blob(&f, 1, &cells[1]).unwrap(), b1);
    assert_eq!(decode_blob(&f, &b1).unwrap(), (1, CellRecord::Skipped));
    assert_eq!((b0.len(), b1.len()), (33, BLOB_MIN_LEN));
    // A blob's record is its store's record.
    let s = doc_store();
    assert_eq!(&b0[10..29], &s[0xa5..0xb8]);
}

#[test]
fn doc_worked_vo_decoding_matches_the_frame() {
    // FORMAT.md sections 3 and 9.1, the prose: the three VOs of cell 0.
    let f = doc_frame();
    let s = doc_store();
    let vo = |k: usize| -> [u8; 6] { s[0xa6 + 6 * k..0xac + 6 * k].try_into().unwrap() };
    let near = QVo::from_bytes(vo(0));
    assert_eq!(near, q(196, 376, 336, 376, 5));
    assert_eq!(vo(0), [0x20, 0x86, 0x17, 0x50, 0xf1, 0x16]);
    let g = f.dequantize(0, 4, &near).unwrap();
    assert_eq!(
        (g.a, g.b, g.g, g.h),
        ([20.0, 110.0], [90.0, 110.0], 162.0, 172.20703125)
    );
    let w = u64::from_le_bytes([0x13, 0x66, 0x79, 0x58, 0x2d, 0x53, 0, 0]);
    assert_eq!(w, 0x532d_5879_6613);
    assert_eq!(
        (w & 0x1f_ffff, w >> 21 & 0x1f_ffff, w >> 42),
        (0x19_6613, 0x19_6ac3, 20)
    );
    let far = QVo::from_bytes(vo(1));
    assert_eq!(
        (far.a, far.b, far.level),
        (p(3, 194, 406), p(3, 344, 406), 20)
    );
    assert_eq!(far.a.offset(f.quantum), [-248.0, 600.0]);
    let g = f.dequantize(0, 4, &far).unwrap();
    assert_eq!(
        (g.a, g.b, g.h),
        ([-198.0, 650.0], [402.0, 650.0], 506.9446951953614)
    );
    let north = QVo::from_bytes(vo(2));
    assert_eq!(
        (north.a, north.b, north.level),
        (p(0, 376, 346), p(2, 286, 456), 16)
    );
    let g = f.dequantize(0, 4, &north).unwrap();
    assert_eq!(
        (g.a, g.b, g.h),
        ([110.0, 95.0], [110.0, 450.0], 302.10854715202004)
    );
    // Section 3.2's canonical forms.
    assert!(!p(3, 200, 300).is_canonical());
    assert_eq!(p(3, 200, 300).canonical(), p(1, 32, 432));
    assert_eq!(p(1, 32, 432).steps(), p(3, 200, 300).steps());
    assert!(p(3, 194, 406).is_canonical() && p(2, 286, 456).is_canonical());
    assert!(!p(3, 256, 256).is_canonical() && p(0, 256, 256).is_canonical());
    // Section 7's check value.
    assert_eq!(crc32(b"123456789"), 0xCBF43926);
}

#[test]
fn doc_sizes_of_section_10() {
    // The worked city: 10,000 cells, 9,000 of them with 8 VOs on their own ground (1 byte), a
    // CRS name of 9 bytes.
    let blocks = 10_000usize.div_ceil(64);
    assert_eq!(blocks, 157);
    assert_eq!(
        136 + 13 + 9 + 10_000 + 4 * blocks + 9_000 * (1 + 6 * 8),
        451_786
    );
    // The same in 1.0: 5 bytes per VO, no scene section.
    assert_eq!(136 + 10_000 + 4 * blocks + 9_000 * (1 + 5 * 8), 379_764);
    // Checked against the encoder on a smaller grid of the same shape: 100 cells, 90 with 8.
    let mut f = doc_frame();
    f.grid.nx = 10;
    f.grid.ny = 10;
    let rec = CellRecord::new(7, &[q(1, 2, 3, 4, 5); 8]).unwrap();
    let cells: Vec<CellRecord> = (0..100)
        .map(|i| if i < 90 { rec } else { CellRecord::EMPTY })
        .collect();
    let scene = SceneSection {
        crs: "EPSG:3946",
        ..SceneSection::NONE
    };
    let b = encode_store_with(&f, &cells, &scene).unwrap();
    assert_eq!(b.len(), 136 + 13 + 9 + 100 + 4 * 2 + 90 * 49);
    assert_eq!(encode_v1(&f, &cells).len(), 136 + 100 + 4 * 2 + 90 * 41);
}

#[test]
fn doc_v1_examples_are_still_read() {
    // FORMAT.md section 12: the 1.0 bytes, pinned by this file's 1.0 writer, read as 2.0
    // records with exponents 0.
    let doc = doc_hex("store-1.0");
    assert_eq!(doc.len(), 154);
    assert_eq!(encode_v1(&doc_frame(), &doc_cells_v1()), doc);
    let s = Store::parse(&doc).unwrap();
    assert_eq!((s.version(), s.major(), s.vo_bytes()), ((1, 0), 1, 5));
    assert_eq!(s.scene_section(), SceneSection::NONE);
    assert_eq!(*s.frame(), doc_frame());
    for (i, rec) in doc_cells_v1().iter().enumerate() {
        assert_eq!(s.cell(i as u32).unwrap(), *rec);
    }
    assert_eq!((s.cell_bytes(0), s.cell_bytes(1)), (12, 1));
    let f = doc_frame();
    for (name, id, rec) in [
        ("blob-1.0-cell0", 0, doc_cells_v1()[0]),
        ("blob-1.0-cell1", 1, CellRecord::Skipped),
    ] {
        let b = doc_hex(name);
        assert_eq!(encode_v1_blob(&f, id, &rec), b);
        assert_eq!(decode_blob(&f, &b).unwrap(), (id, rec));
    }
    assert_eq!(doc_hex("blob-1.0-cell0").len(), 25);
    // The prose of section 12: the two VOs.
    let a = QVo::from_bytes_v1([0xc4, 0xf0, 0x42, 0xc5, 0x5b]);
    assert_eq!(a, q(196, 376, 336, 376, 5));
    let g = f.dequantize(0, 4, &a).unwrap();
    assert_eq!(
        (g.a, g.b, g.g, g.h),
        ([20.0, 110.0], [90.0, 110.0], 162.0, 172.20703125)
    );
    let b = QVo::from_bytes_v1([0x78, 0x61, 0xe1, 0xd5, 0x3a]);
    assert_eq!(b, q(376, 176, 376, 346, 3));
    let g = f.dequantize(0, 4, &b).unwrap();
    assert_eq!((g.a, g.b, g.h), ([110.0, 10.0], [110.0, 95.0], 167.8125));
    // Re-encoded, a 1.0 store is the 2.0 store of the same records with an empty scene
    // section; the same VO takes 6 bytes there.
    let again = encode_store(s.frame(), &doc_cells_v1()).unwrap();
    assert_eq!(again.len(), 154 + 13 + 2);
    let s2 = Store::parse(&again).unwrap();
    assert_eq!(s2.major(), 2);
    assert_eq!(s2.cell(0).unwrap(), s.cell(0).unwrap());
    assert_eq!(&again[0x9d..0xa3], &q(196, 376, 336, 376, 5).to_bytes());
}

#[test]
fn doc_stores_drive_the_culler() {
    // What an engine does: parse once, build the tree once, query on cell entry; the same for
    // both versions.
    for d in docs() {
        let store = Store::parse(&d.bytes).unwrap();
        let boxes = [
            [50.0, 115.0, 162.0, 55.0, 118.0, 164.5], // 0: low, right behind cell 0's first VO
            [50.0, 115.0, 162.0, 55.0, 118.0, 180.0], // 1: too tall
            [50.0, 40.0, 162.0, 55.0, 45.0, 163.0],   // 2: inside cell 0
            [250.0, 50.0, 162.0, 260.0, 60.0, 163.0], // 3: inside cell 2
        ];
        let tree = BoxTree::new(&boxes);
        let mut visible = Vec::new();
        let id = store.cell_at(10.0, 10.0).unwrap();
        pvs(
            store.frame(),
            id,
            &store.cell(id).unwrap(),
            &tree,
            &mut visible,
        );
        assert_eq!(visible, [1, 2, 3], "{}.0", d.major);
        // Skipped cell 1, empty cell 2: everything.
        for id in [1, 2] {
            pvs(
                store.frame(),
                id,
                &store.cell(id).unwrap(),
                &tree,
                &mut visible,
            );
            assert_eq!(visible, [0, 1, 2, 3]);
        }
    }
    // 2.0's far VO (600 m north, 343 m above the top eye) hides a tower behind it.
    let bytes = doc_store();
    let store = Store::parse(&bytes).unwrap();
    let tree = BoxTree::new(&[
        [0.0, 700.0, 162.0, 40.0, 740.0, 400.0], // 0: behind the far VO, under its top
        [0.0, 700.0, 162.0, 40.0, 740.0, 1000.0], // 1: far above it
    ]);
    let mut visible = Vec::new();
    pvs(
        store.frame(),
        0,
        &store.cell(0).unwrap(),
        &tree,
        &mut visible,
    );
    assert_eq!(visible, [1]);
}

// ---------------------------------------------------------------------------------------------
// Section 8.2: the frame alone.

#[test]
fn frame_round_trips_and_r1_r2_lengths() {
    let f = doc_frame();
    let b = encode_frame(&f);
    assert_eq!(decode_frame(&b), Ok(f));
    assert_eq!(
        decode_frame(&b[..111]),
        Err(FormatError::Truncated {
            needed: 112,
            got: 111
        })
    );
    assert_eq!(
        decode_frame(&[]),
        Err(FormatError::Truncated {
            needed: 112,
            got: 0
        })
    );
    let mut long = b.to_vec();
    long.push(0);
    assert_eq!(
        decode_frame(&long),
        Err(FormatError::TrailingBytes {
            expected: 112,
            got: 113
        })
    );
}

#[test]
fn frame_rules_f1_to_f12_r3() {
    type Mutation = (&'static str, fn(&mut Frame));
    let cases: &[Mutation] = &[
        ("F1", |f| f.origin[0] = f64::NAN),
        ("F1", |f| f.origin[2] = f64::INFINITY),
        ("F1", |f| f.grid.min_y = f64::NEG_INFINITY),
        ("F1", |f| f.h_ratio = f64::NAN),
        ("F1", |f| f.ground_step = f64::INFINITY),
        ("F2", |f| f.grid.cell_size = 0.0),
        ("F2", |f| f.grid.cell_size = -100.0),
        ("F3", |f| f.grid.nx = 0),
        ("F3", |f| f.grid.ny = 0),
        ("F4", |f| {
            f.grid.nx = 1 << 16;
            f.grid.ny = (1 << 15) + 1;
        }),
        ("F4", |f| {
            f.grid.nx = u32::MAX;
            f.grid.ny = u32::MAX;
        }),
        ("F5", |f| f.quantum = 0.3),
        ("F5", |f| f.quantum = 2048.0),
        ("F5", |f| f.quantum = 1.0 / 2048.0),
        ("F5", |f| f.quantum = -0.5),
        ("F5", |f| f.quantum = 0.0),
        ("F6", |f| f.eye_lo = -0.1),
        ("F7", |f| f.eye_lo = 2.5),
        ("F8", |f| f.ground_step = -0.5),
        ("F9", |f| f.h0 = 0.0),
        ("F9", |f| f.h0 = -1.0),
        ("F10", |f| f.h_ratio = 0.99),
        ("F11", |f| {
            f.grid.cell_size = 1e306;
            f.grid.nx = 1000;
        }),
        ("F12", |f| f.ground_step = 1e307),
        ("F12", |f| f.h_ratio = 1e30),
    ];
    for (rule, m) in cases {
        let mut f = doc_frame();
        m(&mut f);
        assert_eq!(frame_rule(decode_frame(&encode_frame(&f))), *rule, "{f:?}");
        // The encoders refuse it too, and a store of either version carrying it is refused
        // with the same rule.
        assert_eq!(frame_rule(encode_store(&f, &[])), *rule);
        for d in docs() {
            let mut s = d.bytes.clone();
            s[16..128].copy_from_slice(&encode_frame(&f));
            fix_store_crc(&mut s);
            assert_eq!(frame_rule(Store::parse(&s)), *rule, "{}.0", d.major);
        }
    }
    // The limits themselves are accepted: 2^31 cells, quantum 2^-10 and 2^10.
    let mut f = doc_frame();
    f.grid.nx = 1 << 16;
    f.grid.ny = 1 << 15;
    f.quantum = 1.0 / 1024.0;
    assert_eq!(decode_frame(&encode_frame(&f)), Ok(f));
    f.quantum = 1024.0;
    assert_eq!(decode_frame(&encode_frame(&f)), Ok(f));
}

#[test]
fn f12_takes_the_highest_level_of_the_major() {
    // h0 = 1e306: the top of level 15 is finite (4.5e307), that of level 31 is not. A 1.0 store
    // may carry this frame (its levels stop at 15); a 2.0 store, a frame on its own and the
    // encoders may not.
    let mut f = doc_frame();
    f.h0 = 1e306;
    assert!(f.vo_top(f.ground_z(255) + f.eye_hi, 15).is_finite());
    assert!(!f.vo_top(f.ground_z(255) + f.eye_hi, 31).is_finite());
    let v1 = encode_v1(&f, &doc_cells_v1());
    assert_eq!(
        Store::parse(&v1).unwrap().cell(0).unwrap(),
        doc_cells_v1()[0]
    );
    assert_eq!(frame_rule(decode_frame(&encode_frame(&f))), "F12");
    assert_eq!(frame_rule(encode_store(&f, &doc_cells_v1())), "F12");
    assert_eq!(
        frame_rule(decode_blob(
            &f,
            &encode_v1_blob(&doc_frame(), 0, &doc_cells_v1()[0])
        )),
        "F12"
    );
    let mut s = doc_store();
    s[16..128].copy_from_slice(&encode_frame(&f));
    fix_store_crc(&mut s);
    assert_eq!(frame_rule(Store::parse(&s)), "F12");
}

#[test]
fn frame_r4_edge_values_are_accepted() {
    let mut f = doc_frame();
    f.eye_lo = 2.0;
    f.eye_hi = 2.0;
    f.h_ratio = 1.0;
    f.grid.min_x = -5000.0;
    f.grid.min_y = -7.5;
    f.ground_z0 = -30.0;
    f.eye_lo = 0.0;
    assert_eq!(decode_frame(&encode_frame(&f)), Ok(f));
}

// ---------------------------------------------------------------------------------------------
// Section 8.1: the store.

#[test]
fn s1_shorter_than_the_header() {
    for d in docs() {
        for n in [0, 1, 8, 135] {
            assert_eq!(
                Store::parse(&d.bytes[..n]).unwrap_err(),
                FormatError::Truncated {
                    needed: 136,
                    got: n as u64
                }
            );
        }
    }
}

#[test]
fn s2_bad_magic() {
    for d in docs() {
        let mut s = d.bytes.clone();
        s[0] = 0x88;
        assert_eq!(Store::parse(&s).unwrap_err(), FormatError::BadMagic);
        let mut s = d.bytes.clone();
        s[..8].copy_from_slice(b"\x89PNG\r\n\x1a\n");
        assert_eq!(Store::parse(&s).unwrap_err(), FormatError::BadMagic);
        // A store is not a blob.
        assert_eq!(
            decode_blob(&doc_frame(), &d.bytes).unwrap_err(),
            FormatError::BadMagic
        );
    }
    // A blob is not a store.
    for name in ["blob-cell0", "blob-1.0-cell0"] {
        let mut blob = doc_hex(name);
        blob.resize(200, 0);
        assert_eq!(Store::parse(&blob).unwrap_err(), FormatError::BadMagic);
    }
}

#[test]
fn s3_unknown_major() {
    for d in docs() {
        for major in [0u16, 3, 0x0102, 0xffff] {
            let mut s = d.bytes.clone();
            s[8..10].copy_from_slice(&major.to_le_bytes());
            fix_store_crc(&mut s);
            assert_eq!(
                Store::parse(&s).unwrap_err(),
                FormatError::UnsupportedVersion { major }
            );
        }
    }
    // The message names both majors read.
    assert_eq!(
        FormatError::UnsupportedVersion { major: 3 }.to_string(),
        "unsupported major version 3 (this reader implements 1 and 2)"
    );
}

#[test]
fn s4_any_minor_is_accepted() {
    for d in docs() {
        let mut s = d.bytes.clone();
        s[10..12].copy_from_slice(&7u16.to_le_bytes());
        fix_store_crc(&mut s);
        let st = Store::parse(&s).unwrap();
        assert_eq!(st.version(), (d.major, 7));
        assert_eq!(st.cell(0).unwrap(), d.cells[0]);
    }
}

#[test]
fn s5_nonzero_flags() {
    for d in docs() {
        for flags in [1u32, 0x8000_0000] {
            let mut s = d.bytes.clone();
            s[12..16].copy_from_slice(&flags.to_le_bytes());
            fix_store_crc(&mut s);
            assert_eq!(
                Store::parse(&s).unwrap_err(),
                FormatError::UnknownFlags { flags }
            );
        }
    }
}

#[test]
fn s6_bad_frame_in_the_header() {
    for d in docs() {
        let mut s = d.bytes.clone();
        // cell_size (frame offset 40, file offset 56) = -100.0
        s[56..64].copy_from_slice(&(-100.0f64).to_le_bytes());
        fix_store_crc(&mut s);
        assert_eq!(frame_rule(Store::parse(&s)), "F2");
        // nx = 0 (file offset 64): the frame is checked before the checksum.
        let mut s = d.bytes.clone();
        s[64..68].fill(0);
        assert_eq!(frame_rule(Store::parse(&s)), "F3");
    }
}

#[test]
fn s7_shorter_than_its_length_fields_say() {
    for d in docs() {
        let n = d.bytes.len() as u64;
        assert_eq!(
            Store::parse(&d.bytes[..n as usize - 1]).unwrap_err(),
            FormatError::Truncated {
                needed: n,
                got: n - 1
            }
        );
        // An oversized payload_len: refused before anything is read or allocated.
        let mut s = d.bytes.clone();
        s[128..132].copy_from_slice(&u32::MAX.to_le_bytes());
        fix_store_crc(&mut s);
        let payload_offset = d.ground as u64;
        assert_eq!(
            Store::parse(&s).unwrap_err(),
            FormatError::Truncated {
                needed: payload_offset + u32::MAX as u64,
                got: n
            }
        );
        // A grid of 2^31 cells in a small file.
        let mut s = d.bytes.clone();
        s[64..68].copy_from_slice(&(1u32 << 16).to_le_bytes());
        s[68..72].copy_from_slice(&(1u32 << 15).to_le_bytes());
        let cells = 1u64 << 31;
        assert_eq!(
            Store::parse(&s).unwrap_err(),
            FormatError::Truncated {
                needed: d.index as u64 + cells + 4 * (cells / 64) + d.payload_len as u64,
                got: n
            }
        );
    }
    // 2.0: a file that ends inside the scene section's 13 fixed bytes, or whose crs_len reaches
    // past its end.
    let s = doc_store();
    for n in [136, 140, 148] {
        assert_eq!(
            Store::parse(&s[..n]).unwrap_err(),
            FormatError::Truncated {
                needed: 149,
                got: n as u64
            }
        );
    }
    assert_eq!(
        Store::parse(&s[..150]).unwrap_err(),
        FormatError::Truncated {
            needed: 184,
            got: 150
        }
    );
    let mut s = doc_store();
    s[0x94] = 255;
    fix_store_crc(&mut s);
    assert_eq!(
        Store::parse(&s).unwrap_err(),
        FormatError::Truncated {
            needed: 184 + 246,
            got: 184
        }
    );
}

#[test]
fn s8_trailing_bytes() {
    for d in docs() {
        let mut s = d.bytes.clone();
        s.push(0);
        let n = d.bytes.len() as u64;
        assert_eq!(
            Store::parse(&s).unwrap_err(),
            FormatError::TrailingBytes {
                expected: n,
                got: n + 1
            }
        );
    }
    // 2.0: a crs_len one short leaves a byte over.
    let mut s = doc_store();
    s[0x94] = 8;
    fix_store_crc(&mut s);
    assert_eq!(
        Store::parse(&s).unwrap_err(),
        FormatError::TrailingBytes {
            expected: 183,
            got: 184
        }
    );
}

#[test]
fn s9_checksum_mismatch() {
    for d in docs() {
        let mut s = d.bytes.clone();
        s[d.vo0] ^= 0x01; // a bit of cell 0's first VO
        let Err(FormatError::Checksum { stored, computed }) = Store::parse(&s) else {
            panic!("expected Checksum");
        };
        assert_eq!(stored, d.crc);
        assert_ne!(computed, stored);
        // The checksum covers the frame, the scene section (2.0) and the index too.
        let mut places = vec![20, 100, d.index + 1, d.table, d.ground];
        if d.major == 2 {
            places.extend([0x88, 0x8c, 0x93, 0x95, 0x9d]);
        }
        for at in places {
            let mut s = d.bytes.clone();
            s[at] ^= 0x40;
            assert!(
                matches!(Store::parse(&s), Err(FormatError::Checksum { .. })),
                "{}.0, offset {at:#x}",
                d.major
            );
        }
    }
}

#[test]
fn s10_reserved_index_values() {
    for d in docs() {
        // 11..=20 announce a rise byte in 2.1 (section 13): reserved in 1.0 only.
        let values: &[u8] = if d.major == 1 {
            &[11, 12, 20, 21, 0x80, 254]
        } else {
            &[21, 0x80, 254]
        };
        for &value in values {
            let mut s = d.bytes.clone();
            s[d.index + 1] = value; // cell 1
            fix_store_crc(&mut s);
            assert_eq!(
                Store::parse(&s).unwrap_err(),
                FormatError::BadIndexByte {
                    cell: 1,
                    value,
                    offset: d.index as u64 + 1
                }
            );
        }
    }
}

#[test]
fn s11_block_table_inconsistent_with_the_counts() {
    for d in docs() {
        let mut s = d.bytes.clone();
        s[d.table] = 1; // block 0 must start at 0
        fix_store_crc(&mut s);
        assert_eq!(
            Store::parse(&s).unwrap_err(),
            FormatError::BlockOffset {
                block: 0,
                stored: 1,
                expected: 0
            }
        );
        // A second block, off by 5.
        let mut f = doc_frame();
        f.grid.nx = 100;
        let mut cells = vec![CellRecord::EMPTY; 100];
        cells[3] = d.cells[0];
        cells[70] = d.cells[0];
        let (good, table) = if d.major == 2 {
            (encode_store(&f, &cells).unwrap(), HEADER_LEN + 13 + 100)
        } else {
            (encode_v1(&f, &cells), HEADER_LEN + 100)
        };
        let size = d.payload_len as u8;
        assert_eq!(&good[table..table + 8], &[0, 0, 0, 0, size, 0, 0, 0]);
        let mut s = good.clone();
        s[table + 4] = size + 5;
        fix_store_crc(&mut s);
        assert_eq!(
            Store::parse(&s).unwrap_err(),
            FormatError::BlockOffset {
                block: 1,
                stored: size as u32 + 5,
                expected: size as u64
            }
        );
    }
}

#[test]
fn s12_payload_len_inconsistent_with_the_counts() {
    for d in docs() {
        let record = |n: u32| 1 + n * d.vo_bytes as u32;
        let mut s = d.bytes.clone();
        s[d.index] = 1; // cell 0 claims 1 VO: a smaller record than payload_len says
        fix_store_crc(&mut s);
        assert_eq!(
            Store::parse(&s).unwrap_err(),
            FormatError::PayloadLength {
                stored: d.payload_len,
                expected: record(1) as u64
            }
        );
        // Counts asking for more than the payload holds.
        let mut s = d.bytes.clone();
        s[d.index + 2] = 1; // cell 2 claims 1 VO
        fix_store_crc(&mut s);
        assert_eq!(
            Store::parse(&s).unwrap_err(),
            FormatError::PayloadLength {
                stored: d.payload_len,
                expected: (d.payload_len + record(1)) as u64
            }
        );
    }
}

/// `d`'s bytes with VO `k` of cell 0 replaced by `vo` (its bytes in `d`'s version) and the
/// checksum made right.
fn with_vo(d: &Doc, k: usize, vo: &[u8]) -> Vec<u8> {
    let mut s = d.bytes.clone();
    s[d.vo(k)..d.vo(k) + d.vo_bytes].copy_from_slice(vo);
    fix_store_crc(&mut s);
    s
}

#[test]
fn s13_degenerate_vo() {
    for d in docs() {
        let degenerate = q(300, 20, 300, 20, 9);
        let bytes = if d.major == 2 {
            degenerate.to_bytes().to_vec()
        } else {
            degenerate.to_bytes_v1().to_vec()
        };
        assert_eq!(
            Store::parse(&with_vo(&d, 1, &bytes)).unwrap_err(),
            FormatError::DegenerateVo {
                cell: 0,
                vo: 1,
                offset: d.vo(1) as u64
            }
        );
        // All zero: both endpoints (0, 0) of exponent 0.
        assert_eq!(
            Store::parse(&with_vo(&d, 0, &vec![0; d.vo_bytes])).unwrap_err(),
            FormatError::DegenerateVo {
                cell: 0,
                vo: 0,
                offset: d.vo(0) as u64
            }
        );
    }
    // 2.0: the same far point at both ends, each canonical.
    let far = QVo {
        a: p(5, 0, 511),
        b: p(5, 0, 511),
        level: 31,
        deep: false,
    };
    assert_eq!(
        Store::parse(&with_vo(&docs()[0], 2, &far.to_bytes())).unwrap_err(),
        FormatError::DegenerateVo {
            cell: 0,
            vo: 2,
            offset: 0xb2
        }
    );
}

#[test]
fn s14_s15_s16_accepted_edge_cases() {
    // S14: no payload at all.
    let f = doc_frame();
    let cells = [CellRecord::EMPTY, CellRecord::Skipped, CellRecord::EMPTY];
    for (s, len) in [
        (encode_store(&f, &cells).unwrap(), 136 + 13 + 3 + 4),
        (encode_v1(&f, &cells), 136 + 3 + 4),
    ] {
        assert_eq!(s.len(), len);
        assert_eq!(&s[128..132], &[0, 0, 0, 0]);
        let st = Store::parse(&s).unwrap();
        for (i, r) in cells.iter().enumerate() {
            assert_eq!(st.cell(i as u32).unwrap(), *r);
        }
    }
    // S15: any ground byte.
    for d in docs() {
        let mut s = d.bytes.clone();
        s[d.ground] = 255;
        fix_store_crc(&mut s);
        assert_eq!(Store::parse(&s).unwrap().cell(0).unwrap().ground(), 255);
    }
    // S16: ground_step = -0.0 is flat: no ground byte.
    let mut f = doc_frame();
    f.ground_step = -0.0;
    let cells = [
        CellRecord::new(0, &[q(196, 376, 336, 376, 5)]).unwrap(),
        CellRecord::EMPTY,
        CellRecord::Skipped,
    ];
    for (s, len) in [
        (encode_store(&f, &cells).unwrap(), 136 + 13 + 3 + 4 + 6),
        (encode_v1(&f, &cells), 136 + 3 + 4 + 5),
    ] {
        assert_eq!(s.len(), len);
        let st = Store::parse(&s).unwrap();
        assert_eq!(st.frame().ground_step.to_bits(), (-0.0f64).to_bits());
        assert_eq!(st.cell(0).unwrap(), cells[0]);
    }
}

#[test]
fn s17_crs_not_utf8() {
    // "EPSG:2154" with its third byte replaced by 0xff: no UTF-8 sequence starts with it.
    let mut s = doc_store();
    s[0x97] = 0xff;
    fix_store_crc(&mut s);
    assert_eq!(
        Store::parse(&s).unwrap_err(),
        FormatError::CrsNotUtf8 { offset: 0x97 }
    );
    // A sequence cut by the end of the name ("EPSG:215" then the first byte of "é").
    let mut s = doc_store();
    s[0x9d] = 0xc3;
    fix_store_crc(&mut s);
    assert_eq!(
        Store::parse(&s).unwrap_err(),
        FormatError::CrsNotUtf8 { offset: 0x9d }
    );
    // Checked after the checksum and before the index.
    let mut s = doc_store();
    s[0x97] = 0xff;
    assert!(matches!(
        Store::parse(&s),
        Err(FormatError::Checksum { .. })
    ));
    s[0x9f] = 11; // cell 1's index byte, reserved
    fix_store_crc(&mut s);
    assert_eq!(
        Store::parse(&s).unwrap_err(),
        FormatError::CrsNotUtf8 { offset: 0x97 }
    );
}

#[test]
fn s18_deep_vo_bit_is_read_in_2_1() {
    // Bit 47 was reserved in 2.0; 2.1 reads it as the deep flag (FORMAT.md 3.1): the VO
    // stands from ground_z0. The same bytes otherwise.
    let d = &docs()[0];
    let mut s = d.bytes.clone();
    s[d.vo(1) + 5] |= 0x80; // bit 47 of cell 0's VO 1
    fix_store_crc(&mut s);
    let st = Store::parse(&s).unwrap();
    let rec = st.cell(0).unwrap();
    assert!(rec.vos()[1].deep && !rec.vos()[0].deep && !rec.vos()[2].deep);
    let g = st
        .frame()
        .dequantize(0, rec.stand(), &rec.vos()[1])
        .unwrap();
    assert_eq!(g.g, 160.0); // ground_z0, not the cell's 162
    assert_eq!(g.h, 506.9446951953614);
    // Re-encoded: the same records, minor 1.
    let mut cells = doc_cells();
    cells[0] = rec;
    let again = encode_store_with(&doc_frame(), &cells, &doc_scene()).unwrap();
    assert_eq!(&again[8..12], &[2, 0, 1, 0]);
    assert_eq!(Store::parse(&again).unwrap().cell(0).unwrap(), rec);
    // An all-ones VO is deep, canonical and degenerate (both ends (7, 511, 511)).
    assert!(matches!(
        Store::parse(&with_vo(d, 0, &[0xff; 6])).unwrap_err(),
        FormatError::DegenerateVo { .. }
    ));
}

#[test]
fn s19_non_canonical_endpoint() {
    let d = &docs()[0];
    // Endpoint a of VO 0, (20, 110), written with exponent 1: (196, 376) of 0.5 m is
    // (-60, 120) steps, (-30, 60) of 1 m, both inside -128..128.
    let a = p(1, 256 - 30, 256 + 60);
    assert_eq!(a.canonical(), p(0, 196, 376));
    let bad = QVo {
        a,
        b: p(0, 336, 376),
        level: 5,
        deep: false,
    };
    assert_eq!(
        Store::parse(&with_vo(d, 0, &bad.to_bytes())).unwrap_err(),
        FormatError::NonCanonicalVo {
            cell: 0,
            vo: 0,
            offset: 0xa6,
            endpoint: 'a'
        }
    );
    // Endpoint b of VO 1, (402, 650), with exponent 4 instead of 3: (44, 75) steps of 8 m.
    let bad = QVo {
        a: p(3, 194, 406),
        b: p(4, 256 + 44, 256 + 75),
        level: 20,
        deep: false,
    };
    assert_eq!(bad.b.canonical(), p(3, 344, 406));
    assert_eq!(
        Store::parse(&with_vo(d, 1, &bad.to_bytes())).unwrap_err(),
        FormatError::NonCanonicalVo {
            cell: 0,
            vo: 1,
            offset: 0xac,
            endpoint: 'b'
        }
    );
    // Checked before degeneracy: one position written two ways is refused as non-canonical.
    let twice = QVo {
        a,
        b: p(0, 196, 376),
        level: 5,
        deep: false,
    };
    assert_eq!(
        Store::parse(&with_vo(d, 2, &twice.to_bytes())).unwrap_err(),
        FormatError::NonCanonicalVo {
            cell: 0,
            vo: 2,
            offset: 0xb2,
            endpoint: 'a'
        }
    );
    // The first violation in file order wins: VO 0 non-canonical before VO 2 degenerate.
    let mut s = with_vo(d, 0, &twice.to_bytes());
    s[0xb2..0xb8].copy_from_slice(&q(1, 1, 1, 1, 0).to_bytes());
    fix_store_crc(&mut s);
    assert!(matches!(
        Store::parse(&s),
        Err(FormatError::NonCanonicalVo { vo: 0, .. })
    ));
}

#[test]
fn s20_exponents_levels_and_scene_values_are_accepted() {
    // Every exponent at either end, levels up to 31, any objects and fingerprint, a CRS name of
    // 255 bytes or of non-ASCII UTF-8.
    let f = doc_frame();
    let vos: Vec<QVo> = (0..8u8)
        .map(|e| QVo {
            a: p(e, 511, 0),
            b: p(7 - e, 0, 300 + e as u16),
            level: 24 + e,
            deep: false,
        })
        .collect();
    assert!(vos.iter().all(|v| v.is_canonical() && !v.is_degenerate()));
    let cells = [
        CellRecord::new(9, &vos).unwrap(),
        CellRecord::EMPTY,
        CellRecord::new(0, &vos[..1]).unwrap(),
    ];
    let long = "x".repeat(255);
    for crs in ["", "EPSG:3946", "RGF93 v1 / CC46 – Lyon", long.as_str()] {
        for (objects, scene) in [(0, 0), (u32::MAX, u64::MAX), (1, 1)] {
            let section = SceneSection {
                objects,
                scene,
                crs,
            };
            let b = encode_store_with(&f, &cells, &section).unwrap();
            assert_eq!(b.len(), 136 + 13 + crs.len() + 3 + 4 + (1 + 48) + (1 + 6));
            let s = Store::parse(&b).unwrap();
            assert_eq!(s.scene_section(), section);
            for (i, r) in cells.iter().enumerate() {
                assert_eq!(s.cell(i as u32).unwrap(), *r);
            }
        }
    }
    // The far ends dequantize exactly: exponent 7 is 64 m steps at quantum 0.5.
    let g = f.dequantize(0, 9, &vos[0]).unwrap();
    assert_eq!(g.b, [50.0 - 256.0 * 64.0, 50.0 + 44.0 * 64.0]);
}

#[test]
fn s21_a_1_0_store_is_read() {
    // Every row of 1.0 that 2.0 keeps is run on the 1.0 example above; here, its records come
    // out as 2.0 records (exponents 0) and it records no scene.
    let s1 = doc_hex("store-1.0");
    let st = Store::parse(&s1).unwrap();
    assert_eq!(st.major(), 1);
    assert_eq!((st.objects(), st.scene(), st.crs()), (0, 0, ""));
    let rec = st.cell(0).unwrap();
    assert!(rec.vos().iter().all(|v| v.a.e == 0 && v.b.e == 0));
    assert_eq!(rec, doc_cells_v1()[0]);
    // A 1.0 VO has no reserved bit and no exponent: every 5-byte value decodes (but a
    // degenerate one), here a level of 15, 1.0's highest.
    let d = &docs()[1];
    let s = with_vo(d, 1, &[0xff, 0xff, 0xff, 0xff, 0xf0]);
    let v = Store::parse(&s).unwrap().cell(0).unwrap().vos()[1];
    assert_eq!(v, q(511, 511, 511, 31, 15));
}

#[test]
fn store_cell_lookup_out_of_grid() {
    for d in docs() {
        let st = Store::parse(&d.bytes).unwrap();
        for id in [3, 64, u32::MAX] {
            assert_eq!(
                st.cell(id).unwrap_err(),
                FormatError::CellOutOfGrid { id, cells: 3 }
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Section 8.3: the blob.

#[test]
fn b0_blob_decoded_with_a_bad_frame() {
    let mut f = doc_frame();
    f.quantum = 0.3;
    for (_, b, _, _) in doc_blobs() {
        assert_eq!(frame_rule(decode_blob(&f, &b)), "F5");
    }
    assert_eq!(frame_rule(encode_blob(&f, 0, &CellRecord::EMPTY)), "F5");
}

#[test]
fn b1_to_b3_short_magic_major() {
    let f = doc_frame();
    for (_, b, _, _) in doc_blobs() {
        for n in [0, 4, 13] {
            assert_eq!(
                decode_blob(&f, &b[..n]).unwrap_err(),
                FormatError::Truncated {
                    needed: 14,
                    got: n as u64
                }
            );
        }
        let mut m = b.clone();
        m[3] = b'C';
        assert_eq!(decode_blob(&f, &m).unwrap_err(), FormatError::BadMagic);
        for major in [0u8, 3, 255] {
            let mut m = b.clone();
            m[4] = major;
            fix_blob_crc(&mut m);
            assert_eq!(
                decode_blob(&f, &m).unwrap_err(),
                FormatError::UnsupportedVersion {
                    major: major as u16
                }
            );
        }
    }
}

#[test]
fn b4_reserved_count() {
    let f = doc_frame();
    for (major, b, _, _) in doc_blobs() {
        // 11..=20 announce a rise byte in 2.1 (section 13): reserved in 1.0 only.
        let values: &[u8] = if major == 1 {
            &[11, 20, 21]
        } else {
            &[21, 254]
        };
        for &value in values {
            let mut b = b.clone();
            b[9] = value;
            assert_eq!(
                decode_blob(&f, &b).unwrap_err(),
                FormatError::BadIndexByte {
                    cell: 0,
                    value,
                    offset: 9
                }
            );
        }
    }
}

#[test]
fn b5_b6_length_must_match_the_count() {
    let f = doc_frame();
    for (major, b, _, _) in doc_blobs() {
        let n = b.len() as u64;
        assert_eq!(
            decode_blob(&f, &b[..n as usize - 1]).unwrap_err(),
            FormatError::Truncated {
                needed: n,
                got: n - 1
            }
        );
        let mut long = b.clone();
        long.push(0);
        assert_eq!(
            decode_blob(&f, &long).unwrap_err(),
            FormatError::TrailingBytes {
                expected: n,
                got: n + 1
            }
        );
        // With flat ground, the cell-0 blob has one byte too many.
        let mut flat = f;
        flat.ground_step = 0.0;
        assert_eq!(
            decode_blob(&flat, &b).unwrap_err(),
            FormatError::TrailingBytes {
                expected: n - 1,
                got: n
            }
        );
        // The major says how long a VO is: read as the other major, the length is wrong.
        let mut other = b.clone();
        other[4] = 3 - major as u8;
        fix_blob_crc(&mut other);
        assert!(matches!(
            decode_blob(&f, &other),
            Err(FormatError::Truncated { .. } | FormatError::TrailingBytes { .. })
        ));
    }
    // A skipped cell carries no ground byte and no VOs.
    for name in ["blob-cell1", "blob-1.0-cell1"] {
        let mut m = doc_hex(name);
        m.insert(10, 4);
        fix_blob_crc(&mut m);
        assert_eq!(
            decode_blob(&doc_frame(), &m).unwrap_err(),
            FormatError::TrailingBytes {
                expected: 14,
                got: 15
            }
        );
    }
}

#[test]
fn b7_checksum() {
    let f = doc_frame();
    for ((_, mut b, _, _), stored) in doc_blobs().into_iter().zip([0x2659_d4e8, 0x6735_9185]) {
        b[12] ^= 0x10;
        assert_eq!(
            decode_blob(&f, &b),
            Err(FormatError::Checksum {
                stored,
                computed: crc32(&b[..b.len() - 4])
            })
        );
    }
    // The id is covered too.
    for name in ["blob-cell1", "blob-1.0-cell1"] {
        let mut b = doc_hex(name);
        b[5] = 2;
        assert!(matches!(
            decode_blob(&f, &b),
            Err(FormatError::Checksum { .. })
        ));
    }
}

#[test]
fn b8_id_outside_the_grid() {
    let f = doc_frame();
    for name in ["blob-cell1", "blob-1.0-cell1"] {
        for id in [3u32, 1 << 31, u32::MAX] {
            let mut b = doc_hex(name);
            b[5..9].copy_from_slice(&id.to_le_bytes());
            fix_blob_crc(&mut b);
            assert_eq!(
                decode_blob(&f, &b).unwrap_err(),
                FormatError::CellOutOfGrid { id, cells: 3 }
            );
        }
    }
    assert_eq!(
        encode_blob(&f, 3, &CellRecord::EMPTY).unwrap_err(),
        FormatError::CellOutOfGrid { id: 3, cells: 3 }
    );
}

/// A blob with VO `k` replaced by `vo` and the checksum made right.
fn blob_with_vo(b: &[u8], vo_bytes: usize, k: usize, vo: &[u8]) -> Vec<u8> {
    let mut b = b.to_vec();
    let at = 11 + k * vo_bytes;
    b[at..at + vo_bytes].copy_from_slice(vo);
    fix_blob_crc(&mut b);
    b
}

#[test]
fn b9_degenerate_vo() {
    let f = doc_frame();
    for (major, b, _, vo_bytes) in doc_blobs() {
        let v = q(7, 8, 7, 8, 0);
        let bytes = if major == 2 {
            v.to_bytes().to_vec()
        } else {
            v.to_bytes_v1().to_vec()
        };
        assert_eq!(
            decode_blob(&f, &blob_with_vo(&b, vo_bytes, 1, &bytes)).unwrap_err(),
            FormatError::DegenerateVo {
                cell: 0,
                vo: 1,
                offset: 11 + vo_bytes as u64
            }
        );
    }
}

#[test]
fn b10_empty_and_skipped_blobs_are_14_bytes() {
    for ground_step in [0.0, 0.5] {
        let mut f = doc_frame();
        f.ground_step = ground_step;
        for rec in [CellRecord::EMPTY, CellRecord::Skipped] {
            for b in [
                encode_blob(&f, 2, &rec).unwrap(),
                encode_v1_blob(&f, 2, &rec),
            ] {
                assert_eq!(b.len(), 14);
                assert_eq!(decode_blob(&f, &b).unwrap(), (2, rec));
            }
        }
    }
}

#[test]
fn b11_deep_vo_bit_is_read_in_2_1() {
    let f = doc_frame();
    let mut b = doc_hex("blob-cell0");
    b[0x17 + 5] |= 0x80; // bit 47 of VO 2
    fix_blob_crc(&mut b);
    let (_, rec) = decode_blob(&f, &b).unwrap();
    assert!(rec.vos()[2].deep);
}

#[test]
fn b12_non_canonical_endpoint() {
    let f = doc_frame();
    let b = doc_hex("blob-cell0");
    // VO 0's endpoint b, (90, 110) = (80, 120) steps of 0.5 m, written as (40, 60) of 1 m.
    let bad = QVo {
        a: p(0, 196, 376),
        b: p(1, 256 + 40, 256 + 60),
        level: 5,
        deep: false,
    };
    assert_eq!(bad.b.canonical(), p(0, 336, 376));
    assert_eq!(
        decode_blob(&f, &blob_with_vo(&b, 6, 0, &bad.to_bytes())).unwrap_err(),
        FormatError::NonCanonicalVo {
            cell: 0,
            vo: 0,
            offset: 0x0b,
            endpoint: 'b'
        }
    );
}

#[test]
fn b13_a_1_0_blob_is_read() {
    // Its major says its VOs take 5 bytes; its record is the 2.0 record of exponents 0, which
    // encodes to the 2.0 blob of the same cell.
    let f = doc_frame();
    let b = doc_hex("blob-1.0-cell0");
    assert_eq!(b[4], 1);
    let (id, rec) = decode_blob(&f, &b).unwrap();
    assert_eq!((id, rec), (0, doc_cells_v1()[0]));
    let again = encode_blob(&f, id, &rec).unwrap();
    assert_eq!((again[4], again.len()), (2, b.len() + 2));
    assert_eq!(decode_blob(&f, &again).unwrap(), (id, rec));
    assert_eq!(
        decode_blob(&f, &doc_hex("blob-1.0-cell1")).unwrap(),
        (1, CellRecord::Skipped)
    );
}

// ---------------------------------------------------------------------------------------------
// Section 8.4: the encoder refuses what a decoder would refuse.

#[test]
fn encoder_refusals() {
    let f = doc_frame();
    let good = q(1, 2, 3, 4, 5);
    assert_eq!(
        encode_store(&f, &doc_cells()[..2]).unwrap_err(),
        FormatError::CellCount {
            expected: 3,
            got: 2
        }
    );
    let out_of_range = [
        q(512, 0, 1, 1, 0),
        q(0, 600, 1, 1, 0),
        q(0, 0, 1000, 1, 0),
        q(0, 0, 1, 512, 0),
        q(0, 0, 1, 1, 32),
        q(0, 0, 1, 1, 255),
        QVo {
            a: p(8, 0, 0),
            ..good
        },
        QVo {
            b: p(255, 0, 0),
            ..good
        },
    ];
    for bad in out_of_range {
        let rec = CellRecord::new(0, &[good, bad]).unwrap();
        assert_eq!(
            encode_store(&f, &[CellRecord::EMPTY, rec, CellRecord::EMPTY]).unwrap_err(),
            FormatError::VoOutOfRange { cell: 1, vo: 1 }
        );
        assert_eq!(
            encode_blob(&f, 1, &rec).unwrap_err(),
            FormatError::VoOutOfRange { cell: 1, vo: 1 }
        );
    }
    // Non-canonical and degenerate VOs: the offset is where the decoder would find them (cell
    // 0's record is 19 bytes; the doc's scene section takes 9 more bytes of CRS name).
    let non_canonical = QVo {
        a: p(1, 256, 300),
        ..good
    };
    for (bad, err) in [
        (
            non_canonical,
            FormatError::NonCanonicalVo {
                cell: 2,
                vo: 2,
                offset: 0,
                endpoint: 'a',
            },
        ),
        (
            q(5, 5, 5, 5, 1),
            FormatError::DegenerateVo {
                cell: 2,
                vo: 2,
                offset: 0,
            },
        ),
    ] {
        let at = |offset: u64| match err {
            FormatError::NonCanonicalVo { endpoint, .. } => FormatError::NonCanonicalVo {
                cell: 2,
                vo: 2,
                offset,
                endpoint,
            },
            _ => FormatError::DegenerateVo {
                cell: 2,
                vo: 2,
                offset,
            },
        };
        let rec = CellRecord::new(9, &[good, good, bad]).unwrap();
        let cells = [doc_cells()[0], CellRecord::Skipped, rec];
        let record = 136 + 13 + 3 + 4 + 19;
        assert_eq!(encode_store(&f, &cells).unwrap_err(), at(record + 1 + 12));
        assert_eq!(
            encode_store_with(&f, &cells, &doc_scene()).unwrap_err(),
            at(record + 9 + 1 + 12)
        );
        assert_eq!(encode_blob(&f, 2, &rec).unwrap_err(), at(23));
    }
    // A CRS name over 255 bytes, refused before the records are looked at.
    let long = "é".repeat(128);
    assert_eq!(
        encode_store_with(
            &f,
            &[],
            &SceneSection {
                crs: &long,
                ..SceneSection::NONE
            }
        )
        .unwrap_err(),
        FormatError::CrsTooLong { len: 256 }
    );
    // A ground that would not be stored: an empty cell, or flat ground.
    let empty_high = CellRecord::new(3, &[]).unwrap();
    assert_eq!(
        encode_blob(&f, 0, &empty_high).unwrap_err(),
        FormatError::GroundNotStored { cell: 0, ground: 3 }
    );
    let mut flat = f;
    flat.ground_step = 0.0;
    let high = CellRecord::new(3, &[good]).unwrap();
    assert_eq!(
        encode_store(&flat, &[CellRecord::EMPTY, CellRecord::EMPTY, high]).unwrap_err(),
        FormatError::GroundNotStored { cell: 2, ground: 3 }
    );
    // More than 10 VOs cannot be put in a record.
    assert_eq!(
        CellRecord::new(0, &[good; 11]).unwrap_err(),
        FormatError::TooManyVos { count: 11 }
    );
}

// ---------------------------------------------------------------------------------------------
// No allocation while decoding.

#[test]
fn decoding_allocates_nothing() {
    let mut f = doc_frame();
    f.grid.nx = 20;
    f.grid.ny = 10;
    let cells: Vec<CellRecord> = (0..200u16)
        .map(|i| {
            if i % 3 == 0 {
                CellRecord::Skipped
            } else {
                let vos: Vec<QVo> = (0..(i % 11)).map(|k| q(i, k, 511 - i, 300, 2)).collect();
                CellRecord::new(if vos.is_empty() { 0 } else { i as u8 }, &vos).unwrap()
            }
        })
        .collect();
    let scene = SceneSection {
        objects: 7,
        scene: 9,
        crs: "RGF93 / CC46",
    };
    let stores = [
        encode_store_with(&f, &cells, &scene).unwrap(),
        encode_v1(&f, &cells),
    ];
    let blobs: Vec<[Vec<u8>; 2]> = cells
        .iter()
        .enumerate()
        .map(|(i, r)| {
            [
                encode_blob(&f, i as u32, r).unwrap(),
                encode_v1_blob(&f, i as u32, r),
            ]
        })
        .collect();
    let frame_bytes = encode_frame(&f);
    let (ok, n) = allocations(|| {
        let mut all = true;
        for bytes in &stores {
            let s = Store::parse(bytes).unwrap();
            all &= s.crs().len() == 12 || s.crs().is_empty();
            for (i, r) in cells.iter().enumerate() {
                all &= s.cell(i as u32).unwrap() == *r;
                for b in &blobs[i] {
                    all &= decode_blob(&f, b).unwrap() == (i as u32, *r);
                }
            }
            // Refusals allocate nothing either.
            all &= Store::parse(&bytes[..bytes.len() - 1]).is_err();
        }
        all &= decode_frame(&frame_bytes).unwrap() == f;
        all &= Store::parse(&[0u8; 300]).is_err();
        all
    });
    assert!(ok);
    assert_eq!(n, 0, "decoding allocated {n} times");
}

// ---------------------------------------------------------------------------------------------
// Property tests.

fn arb_frame() -> impl Strategy<Value = Frame> {
    (
        1u32..12,
        1u32..12,
        prop_oneof![Just(0.0), Just(0.25), Just(1.0)],
        -3i32..=3,
        -1000.0f64..1000.0,
    )
        .prop_map(|(nx, ny, ground_step, k, min)| Frame {
            origin: [843000.0, 6518000.0, 12.0],
            grid: GridDescriptor {
                min_x: min,
                min_y: -min,
                cell_size: 50.0,
                nx,
                ny,
            },
            quantum: 2f64.powi(k),
            eye_lo: 1.0,
            eye_hi: 2.5,
            ground_z0: 150.0,
            ground_step,
            h0: 3.0,
            h_ratio: 1.3,
        })
}

/// A canonical endpoint: any exponent and mantissas, brought to canonical form (about half of
/// them are already).
fn arb_point() -> impl Strategy<Value = QPoint> {
    (0u8..8, 0u16..512, 0u16..512).prop_map(|(e, x, y)| p(e, x, y).canonical())
}

/// A 2.0 VO: canonical endpoints of any exponent, levels 0..32.
fn arb_qvo() -> impl Strategy<Value = QVo> {
    (arb_point(), arb_point(), 0u8..32)
        .prop_map(|(a, b, level)| QVo {
            a,
            b,
            level,
            deep: false,
        })
        .prop_filter("degenerate", |v| !v.is_degenerate())
}

/// A VO that 1.0 holds: exponents 0, levels 0..16.
fn arb_qvo_v1() -> impl Strategy<Value = QVo> {
    (0u16..512, 0u16..512, 0u16..512, 0u16..512, 0u8..16)
        .prop_map(|(x1, y1, x2, y2, level)| q(x1, y1, x2, y2, level))
        .prop_filter("degenerate", |v| !v.is_degenerate())
}

fn arb_record(
    per_cell_ground: bool,
    vo: impl Strategy<Value = QVo> + Clone + 'static,
) -> impl Strategy<Value = CellRecord> {
    prop_oneof![
        1 => Just(CellRecord::Skipped),
        1 => Just(CellRecord::EMPTY),
        4 => (any::<u8>(), prop::collection::vec(vo, 1..=10)).prop_map(move |(g, v)| {
            CellRecord::Vos {
                ground: if per_cell_ground { g } else { 0 },
                rise: 0,
                vos: VoList::from_slice(&v).unwrap(),
            }
        }),
    ]
}

/// A frame, its records (2.0 VOs, or 1.0 ones when `v1`) and a scene section (objects,
/// fingerprint, CRS name).
fn arb_store(v1: bool) -> impl Strategy<Value = (Frame, Vec<CellRecord>, (u32, u64, String))> {
    arb_frame().prop_flat_map(move |f| {
        let n = f.grid.cell_count() as usize;
        let records = if v1 {
            prop::collection::vec(arb_record(f.per_cell_ground(), arb_qvo_v1().boxed()), n).boxed()
        } else {
            prop::collection::vec(arb_record(f.per_cell_ground(), arb_qvo().boxed()), n).boxed()
        };
        let section = (
            any::<u32>(),
            any::<u64>(),
            prop_oneof![
                Just(String::new()),
                "[ -~é]{0,12}",
                Just("EPSG:3946".to_string())
            ],
        );
        (Just(f), records, section)
    })
}

fn section(s: &(u32, u64, String)) -> SceneSection<'_> {
    SceneSection {
        objects: s.0,
        scene: s.1,
        crs: &s.2,
    }
}

#[derive(Clone, Debug)]
enum Mutation {
    Flip(usize, u8),
    Set(usize, u8),
    Truncate(usize),
    Insert(usize, u8),
    Remove(usize),
    /// A u32 at a random place, or at a length/count field.
    SetU32(usize, u32),
}

fn arb_mutation() -> impl Strategy<Value = Mutation> {
    let big = prop_oneof![
        Just(0u32),
        Just(1),
        Just(u32::MAX),
        Just(1 << 31),
        Just(1 << 16),
        any::<u32>()
    ];
    prop_oneof![
        (any::<usize>(), 0u8..8).prop_map(|(i, b)| Mutation::Flip(i, b)),
        (any::<usize>(), any::<u8>()).prop_map(|(i, v)| Mutation::Set(i, v)),
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), any::<u8>()).prop_map(|(i, v)| Mutation::Insert(i, v)),
        any::<usize>().prop_map(Mutation::Remove),
        (
            prop_oneof![
                Just(5usize),
                Just(8),
                Just(16 + 48),
                Just(16 + 52),
                Just(128),
                Just(136),
                Just(145),
                any::<usize>()
            ],
            big
        )
            .prop_map(|(i, v)| Mutation::SetU32(i, v)),
    ]
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    let len = bytes.len();
    match *m {
        Mutation::Flip(i, b) if len > 0 => bytes[i % len] ^= 1 << b,
        Mutation::Set(i, v) if len > 0 => bytes[i % len] = v,
        Mutation::Truncate(i) => bytes.truncate(i % (len + 1)),
        Mutation::Insert(i, v) => bytes.insert(i % (len + 1), v),
        Mutation::Remove(i) if len > 0 => {
            bytes.remove(i % len);
        }
        Mutation::SetU32(i, v) if len >= 4 => {
            let at = i % (len - 3);
            bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
        }
        _ => {}
    }
}

/// Reads every cell of an accepted store; returns its records.
fn read_all(s: &Store<'_>) -> Vec<CellRecord> {
    (0..s.cell_count())
        .map(|i| s.cell(i).expect("a parsed store reads every cell"))
        .collect()
}

/// An accepted store re-encoded in its own version (2.0 by the encoder, 1.0 by this file's
/// writer): canonical encoding gives back its bytes, the minor version (and so the checksum)
/// aside. Its records also encode as 2.0 and read back the same.
fn check_canonical(bytes: &[u8], s: &Store<'_>) -> Result<(), TestCaseError> {
    let recs = read_all(s);
    let again = match s.major() {
        2 => encode_store_with(s.frame(), &recs, &s.scene_section()).unwrap(),
        1 => encode_v1(s.frame(), &recs),
        m => panic!("major {m} accepted"),
    };
    let mut expect = bytes.to_vec();
    // The encoder writes the lowest minor its records need: 1 with a deep VO (2.1), else 0.
    let deep = recs.iter().any(|r| r.vos().iter().any(|q| q.deep));
    expect[10..12].copy_from_slice(&[(deep && s.major() == 2) as u8, 0]);
    fix_store_crc(&mut expect);
    prop_assert_eq!(again, expect);
    match encode_store(s.frame(), &recs) {
        Ok(v2) => prop_assert_eq!(read_all(&Store::parse(&v2).unwrap()), recs),
        // A 1.0 frame whose top of level 31 is infinite cannot be written as 2.0.
        Err(FormatError::BadFrame(r)) if s.major() == 1 && r.starts_with("F12") => {}
        Err(e) => panic!("{e}"),
    }
    Ok(())
}

proptest! {
    #![proptest_config(Config {
        cases: 2000,
        rng_seed: RngSeed::Fixed(0x5eed_0005),
        failure_persistence: None,
        ..Config::default()
    })]

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        let f = doc_frame();
        let _ = Store::parse(&bytes);
        let _ = decode_blob(&f, &bytes);
        let _ = decode_frame(&bytes);
        // Behind a valid magic and major of either version too.
        for d in docs() {
            let mut s = d.bytes[..16].to_vec();
            s.extend_from_slice(&bytes);
            if let Ok(st) = Store::parse(&s) {
                read_all(&st);
            }
        }
        for (_, blob, _, _) in doc_blobs() {
            let mut b = blob[..5].to_vec();
            b.extend_from_slice(&bytes);
            let _ = decode_blob(&f, &b);
        }
    }

    #[test]
    fn mutated_stores_never_panic_and_accepted_ones_are_canonical(
        (v1, (f, cells, scene)) in any::<bool>().prop_flat_map(|v| (Just(v), arb_store(v))),
        muts in prop::collection::vec(arb_mutation(), 1..4),
        fix_crc in any::<bool>(),
    ) {
        let good = if v1 {
            encode_v1(&f, &cells)
        } else {
            encode_store_with(&f, &cells, &section(&scene)).unwrap()
        };
        let mut bytes = good.clone();
        for m in &muts {
            apply(&mut bytes, m);
        }
        if fix_crc {
            fix_store_crc(&mut bytes);
        }
        if let Ok(s) = Store::parse(&bytes) {
            check_canonical(&bytes, &s)?;
        }
    }

    #[test]
    fn mutated_blobs_never_panic_and_accepted_ones_are_canonical(
        (f, cells, _) in any::<bool>().prop_flat_map(arb_store),
        pick in any::<usize>(),
        muts in prop::collection::vec(arb_mutation(), 1..4),
        fix_crc in any::<bool>(),
    ) {
        let id = (pick % cells.len()) as u32;
        let rec = &cells[id as usize];
        let mut bytes = if rec.vos().iter().all(QVo::fits_v1) && pick % 2 == 1 {
            encode_v1_blob(&f, id, rec)
        } else {
            encode_blob(&f, id, rec).unwrap()
        };
        for m in &muts {
            apply(&mut bytes, m);
        }
        if fix_crc {
            fix_blob_crc(&mut bytes);
        }
        if let Ok((id2, rec)) = decode_blob(&f, &bytes) {
            // Re-encoded in the blob's own version: the same bytes.
            match bytes[4] {
                2 => prop_assert_eq!(encode_blob(&f, id2, &rec).unwrap(), bytes),
                1 => prop_assert_eq!(encode_v1_blob(&f, id2, &rec), bytes),
                m => panic!("major {m} accepted"),
            }
        }
    }
}

proptest! {
    #![proptest_config(Config {
        cases: 300,
        rng_seed: RngSeed::Fixed(0x5eed_0006),
        failure_persistence: None,
        ..Config::default()
    })]

    #[test]
    fn stores_and_blobs_round_trip((f, cells, scene) in arb_store(false)) {
        let bytes = encode_store_with(&f, &cells, &section(&scene)).unwrap();
        let n = f.grid.cell_count() as usize;
        let size = |r: &CellRecord| match r.vos().len() {
            0 => 0,
            k => 6 * k + f.per_cell_ground() as usize,
        };
        let records: usize = cells.iter().map(size).sum();
        prop_assert_eq!(
            bytes.len(),
            HEADER_LEN + 13 + scene.2.len() + n + 4 * n.div_ceil(64) + records
        );
        let s = Store::parse(&bytes).unwrap();
        prop_assert_eq!(*s.frame(), f);
        prop_assert_eq!(s.scene_section(), section(&scene));
        prop_assert_eq!(&read_all(&s), &cells);
        for (i, rec) in cells.iter().enumerate() {
            prop_assert_eq!(s.cell_bytes(i as u32), 1 + size(rec) as u64);
            let b = encode_blob(&f, i as u32, rec).unwrap();
            prop_assert_eq!(b.len(), BLOB_MIN_LEN + size(rec));
            prop_assert_eq!(decode_blob(&f, &b).unwrap(), (i as u32, *rec));
        }
        prop_assert_eq!(decode_frame(&encode_frame(&f)).unwrap(), f);
        prop_assert_eq!(FRAME_LEN, 112);
    }

    #[test]
    fn v1_stores_read_as_the_2_0_stores_of_their_records((f, cells, _) in arb_store(true)) {
        let old = encode_v1(&f, &cells);
        let new = encode_store(&f, &cells).unwrap();
        let (a, b) = (Store::parse(&old).unwrap(), Store::parse(&new).unwrap());
        prop_assert_eq!((a.major(), b.major()), (1, 2));
        prop_assert_eq!(read_all(&a), read_all(&b));
        prop_assert_eq!(&read_all(&a), &cells);
        for (i, rec) in cells.iter().enumerate() {
            let blob = encode_v1_blob(&f, i as u32, rec);
            prop_assert_eq!(decode_blob(&f, &blob).unwrap(), (i as u32, *rec));
            // Per cell, 2.0 costs one byte more per VO.
            prop_assert_eq!(
                b.cell_bytes(i as u32) - a.cell_bytes(i as u32),
                rec.vos().len() as u64
            );
        }
    }
}

/// The records of FORMAT.md section 13 (2.1): cell 0 with a rise of 6 and a deep far wall.
fn doc_cells_2_1() -> Vec<CellRecord> {
    let far = QVo {
        a: p(3, 194, 406),
        b: p(3, 344, 406),
        level: 20,
        deep: true,
    };
    vec![
        CellRecord::new(4, &[q(196, 376, 336, 376, 5), far])
            .unwrap()
            .with_rise(6),
        CellRecord::Skipped,
        CellRecord::EMPTY,
    ]
}

#[test]
fn doc_2_1_examples_are_the_encoder_output_and_read_back() {
    let f = doc_frame();
    let cells = doc_cells_2_1();
    let bytes = encode_store_with(&f, &cells, &doc_scene()).unwrap();
    assert_eq!(bytes, doc_hex("store-2.1"));
    let st = Store::parse(&bytes).unwrap();
    assert_eq!(st.version(), (2, 1));
    assert_eq!(st.cell(0).unwrap(), cells[0]);
    let blob = encode_blob(&f, 0, &cells[0]).unwrap();
    assert_eq!(blob, doc_hex("blob-2.1-cell0"));
    assert_eq!(decode_blob(&f, &blob).unwrap(), (0, cells[0]));
    // Section 13's worked figures.
    let rec = cells[0];
    let view = f.cell_view(0, rec.stand()).unwrap();
    assert_eq!((view.e0, view.e1), (163.5, 167.0));
    let g0 = f.dequantize(0, rec.stand(), &rec.vos()[0]).unwrap();
    assert_eq!((g0.g, g0.h), (162.0, 175.20703125));
    let g1 = f.dequantize(0, rec.stand(), &rec.vos()[1]).unwrap();
    assert_eq!((g1.g, g1.h), (160.0, 509.9446951953614));
    // Without the rise and the deep VO, the same records write a 2.0 file.
    let plain = encode_store_with(&f, &doc_cells(), &doc_scene()).unwrap();
    assert_eq!(&plain[8..12], &[2, 0, 0, 0]);
}

#[test]
fn s22_b14_bad_rise_and_rise_values_where_they_cannot_be() {
    let f = doc_frame();
    let good = doc_hex("store-2.1");
    // Rise 0 (offset 0xa6), and ground 4 + rise 252 > 255.
    for (rise, what) in [(0u8, "zero"), (252, "past 255")] {
        let mut s = good.clone();
        s[0xa6] = rise;
        fix_store_crc(&mut s);
        assert_eq!(
            Store::parse(&s).unwrap_err(),
            FormatError::BadRise {
                cell: 0,
                ground: 4,
                rise,
                offset: 0xa6
            },
            "{what}"
        );
    }
    let mut b = doc_hex("blob-2.1-cell0");
    b[0x0b] = 0;
    fix_blob_crc(&mut b);
    assert!(matches!(
        decode_blob(&f, &b).unwrap_err(),
        FormatError::BadRise { rise: 0, .. }
    ));
    // 11..=20 need ground bytes: a flat frame refuses them (S10, B4); 21 is reserved.
    let flat = Frame {
        ground_step: 0.0,
        ..f
    };
    let mut b = doc_hex("blob-2.1-cell0");
    fix_blob_crc(&mut b);
    assert!(matches!(
        decode_blob(&flat, &b).unwrap_err(),
        FormatError::BadIndexByte { value: 12, .. }
    ));
    let mut s = good.clone();
    s[0x9e] = 21;
    fix_store_crc(&mut s);
    assert!(matches!(
        Store::parse(&s).unwrap_err(),
        FormatError::BadIndexByte { value: 21, .. }
    ));
    // The encoder refuses what a decoder would.
    let over = CellRecord::new(250, &[q(196, 376, 336, 376, 5)])
        .unwrap()
        .with_rise(6);
    assert!(matches!(
        encode_store_with(
            &f,
            &[over, CellRecord::Skipped, CellRecord::EMPTY],
            &doc_scene()
        ),
        Err(FormatError::BadRise { .. })
    ));
}
