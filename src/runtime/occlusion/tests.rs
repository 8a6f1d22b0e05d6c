//! Tests of rule 3 ([`super`]): boxes behind a wide wall hidden, beside, in front or touching
//! not; the height bounds; monotone under inclusion; the half-planes a group found need no test
//! below it; and the rule, with its tighter bound, against 3D rays on random VOs and boxes.
//!
//! Input: hand-made and seeded random cells, VOs and boxes. Output: pass or fail.
//! Invariant: what the rule hides is hidden for the rays; the culler's forms agree with it.

use super::*;

fn view() -> CellView {
    CellView {
        rect: [0.0, 0.0, 10.0, 10.0],
        e0: 1.5,
        e1: 2.0,
    }
}

fn wall(h: f64) -> VoGeom {
    VoGeom {
        a: [-20.0, 20.0],
        b: [30.0, 20.0],
        g: 0.0,
        h,
    }
}

#[test]
fn a_low_box_right_behind_a_wide_wall_is_hidden() {
    let bx = [3.0, 25.0, 0.0, 7.0, 28.0, 2.0];
    assert_eq!(
        PreparedVo::new(&view(), &wall(10.0)).cover(&view(), &bx),
        Cover::Hidden
    );
    // Either orientation of the VO.
    let mut w = wall(10.0);
    std::mem::swap(&mut w.a, &mut w.b);
    assert!(hides(&view(), &w, &bx));
}

#[test]
fn the_height_bounds_follow_rule_3() {
    // The VO's line y = 20 lies 20 m from the cell's far edge y = 0 (20.001 m from the
    // grown cell): a box 5 m beyond it has the factor F = 1 + 5 / 20 = 1.25, so its top may
    // reach 2 + 8 * 1.25 = 12 (less the margins). The plain rule's D_near / D_far is 15 /
    // sqrt(1300) < 1, and the bound through D_far' of the crossings, 16/13, is lower too.
    let v = view();
    let w = wall(10.0);
    let top = 2.0 + 8.0 * 1.25;
    let under = [3.0, 25.0, 0.0, 7.0, 28.0, top - 0.02];
    let over = [3.0, 25.0, 0.0, 7.0, 28.0, top + 0.02];
    assert!(hides(&v, &w, &under));
    assert!(!hides(&v, &w, &over));
    // Far behind: 80 m beyond the line, F = 5, the top 2 + 8 * 5 = 42.
    let top = 42.0;
    assert!(hides(&v, &w, &[3.0, 100.0, 0.0, 7.0, 101.0, top - 0.02]));
    assert!(!hides(&v, &w, &[3.0, 100.0, 0.0, 7.0, 101.0, top + 0.02]));
    // Below the VO's bottom g = 0: the lowest eye e0 = 1.5 looks down at it, and the ray
    // still passes over the bottom when zmin >= e0 - (e0 - g) F = 1.5 - 1.5 F. At 5 m
    // beyond the line that is -0.375; at 80 m, -6.
    assert!(hides(&v, &w, &[3.0, 25.0, -0.35, 7.0, 28.0, 1.0]));
    assert!(!hides(&v, &w, &[3.0, 25.0, -0.4, 7.0, 28.0, 1.0]));
    assert!(hides(&v, &w, &[3.0, 100.0, -5.98, 7.0, 101.0, 1.0]));
    assert!(!hides(&v, &w, &[3.0, 100.0, -6.02, 7.0, 101.0, 1.0]));
    // With the eyes at the VO's bottom (e0 = g), nothing below it is hidden.
    let flat = CellView { e0: 0.0, ..v };
    assert!(hides(&flat, &w, &[3.0, 100.0, 0.0, 7.0, 101.0, 1.0]));
    assert!(!hides(&flat, &w, &[3.0, 100.0, -0.01, 7.0, 101.0, 1.0]));
}

