//! The exact hidden-interval verifier against an independent brute-force oracle: literal cases
//! and property tests with fixed seeds on random scenes.

use crate::common;

use common::{brute_hidden, dyadic_points};
use glam::DVec2;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use vocc::geom::verify::{Hidden, Verifier};

fn v(x: f64, y: f64) -> DVec2 {
    DVec2::new(x, y)
}

fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<DVec2> {
    vec![v(x0, y0), v(x1, y0), v(x1, y1), v(x0, y1)]
}

fn hidden_len(parts: &[Hidden]) -> f64 {
    parts.iter().map(|h| h.p0.distance(h.p1)).sum()
}

/// Every certified point sampled is hidden for the oracle.
fn assert_sound(cell: &[DVec2], blockers: &[Vec<DVec2>], parts: &[Hidden]) {
    for h in parts {
        for q in dyadic_points(h.p0, h.p1, 4) {
            assert!(
                brute_hidden(cell, blockers, q, 400),
                "certified point {q:?} of {h:?} is visible"
            );
        }
    }
}

#[test]
fn single_blocker_umbra_is_certified_and_its_penumbra_is_not() {
    let cell = rect(0.0, 0.0, 10.0, 10.0);
    let wall = rect(-10.0, 20.0, 20.0, 22.0);
    let blockers = vec![wall];
    let ver = Verifier::new(&cell, blockers.iter().map(|b| b.as_slice()));
    // The wall is wider than the cell, so its umbra widens with distance: the outer tangents
    // run through (0,0)-(-10,20) and (10,0)-(20,20), and meet y = 40 at x = -20 and x = 30.
    let parts = ver.hidden_parts(v(-20.0, 40.0), v(30.0, 40.0));
    assert_sound(&cell, &blockers, &parts);
    assert_eq!(parts.len(), 1);
    // The segment spans the umbra exactly, ends on its boundary (closed: hidden).
    assert!(ver.is_hidden(v(-20.0, 40.0), v(30.0, 40.0)));
    // A segment reaching past the umbra is cut.
    let parts = ver.hidden_parts(v(-60.0, 40.0), v(30.0, 40.0));
    assert_sound(&cell, &blockers, &parts);
    let h = parts[0];
    assert!(h.p0.x >= -20.0 && h.p0.x < -20.0 + 0.05, "{h:?}");
    assert_eq!(h.p1, v(30.0, 40.0));
}

#[test]
fn gap_through_which_one_line_escapes_does_not_fuse() {
    // Two walls in a row with a gap: from the cell's corner (0,10) a line runs through the gap.
    let cell = rect(0.0, 0.0, 10.0, 10.0);
    let blockers = vec![rect(-20.0, 20.0, 4.9, 21.0), rect(5.1, 20.0, 30.0, 21.0)];
    let ver = Verifier::new(&cell, blockers.iter().map(|b| b.as_slice()));
    let parts = ver.hidden_parts(v(-10.0, 40.0), v(20.0, 40.0));
    assert_sound(&cell, &blockers, &parts);
    // Points straight behind the gap see through it; no part of the segment around x = 5 is hidden.
    for h in &parts {
        assert!(h.p1.x < 4.0 || h.p0.x > 6.0, "{h:?}");
    }
}

#[test]
fn points_inside_the_cell_or_in_front_are_never_hidden() {
    let cell = rect(0.0, 0.0, 10.0, 10.0);
    let blockers = [rect(-10.0, 20.0, 20.0, 22.0)];
    let ver = Verifier::new(&cell, blockers.iter().map(|b| b.as_slice()));
    assert!(ver.hidden_parts(v(2.0, 5.0), v(8.0, 5.0)).is_empty());
    assert!(ver.hidden_parts(v(2.0, 15.0), v(8.0, 15.0)).is_empty());
}

#[test]
fn verifier_is_exact_at_large_offsets() {
    for off in [0.0, 1.0e6, 1.0e7] {
        let o = v(off, off);
        let cell: Vec<DVec2> = rect(0.0, 0.0, 10.0, 10.0).iter().map(|p| *p + o).collect();
        let blockers: Vec<Vec<DVec2>> = vec![rect(-10.0, 20.0, 20.0, 22.0)]
            .into_iter()
            .map(|b| b.iter().map(|p| *p + o).collect())
            .collect();
        let ver = Verifier::new(&cell, blockers.iter().map(|b| b.as_slice()));
        assert!(
            ver.is_hidden(v(-20.0, 40.0) + o, v(30.0, 40.0) + o),
            "offset {off}"
        );
        let parts = ver.hidden_parts(v(-60.0, 40.0) + o, v(30.0, 40.0) + o);
        assert_sound(&cell, &blockers, &parts);
        assert!(
            (hidden_len(&parts) - 50.0).abs() < 0.05,
            "offset {off}: {parts:?}"
        );
    }
}

