//! The encoder's refusals, and decoding that allocates nothing.

#[allow(unused_imports)]
use super::*;

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
