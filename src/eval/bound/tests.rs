//! Tests of the fusion bound and the 10-VO ceiling ([`super`]): what a row of blockers lets
//! the ceiling cull (nothing in front of it; with slices, only what rule 3 lets a VO as tall as
//! the row hide), nothing without blockers, and the umbra test's margin and side lines.
//!
//! Input: small scenes built here. Output: pass or fail.
//! Invariant: expected answers are derived by hand from the scene.

use super::*;
use crate::scene::ReadOptions;

/// A scene from axis-aligned boxes `[x0, y0, x1, y1]` (world metres), 20 m tall, in order.
fn boxes_scene(boxes: &[[f64; 4]]) -> Scene {
    let tall: Vec<([f64; 4], f64)> = boxes.iter().map(|&b| (b, 20.0)).collect();
    crate::scene::boxes_scene(&tall)
}

/// The cell `[0, 0] - [100, 100]` (world) in the scene's local frame.
fn cell(s: &Scene) -> [f64; 4] {
    let (x, y) = (s.origin.x, s.origin.y);
    [-x, -y, 100.0 - x, 100.0 - y]
}

/// 26 touching buildings of `height` in a row from x = -600 to 700 at y = 130..150.
fn row_of(height: f64) -> Vec<([f64; 4], f64)> {
    (0..26)
        .map(|i| {
            let x = -600.0 + 50.0 * i as f64;
            ([x, 130.0, x + 50.0, 150.0], height)
        })
        .collect()
}

/// Eyes 1.5..2 m above a ground at 0.
const GROUND_EYES: Heights = Heights {
    g: 0.0,
    e0: 1.5,
    e1: 2.0,
};

/// 26 touching buildings in a row from x = -600 to 700 at y = 130..150 (objects 0..26), two
/// objects the cell sees (26 in front of the row, 27 beside the cell), four behind the row
/// (28..32).
fn row_scene() -> Scene {
    let mut b: Vec<[f64; 4]> = row_of(20.0).into_iter().map(|(r, _)| r).collect();
    b.push([40.0, 110.0, 60.0, 120.0]);
    b.push([150.0, 40.0, 170.0, 60.0]);
    b.push([-100.0, 200.0, -80.0, 215.0]);
    b.push([40.0, 200.0, 60.0, 215.0]);
    b.push([200.0, 200.0, 220.0, 215.0]);
    b.push([0.0, 400.0, 30.0, 420.0]);
    boxes_scene(&b)
}

#[test]
fn ceiling_culls_what_a_row_hides_and_nothing_in_front() {
    let s = row_scene();
    assert_eq!(s.objects.len(), 32);
    let r = cell(&s);
    let p = CeilingParams::default();
    let c = ceiling_2d(&s, r, &p);
    assert_eq!(c.culled, vec![28, 29, 30, 31], "{c:?}");
    let hidden = hidden_2d(&s, r, &BoundParams::default());
    assert!(
        c.culled.iter().all(|o| hidden.binary_search(o).is_ok()),
        "ceiling {:?} not within hidden {hidden:?}",
        c.culled
    );
    assert_eq!(c.by_count.len(), p.vos);
    assert!(
        c.by_count.windows(2).all(|w| w[0] <= w[1]),
        "{:?}",
        c.by_count
    );
    assert_eq!(*c.by_count.last().unwrap(), c.culled.len());
    // One segment behind the row culls all four; nothing adds more, so one is chosen.
    assert_eq!(c.by_count[0], 4);
    assert_eq!(c.vos.len(), 1);
    let [ax, ay, bx, by] = c.vos[0];
    let (ay, by) = (ay + s.origin.y, by + s.origin.y);
    let (ax, bx) = (ax + s.origin.x, bx + s.origin.x);
    assert!(
        ay > 150.0 && by > 150.0 && ay < 200.0 && by < 200.0,
        "{:?}",
        c.vos
    );
    assert!(
        (ax - bx).abs() > 500.0,
        "a long segment along the row: {:?}",
        c.vos
    );
}