/// The verifier's completeness on a long far segment of a real city, and what it owes to the
/// segment's ends lying on the VO grid (ARCHITECTURE.md invariant 8). Literal input: Tokyo
/// centre's cell 130 (local `[604, 498] - [704, 598]`) and the 3.4 km line 556 m east of it that
/// the whole-scene ceiling picked for it (`vocc eval --ceiling`), with its ends as the ceiling
/// sampled them. Hidden from the whole cell by the blockers outside it (checked by the
/// brute-force oracle at points along it), it was certified over 6% of its length as given and
/// 99% with its ends snapped to the grid, as the bake's proposals are.
#[test]
fn verifier_certifies_a_long_tokyo_segment_once_its_ends_are_on_the_vo_grid() {
    let opts = vocc::scene::ReadOptions {
        height_attr: Some("height".into()),
        ..Default::default()
    };
    let s = vocc::scene::load(
        &[common::repo(
            "data/tokyo-central/tokyo_central_utm54n.geojson",
        )],
        &opts,
    )
    .expect("Tokyo loads");
    let cell = rect(604.0, 498.0, 704.0, 598.0);
    let inside = |p: &DVec2| p.x > 604.0 && p.x < 704.0 && p.y > 498.0 && p.y < 598.0;
    let blockers: Vec<Vec<DVec2>> = s
        .blockers
        .iter()
        .filter(|b| !b.polygon.iter().any(inside))
        .map(|b| b.polygon.clone())
        .collect();
    let ver = Verifier::new(&cell, blockers.iter().map(|b| b.as_slice()));
    let (a, b) = (v(1260.0, -95.55209161129517), v(1260.0, 3299.9798483578343));
    let grid = |p: DVec2| (p * 1024.0).round() / 1024.0;
    let (ga, gb) = (grid(a), grid(b));
    // The line is hidden: the oracle finds no sight line to points along it.
    for k in 1..8 {
        let q = ga + (gb - ga) * (k as f64 / 8.0);
        assert!(brute_hidden(&cell, &blockers, q, 400), "{q:?} is seen");
    }
    let parts = ver.hidden_parts(ga, gb);
    assert_sound(&cell, &blockers, &parts);
    let share = hidden_len(&parts) / ga.distance(gb);
    assert!(
        share > 0.98,
        "on the VO grid: {:.1}% certified",
        100.0 * share
    );
    // As sampled, its exact points are sparse, and far less is certified (6% when this test was
    // written); what is certified is sound all the same (the oracle reads each part's ends, its
    // only exact points).
    let parts = ver.hidden_parts(a, b);
    assert!(!parts.is_empty());
    for h in &parts {
        for q in [h.p0, h.p1] {
            assert!(
                brute_hidden(&cell, &blockers, q, 400),
                "certified {q:?} is seen"
            );
        }
    }
}

/// A random convex blocker: a rotated rectangle, centre in the field beyond the cell.
fn blocker() -> impl Strategy<Value = Vec<DVec2>> {
    (-40i32..50, 14i32..60, 1i32..40, 1i32..12, 0i32..16).prop_map(|(cx, cy, w, h, rot)| {
        let (cx, cy) = (cx as f64, cy as f64);
        let (w, h) = (w as f64 * 0.5, h as f64 * 0.5);
        // Rotation by a rational slope keeps coordinates modest; exactness is not needed here.
        let t = rot as f64 * std::f64::consts::PI / 16.0;
        let (c, s) = (t.cos(), t.sin());
        [(-w, -h), (w, -h), (w, h), (-w, h)]
            .iter()
            .map(|&(x, y)| v(cx + x * c - y * s, cy + x * s + y * c))
            .collect()
    })
}

/// A random segment with dyadic endpoints behind the field.
fn segment() -> impl Strategy<Value = (DVec2, DVec2)> {
    (-4000i32..4000, 3000i32..6000, -4000i32..4000, 3000i32..6000).prop_map(|(a, b, c, d)| {
        (
            v(a as f64 / 64.0, b as f64 / 64.0),
            v(c as f64 / 64.0, d as f64 / 64.0),
        )
    })
}