#[test]
fn boxes_beside_in_front_or_touching_are_not_hidden() {
    let v = view();
    let w = wall(10.0);
    // Beside the umbra: the cone from cell corner (10, 0) through (30, 20) leaves x = 40 at
    // y = 30.
    assert_eq!(
        PreparedVo::new(&v, &w).cover(&v, &[45.0, 25.0, 0.0, 50.0, 30.0, 1.0]),
        Cover::Outside
    );
    // In front of the VO.
    assert_eq!(
        PreparedVo::new(&v, &w).cover(&v, &[3.0, 12.0, 0.0, 7.0, 15.0, 1.0]),
        Cover::Outside
    );
    // Straddling the umbra's edge.
    assert_eq!(
        PreparedVo::new(&v, &w).cover(&v, &[25.0, 25.0, 0.0, 45.0, 30.0, 1.0]),
        Cover::Partial
    );
    // A VO whose line crosses the cell hides nothing.
    let crossing = VoGeom {
        a: [5.0, -10.0],
        b: [5.0, 40.0],
        g: 0.0,
        h: 50.0,
    };
    assert_eq!(
        PreparedVo::new(&v, &crossing).cover(&v, &[20.0, 0.0, 0.0, 22.0, 2.0, 1.0]),
        Cover::Outside
    );
}

#[test]
fn hidden_is_monotone_under_inclusion() {
    let v = view();
    let p = PreparedVo::new(&v, &wall(10.0));
    let outer = [0.0, 22.0, 0.0, 10.0, 40.0, 3.0];
    assert_eq!(p.cover(&v, &outer), Cover::Hidden);
    for inner in [
        [1.0, 23.0, 0.5, 9.0, 39.0, 2.5],
        [4.0, 30.0, 1.0, 5.0, 31.0, 2.0],
    ] {
        assert_eq!(p.cover(&v, &inner), Cover::Hidden);
    }
}

use crate::testutil::uniform as lcg;

/// A random VO standing on the ground around the 10 m cell of [`view`].
fn random_vo(r: &mut impl FnMut(f64, f64) -> f64) -> VoGeom {
    VoGeom {
        a: [r(-60.0, 70.0), r(-60.0, 70.0)],
        b: [r(-60.0, 70.0), r(-60.0, 70.0)],
        g: 0.0,
        h: r(2.0, 30.0),
    }
}

#[test]
fn half_planes_found_inside_a_group_need_no_test_below_it() {
    // Random VOs around a 10 m cell, random groups and boxes inside them: testing only the
    // half-planes the group was not found strictly inside answers as testing all three,
    // and a box inside a group found apart from the cell is apart from it.
    let mut r = lcg(987654321);
    let v = view();
    let (mut skipped, mut hidden) = (0, 0);
    let mut touching = 0;
    for _ in 0..3000 {
        let vo = random_vo(&mut r);
        let p = PreparedVo::new(&v, &vo);
        let (cx, cy) = (r(-150.0, 160.0), r(-150.0, 160.0));
        let outer = [
            cx,
            cy,
            0.0,
            cx + r(1.0, 60.0),
            cy + r(1.0, 60.0),
            r(1.0, 60.0),
        ];
        let g = GroupProbe::new(&v, &outer, r(0.0, outer[5]));
        let (c, left) = p.cover_group_planes(&v, &g, ALL_PLANES);
        assert_eq!(c, p.cover_group_probe(&v, &g), "{vo:?} {outer:?}");
        if c != Cover::Partial {
            continue;
        }
        skipped += usize::from(left != ALL_PLANES);
        let mut inners = Vec::new();
        for _ in 0..20 {
            let (x0, x1) = (r(outer[0], outer[3]), r(outer[0], outer[3]));
            let (y0, y1) = (r(outer[1], outer[4]), r(outer[1], outer[4]));
            let z1 = r(0.0, outer[5]);
            let inner = [x0.min(x1), y0.min(y1), 0.0, x0.max(x1), y0.max(y1), z1];
            let min_top = r(0.0, z1);
            let gi = GroupProbe::new(&v, &inner, min_top);
            let apart = g.probe.is_apart();
            let gw = GroupProbe::within(&v, &inner, min_top, apart);
            assert_eq!(
                gw.probe.is_apart(),
                gi.probe.is_apart(),
                "{outer:?} {inner:?}"
            );
            assert_eq!(
                p.cover_group_planes(&v, &gw, left).0,
                p.cover_group_probe(&v, &gi),
                "{vo:?} {outer:?} {inner:?}"
            );
            let pi = Probe::new(&v, &inner);
            let pw = Probe::within(&v, &inner, apart);
            assert_eq!(pw.is_apart(), pi.is_apart(), "{outer:?} {inner:?}");
            touching += usize::from(!pi.is_apart());
            let h = p.hides_probe(&v, &pi);
            assert_eq!(p.hides_probe_planes(&v, &pw, left), h, "{vo:?} {inner:?}");
            hidden += usize::from(h);
            inners.push((inner, h));
        }
        // The lane test of the same boxes, up to LANES at a time, answers box by box.
        for chunk in inners.chunks(LANES) {
            let boxes: Vec<[f64; 6]> = chunk.iter().map(|c| c.0).collect();
            let l = Lanes::new(&boxes);
            let bits = p.hides_lanes(&v, &l, l.apart(&v, g.probe.is_apart()), left);
            for (j, &(inner, h)) in chunk.iter().enumerate() {
                assert_eq!(bits >> j & 1 == 1, h, "{vo:?} {inner:?}");
            }
        }
    }
    assert!(
        skipped > 100 && hidden > 100 && touching > 50,
        "{skipped} groups skipped a half-plane, {hidden} boxes hidden, {touching} touching"
    );
}

