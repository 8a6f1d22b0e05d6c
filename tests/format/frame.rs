//! The frame: round trips and rules F1 to F12, R1 to R4.

#[allow(unused_imports)]
use super::*;

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