proptest! {
    #![proptest_config(Config { cases: 64, rng_seed: RngSeed::Fixed(0x5eed_0003), failure_persistence: None, ..Config::default() })]

    #[test]
    fn verifier_agrees_with_brute_force(
        blockers in prop::collection::vec(blocker(), 1..12),
        (a, b) in segment(),
    ) {
        let cell = rect(0.0, 0.0, 10.0, 10.0);
        // Blockers must not overlap the cell; the field starts at y >= 14 - 20.
        let blockers: Vec<Vec<DVec2>> = blockers
            .into_iter()
            .filter(|b| b.iter().all(|p| p.y > 11.0))
            .collect();
        let ver = Verifier::new(&cell, blockers.iter().map(|b| b.as_slice()));
        let parts = ver.hidden_parts(a, b);
        assert_sound(&cell, &blockers, &parts);
        // Tightness: brute-force-hidden samples outside the certified parts lie within a few
        // minimum pieces of a part boundary or of the segment's ends.
        let len = a.distance(b);
        let samples = dyadic_points(a, b, 7);
        let mut missed = 0.0;
        for q in samples {
            let t = if len > 0.0 { a.distance(q) / len } else { 0.0 };
            let inside = parts.iter().any(|h| t >= h.t0 && t <= h.t1);
            if !inside && brute_hidden(&cell, &blockers, q, 400) {
                let near = parts.iter().any(|h| (t - h.t0).abs() * len < 0.5 || (t - h.t1).abs() * len < 0.5);
                if !near {
                    missed += len / 128.0;
                }
            }
        }
        prop_assert!(missed <= 0.02 * len + 1.0, "verifier missed {missed} m of {len} m");
    }

    #[test]
    fn adding_a_blocker_never_shrinks_the_hidden_part(
        blockers in prop::collection::vec(blocker(), 1..10),
        extra in blocker(),
        (a, b) in segment(),
    ) {
        let cell = rect(0.0, 0.0, 10.0, 10.0);
        let mut blockers: Vec<Vec<DVec2>> = blockers
            .into_iter()
            .filter(|b| b.iter().all(|p| p.y > 11.0))
            .collect();
        let before = Verifier::new(&cell, blockers.iter().map(|b| b.as_slice())).hidden_parts(a, b);
        if extra.iter().all(|p| p.y > 11.0) {
            blockers.push(extra);
        }
        let after = Verifier::new(&cell, blockers.iter().map(|b| b.as_slice())).hidden_parts(a, b);
        // Up to the sweep's resolution: where a hidden part begins after a visible one is found
        // to within the least step, from wherever the sweep happened to step on.
        let tol = 2.0 * vocc::geom::verify::MIN_PIECE_M / a.distance(b).max(1e-9);
        for h in &before {
            prop_assert!(
                after.iter().any(|g| g.t0 <= h.t0 + tol && g.t1 >= h.t1 - tol),
                "hidden part {h:?} lost after adding a blocker: {after:?}"
            );
        }
    }
}

/// A fixed-seed sweep over dense random scenes that reports how much the verifier certifies
/// against the brute-force hidden length, and fails if it is unsound or loose.
#[test]
fn verifier_tightness_over_dense_random_scenes() {
    let mut rng = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        rng = rng.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = rng;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        (z ^ (z >> 31)) as f64 / u64::MAX as f64
    };
    let cell = rect(0.0, 0.0, 10.0, 10.0);
    let (mut brute_total, mut cert_total, mut fused) = (0.0, 0.0, 0usize);
    for _ in 0..40 {
        // A street front of 6-14 buildings 15-35 m ahead, with gaps.
        let n = 6 + (next() * 8.0) as usize;
        let blockers: Vec<Vec<DVec2>> = (0..n)
            .map(|_| {
                let x = -60.0 + next() * 130.0;
                let y = 15.0 + next() * 20.0;
                let w = 3.0 + next() * 12.0;
                let h = 2.0 + next() * 8.0;
                rect(x, y, x + w, y + h)
            })
            .collect();
        let ver = Verifier::new(&cell, blockers.iter().map(|b| b.as_slice()));
        let (a, b) = (v(-120.0, 80.0), v(130.0, 80.0));
        let parts = ver.hidden_parts(a, b);
        assert_sound(&cell, &blockers, &parts);
        cert_total += hidden_len(&parts);
        let single: f64 = blockers
            .iter()
            .map(|bl| hidden_len(&Verifier::new(&cell, [bl.as_slice()]).hidden_parts(a, b)))
            .sum();
        if hidden_len(&parts) > single + 1.0 {
            fused += 1;
        }
        let pts = dyadic_points(a, b, 8);
        let step = a.distance(b) / 256.0;
        brute_total += pts
            .iter()
            .filter(|&&q| brute_hidden(&cell, &blockers, q, 200))
            .count() as f64
            * step;
    }
    eprintln!(
        "certified {cert_total:.1} m of {brute_total:.1} m brute-force hidden; fusion beat single blockers in {fused} of 40 scenes"
    );
    assert!(brute_total > 500.0, "scenes too sparse to test anything");
    assert!(cert_total >= 0.97 * brute_total, "verifier too loose");
    assert!(fused >= 10, "fusion is not exercised");
}

