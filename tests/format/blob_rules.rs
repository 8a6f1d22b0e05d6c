//! The blob's "accepted?" table, one test per row (B0 to B13).

#[allow(unused_imports)]
use super::*;

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
