//! The C ABI's PVS against the Rust culler: every cell of the fixture's store, as ids and as a
//! bitmap, world boxes with the origin against local ones, and cell lookup against the grid.
//!
//! Input: the fixture store and boxes of [`super`]. Output: pass or fail.
//! Invariant: every answer is compared with the Rust runtime's own.

use super::*;

#[test]
fn pvs_equals_the_rust_culler_for_every_cell_as_ids_and_bitmap() {
    let fx = Fixture::new();
    let f = frame();
    assert_eq!(fx.frame, VoccFrame::from(&f));
    assert_eq!(unsafe { vocc_store_cell_count(fx.store) }, 25);
    assert_eq!(unsafe { vocc_tree_len(fx.tree) }, fx.boxes.len());
    let tree = BoxTree::new(&fx.boxes);
    let recs = records();
    let mut ids = vec![0u32; fx.boxes.len()];
    let mut bits = vec![0u8; fx.boxes.len().div_ceil(8)];
    let mut some_culled = false;
    for id in 0..25u32 {
        let cell = fx.cell(id);
        assert_eq!(cell, VoccCell::from(&recs[id as usize]), "cell {id}");
        let mut want = Vec::new();
        pvs(&f, id, &recs[id as usize], &tree, &mut want);
        some_culled |= want.len() < fx.boxes.len();
        let mut n = 0;
        let mut e = blank_error();
        let st = unsafe {
            vocc_pvs(
                fx.query,
                fx.tree,
                &fx.frame,
                id,
                &cell,
                ids.as_mut_ptr(),
                ids.len(),
                &mut n,
                &mut e,
            )
        };
        assert_eq!((st, e.code), (VOCC_OK, VOCC_OK));
        assert_eq!(&ids[..n], &want[..], "cell {id}");
        let mut m = 0;
        let (p, got) = unsafe {
            let p = vocc_query_ids(fx.query, &mut m);
            (p, std::slice::from_raw_parts(p, m))
        };
        assert!(!p.is_null());
        assert_eq!(got, &want[..]);
        let st = unsafe {
            vocc_pvs_bitmap(
                fx.query,
                fx.tree,
                &fx.frame,
                id,
                &cell,
                bits.as_mut_ptr(),
                bits.len(),
                &mut m,
                ptr::null_mut(),
            )
        };
        assert_eq!(st, VOCC_OK);
        assert_eq!(m, want.len());
        let from_bits: Vec<u32> = (0..fx.boxes.len() as u32)
            .filter(|&i| bits[i as usize / 8] >> (i % 8) & 1 == 1)
            .collect();
        assert_eq!(from_bits, want, "cell {id}");
    }
    assert!(some_culled, "the fixture must cull something");
    // The two invalid boxes are in every PVS.
    let cell = fx.cell(12);
    let mut n = 0;
    unsafe {
        vocc_pvs(
            fx.query,
            fx.tree,
            &fx.frame,
            12,
            &cell,
            ids.as_mut_ptr(),
            ids.len(),
            &mut n,
            ptr::null_mut(),
        );
    }
    assert!(ids[..n].ends_with(&[3000, 3001]));
}

#[test]
fn world_boxes_with_the_origin_give_the_local_result() {
    let fx = Fixture::new();
    let o = frame().origin;
    let world: Vec<[f64; 6]> = fx
        .boxes
        .iter()
        .map(|b| {
            [
                b[0] + o[0],
                b[1] + o[1],
                b[2] + o[2],
                b[3] + o[0],
                b[4] + o[1],
                b[5] + o[2],
            ]
        })
        .collect();
    let mut t = ptr::null_mut();
    let mut e = blank_error();
    let rust = BoxTree::from_world(&world, o);
    assert_eq!(
        unsafe {
            vocc_tree_new(
                world.as_ptr().cast(),
                world.len(),
                o.as_ptr(),
                &mut t,
                &mut e,
            )
        },
        VOCC_OK
    );
    let cell = fx.cell(12);
    let mut want = Vec::new();
    pvs(&frame(), 12, &records()[12], &rust, &mut want);
    let mut n = 0;
    let mut ids = vec![0u32; world.len()];
    let st = unsafe {
        vocc_pvs(
            fx.query,
            t,
            &fx.frame,
            12,
            &cell,
            ids.as_mut_ptr(),
            ids.len(),
            &mut n,
            &mut e,
        )
    };
    assert_eq!(st, VOCC_OK);
    assert_eq!(&ids[..n], &want[..]);
    assert!(n < world.len());
    unsafe { vocc_tree_free(t) };
}

#[test]
fn cell_at_and_rect_follow_the_grid() {
    let fx = Fixture::new();
    let mut id = 99;
    unsafe {
        assert_eq!(vocc_cell_at(&fx.frame, 250.0, 250.0, &mut id), VOCC_OK);
        assert_eq!(id, 12);
        assert_eq!(
            vocc_cell_at_world(&fx.frame, 843000.0 + 499.9, 6518000.0 + 0.5, &mut id),
            VOCC_OK
        );
        assert_eq!(id, 4);
        id = 99;
        assert_eq!(
            vocc_cell_at(&fx.frame, 500.0, 10.0, &mut id),
            VOCC_ERR_OUTSIDE_GRID
        );
        assert_eq!(
            vocc_cell_at(&fx.frame, f64::NAN, 10.0, &mut id),
            VOCC_ERR_OUTSIDE_GRID
        );
        assert_eq!(id, 99, "no output on failure");
        let mut r = [0.0; 4];
        assert_eq!(vocc_cell_rect(&fx.frame, 7, r.as_mut_ptr()), VOCC_OK);
        assert_eq!(r, [200.0, 100.0, 300.0, 200.0]);
        assert_eq!(
            vocc_cell_rect(&fx.frame, 25, r.as_mut_ptr()),
            VOCC_ERR_OUTSIDE_GRID
        );
        let cell = fx.cell(12);
        let mut g = VoccVoGeom::default();
        assert_eq!(vocc_vo_geometry(&fx.frame, 12, &cell, 0, &mut g), VOCC_OK);
        let want = frame().dequantize(12, 0, &records()[12].vos()[0]).unwrap();
        assert_eq!((g.a, g.b, g.g, g.h), (want.a, want.b, want.g, want.h));
        assert_eq!(
            vocc_vo_geometry(&fx.frame, 12, &cell, 2, &mut g),
            VOCC_ERR_ARGUMENT
        );
        let s = CStr::from_ptr(vocc_version()).to_str().unwrap();
        assert_eq!(s, env!("CARGO_PKG_VERSION"));
    }
}