// ---- Segment blockers (walls seen from above: 2-vertex blockers) ----

/// The four walls of a rectangle, as segments (an open box seen from above).
fn walls_of(r: &[DVec2]) -> Vec<Vec<DVec2>> {
    (0..r.len())
        .map(|i| vec![r[i], r[(i + 1) % r.len()]])
        .collect()
}

#[test]
fn single_wall_umbra_is_certified_and_its_penumbra_is_not() {
    let cell = rect(0.0, 0.0, 10.0, 10.0);
    // One wall from (-10,20) to (20,20): outer tangents (0,0)-(-10,20) and (10,0)-(20,20).
    let blockers = vec![vec![v(-10.0, 20.0), v(20.0, 20.0)]];
    let ver = Verifier::new(&cell, blockers.iter().map(|b| b.as_slice()));
    assert!(ver.is_hidden(v(-20.0, 40.0), v(30.0, 40.0)));
    let parts = ver.hidden_parts(v(-60.0, 40.0), v(30.0, 40.0));
    assert_sound(&cell, &blockers, &parts);
    let h = parts[0];
    assert!(h.p0.x >= -20.0 && h.p0.x < -20.0 + 0.05, "{h:?}");
    assert_eq!(h.p1, v(30.0, 40.0));
    // Reversed vertex order: the same wall.
    let rev = [vec![v(20.0, 20.0), v(-10.0, 20.0)]];
    let ver = Verifier::new(&cell, rev.iter().map(|b| b.as_slice()));
    assert!(ver.is_hidden(v(-20.0, 40.0), v(30.0, 40.0)));
    assert!(!ver.is_hidden(v(-21.0, 40.0), v(30.0, 40.0)));
    // A segment lying on the wall is hidden (every segment to it meets the wall there).
    assert!(ver.is_hidden(v(-5.0, 20.0), v(15.0, 20.0)));
}

#[test]
fn vo_on_a_radial_walls_line_beyond_its_end_is_not_in_the_wall() {
    // Regression: point_in_convex on a 2-vertex polygon said Boundary for every point of its
    // line (both edge tests collinear). A VO on the line of a wall that points at the cell, past
    // the wall's far end, then had both ends "in" the wall, and the verifier's shortcut for a
    // piece inside one blocker certified it, though the cell sees it on both sides of the wall.
    let cell = rect(0.0, 0.0, 10.0, 10.0);
    let blockers = vec![vec![v(5.0, 20.0), v(5.0, 30.0)]];
    let ver = Verifier::new(&cell, blockers.iter().map(|b| b.as_slice()));
    assert!(!ver.is_hidden(v(5.0, 35.0), v(5.0, 40.0)));
    assert!(ver.hidden_parts(v(5.0, 35.0), v(5.0, 40.0)).is_empty());
    assert!(!brute_hidden(&cell, &blockers, v(5.0, 37.0), 400));
    // On the wall itself it is hidden: every segment to it meets the wall there.
    assert!(ver.is_hidden(v(5.0, 22.0), v(5.0, 28.0)));
}

