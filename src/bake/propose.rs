//! Proposals: long candidate VOs, the maximal hidden runs of lines around a cell.
//!
//! Input: a cell (counter-clockwise rectangle), the [`HiddenMap`] of one slice, and
//! [`ProposeParams`] (line directions, spacing, shortest run, how many per direction).
//! Output: candidate segments, each the hidden run of one line shortened by a pixel at both ends,
//! ranked within each direction by the angle their umbra opens at infinity.
//! Why long runs: a VO shorter than the cell is wide has a closed triangular umbra; a longer one
//! has a wedge that widens behind it, and the good VOs run through blocks and across the streets
//! the cell cannot see down (DESIGN.md 4b). Lines at every direction and offset are sampled at
//! the map's pixel size; a run breaks at the first visible pixel.
//! Invariant: a proposal only; [`super::certify`] decides with the exact verifier.

use glam::DVec2;

use super::hidden::HiddenMap;

/// Proposed endpoints lie on this grid, metres (2^-10 m): dyadic, so the verifier's bisection
/// midpoints are exact and lie exactly on the segment (ARCHITECTURE.md invariant 8).
pub const VO_GRID_M: f64 = 1.0 / 1024.0;

fn snap(p: DVec2) -> DVec2 {
    (p / VO_GRID_M).round() * VO_GRID_M
}

/// Which lines are scanned and which runs are kept.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProposeParams {
    /// Line normals, evenly spread over the full turn.
    pub directions: usize,
    /// Spacing of parallel lines, metres.
    pub spacing: f64,
    /// Farthest line from the cell centre, metres.
    pub max_offset: f64,
    /// Shortest run kept, metres.
    pub min_len: f64,
    /// Runs kept per direction, widest umbra first.
    pub per_direction: usize,
}

impl Default for ProposeParams {
    fn default() -> Self {
        ProposeParams {
            directions: 64,
            spacing: 4.0,
            max_offset: 400.0,
            min_len: 60.0,
            per_direction: 3,
        }
    }
}

/// A proposed segment; `a` lies counter-clockwise of `b` seen from the cell centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Proposal {
    pub a: DVec2,
    pub b: DVec2,
    /// Angle the umbra opens at infinity, radians (negative: it closes behind the segment).
    pub spread: f64,
}

/// The angle at infinity of the umbra of `a`–`b` seen from `cell` (module header). `a` must be
/// counter-clockwise of `b` seen from inside the cell.
pub fn spread(cell: &[DVec2; 4], a: DVec2, b: DVec2) -> f64 {
    // The boundary through a comes from the corner that makes a - c most clockwise, the one
    // through b from the corner that makes b - c most counter-clockwise.
    let mut da = a - cell[0];
    let mut db = b - cell[0];
    for &c in &cell[1..] {
        let (xa, xb) = (a - c, b - c);
        if da.perp_dot(xa) < 0.0 {
            da = xa;
        }
        if db.perp_dot(xb) > 0.0 {
            db = xb;
        }
    }
    db.perp_dot(da).atan2(db.dot(da))
}

/// The candidate runs of `map` around `cell`.
pub fn runs(cell: &[DVec2; 4], map: &HiddenMap, p: &ProposeParams) -> Vec<Proposal> {
    let centre = (cell[0] + cell[2]) * 0.5;
    let half_w = 0.5 * (cell[2].x - cell[0].x).abs().max((cell[2].y - cell[0].y).abs());
    let reach = 0.5 * map.n as f64 * map.px * std::f64::consts::SQRT_2;
    let step = map.px;
    let mut out = Vec::new();
    for j in 0..p.directions {
        let phi = std::f64::consts::TAU * j as f64 / p.directions as f64;
        let n = DVec2::new(phi.cos(), phi.sin());
        // Counter-clockwise along the line, seen from the cell: from b's side to a's.
        let along = n.perp();
        let clear = half_w * (n.x.abs() + n.y.abs()) + p.spacing;
        let mut best: Vec<Proposal> = Vec::new();
        let mut o = clear;
        while o <= p.max_offset {
            let foot = centre + n * o;
            // Only the chord of the line inside the raster's circumcircle.
            let chord = (reach * reach - o * o).max(0.0).sqrt();
            let m = (chord / step) as i64;
            let mut start: Option<i64> = None;
            for i in -m..=m + 1 {
                let h = i <= m && map.hidden(foot + along * (i as f64 * step));
                match (h, start) {
                    (true, None) => start = Some(i),
                    (false, Some(s)) => {
                        start = None;
                        // Shortened by a sample at each end: off the boundary pixels.
                        let (t0, t1) = ((s + 1) as f64 * step, (i - 2) as f64 * step);
                        if t1 - t0 >= p.min_len {
                            let (b, a) = (snap(foot + along * t0), snap(foot + along * t1));
                            let s = spread(cell, a, b);
                            best.push(Proposal { a, b, spread: s });
                        }
                    }
                    _ => {}
                }
            }
            o += p.spacing;
        }
        best.sort_by(|x, y| y.spread.total_cmp(&x.spread));
        out.extend(best.into_iter().take(p.per_direction));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_opens_for_long_segments_and_closes_for_short_ones() {
        let cell = [
            DVec2::new(-50.0, -100.0),
            DVec2::new(50.0, -100.0),
            DVec2::new(50.0, 0.0),
            DVec2::new(-50.0, 0.0),
        ];
        // 100 m away, 300 m long: at infinity the binding rays come from the far corners,
        // directions (-100, 200) and (100, 200).
        let s = spread(&cell, DVec2::new(-150.0, 100.0), DVec2::new(150.0, 100.0));
        assert!((s - 2.0 * 0.5f64.atan()).abs() < 1e-12, "{s}");
        let short = spread(&cell, DVec2::new(-30.0, 100.0), DVec2::new(30.0, 100.0));
        assert!(short < 0.0);
    }
}
