//! Scan: candidate VOs as the long hidden runs of lines around the cell.
//!
//! Input: a cell, the blocker set, the ids of the usable blockers (sorted), and scan parameters.
//! Output: segments, each with the blockers that cut the sampled rays to it.
//! Rule: lines square to [`DIRECTIONS`] directions at [`DISTANCES`] from the cell centre, reaching
//! [`HALF_LENGTH`] either side, are sampled every [`STEP_M`]; a sample counts as hidden when the segments to it from points of the
//! cell's boundary all meet a usable blocker (in floating point, sampled: a proposal). A run of
//! hidden samples at least [`MIN_RUN_M`] long, shortened by one step at each end, is proposed.
//! Such runs cross blocks and streets hidden from the cell, so they are longer than any chain of
//! touching blockers, and a VO longer than the cell is wide has an umbra that widens behind it.
//! Invariant: a proposal only. Runs go to the same gate as every other VO (quantization, rule 2
//! and the exact verifier over the rule-2 blockers), which alone decides what is stored.

use glam::DVec2;

use super::BlockerSet;
use crate::geom::predicates::segment_meets_convex;

/// Directions of the scan lines' normals, evenly spread.
pub const DIRECTIONS: usize = 16;
/// Distances of the scan lines from the cell centre, in cell sizes.
pub const DISTANCES: [f64; 5] = [0.8, 1.2, 1.8, 2.6, 3.6];
/// How far each line reaches either side of its foot, in cell sizes.
pub const HALF_LENGTH: f64 = 4.0;
/// Sampling step along a line, metres.
pub const STEP_M: f64 = 6.0;
/// Shortest run proposed, metres.
pub const MIN_RUN_M: f64 = 40.0;
/// Points per cell edge the rays start from (besides the corners).
const EDGE_POINTS: usize = 3;

/// A proposed run: its ends, and the blockers that cut its sampled rays.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    pub a: DVec2,
    pub b: DVec2,
    pub chain: Vec<u32>,
}

/// The first usable blocker met by the segment `[p, q]`, if any (R-tree-free: bucket grid).
fn cut(
    set: &BlockerSet,
    usable: &[u32],
    p: DVec2,
    q: DVec2,
    hint: &mut Option<u32>,
) -> Option<u32> {
    if let Some(h) = *hint {
        if segment_meets_convex(p, q, &set.polys[h as usize]) {
            return Some(h);
        }
    }
    let len = p.distance(q);
    let steps = (len / 25.0).ceil().max(1.0) as usize;
    let mut found = None;
    for s in 0..steps {
        let a = p + (q - p) * (s as f64 / steps as f64);
        let b = p + (q - p) * ((s + 1) as f64 / steps as f64);
        set.each_in_box(a.min(b), a.max(b), |id| {
            if found.is_none()
                && usable.binary_search(&id).is_ok()
                && segment_meets_convex(p, q, &set.polys[id as usize])
            {
                found = Some(id);
            }
        });
        if found.is_some() {
            break;
        }
    }
    *hint = found;
    found
}

/// Hidden runs around the cell `cell` (counter-clockwise rectangle) at the given distances from
/// its centre, lines reaching `half_len` either side.
pub fn runs(
    set: &BlockerSet,
    usable: &[u32],
    cell: &[DVec2; 4],
    distances: &[f64],
    half_len: f64,
) -> Vec<Run> {
    let centre = (cell[0] + cell[2]) * 0.5;
    let mut eyes: Vec<DVec2> = cell.to_vec();
    for i in 0..4 {
        let (a, b) = (cell[i], cell[(i + 1) % 4]);
        for k in 1..=EDGE_POINTS {
            eyes.push(a + (b - a) * (k as f64 / (EDGE_POINTS + 1) as f64));
        }
    }
    let mut hints: Vec<Option<u32>> = vec![None; eyes.len()];
    let mut out = Vec::new();
    for k in 0..DIRECTIONS {
        let th = std::f64::consts::TAU * k as f64 / DIRECTIONS as f64;
        let n = DVec2::new(th.cos(), th.sin());
        let along = n.perp();
        for &d in distances {
            let o = centre + n * d;
            let m = (half_len / STEP_M).floor() as i64;
            let mut run: Option<(i64, i64, Vec<u32>)> = None;
            let close = |run: &mut Option<(i64, i64, Vec<u32>)>, out: &mut Vec<Run>| {
                if let Some((i0, i1, mut chain)) = run.take() {
                    let (t0, t1) = ((i0 + 1) as f64 * STEP_M, (i1 - 1) as f64 * STEP_M);
                    if t1 - t0 >= MIN_RUN_M {
                        chain.sort_unstable();
                        chain.dedup();
                        out.push(Run {
                            a: o + along * t0,
                            b: o + along * t1,
                            chain,
                        });
                    }
                }
            };
            for i in -m..=m {
                let p = o + along * (i as f64 * STEP_M);
                let mut hit = Vec::with_capacity(eyes.len());
                let hidden = eyes.iter().zip(hints.iter_mut()).all(|(&e, h)| {
                    let c = cut(set, usable, e, p, h);
                    hit.extend(c);
                    c.is_some()
                });
                if hidden {
                    match &mut run {
                        Some((_, i1, chain)) => {
                            *i1 = i;
                            chain.extend(hit);
                        }
                        None => run = Some((i, i, hit)),
                    }
                } else {
                    close(&mut run, &mut out);
                }
            }
            close(&mut run, &mut out);
        }
    }
    out
}