#[test]
fn walls_meeting_at_a_corner_fuse_and_radial_walls_hide_nothing() {
    let cell = rect(0.0, 0.0, 10.0, 10.0);
    // An L of two walls meeting at (5, 20): together as wide as the single wall above.
    let blockers = vec![
        vec![v(-10.0, 20.0), v(5.0, 20.0)],
        vec![v(5.0, 20.0), v(20.0, 20.0)],
    ];
    let ver = Verifier::new(&cell, blockers.iter().map(|b| b.as_slice()));
    assert!(ver.is_hidden(v(-20.0, 40.0), v(30.0, 40.0)));
    for one in &blockers {
        let alone = Verifier::new(&cell, [one.as_slice()]);
        assert!(!alone.is_hidden(v(-20.0, 40.0), v(30.0, 40.0)));
    }
    // A wall bent back (a real corner): the second leg runs away from the cell.
    let bent = vec![
        vec![v(-10.0, 20.0), v(10.0, 20.0)],
        vec![v(10.0, 20.0), v(14.0, 30.0)],
    ];
    let ver = Verifier::new(&cell, bent.iter().map(|b| b.as_slice()));
    let parts = ver.hidden_parts(v(-30.0, 50.0), v(40.0, 50.0));
    assert_sound(&cell, &bent, &parts);
    assert!(hidden_len(&parts) > 10.0, "{parts:?}");
    // Walls pointing at the cell centre hide nothing beyond them: a point behind one is on its
    // line, seen from the cell's points on either side.
    let c = v(5.0, 5.0);
    let radial: Vec<Vec<DVec2>> = (0..9)
        .map(|k| {
            let t = std::f64::consts::PI * (0.1 + 0.1 * k as f64);
            let d = v(t.cos(), t.sin());
            vec![c + d * 20.0, c + d * 40.0]
        })
        .collect();
    let ver = Verifier::new(&cell, radial.iter().map(|b| b.as_slice()));
    assert!(ver.hidden_parts(v(-60.0, 50.0), v(70.0, 50.0)).is_empty());
}

#[test]
fn open_boxes_hide_what_their_rectangles_hide() {
    // The four walls of a rectangle hide from an outside cell exactly what the rectangle hides:
    // a segment from outside into the rectangle crosses its boundary. The verifier should
    // certify about as much from the walls as from the solid prisms.
    let cell = rect(0.0, 0.0, 10.0, 10.0);
    let mut rng = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut solid_total, mut wall_total) = (0.0, 0.0);
    for _ in 0..12 {
        let rects: Vec<Vec<DVec2>> = (0..8)
            .map(|_| {
                let x = (-60.0 + next() * 130.0).round();
                let y = (15.0 + next() * 20.0).round();
                let (w, h) = ((3.0 + next() * 12.0).round(), (2.0 + next() * 8.0).round());
                rect(x, y, x + w, y + h)
            })
            .collect();
        let walls: Vec<Vec<DVec2>> = rects.iter().flat_map(|r| walls_of(r)).collect();
        let (a, b) = (v(-120.0, 80.0), v(130.0, 80.0));
        let solid = Verifier::new(&cell, rects.iter().map(|b| b.as_slice())).hidden_parts(a, b);
        let parts = Verifier::new(&cell, walls.iter().map(|b| b.as_slice())).hidden_parts(a, b);
        assert_sound(&cell, &walls, &parts);
        solid_total += hidden_len(&solid);
        wall_total += hidden_len(&parts);
    }
    eprintln!("walls certify {wall_total:.1} m, the solid rectangles {solid_total:.1} m");
    assert!(solid_total > 200.0, "scenes too sparse to test anything");
    assert!(wall_total >= 0.97 * solid_total, "walls certify too little");
}

/// A random wall: a segment in the field beyond the cell, any direction.
fn wall() -> impl Strategy<Value = Vec<DVec2>> {
    (-40i32..50, 14i32..60, 1i32..40, 0i32..32).prop_map(|(cx, cy, len, rot)| {
        let t = rot as f64 * std::f64::consts::PI / 16.0;
        let (c, s) = (t.cos(), t.sin());
        let h = len as f64 * 0.5;
        let o = v(cx as f64, cy as f64);
        vec![o + v(-h * c, -h * s), o + v(h * c, h * s)]
    })
}

/// Walls and polygons mixed, none reaching the cell.
fn mixed() -> impl Strategy<Value = Vec<Vec<DVec2>>> {
    prop::collection::vec(prop_oneof![wall(), wall(), blocker()], 1..16).prop_map(|bs| {
        bs.into_iter()
            .filter(|b| b.iter().all(|p| p.y > 11.0))
            .collect()
    })
}