/// Rule 3 written out plainly: every grown corner strictly inside all nine umbra
/// half-planes (the beyond-line plane and both planes of each cell corner), then heights.
fn plain_hidden(v: &CellView, vo: &VoGeom, bx: &[f64; 6]) -> bool {
    let m = MARGIN_M;
    let d = [vo.b[0] - vo.a[0], vo.b[1] - vo.a[1]];
    let len = d[0].hypot(d[1]);
    let s = m / len;
    let (mut a, mut b) = (
        [vo.a[0] + d[0] * s, vo.a[1] + d[1] * s],
        [vo.b[0] - d[0] * s, vo.b[1] - d[1] * s],
    );
    let cs = corners(v);
    if cs.iter().all(|&c| orient(a, b, c) < 0.0) {
        std::mem::swap(&mut a, &mut b);
    } else if !cs.iter().all(|&c| orient(a, b, c) > 0.0) {
        return false;
    }
    let (x0, y0, x1, y1) = (bx[0] - m, bx[1] - m, bx[3] + m, bx[4] + m);
    for p in [[x0, y0], [x1, y0], [x1, y1], [x0, y1]] {
        if !(orient(a, b, p) < 0.0) {
            return false;
        }
        for c in cs {
            if !(orient(c, a, p) > 0.0 && orient(c, p, b) > 0.0) {
                return false;
            }
        }
    }
    let [cx0, cy0, cx1, cy1] = v.rect;
    let dx = (x0 - (cx1 + m)).max((cx0 - m) - x1).max(0.0);
    let dy = (y0 - (cy1 + m)).max((cy0 - m) - y1).max(0.0);
    let d_near = dx.hypot(dy);
    let mut d_far: f64 = 0.0;
    for c in cs {
        for q in [vo.a, vo.b] {
            d_far = d_far.max((c[0] - q[0]).hypot(c[1] - q[1]));
        }
    }
    let top = v.e1 + (vo.h - v.e1) * (d_near / (d_far + m)).max(1.0);
    d_near > 0.0 && bx[2] >= vo.g && bx[5] + m <= top && vo.h >= v.e1
}

/// Whether the 3D segment from eye `p` to point `w` passes through the VO's quad (the 2D
/// segments cross and the ray's height over the crossing lies in `[g, h]`): a brute-force
/// ray, written apart from the rule.
fn ray_meets_quad(vo: &VoGeom, p: [f64; 3], w: [f64; 3]) -> bool {
    let (a, b) = (vo.a, vo.b);
    let r = [w[0] - p[0], w[1] - p[1]];
    let d = [b[0] - a[0], b[1] - a[1]];
    let den = r[0] * d[1] - r[1] * d[0];
    if den == 0.0 {
        return false;
    }
    let ap = [a[0] - p[0], a[1] - p[1]];
    let t = (ap[0] * d[1] - ap[1] * d[0]) / den; // along p -> w
    let u = (ap[0] * r[1] - ap[1] * r[0]) / den; // along a -> b
    if !((0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u)) {
        return false;
    }
    let z = p[2] + t * (w[2] - p[2]);
    vo.g <= z && z <= vo.h
}

