//! The store's "accepted?" table, one test per row (S1 to S21), both versions where a row applies.

#[allow(unused_imports)]
use super::*;

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
