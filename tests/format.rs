//! The store format against its specification, `docs/FORMAT.md`: the worked hex examples read
//! from the document and compared byte for byte with the encoder, one test per row of the
//! "accepted?" tables, round trips, a no-allocation check, and property tests with fixed seeds
//! (random bytes and mutations of valid stores and blobs never panic; accepted mutations
//! re-encode to the same bytes). Builds and runs with `--no-default-features`.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use vocc::runtime::crc::crc32;
use vocc::runtime::format::{
    decode_blob, decode_frame, encode_blob, encode_frame, encode_store, CellRecord, FormatError,
    Store, VoList, BLOB_MIN_LEN, FRAME_LEN, HEADER_LEN,
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

/// The frame of FORMAT.md section 9.
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

fn q(x1: u16, y1: u16, x2: u16, y2: u16, level: u8) -> QVo {
    QVo {
        a: QPoint::fine(x1, y1),
        b: QPoint::fine(x2, y2),
        level,
    }
}

/// The records of FORMAT.md section 9.
fn doc_cells() -> Vec<CellRecord> {
    vec![
        CellRecord::new(4, &[q(196, 376, 336, 376, 5), q(376, 176, 376, 346, 3)]).unwrap(),
        CellRecord::Skipped,
        CellRecord::EMPTY,
    ]
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

#[test]
fn doc_store_example_is_the_encoder_output() {
    let doc = doc_hex("store");
    assert_eq!(doc.len(), 154);
    let bytes = encode_store(&doc_frame(), &doc_cells()).unwrap();
    assert_eq!(bytes, doc);
    let s = Store::parse(&doc).unwrap();
    assert_eq!(*s.frame(), doc_frame());
    assert_eq!(s.version(), (1, 0));
    assert_eq!(s.cell_count(), 3);
    for (i, rec) in doc_cells().iter().enumerate() {
        assert_eq!(s.cell(i as u32).unwrap(), *rec);
    }
    assert_eq!(s.cell_at(150.0, 99.0), Some(1));
    assert_eq!(s.cell_at(300.0, 0.0), None);
    // The frame's 112 bytes sit at offset 16.
    assert_eq!(&doc[16..128], &encode_frame(&doc_frame())[..]);
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
    assert_eq!((b0.len(), b1.len()), (25, BLOB_MIN_LEN));
}

#[test]
fn doc_worked_vo_decoding_matches_the_frame() {
    // FORMAT.md section 9.1, prose after the dump.
    let f = doc_frame();
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
    // Section 7's check value and section 10's size.
    assert_eq!(crc32(b"123456789"), 0xCBF43926);
    assert_eq!(
        136 + 10_000 + 4 * 10_000usize.div_ceil(64) + 9_000 * 41,
        379_764
    );
}

#[test]
fn doc_store_drives_the_culler() {
    // What an engine does: parse once, build the tree once, query on cell entry.
    let bytes = doc_store();
    let store = Store::parse(&bytes).unwrap();
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
    assert_eq!(visible, [1, 2, 3]);
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
        // The encoders refuse it too, and a store carrying it is refused with the same rule.
        assert_eq!(frame_rule(encode_store(&f, &[])), *rule);
        let mut s = doc_hex("store");
        s[16..128].copy_from_slice(&encode_frame(&f));
        fix_store_crc(&mut s);
        assert_eq!(frame_rule(Store::parse(&s)), *rule);
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

fn doc_store() -> Vec<u8> {
    doc_hex("store")
}

#[test]
fn s1_shorter_than_the_header() {
    let s = doc_store();
    for n in [0, 1, 8, 135] {
        assert_eq!(
            Store::parse(&s[..n]).unwrap_err(),
            FormatError::Truncated {
                needed: 136,
                got: n as u64
            }
        );
    }
}

#[test]
fn s2_bad_magic() {
    let mut s = doc_store();
    s[0] = 0x88;
    assert_eq!(Store::parse(&s).unwrap_err(), FormatError::BadMagic);
    let mut s = doc_store();
    s[..8].copy_from_slice(b"\x89PNG\r\n\x1a\n");
    assert_eq!(Store::parse(&s).unwrap_err(), FormatError::BadMagic);
    // A blob is not a store, and a store is not a blob.
    let mut blob = doc_hex("blob-cell0");
    blob.resize(200, 0);
    assert_eq!(Store::parse(&blob).unwrap_err(), FormatError::BadMagic);
    let s = doc_store();
    assert_eq!(
        decode_blob(&doc_frame(), &s).unwrap_err(),
        FormatError::BadMagic
    );
}

#[test]
fn s3_unknown_major() {
    for major in [0u16, 2, 0xffff] {
        let mut s = doc_store();
        s[8..10].copy_from_slice(&major.to_le_bytes());
        fix_store_crc(&mut s);
        assert_eq!(
            Store::parse(&s).unwrap_err(),
            FormatError::UnsupportedVersion { major }
        );
    }
}

#[test]
fn s4_any_minor_is_accepted() {
    let mut s = doc_store();
    s[10..12].copy_from_slice(&7u16.to_le_bytes());
    fix_store_crc(&mut s);
    let st = Store::parse(&s).unwrap();
    assert_eq!(st.version(), (1, 7));
    assert_eq!(st.cell(0).unwrap(), doc_cells()[0]);
}

#[test]
fn s5_nonzero_flags() {
    for flags in [1u32, 0x8000_0000] {
        let mut s = doc_store();
        s[12..16].copy_from_slice(&flags.to_le_bytes());
        fix_store_crc(&mut s);
        assert_eq!(
            Store::parse(&s).unwrap_err(),
            FormatError::UnknownFlags { flags }
        );
    }
}

#[test]
fn s6_bad_frame_in_the_header() {
    let mut s = doc_store();
    // cell_size (frame offset 40, file offset 56) = -100.0
    s[56..64].copy_from_slice(&(-100.0f64).to_le_bytes());
    fix_store_crc(&mut s);
    assert_eq!(frame_rule(Store::parse(&s)), "F2");
    // nx = 0 (file offset 64)
    let mut s = doc_store();
    s[64..68].fill(0);
    assert_eq!(frame_rule(Store::parse(&s)), "F3");
}

#[test]
fn s7_shorter_than_its_length_fields_say() {
    let s = doc_store();
    assert_eq!(
        Store::parse(&s[..153]).unwrap_err(),
        FormatError::Truncated {
            needed: 154,
            got: 153
        }
    );
    // An oversized payload_len: refused before anything is read or allocated.
    let mut s = doc_store();
    s[128..132].copy_from_slice(&u32::MAX.to_le_bytes());
    fix_store_crc(&mut s);
    assert_eq!(
        Store::parse(&s).unwrap_err(),
        FormatError::Truncated {
            needed: 143 + u32::MAX as u64,
            got: 154
        }
    );
    // A grid of 2^31 cells in a 154-byte file.
    let mut s = doc_store();
    s[64..68].copy_from_slice(&(1u32 << 16).to_le_bytes());
    s[68..72].copy_from_slice(&(1u32 << 15).to_le_bytes());
    let cells = 1u64 << 31;
    assert_eq!(
        Store::parse(&s).unwrap_err(),
        FormatError::Truncated {
            needed: 136 + cells + 4 * (cells / 64) + 11,
            got: 154
        }
    );
}

#[test]
fn s8_trailing_bytes() {
    let mut s = doc_store();
    s.push(0);
    assert_eq!(
        Store::parse(&s).unwrap_err(),
        FormatError::TrailingBytes {
            expected: 154,
            got: 155
        }
    );
}

#[test]
fn s9_checksum_mismatch() {
    let mut s = doc_store();
    s[0x90] ^= 0x01; // a bit of cell 0's first VO
    let Err(FormatError::Checksum { stored, computed }) = Store::parse(&s) else {
        panic!("expected Checksum");
    };
    assert_eq!(stored, 0x82b0c79a);
    assert_ne!(computed, stored);
    // The checksum covers the frame and the index too.
    for at in [20, 100, 0x89] {
        let mut s = doc_store();
        s[at] ^= 0x40;
        assert!(matches!(
            Store::parse(&s),
            Err(FormatError::Checksum { .. })
        ));
    }
}

#[test]
fn s10_reserved_index_values() {
    for value in [11u8, 12, 0x80, 254] {
        let mut s = doc_store();
        s[0x89] = value; // cell 1
        fix_store_crc(&mut s);
        assert_eq!(
            Store::parse(&s).unwrap_err(),
            FormatError::BadIndexByte {
                cell: 1,
                value,
                offset: 0x89
            }
        );
    }
}

#[test]
fn s11_block_table_inconsistent_with_the_counts() {
    let mut s = doc_store();
    s[0x8b] = 1; // block 0 must start at 0
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
    cells[3] = doc_cells()[0];
    cells[70] = doc_cells()[0];
    let good = encode_store(&f, &cells).unwrap();
    let table = HEADER_LEN + 100;
    assert_eq!(&good[table..table + 8], &[0, 0, 0, 0, 11, 0, 0, 0]);
    let mut s = good.clone();
    s[table + 4] = 16;
    fix_store_crc(&mut s);
    assert_eq!(
        Store::parse(&s).unwrap_err(),
        FormatError::BlockOffset {
            block: 1,
            stored: 16,
            expected: 11
        }
    );
}

#[test]
fn s12_payload_len_inconsistent_with_the_counts() {
    let mut s = doc_store();
    s[0x88] = 1; // cell 0 claims 1 VO: 6 payload bytes, but payload_len says 11
    fix_store_crc(&mut s);
    assert_eq!(
        Store::parse(&s).unwrap_err(),
        FormatError::PayloadLength {
            stored: 11,
            expected: 6
        }
    );
    // Counts asking for more than the payload holds.
    let mut s = doc_store();
    s[0x8a] = 1; // cell 2 claims 1 VO
    fix_store_crc(&mut s);
    assert_eq!(
        Store::parse(&s).unwrap_err(),
        FormatError::PayloadLength {
            stored: 11,
            expected: 17
        }
    );
}

#[test]
fn s13_degenerate_vo() {
    let mut s = doc_store();
    let degenerate = q(300, 20, 300, 20, 9).to_bytes_v1();
    s[0x95..0x9a].copy_from_slice(&degenerate);
    fix_store_crc(&mut s);
    assert_eq!(
        Store::parse(&s).unwrap_err(),
        FormatError::DegenerateVo {
            cell: 0,
            vo: 1,
            offset: 0x95
        }
    );
    // All zero: both endpoints (0, 0).
    let mut s = doc_store();
    s[0x90..0x95].fill(0);
    fix_store_crc(&mut s);
    assert_eq!(
        Store::parse(&s).unwrap_err(),
        FormatError::DegenerateVo {
            cell: 0,
            vo: 0,
            offset: 0x90
        }
    );
}

#[test]
fn s14_s15_s16_accepted_edge_cases() {
    // S14: no payload at all.
    let f = doc_frame();
    let cells = [CellRecord::EMPTY, CellRecord::Skipped, CellRecord::EMPTY];
    let s = encode_store(&f, &cells).unwrap();
    assert_eq!(s.len(), 136 + 3 + 4);
    assert_eq!(&s[128..132], &[0, 0, 0, 0]);
    let st = Store::parse(&s).unwrap();
    for (i, r) in cells.iter().enumerate() {
        assert_eq!(st.cell(i as u32).unwrap(), *r);
    }
    // S15: any ground byte.
    let mut s = doc_store();
    s[0x8f] = 255;
    fix_store_crc(&mut s);
    assert_eq!(Store::parse(&s).unwrap().cell(0).unwrap().ground(), 255);
    // S16: ground_step = -0.0 is flat: no ground byte.
    let mut f = doc_frame();
    f.ground_step = -0.0;
    let cells = [
        CellRecord::new(0, &[q(196, 376, 336, 376, 5)]).unwrap(),
        CellRecord::EMPTY,
        CellRecord::Skipped,
    ];
    let s = encode_store(&f, &cells).unwrap();
    assert_eq!(s.len(), 136 + 3 + 4 + 5);
    let st = Store::parse(&s).unwrap();
    assert_eq!(st.frame().ground_step.to_bits(), (-0.0f64).to_bits());
    assert_eq!(st.cell(0).unwrap(), cells[0]);
}

#[test]
fn store_cell_lookup_out_of_grid() {
    let s = doc_store();
    let st = Store::parse(&s).unwrap();
    for id in [3, 64, u32::MAX] {
        assert_eq!(
            st.cell(id).unwrap_err(),
            FormatError::CellOutOfGrid { id, cells: 3 }
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Section 8.3: the blob.

#[test]
fn b0_blob_decoded_with_a_bad_frame() {
    let mut f = doc_frame();
    f.quantum = 0.3;
    assert_eq!(frame_rule(decode_blob(&f, &doc_hex("blob-cell0"))), "F5");
    assert_eq!(frame_rule(encode_blob(&f, 0, &CellRecord::EMPTY)), "F5");
}

#[test]
fn b1_to_b3_short_magic_major() {
    let f = doc_frame();
    let b = doc_hex("blob-cell0");
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
    let mut m = b.clone();
    m[4] = 2;
    fix_blob_crc(&mut m);
    assert_eq!(
        decode_blob(&f, &m).unwrap_err(),
        FormatError::UnsupportedVersion { major: 2 }
    );
}

#[test]
fn b4_reserved_count() {
    let f = doc_frame();
    let mut b = doc_hex("blob-cell0");
    b[9] = 11;
    assert_eq!(
        decode_blob(&f, &b).unwrap_err(),
        FormatError::BadIndexByte {
            cell: 0,
            value: 11,
            offset: 9
        }
    );
}

#[test]
fn b5_b6_length_must_match_the_count() {
    let f = doc_frame();
    let b = doc_hex("blob-cell0");
    assert_eq!(
        decode_blob(&f, &b[..24]).unwrap_err(),
        FormatError::Truncated {
            needed: 25,
            got: 24
        }
    );
    let mut long = b.clone();
    long.push(0);
    assert_eq!(
        decode_blob(&f, &long).unwrap_err(),
        FormatError::TrailingBytes {
            expected: 25,
            got: 26
        }
    );
    // A skipped cell carries no ground byte and no VOs.
    let mut m = doc_hex("blob-cell1");
    m.insert(10, 4);
    fix_blob_crc(&mut m);
    assert_eq!(
        decode_blob(&f, &m).unwrap_err(),
        FormatError::TrailingBytes {
            expected: 14,
            got: 15
        }
    );
    // With flat ground, the cell-0 blob has one byte too many.
    let mut flat = f;
    flat.ground_step = 0.0;
    assert_eq!(
        decode_blob(&flat, &b).unwrap_err(),
        FormatError::TrailingBytes {
            expected: 24,
            got: 25
        }
    );
}

#[test]
fn b7_checksum() {
    let f = doc_frame();
    let mut b = doc_hex("blob-cell0");
    b[12] ^= 0x10;
    assert!(matches!(
        decode_blob(&f, &b),
        Err(FormatError::Checksum {
            stored: 0x67359185,
            ..
        })
    ));
    // The id is covered too.
    let mut b = doc_hex("blob-cell1");
    b[5] = 2;
    assert!(matches!(
        decode_blob(&f, &b),
        Err(FormatError::Checksum { .. })
    ));
}

#[test]
fn b8_id_outside_the_grid() {
    let f = doc_frame();
    for id in [3u32, 1 << 31, u32::MAX] {
        let mut b = doc_hex("blob-cell1");
        b[5..9].copy_from_slice(&id.to_le_bytes());
        fix_blob_crc(&mut b);
        assert_eq!(
            decode_blob(&f, &b).unwrap_err(),
            FormatError::CellOutOfGrid { id, cells: 3 }
        );
    }
    assert_eq!(
        encode_blob(&f, 3, &CellRecord::EMPTY).unwrap_err(),
        FormatError::CellOutOfGrid { id: 3, cells: 3 }
    );
}

#[test]
fn b9_degenerate_vo() {
    let f = doc_frame();
    let mut b = doc_hex("blob-cell0");
    b[0x10..0x15].copy_from_slice(&q(7, 8, 7, 8, 0).to_bytes_v1());
    fix_blob_crc(&mut b);
    assert_eq!(
        decode_blob(&f, &b).unwrap_err(),
        FormatError::DegenerateVo {
            cell: 0,
            vo: 1,
            offset: 0x10
        }
    );
}

#[test]
fn b10_empty_and_skipped_blobs_are_14_bytes() {
    for ground_step in [0.0, 0.5] {
        let mut f = doc_frame();
        f.ground_step = ground_step;
        for rec in [CellRecord::EMPTY, CellRecord::Skipped] {
            let b = encode_blob(&f, 2, &rec).unwrap();
            assert_eq!(b.len(), 14);
            assert_eq!(decode_blob(&f, &b).unwrap(), (2, rec));
        }
    }
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
        q(0, 0, 1, 1, 16),
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
    // Degenerate VO: the offset is where the decoder would find it.
    let rec = CellRecord::new(9, &[good, good, q(5, 5, 5, 5, 1)]).unwrap();
    assert_eq!(
        encode_store(&f, &[doc_cells()[0], CellRecord::Skipped, rec]).unwrap_err(),
        FormatError::DegenerateVo {
            cell: 2,
            vo: 2,
            offset: 0x8f + 11 + 1 + 10
        }
    );
    assert_eq!(
        encode_blob(&f, 2, &rec).unwrap_err(),
        FormatError::DegenerateVo {
            cell: 2,
            vo: 2,
            offset: 21
        }
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
    let bytes = encode_store(&f, &cells).unwrap();
    let blobs: Vec<Vec<u8>> = cells
        .iter()
        .enumerate()
        .map(|(i, r)| encode_blob(&f, i as u32, r).unwrap())
        .collect();
    let frame_bytes = encode_frame(&f);
    let (ok, n) = allocations(|| {
        let s = Store::parse(&bytes).unwrap();
        let mut all = true;
        for (i, r) in cells.iter().enumerate() {
            all &= s.cell(i as u32).unwrap() == *r;
            all &= decode_blob(&f, &blobs[i]).unwrap() == (i as u32, *r);
        }
        all &= decode_frame(&frame_bytes).unwrap() == f;
        // Refusals allocate nothing either.
        all &= Store::parse(&bytes[..bytes.len() - 1]).is_err();
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

fn arb_qvo() -> impl Strategy<Value = QVo> {
    (0u16..512, 0u16..512, 0u16..512, 0u16..512, 0u8..16)
        .prop_map(|(x1, y1, x2, y2, level)| q(x1, y1, x2, y2, level))
        .prop_filter("degenerate", |v| !v.is_degenerate())
}

fn arb_record(per_cell_ground: bool) -> impl Strategy<Value = CellRecord> {
    prop_oneof![
        1 => Just(CellRecord::Skipped),
        1 => Just(CellRecord::EMPTY),
        4 => (any::<u8>(), prop::collection::vec(arb_qvo(), 1..=10)).prop_map(move |(g, v)| {
            CellRecord::Vos {
                ground: if per_cell_ground { g } else { 0 },
                vos: VoList::from_slice(&v).unwrap(),
            }
        }),
    ]
}

fn arb_store() -> impl Strategy<Value = (Frame, Vec<CellRecord>)> {
    arb_frame().prop_flat_map(|f| {
        let n = f.grid.cell_count() as usize;
        (
            Just(f),
            prop::collection::vec(arb_record(f.per_cell_ground()), n),
        )
    })
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
                Just(16 + 48),
                Just(16 + 52),
                Just(128),
                Just(136),
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
        // Behind a valid magic and major too.
        let mut s = doc_store()[..16].to_vec();
        s.extend_from_slice(&bytes);
        if let Ok(st) = Store::parse(&s) {
            read_all(&st);
        }
        let mut b = doc_hex("blob-cell0")[..5].to_vec();
        b.extend_from_slice(&bytes);
        let _ = decode_blob(&f, &b);
    }

    #[test]
    fn mutated_stores_never_panic_and_accepted_ones_are_canonical(
        (f, cells) in arb_store(),
        muts in prop::collection::vec(arb_mutation(), 1..4),
        fix_crc in any::<bool>(),
    ) {
        let good = encode_store(&f, &cells).unwrap();
        let mut bytes = good.clone();
        for m in &muts {
            apply(&mut bytes, m);
        }
        if fix_crc {
            fix_store_crc(&mut bytes);
        }
        if let Ok(s) = Store::parse(&bytes) {
            let recs = read_all(&s);
            // Canonical: re-encoding gives the same bytes, the minor version (and so the
            // checksum) aside.
            let again = encode_store(s.frame(), &recs).unwrap();
            let mut expect = bytes.clone();
            expect[10..12].fill(0);
            fix_store_crc(&mut expect);
            prop_assert_eq!(again, expect);
        }
    }

    #[test]
    fn mutated_blobs_never_panic_and_accepted_ones_are_canonical(
        (f, cells) in arb_store(),
        pick in any::<usize>(),
        muts in prop::collection::vec(arb_mutation(), 1..4),
        fix_crc in any::<bool>(),
    ) {
        let id = (pick % cells.len()) as u32;
        let mut bytes = encode_blob(&f, id, &cells[id as usize]).unwrap();
        for m in &muts {
            apply(&mut bytes, m);
        }
        if fix_crc {
            fix_blob_crc(&mut bytes);
        }
        if let Ok((id2, rec)) = decode_blob(&f, &bytes) {
            prop_assert_eq!(encode_blob(&f, id2, &rec).unwrap(), bytes);
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
    fn stores_and_blobs_round_trip((f, cells) in arb_store()) {
        let bytes = encode_store(&f, &cells).unwrap();
        let n = f.grid.cell_count() as usize;
        let size = |r: &CellRecord| match r.vos().len() {
            0 => 0,
            k => 5 * k + f.per_cell_ground() as usize,
        };
        let records: usize = cells.iter().map(size).sum();
        prop_assert_eq!(bytes.len(), HEADER_LEN + n + 4 * n.div_ceil(64) + records);
        let s = Store::parse(&bytes).unwrap();
        prop_assert_eq!(*s.frame(), f);
        prop_assert_eq!(&read_all(&s), &cells);
        for (i, rec) in cells.iter().enumerate() {
            let b = encode_blob(&f, i as u32, rec).unwrap();
            prop_assert_eq!(b.len(), BLOB_MIN_LEN + size(rec));
            prop_assert_eq!(decode_blob(&f, &b).unwrap(), (i as u32, *rec));
        }
        prop_assert_eq!(decode_frame(&encode_frame(&f)).unwrap(), f);
        prop_assert_eq!(FRAME_LEN, 112);
    }
}