#[test]
fn the_sliced_ceiling_culls_only_what_rule_3_lets_a_vo_as_tall_as_the_row_hide() {
    // A row 10 m tall at y 130..150 in front of the cell [0, 100]^2; behind it, at y 200
    // an 8 m and a 30 m box, and at y 400 a 15 m and a 30 m box. A VO just behind the row
    // (about 152 m from the cell's far edge) is no taller than the row's 8 m above the eyes
    // (lambda near 1) and allows tops of about 2 + 8 F, F = 1.3 at y 200 and 2.6 at y 400:
    // 12.4 m and 22.8 m. Farther back, rule 2's perspective lets the row hold taller VOs,
    // whose F falls as fast: no VO covers a 30 m box.
    let mut b = row_of(10.0);
    b.push(([40.0, 200.0, 60.0, 215.0], 8.0));
    b.push(([-20.0, 200.0, 0.0, 215.0], 30.0));
    b.push(([0.0, 400.0, 30.0, 420.0], 15.0));
    b.push(([60.0, 400.0, 90.0, 420.0], 30.0));
    let s = crate::scene::boxes_scene(&b);
    let r = cell(&s);
    let p = CeilingParams::default();
    assert_eq!(ceiling_2d(&s, r, &p).culled, vec![26, 27, 28, 29]);
    let h = GROUND_EYES;
    let c = ceiling_sliced(&s, r, h, &p);
    assert_eq!(c.culled, vec![26, 28], "{c:?}");
    // Eyes 6 m higher: near the row a VO is at most 2 m above them, and 8 + 2 F at y 400
    // (about 13.2 m) no longer reaches 15 m; a VO of 4 m above the eyes needs lambda <= 1/2,
    // a line at y 300 or beyond, where F = 1.33 gives 13.3 m. At y 200, 8 + 2 F still
    // covers 8 m.
    let high = Heights {
        g: 0.0,
        e0: 7.5,
        e1: 8.0,
    };
    assert_eq!(ceiling_sliced(&s, r, high, &p).culled, vec![26]);
}

#[test]
fn ceiling_without_blockers_culls_nothing() {
    let mut s = row_scene();
    s.blockers.clear();
    let c = ceiling_2d(&s, cell(&s), &CeilingParams::default());
    assert!(c.culled.is_empty() && c.vos.is_empty(), "{c:?}");
    assert_eq!(c.by_count, vec![0; 10]);
    // Blockers that all meet the cell are not outside it: nothing either.
    let s = boxes_scene(&[[-10.0, 40.0, 500.0, 60.0], [40.0, 200.0, 60.0, 215.0]]);
    let mut only_inside = s.clone();
    only_inside.blockers.retain(|b| b.object == 0);
    let c = ceiling_2d(&only_inside, cell(&s), &CeilingParams::default());
    assert!(c.culled.is_empty(), "{c:?}");
}

#[test]
fn umbra_test_keeps_its_margin_and_the_side_lines() {
    let cell = cell_corners([0.0, 0.0, 10.0, 10.0]);
    let (a, b) = (DVec2::new(-100.0, 20.0), DVec2::new(110.0, 20.0));
    let bx = |x0: f64, y0: f64, x1: f64, y1: f64| {
        [
            DVec2::new(x0, y0),
            DVec2::new(x1, y0),
            DVec2::new(x1, y1),
            DVec2::new(x0, y1),
        ]
    };
    assert!(box_in_umbra(&cell, &bx(40.0, 30.0, 60.0, 40.0), a, b));
    // Touching the segment's line, or within the margin of it: not culled.
    assert!(!box_in_umbra(&cell, &bx(40.0, 20.0, 60.0, 40.0), a, b));
    assert!(!box_in_umbra(&cell, &bx(40.0, 20.0005, 60.0, 40.0), a, b));
    assert!(box_in_umbra(&cell, &bx(40.0, 20.01, 60.0, 40.0), a, b));
    // In front of the segment, or past the side line through a cell corner and an end.
    assert!(!box_in_umbra(&cell, &bx(40.0, 12.0, 60.0, 18.0), a, b));
    assert!(!box_in_umbra(&cell, &bx(200.0, 30.0, 210.0, 40.0), a, b));
    // The side line from the corner (10, 0) through b = (110, 20) reaches y = 30 at x = 160
    // (the one from (10, 10) only at x = 210): a box just inside it at y = 30 is culled,
    // one reaching past it is not.
    assert!(box_in_umbra(&cell, &bx(150.0, 30.0, 159.0, 31.0), a, b));
    assert!(!box_in_umbra(&cell, &bx(150.0, 30.0, 161.0, 31.0), a, b));
}

