//! Property tests with fixed seeds: random bytes and mutations of valid stores and blobs of both
//! versions never panic; accepted mutations re-encode to the same bytes.

#[allow(unused_imports)]
use super::*;

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
