//! Bad arguments at the C ABI: null pointers, short lengths, bad frames, cells and byte strings
//! each give their status and message, never a crash.
//!
//! Input: the fixture of [`super`] and deliberately bad arguments. Output: pass or fail.
//! Invariant: every call returns a status; none panics or writes past what it was given.

use super::*;

#[test]
fn null_pointers_and_bad_arguments_give_statuses_not_crashes() {
    let fx = Fixture::new();
    let cell = fx.cell(12);
    let mut n = 0usize;
    let mut ids = vec![0u32; fx.boxes.len()];
    let mut e = blank_error();
    unsafe {
        assert_eq!(
            vocc_store_frame(ptr::null(), ptr::null_mut()),
            VOCC_ERR_NULL
        );
        assert_eq!(vocc_store_frame(fx.store, ptr::null_mut()), VOCC_ERR_NULL);
        assert_eq!(vocc_store_cell_count(ptr::null()), 0);
        assert_eq!(vocc_tree_len(ptr::null()), 0);
        assert_eq!(
            vocc_store_cell(fx.store, 0, ptr::null_mut(), &mut e),
            VOCC_ERR_NULL
        );
        let mut c = VoccCell::default();
        assert_eq!(
            vocc_store_cell(fx.store, 25, &mut c, &mut e),
            VOCC_ERR_OUTSIDE_GRID
        );
        assert_eq!(msg(&e), "cell 25 is outside the grid of 25 cells");
        assert_eq!(vocc_cell_at(ptr::null(), 1.0, 1.0, &mut 0), VOCC_ERR_NULL);
        assert_eq!(
            vocc_cell_at_world(ptr::null(), 1.0, 1.0, &mut 0),
            VOCC_ERR_NULL
        );
        assert_eq!(
            vocc_cell_at(&fx.frame, 1.0, 1.0, ptr::null_mut()),
            VOCC_ERR_NULL
        );
        assert_eq!(vocc_cell_rect(&fx.frame, 0, ptr::null_mut()), VOCC_ERR_NULL);
        let mut count = 7;
        assert!(vocc_query_ids(ptr::null(), &mut count).is_null());
        assert_eq!(count, 0);
        vocc_store_free(ptr::null_mut());
        vocc_tree_free(ptr::null_mut());
        vocc_query_free(ptr::null_mut());

        let call = |q, t, f: *const VoccFrame, id, c: *const VoccCell, ids: *mut u32, cap, n| {
            let mut e = blank_error();
            let st = vocc_pvs(q, t, f, id, c, ids, cap, n, &mut e);
            assert_eq!(st, e.code);
            (st, msg(&e))
        };
        let p = ids.as_mut_ptr();
        let cap = ids.len();
        assert_eq!(
            call(
                ptr::null_mut(),
                fx.tree,
                &fx.frame,
                12,
                &cell,
                p,
                cap,
                &mut n
            )
            .0,
            VOCC_ERR_NULL
        );
        assert_eq!(
            call(
                fx.query,
                ptr::null_mut(),
                &fx.frame,
                12,
                &cell,
                p,
                cap,
                &mut n
            )
            .0,
            VOCC_ERR_NULL
        );
        assert_eq!(
            call(fx.query, fx.tree, ptr::null(), 12, &cell, p, cap, &mut n).0,
            VOCC_ERR_NULL
        );
        assert_eq!(
            call(
                fx.query,
                fx.tree,
                &fx.frame,
                12,
                ptr::null(),
                p,
                cap,
                &mut n
            )
            .0,
            VOCC_ERR_NULL
        );
        assert_eq!(
            call(
                fx.query,
                fx.tree,
                &fx.frame,
                12,
                &cell,
                p,
                cap,
                ptr::null_mut()
            )
            .0,
            VOCC_ERR_NULL
        );
        assert_eq!(
            call(fx.query, fx.tree, &fx.frame, 25, &cell, p, cap, &mut n),
            (
                VOCC_ERR_OUTSIDE_GRID,
                "cell 25 is outside the grid of 25 cells".into()
            )
        );
        // Too small a buffer: the count says what is needed, nothing is written.
        ids.fill(u32::MAX);
        let (st, m) = call(fx.query, fx.tree, &fx.frame, 12, &cell, p, 10, &mut n);
        assert_eq!(st, VOCC_ERR_BUFFER_TOO_SMALL, "{m}");
        assert!(n > 10 && n < fx.boxes.len());
        assert!(ids.iter().all(|&i| i == u32::MAX));
        let mut bits = [0u8; 4];
        assert_eq!(
            vocc_pvs_bitmap(
                fx.query,
                fx.tree,
                &fx.frame,
                12,
                &cell,
                bits.as_mut_ptr(),
                4,
                &mut n,
                &mut e
            ),
            VOCC_ERR_BUFFER_TOO_SMALL
        );
        assert_eq!(msg(&e), "3002 objects need a bitmap of 376 bytes, 4 given");

        // Cells and frames the caller made up are checked as a decoder would.
        for (bad, text) in [
            (VoccCell { count: 11, ..cell }, "cell: count 11 is over 10"),
            (
                VoccCell {
                    vos: [VoccVo {
                        x1: 512,
                        ..cell.vos[0]
                    }; 10],
                    ..cell
                },
                "cell: VO 0 has a field out of range (exponents 0..8, coordinates 0..512, level 0..32)",
            ),
            (
                VoccCell {
                    vos: [VoccVo {
                        level: 32,
                        ..cell.vos[0]
                    }; 10],
                    ..cell
                },
                "cell: VO 0 has a field out of range (exponents 0..8, coordinates 0..512, level 0..32)",
            ),
            (
                VoccCell {
                    vos: [VoccVo {
                        exp2: 8,
                        ..cell.vos[0]
                    }; 10],
                    ..cell
                },
                "cell: VO 0 has a field out of range (exponents 0..8, coordinates 0..512, level 0..32)",
            ),
            (
                // (x1, y1) = (56, 376) at exponent 1: 376 - 256 = 120 and 56 - 256 = -200;
                // at (200, 300), both inside -128..128, exponent 0 holds it.
                {
                    let mut c = cell;
                    c.vos[1] = VoccVo {
                        x1: 200,
                        y1: 300,
                        exp1: 1,
                        ..c.vos[1]
                    };
                    c
                },
                "cell: VO 1 has an endpoint that is not canonical (a smaller exponent holds it)",
            ),
            (
                {
                    let mut c = cell;
                    c.vos[1] = VoccVo {
                        x1: 3,
                        y1: 4,
                        x2: 3,
                        y2: 4,
                        level: 1,
                        ..VoccVo::default()
                    };
                    c
                },
                "cell: VO 1 is degenerate (one grid point)",
            ),
        ] {
            assert_eq!(
                call(fx.query, fx.tree, &fx.frame, 12, &bad, p, cap, &mut n),
                (VOCC_ERR_ARGUMENT, text.to_string())
            );
        }
        for (bad, text) in [
            (
                VoccFrame {
                    quantum: 0.3,
                    ..fx.frame
                },
                "bad frame: rule F5: quantum must be a power of two in [2^-10, 2^10]",
            ),
            (
                VoccFrame {
                    cell_size: f64::NAN,
                    ..fx.frame
                },
                "bad frame: rule F1: every float must be finite",
            ),
            (
                VoccFrame { nx: 0, ..fx.frame },
                "bad frame: rule F3: nx and ny must be >= 1",
            ),
            (
                VoccFrame {
                    nx: u32::MAX,
                    ny: u32::MAX,
                    ..fx.frame
                },
                "bad frame: rule F4: nx * ny must be <= 2^31",
            ),
        ] {
            assert_eq!(
                call(fx.query, fx.tree, &bad, 12, &cell, p, cap, &mut n),
                (VOCC_ERR_FRAME, text.to_string())
            );
            assert_eq!(vocc_cell_at(&bad, 1.0, 1.0, &mut 0), VOCC_ERR_FRAME);
        }

        // A query made for a smaller tree is refused, not overrun.
        let mut small_tree = ptr::null_mut();
        let mut small_q = ptr::null_mut();
        assert_eq!(
            vocc_tree_new(
                fx.boxes.as_ptr().cast(),
                10,
                ptr::null(),
                &mut small_tree,
                &mut e
            ),
            VOCC_OK
        );
        assert_eq!(vocc_query_new(small_tree, &mut small_q, &mut e), VOCC_OK);
        let (st, m) = call(small_q, fx.tree, &fx.frame, 12, &cell, p, cap, &mut n);
        assert_eq!(
            (st, m.as_str()),
            (
                VOCC_ERR_ARGUMENT,
                "the query was made for 10 objects, the tree has 3002"
            )
        );
        assert_eq!(
            call(fx.query, small_tree, &fx.frame, 12, &cell, p, cap, &mut n).0,
            VOCC_OK
        );
        vocc_query_free(small_q);
        vocc_tree_free(small_tree);

        // Trees: NULL boxes with a count, too many boxes, an empty tree.
        let mut t = ptr::null_mut();
        assert_eq!(
            vocc_tree_new(ptr::null(), 5, ptr::null(), &mut t, &mut e),
            VOCC_ERR_NULL
        );
        assert!(t.is_null());
        assert_eq!(
            vocc_tree_new(
                fx.boxes.as_ptr().cast(),
                usize::MAX / 2,
                ptr::null(),
                &mut t,
                &mut e
            ),
            VOCC_ERR_ARGUMENT
        );
        // One box past the tree's limit is refused before any box is read.
        assert_eq!(
            vocc_tree_new(
                fx.boxes.as_ptr().cast(),
                vocc::runtime::culler::MAX_BOXES + 1,
                ptr::null(),
                &mut t,
                &mut e
            ),
            VOCC_ERR_ARGUMENT
        );
        assert!(t.is_null());
        assert_eq!(
            vocc_tree_new(ptr::null(), 0, ptr::null(), &mut t, &mut e),
            VOCC_OK
        );
        let mut q = ptr::null_mut();
        assert_eq!(vocc_query_new(t, &mut q, &mut e), VOCC_OK);
        let (st, _) = call(q, t, &fx.frame, 12, &cell, ptr::null_mut(), 0, &mut n);
        assert_eq!((st, n), (VOCC_OK, 0));
        vocc_query_free(q);
        vocc_tree_free(t);
    }
}