/// The ceiling on Lyon, 100 m cells (`cargo test --release --lib eval::bound -- --ignored
/// --nocapture`): per cell, the share of objects hidden in 2D and culled by the ceiling, and
/// the ceiling's milliseconds on one thread. Prints; asserts only what must hold.
#[test]
#[ignore]
fn ceiling_on_lyon_cells() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/lyon1/buildings_lyon1.geojson");
    let s = crate::scene::load(
        &[path],
        &ReadOptions {
            height_attr: Some("HAUTEUR".into()),
            ..ReadOptions::default()
        },
    )
    .unwrap();
    let n = s.objects.len() as f64;
    let e = s.extent();
    // 100 m cells from the extent's corner that hold the centre of some object's box; five of
    // them, evenly spread in that order.
    let mut cells: Vec<(i64, i64)> = s
        .objects
        .iter()
        .map(|o| {
            let c = (o.bbox.min + o.bbox.max) * 0.5 - e.min;
            ((c.x / 100.0).floor() as i64, (c.y / 100.0).floor() as i64)
        })
        .collect();
    cells.sort_unstable();
    cells.dedup();
    let k = std::env::var("VOCC_CEILING_CELLS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5usize);
    let stride = (cells.len() / k).max(1);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let p = CeilingParams::default();
    let (mut hs, mut cs, mut ms) = (Vec::new(), Vec::new(), Vec::new());
    for &(i, j) in cells.iter().skip(stride / 2).step_by(stride).take(k) {
        let (x, y) = (e.min.x + 100.0 * i as f64, e.min.y + 100.0 * j as f64);
        let r = [x, y, x + 100.0, y + 100.0];
        let hidden = hidden_2d(&s, r, &BoundParams::default());
        let t = std::time::Instant::now();
        let c = one.install(|| ceiling_2d(&s, r, &p));
        let t = t.elapsed().as_secs_f64() * 1e3;
        let outside = c
            .culled
            .iter()
            .filter(|o| hidden.binary_search(o).is_err())
            .count();
        let lens: Vec<f64> = c
            .vos
            .iter()
            .map(|v| (v[2] - v[0]).hypot(v[3] - v[1]))
            .collect();
        println!(
                "cell ({i}, {j}): hidden_2d {:.1}%, ceiling {:.1}% (by the first 1 to 10 VOs: {:?}), {outside} culled not in hidden_2d, {t:.0} ms, VO lengths {lens:.0?}",
                100.0 * hidden.len() as f64 / n,
                100.0 * c.culled.len() as f64 / n,
                c.by_count.iter().map(|&b| format!("{:.1}", 100.0 * b as f64 / n)).collect::<Vec<_>>(),
            );
        assert!(c.by_count.windows(2).all(|w| w[0] <= w[1]));
        hs.push(hidden.len() as f64 / n);
        cs.push(c.culled.len() as f64 / n);
        ms.push(t);
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    println!(
        "{} cells: hidden_2d {:.1}%, ceiling {:.1}% (means), {:.0} ms per cell on one thread",
        ms.len(),
        100.0 * mean(&hs),
        100.0 * mean(&cs),
        mean(&ms)
    );
}

#[test]
fn the_scene_ceiling_reaches_a_row_1500_m_out_that_the_600_m_one_never_sees() {
    // A row of ten 20 m buildings at y 1500..1520, x -200..300, and behind it two boxes at
    // y 1700 (objects 10 and 11); the cell is [0, 100]^2. The 600 m ceiling samples points
    // within 800 m of the centre: no candidate, nothing culled. Over the whole scene, lines
    // beyond 600 m are spaced and sampled at the same angle (about 60 m apart, every 10 m
    // along them, near the row), and a run just behind the row hides both boxes.
    let mut b: Vec<[f64; 4]> = (0..10)
        .map(|i| {
            let x = -200.0 + 50.0 * i as f64;
            [x, 1500.0, x + 50.0, 1520.0]
        })
        .collect();
    b.push([40.0, 1700.0, 60.0, 1715.0]);
    b.push([0.0, 1800.0, 30.0, 1820.0]);
    let s = boxes_scene(&b);
    let r = cell(&s);
    assert!(ceiling_2d(&s, r, &CeilingParams::default())
        .culled
        .is_empty());
    let c = ceiling_2d(&s, r, &CeilingParams::scene());
    assert_eq!(c.culled, vec![10, 11], "{c:?}");
    // The culled boxes are hidden in 2D (the ceiling stays within the fusion bound).
    let hidden = hidden_2d(&s, r, &BoundParams::default());
    assert!(c.culled.iter().all(|o| hidden.binary_search(o).is_ok()));
}

#[test]
fn the_scene_ceiling_lets_a_tall_row_hide_a_tower() {
    // A row 100 m tall at y 130..150 in front of the cell [0, 100]^2 and a 150 m tower at
    // y 400..420 (object 26). At the default tops (at most 24 m above the eyes) a VO just
    // behind the row allows at most about 2 + 24 F = 64.6 m at the tower (F = 2.6, the
    // sliced test above); the whole-scene ceiling adds tops up to the tallest blocker (150 m),
    // and one of 64 m above the eyes allows about 168 m there.
    let mut b = row_of(100.0);
    b.push(([0.0, 400.0, 30.0, 420.0], 150.0));
    let s = crate::scene::boxes_scene(&b);
    let r = cell(&s);
    let h = GROUND_EYES;
    assert!(ceiling_sliced(&s, r, h, &CeilingParams::default())
        .culled
        .is_empty());
    assert_eq!(
        ceiling_sliced(&s, r, h, &CeilingParams::scene()).culled,
        vec![26]
    );
}