/// Exact closed segment test on integer coordinates in i128, apart from everything else.
fn int_segments_meet(a: [i64; 2], b: [i64; 2], c: [i64; 2], d: [i64; 2]) -> bool {
    let o = |p: [i64; 2], q: [i64; 2], r: [i64; 2]| {
        let v = (q[0] - p[0]) as i128 * (r[1] - p[1]) as i128
            - (q[1] - p[1]) as i128 * (r[0] - p[0]) as i128;
        v.signum()
    };
    let on = |p: [i64; 2], q: [i64; 2], r: [i64; 2]| {
        o(p, q, r) == 0
            && r[0] >= p[0].min(q[0])
            && r[0] <= p[0].max(q[0])
            && r[1] >= p[1].min(q[1])
            && r[1] <= p[1].max(q[1])
    };
    (o(a, b, c) * o(a, b, d) < 0 && o(c, d, a) * o(c, d, b) < 0)
        || on(a, b, c)
        || on(a, b, d)
        || on(c, d, a)
        || on(c, d, b)
}

proptest! {
    #![proptest_config(Config { cases: 64, rng_seed: RngSeed::Fixed(0x5eed_0012), failure_persistence: None, ..Config::default() })]

    #[test]
    fn verifier_with_walls_agrees_with_brute_force(blockers in mixed(), (a, b) in segment()) {
        let cell = rect(0.0, 0.0, 10.0, 10.0);
        let ver = Verifier::new(&cell, blockers.iter().map(|b| b.as_slice()));
        let parts = ver.hidden_parts(a, b);
        assert_sound(&cell, &blockers, &parts);
        prop_assert_eq!(ver.is_hidden(a, b), parts.len() == 1 && parts[0].p0 == a && parts[0].p1 == b);
        // Tightness, as for polygons.
        let len = a.distance(b);
        let mut missed = 0.0;
        for q in dyadic_points(a, b, 7) {
            let t = if len > 0.0 { a.distance(q) / len } else { 0.0 };
            let inside = parts.iter().any(|h| t >= h.t0 && t <= h.t1);
            if !inside && brute_hidden(&cell, &blockers, q, 400) {
                let near = parts.iter().any(|h| (t - h.t0).abs() * len < 0.5 || (t - h.t1).abs() * len < 0.5);
                if !near {
                    missed += len / 128.0;
                }
            }
        }
        prop_assert!(missed <= 0.02 * len + 1.0, "verifier missed {missed} m of {len} m");
    }

    #[test]
    fn adding_a_wall_never_shrinks_the_hidden_part(blockers in mixed(), extra in wall(), (a, b) in segment()) {
        let cell = rect(0.0, 0.0, 10.0, 10.0);
        let mut blockers = blockers;
        let before = Verifier::new(&cell, blockers.iter().map(|b| b.as_slice())).hidden_parts(a, b);
        if extra.iter().all(|p| p.y > 11.0) {
            blockers.push(extra);
        }
        let after = Verifier::new(&cell, blockers.iter().map(|b| b.as_slice())).hidden_parts(a, b);
        // Up to the sweep's resolution: where a hidden part begins after a visible one is found
        // to within the least step, from wherever the sweep happened to step on.
        let tol = 2.0 * vocc::geom::verify::MIN_PIECE_M / a.distance(b).max(1e-9);
        for h in &before {
            prop_assert!(
                after.iter().any(|g| g.t0 <= h.t0 + tol && g.t1 >= h.t1 - tol),
                "hidden part {h:?} lost after adding a wall: {after:?}"
            );
        }
    }

    #[test]
    fn segment_predicates_agree_with_integer_arithmetic(
        pts in prop::collection::vec((-6i64..7, -6i64..7), 5),
    ) {
        use vocc::geom::predicates::{point_in_convex, segment_meets_convex, Containment};
        let p: Vec<[i64; 2]> = pts.iter().map(|&(x, y)| [x, y]).collect();
        let f = |q: [i64; 2]| v(q[0] as f64, q[1] as f64);
        prop_assume!(p[2] != p[3]);
        let wall = [f(p[2]), f(p[3])];
        prop_assert_eq!(
            segment_meets_convex(f(p[0]), f(p[1]), &wall),
            int_segments_meet(p[0], p[1], p[2], p[3])
        );
        let on = int_segments_meet(p[4], p[4], p[2], p[3]);
        let c = point_in_convex(&wall, f(p[4]));
        prop_assert_eq!(c == Containment::Boundary, on);
        prop_assert!(c != Containment::Inside);
    }
}