#[test]
fn rule_3_with_the_tighter_bound_hides_only_what_3d_rays_show_hidden() {
    // A fixed linear congruential sequence: VOs around a 10 m cell, boxes around them.
    let mut r = lcg(12345);
    let v = view();
    let (mut hidden, mut outside, mut gained, mut below) = (0, 0, 0, 0);
    for _ in 0..4000 {
        let vo = random_vo(&mut r);
        let p = PreparedVo::new(&v, &vo);
        let mut lanes = Vec::new();
        for _ in 0..10 {
            let (cx, cy, w, d) = (
                r(-150.0, 160.0),
                r(-150.0, 160.0),
                r(0.5, 30.0),
                r(0.5, 30.0),
            );
            // Some boxes reach below the VO's bottom (hidden only by the bottom bound).
            let z0 = if r(0.0, 1.0) < 0.3 { r(-8.0, 0.0) } else { 0.0 };
            let bx = [cx, cy, z0, cx + w, cy + d, r(0.5, 80.0)];
            let c = p.cover(&v, &bx);
            // The culler's box test answers the same.
            assert_eq!(
                p.hides_probe(&v, &Probe::new(&v, &bx)),
                c == Cover::Hidden,
                "{vo:?} {bx:?}"
            );
            lanes.push((bx, c == Cover::Hidden));
            // The plain rule (three planes, the D_near / D_far bound) is implied.
            if plain_hidden(&v, &vo, &bx) {
                assert_eq!(c, Cover::Hidden, "{vo:?} {bx:?}");
            }
            if c == Cover::Hidden {
                hidden += 1;
                gained += !plain_hidden(&v, &vo, &bx) as usize;
                below += (z0 < 0.0) as usize;
                // Rays from eyes of the cell (corners, centre, random; lowest and highest
                // eye) to points of the box (corners, random) all pass through the quad.
                for k in 0..40 {
                    let (ex, ey) = match k {
                        0 => (0.0, 0.0),
                        1 => (10.0, 0.0),
                        2 => (10.0, 10.0),
                        3 => (0.0, 10.0),
                        4 => (5.0, 5.0),
                        _ => (r(0.0, 10.0), r(0.0, 10.0)),
                    };
                    let e = [ex, ey, if k % 2 == 0 { v.e0 } else { v.e1 }];
                    let wp = if k < 8 {
                        [
                            bx[3 * (k & 1)],
                            bx[1 + 3 * ((k >> 1) & 1)],
                            bx[2 + 3 * ((k >> 2) & 1)],
                        ]
                    } else {
                        [r(bx[0], bx[3]), r(bx[1], bx[4]), r(bx[2], bx[5])]
                    };
                    assert!(ray_meets_quad(&vo, e, wp), "{vo:?} {bx:?} {e:?} {wp:?}");
                }
            }
            if c == Cover::Outside {
                outside += 1;
                // No sub-box is hidden.
                for k in 0..4 {
                    let f = k as f64 / 4.0;
                    let sub = [
                        cx + f * w,
                        cy + f * d,
                        0.0,
                        cx + f * w + 0.1,
                        cy + f * d + 0.1,
                        0.1,
                    ];
                    assert_ne!(p.cover(&v, &sub), Cover::Hidden, "{vo:?} {sub:?}");
                }
            }
        }
        // The culler's lane test of the same boxes answers the same, box by box (the
        // boxes past the first LANES in a second call).
        for chunk in lanes.chunks(LANES) {
            let boxes: Vec<[f64; 6]> = chunk.iter().map(|c| c.0).collect();
            let l = Lanes::new(&boxes);
            let bits = p.hides_lanes(&v, &l, l.apart(&v, false), ALL_PLANES);
            for (j, &(bx, h)) in chunk.iter().enumerate() {
                assert_eq!(bits >> j & 1 == 1, h, "{vo:?} {bx:?}");
            }
        }
    }
    assert!(
        hidden > 100 && outside > 1000 && gained > 10 && below > 10,
        "{hidden} hidden ({gained} by the tighter bounds alone, {below} reaching below the \
             VO), {outside} outside"
    );
}
