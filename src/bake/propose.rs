//! Proposals: long candidate VOs, the maximal hidden runs of lines around a cell.
//!
//! Input: a cell (counter-clockwise rectangle), the [`HiddenMap`] of one slice, and
//! [`ProposeParams`] (line directions, spacing, shortest run, how many per direction).
//! Output: candidate segments, each the hidden run of one line shortened by a pixel at both ends,
//! ranked within each direction by the angle their umbra opens at infinity.
//! Why long runs: a VO shorter than the cell is wide has a closed triangular umbra; a longer one
//! has a wedge that widens behind it, and the good VOs run through blocks and across the streets
//! the cell cannot see down (docs/DESIGN.md 4b). Lines at every direction and offset are sampled at
//! the map's pixel size; a run breaks at the first visible pixel.
//! Invariant: a proposal only; [`super::certify`] decides with the exact verifier.

use glam::DVec2;

use super::hidden::HiddenMap;

use super::cell::VO_GRID_M;

fn snap(p: DVec2) -> DVec2 {
    (p / VO_GRID_M).round() * VO_GRID_M
}

/// Which lines are scanned and which runs are kept.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProposeParams {
    /// Line normals of the scan, evenly spread over the full turn.
    pub directions: usize,
    /// Spacing of parallel lines in the scan, metres.
    pub spacing: f64,
    /// Sampling step along a line in the scan, in pixels of the map.
    pub step: usize,
    /// Farthest line from the cell centre, metres.
    pub max_offset: f64,
    /// Shortest run kept, metres.
    pub min_len: f64,
    /// Runs kept per direction and band of offsets ([`BANDS_M`]), widest umbra first.
    pub per_direction: usize,
}

impl Default for ProposeParams {
    fn default() -> Self {
        ProposeParams {
            directions: 16,
            spacing: 32.0,
            step: 2,
            max_offset: 900.0,
            min_len: 60.0,
            per_direction: 1,
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

/// Offsets at which the bands of the scan's ranking begin, metres.
pub const BANDS_M: [f64; 3] = [200.0, 400.0, 800.0];

/// A line of the scan: unit normal `n` (away from the cell centre `c`), offset `o`.
#[derive(Clone, Copy, Debug)]
struct Line {
    phi: f64,
    o: f64,
}

impl Line {
    fn normal(&self) -> DVec2 {
        DVec2::new(self.phi.cos(), self.phi.sin())
    }
}

/// The scan of one map around one cell.
struct Scan<'a> {
    cell: &'a [DVec2; 4],
    map: &'a HiddenMap,
    centre: DVec2,
    /// Half the chord of the map's circumcircle at offset 0.
    reach: f64,
}

impl Scan<'_> {
    /// The maximal hidden runs of `l`, sampled every `step` pixels, as parameters `(t0, t1)`
    /// along `n.perp()` from the foot of the line, shortened by a sample at each end.
    fn runs(&self, l: &Line, step: usize, min_len: f64, out: &mut Vec<(f64, f64)>) {
        let n = l.normal();
        let along = n.perp();
        let foot = self.centre + n * l.o;
        let chord = (self.reach * self.reach - l.o * l.o).max(0.0).sqrt();
        let h = self.map.px * step as f64;
        let m = (chord / h) as i64;
        let mut start: Option<i64> = None;
        let d = along * (h / self.map.px);
        let mut q = self.map.raster(foot) - d * m as f64;
        for i in -m..=m + 1 {
            let hid = i <= m && self.map.hidden_at(q);
            q += d;
            match (hid, start) {
                (true, None) => start = Some(i),
                (false, Some(s)) => {
                    start = None;
                    let (t0, t1) = ((s + 1) as f64 * h, (i - 2) as f64 * h);
                    if t1 - t0 >= min_len {
                        out.push((t0, t1));
                    }
                }
                _ => {}
            }
        }
    }

    fn proposal(&self, l: &Line, (t0, t1): (f64, f64)) -> Proposal {
        let n = l.normal();
        let along = n.perp();
        let foot = self.centre + n * l.o;
        let (b, a) = (snap(foot + along * t0), snap(foot + along * t1));
        Proposal {
            a,
            b,
            spread: spread(self.cell, a, b),
        }
    }
}

/// The candidate runs of `map` around `cell`: a scan of lines at every direction and offset, the
/// runs of widest umbra per direction and band of offsets. (A local search that turned and
/// shifted each kept run's line while its umbra widened was tried and removed: it changed the
/// culled share by less than the sampling noise.)
pub fn runs(cell: &[DVec2; 4], map: &HiddenMap, p: &ProposeParams) -> Vec<Proposal> {
    let centre = (cell[0] + cell[2]) * 0.5;
    let half_w = 0.5
        * (cell[2].x - cell[0].x)
            .abs()
            .max((cell[2].y - cell[0].y).abs());
    let scan = Scan {
        cell,
        map,
        centre,
        reach: 0.5 * map.n as f64 * map.px * std::f64::consts::SQRT_2,
    };
    let mut out: Vec<Proposal> = Vec::new();
    let mut found = Vec::new();
    for j in 0..p.directions {
        let phi = std::f64::consts::TAU * j as f64 / p.directions as f64;
        let mut best: Vec<(Line, Proposal)> = Vec::new();
        let mut o = half_w * (phi.cos().abs() + phi.sin().abs()) + p.spacing;
        while o <= p.max_offset {
            let l = Line { phi, o };
            found.clear();
            scan.runs(&l, p.step, p.min_len, &mut found);
            best.extend(found.iter().map(|&r| (l, scan.proposal(&l, r))));
            o += p.spacing;
        }
        // The widest umbrae within each band of distances: near and far VOs both compete.
        best.sort_by(|x, y| y.1.spread.total_cmp(&x.1.spread));
        let mut taken = [0usize; BANDS_M.len() + 1];
        for (l, seed) in best {
            let band = BANDS_M.iter().filter(|&&d| l.o >= d).count();
            if taken[band] < p.per_direction {
                taken[band] += 1;
                out.push(seed);
            }
        }
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
