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

mod blob_rules;
mod docs;
mod encoder;
mod frame;
mod properties;
mod store_rules;
mod v2_1;

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

const DOC: &str = include_str!("../../docs/FORMAT.md");

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

/// `d`'s bytes with VO `k` of cell 0 replaced by `vo` (its bytes in `d`'s version) and the
/// checksum made right.
fn with_vo(d: &Doc, k: usize, vo: &[u8]) -> Vec<u8> {
    let mut s = d.bytes.clone();
    s[d.vo(k)..d.vo(k) + d.vo_bytes].copy_from_slice(vo);
    fix_store_crc(&mut s);
    s
}

/// A blob with VO `k` replaced by `vo` and the checksum made right.
fn blob_with_vo(b: &[u8], vo_bytes: usize, k: usize, vo: &[u8]) -> Vec<u8> {
    let mut b = b.to_vec();
    let at = 11 + k * vo_bytes;
    b[at..at + vo_bytes].copy_from_slice(vo);
    fix_blob_crc(&mut b);
    b
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
