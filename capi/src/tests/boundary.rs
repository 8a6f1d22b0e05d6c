//! What the C ABI promises at its boundary: the culling path allocates nothing (the counting
//! allocator of [`super`]), panics are caught and reported, and long messages are cut at a
//! character boundary.
//!
//! Input: the fixture of [`super`]. Output: pass or fail.
//! Invariant: allocation counts are per thread, so other tests do not disturb them.

use super::*;

#[test]
fn the_culling_path_allocates_nothing() {
    let fx = Fixture::new();
    let f = frame();
    let blobs: Vec<Vec<u8>> = records()
        .iter()
        .enumerate()
        .map(|(i, r)| encode_blob(&f, i as u32, r).unwrap())
        .collect();
    let mut ids = vec![0u32; fx.boxes.len()];
    let mut bits = vec![0u8; fx.boxes.len().div_ceil(8)];
    let (total, n) = allocations(|| {
        let mut total = 0;
        for pass in 0..3 {
            for id in 0..25u32 {
                let mut cell = VoccCell::default();
                let mut got = 0;
                let mut count = 0;
                let mut pos = 0;
                unsafe {
                    let r = fx.frame.min_x + (id % 5) as f64 * 100.0 + 50.0;
                    let s = fx.frame.min_y + (id / 5) as f64 * 100.0 + 50.0;
                    assert_eq!(vocc_cell_at(&fx.frame, r, s, &mut pos), VOCC_OK);
                    let b = &blobs[id as usize];
                    assert_eq!(
                        vocc_blob_decode(
                            &fx.frame,
                            b.as_ptr(),
                            b.len(),
                            &mut got,
                            &mut cell,
                            ptr::null_mut()
                        ),
                        VOCC_OK
                    );
                    assert_eq!(
                        vocc_store_cell(fx.store, pos, &mut cell, ptr::null_mut()),
                        VOCC_OK
                    );
                    let st = if pass == 1 {
                        vocc_pvs_bitmap(
                            fx.query,
                            fx.tree,
                            &fx.frame,
                            id,
                            &cell,
                            bits.as_mut_ptr(),
                            bits.len(),
                            &mut count,
                            ptr::null_mut(),
                        )
                    } else {
                        vocc_pvs(
                            fx.query,
                            fx.tree,
                            &fx.frame,
                            id,
                            &cell,
                            ids.as_mut_ptr(),
                            ids.len(),
                            &mut count,
                            ptr::null_mut(),
                        )
                    };
                    assert_eq!(st, VOCC_OK);
                }
                total += count;
            }
        }
        total
    });
    assert!(total > 0);
    assert_eq!(n, 0, "the culling path allocated {n} times");
}

#[test]
fn panics_are_caught_at_the_boundary() {
    let mut e = blank_error();
    let prev = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let st = guard(&mut e, || panic!("boom"));
    std::panic::set_hook(prev);
    assert_eq!((st, e.code), (VOCC_ERR_PANIC, VOCC_ERR_PANIC));
    assert_eq!(msg(&e), "internal error: boom");
}

#[test]
fn long_messages_are_cut_at_a_character_boundary() {
    let mut e = blank_error();
    let long = "é".repeat(200); // 400 bytes
    report(&mut e, VOCC_ERR_FORMAT, &long);
    let m = msg(&e);
    assert_eq!(m.len(), 254, "255 would split a character");
    assert!(long.starts_with(&m));
}
