//! The document's worked examples (2.0 and 1.0) against the encoder, byte for byte, and driving
//! the culler.

#[allow(unused_imports)]
use super::*;

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
