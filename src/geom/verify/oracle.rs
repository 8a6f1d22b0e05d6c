//! Tests only: a brute-force oracle for the verifier's unit tests, and the small random scenes
//! they draw.
//!
//! Input: a convex cell, blockers (convex polygons or segments), a point. Output: whether every
//! sampled segment from the cell to the point meets a blocker (exact [`segment_meets_convex`]
//! per sample; no certificate, no search), and scenes of dyadic coordinates (exact in f64).
//!
//! Invariant: shares nothing with the verifier but the exact predicates. Sampling can only call
//! a visible point hidden where every sample misses its escape, so a test asserts soundness as
//! "certified implies sampled-hidden", never the converse.

use glam::DVec2;

use crate::geom::predicates::{point_in_convex, segment_meets_convex, Containment};
use crate::testutil::Lcg;

pub(super) fn v(x: f64, y: f64) -> DVec2 {
    DVec2::new(x, y)
}

/// The axis-aligned rectangle, counter-clockwise.
pub(super) fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<DVec2> {
    vec![v(x0, y0), v(x1, y0), v(x1, y1), v(x0, y1)]
}

/// Whether every segment from `n` points spread along the cell's boundary (and its vertices,
/// each pulled a hair inside) to `q` meets one of `blockers`; false for `q` in the cell.
pub(super) fn brute_hidden(cell: &[DVec2], blockers: &[Vec<DVec2>], q: DVec2, n: usize) -> bool {
    if point_in_convex(cell, q) != Containment::Outside {
        return false;
    }
    let centre = cell.iter().copied().sum::<DVec2>() / cell.len() as f64;
    let perimeter: f64 = (0..cell.len())
        .map(|i| cell[i].distance(cell[(i + 1) % cell.len()]))
        .sum();
    let mut targets: Vec<DVec2> = cell.to_vec();
    for k in 0..n {
        let mut d = perimeter * (k as f64 + 0.5) / n as f64;
        for i in 0..cell.len() {
            let (a, b) = (cell[i], cell[(i + 1) % cell.len()]);
            let len = a.distance(b);
            if d <= len {
                targets.push(a + (b - a) * (d / len));
                break;
            }
            d -= len;
        }
    }
    targets.iter().all(|&t| {
        let c = centre + (t - centre) * (1.0 - 1e-9);
        blockers.iter().any(|b| segment_meets_convex(q, c, b))
    })
}

/// Points exactly on `[a, b]` at parameters `k / 2^levels` (dyadic ends keep them exact).
pub(super) fn dyadic_points(a: DVec2, b: DVec2, levels: u32) -> Vec<DVec2> {
    let n = 1u32 << levels;
    (0..=n)
        .map(|k| a + (b - a) * (k as f64 / n as f64))
        .collect()
}

/// A random scene in front of the cell `[0, 16]^2`: `n` rectangles (some thin, as walls seen
/// from above, some 2-vertex segments) between y = 20 and y = 60, on a 1/4 m grid, and a
/// segment between y = 64 and y = 96.
pub(super) fn scene(g: &mut Lcg, n: usize) -> (Vec<DVec2>, Vec<Vec<DVec2>>, (DVec2, DVec2)) {
    let q = |g: &mut Lcg, lo: f64, hi: f64| (g.range(lo, hi) * 4.0).floor() / 4.0;
    let cell = rect(0.0, 0.0, 16.0, 16.0);
    let blockers = (0..n)
        .map(|k| {
            let (x, y) = (q(g, -40.0, 50.0), q(g, 20.0, 56.0));
            let w = q(g, 1.0, 30.0);
            if k % 5 == 4 {
                vec![v(x, y), v(x + w, y + q(g, -2.0, 2.0))]
            } else {
                rect(x, y, x + w, y + q(g, 0.25, 4.0))
            }
        })
        .collect();
    let a = v(q(g, -80.0, 20.0), q(g, 64.0, 96.0));
    let b = v(q(g, 0.0, 100.0), q(g, 64.0, 96.0));
    (cell, blockers, (a, b))
}
