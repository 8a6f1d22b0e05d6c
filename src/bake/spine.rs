//! Spines: candidate VOs that run through the inside of blocks of touching buildings.
//!
//! Input: a cell, the blocker set, the ids of the blockers usable for the cell (sorted), and how
//! many to start from. Output: segments, each with the blockers it runs through.
//! Rule: every point inside a blocker whose interior misses the cell is hidden from the cell
//! (any segment from the cell to it enters the blocker), and so is every point of a run of
//! blockers that touch or overlap along a line: a long segment inside such a run is a VO whose
//! umbra is as wide as the block. For each start blocker (the largest area-angle first), lines
//! through its centre across the view direction and along its longest edge are clipped to every
//! usable blocker they meet, in floating point; the contiguous run of intervals around the start
//! is the spine, shrunk by [`SHRINK_M`] at each end.
//! Invariant: a proposal only. Spines go to the same gate as every other VO (quantization, rule
//! 2 and the exact verifier over the rule-2 blockers), which alone decides what is stored; a
//! run joined across a gap the float clipping missed is refused there.

use glam::DVec2;

use super::BlockerSet;

/// Each spine is shortened by this much at each end, metres.
pub const SHRINK_M: f64 = 0.05;
/// Intervals closer than this along the line count as touching, metres (the gate is exact).
const JOIN_M: f64 = 1e-6;
/// Shortest spine worth proposing, metres.
pub const MIN_SPINE_M: f64 = 10.0;

/// A proposed spine: its ends, and the blockers whose intervals it joins.
#[derive(Clone, Debug, PartialEq)]
pub struct Spine {
    pub a: DVec2,
    pub b: DVec2,
    pub chain: Vec<u32>,
}

/// The parameter interval of the line `o + t d` inside convex polygon `p`, if any.
fn clip(p: &[DVec2], o: DVec2, d: DVec2) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    let n = p.len();
    for i in 0..n {
        let (u, v) = (p[i], p[(i + 1) % n]);
        let e = v - u;
        // Inside of a counter-clockwise polygon: left of every edge.
        let alpha = e.perp_dot(o - u);
        let beta = e.perp_dot(d);
        if beta > 0.0 {
            t0 = t0.max(-alpha / beta);
        } else if beta < 0.0 {
            t1 = t1.min(-alpha / beta);
        } else if alpha < 0.0 {
            return None;
        }
    }
    (t0 < t1).then_some((t0, t1))
}

/// Spines of the cell with centre `centre`, from the `starts` (best first) among `usable`.
pub fn spines(set: &BlockerSet, usable: &[u32], centre: DVec2, starts: &[u32]) -> Vec<Spine> {
    let mut out: Vec<Spine> = Vec::new();
    for &s in starts {
        let p = &set.polys[s as usize];
        let c = p.iter().copied().sum::<DVec2>() / p.len() as f64;
        let view = (c - centre).normalize_or_zero();
        if view == DVec2::ZERO {
            continue;
        }
        let longest = (0..p.len())
            .map(|i| p[(i + 1) % p.len()] - p[i])
            .max_by(|a, b| a.length_squared().total_cmp(&b.length_squared()))
            .unwrap_or(DVec2::ZERO)
            .normalize_or_zero();
        let mut dirs = vec![view.perp()];
        if longest != DVec2::ZERO && longest.dot(view.perp()).abs() < 0.99 {
            dirs.push(longest);
        }
        for d in dirs {
            if let Some(sp) = run(set, usable, s, c, d) {
                if out.iter().all(|o| o.a != sp.a || o.b != sp.b) {
                    out.push(sp);
                }
            }
        }
    }
    out
}

/// The contiguous run of usable blockers along `o + t d` around blocker `s`.
fn run(set: &BlockerSet, usable: &[u32], s: u32, o: DVec2, d: DVec2) -> Option<Spine> {
    let (s0, s1) = clip(&set.polys[s as usize], o, d)?;
    // Gather intervals along the line, outwards from the start, through the bucket grid.
    let mut ivs: Vec<(f64, f64, u32)> = vec![(s0, s1, s)];
    const REACH: f64 = 400.0;
    const STEP: f64 = 25.0;
    let steps = (REACH / STEP) as i64;
    let mut seen: Vec<u32> = vec![s];
    for k in -steps..steps {
        let p = o + d * (k as f64 * STEP);
        let q = o + d * ((k + 1) as f64 * STEP);
        set.each_in_box(p.min(q), p.max(q), |id| {
            if !seen.contains(&id) {
                seen.push(id);
                if usable.binary_search(&id).is_ok() {
                    if let Some((a, b)) = clip(&set.polys[id as usize], o, d) {
                        ivs.push((a, b, id));
                    }
                }
            }
        });
    }
    ivs.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.2.cmp(&y.2)));
    // Grow [lo, hi] from the start's interval over touching intervals, both ways.
    let (mut lo, mut hi) = (s0, s1);
    let mut chain = vec![s];
    loop {
        let mut grew = false;
        for &(a, b, id) in &ivs {
            if a <= hi + JOIN_M && b >= lo - JOIN_M && (a < lo || b > hi) {
                lo = lo.min(a);
                hi = hi.max(b);
                if !chain.contains(&id) {
                    chain.push(id);
                }
                grew = true;
            }
        }
        if !grew {
            break;
        }
    }
    if hi - lo < MIN_SPINE_M + 2.0 * SHRINK_M {
        return None;
    }
    chain.sort_unstable();
    Some(Spine {
        a: o + d * (lo + SHRINK_M),
        b: o + d * (hi - SHRINK_M),
        chain,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<DVec2> {
        vec![
            DVec2::new(x0, y0),
            DVec2::new(x1, y0),
            DVec2::new(x1, y1),
            DVec2::new(x0, y1),
        ]
    }

    #[test]
    fn a_row_of_touching_blocks_gives_one_spine_across_it_and_a_gap_ends_it() {
        // Three touching blocks, then a 2 m gap, then a fourth; the cell is below at y < 0.
        let polys = vec![
            square(0.0, 50.0, 20.0, 70.0),
            square(20.0, 50.0, 45.0, 70.0),
            square(45.0, 50.0, 60.0, 70.0),
            square(62.0, 50.0, 90.0, 70.0),
        ];
        let set = BlockerSet::new(polys, vec![10.0; 4]);
        let usable = [0, 1, 2, 3];
        let sp = spines(&set, &usable, DVec2::new(32.5, -50.0), &[1]);
        let across = sp
            .iter()
            .find(|s| (s.a.y - s.b.y).abs() < 1e-9)
            .expect("a spine across the view");
        let (lo, hi) = (across.a.x.min(across.b.x), across.a.x.max(across.b.x));
        assert!((lo - SHRINK_M).abs() < 1e-9 && (hi - (60.0 - SHRINK_M)).abs() < 1e-9);
        assert_eq!(across.chain, vec![0, 1, 2]);
    }
}
