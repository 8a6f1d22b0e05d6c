//! The sweep along a verified segment: exact dyadic points `a + j / 2^30 (b - a)`, a certificate
//! read off at each point (cached or new, or the blocker the point lies in) and extended as far
//! as it holds, the end found by an estimate checked exactly and a binary search; past points it
//! cannot certify, steps that double up to the verifier's longest, then a bisection back to
//! where the hidden part begins.
//!
//! Input: the verifier (cell, blockers, cache) and a segment `[a, b]`. Output: its certified
//! hidden pieces, merged where they touch, each with the blockers its certificates use.
//!
//! Invariant: a piece is reported only when a certificate was checked exactly at both its ends
//! (Lemma 2), or when it lies in one blocker or in two that share a segment it crosses; what is
//! stepped over counts as visible, so the output can only be smaller than the hidden set.

use glam::DVec2;

use super::certificate::{conditions, exact_midpoint, reach, Cond, Link};
use super::index::NearCache;
use super::{Hidden, Verifier, CACHE_ENOUGH_M, END, NEAR_AHEAD_M, PARAM_BITS, PROBE_M};
use crate::geom::predicates::{
    point_in_convex, segment_intersection, Containment, SegmentIntersection,
};

/// Parameters `j / 2^PARAM_BITS` along one segment, turned into exact points of it.
pub(super) struct Param {
    pub(super) a: DVec2,
    pub(super) b: DVec2,
    pub(super) d: DVec2,
}

impl Param {
    /// The point at parameter `j`, when `a + (j / 2^PARAM_BITS) (b - a)` is exact.
    pub(super) fn at(&self, j: u64) -> Option<DVec2> {
        if j == 0 {
            return Some(self.a);
        }
        if j >= END {
            return Some(self.b);
        }
        let t = j as f64 / END as f64;
        let exact = |a: f64, d: f64| -> Option<f64> {
            let u = d * t;
            // The product is exact when its fused error is zero, the sum by TwoSum.
            if d.mul_add(t, -u) != 0.0 {
                return None;
            }
            let s = a + u;
            let bb = s - a;
            let err = (a - (s - bb)) + (u - bb);
            (err == 0.0 && s.is_finite()).then_some(s)
        };
        Some(DVec2::new(
            exact(self.a.x, self.d.x)?,
            exact(self.a.y, self.d.y)?,
        ))
    }

    /// The exact point at `j` or, failing that, at the nearest coarser parameter in `(lo, j]`
    /// (fewer low bits); `None` when there is none.
    pub(super) fn at_or_below(&self, j: u64, lo: u64) -> Option<(u64, DVec2)> {
        let mut k = j;
        let mut bit = 0;
        while k > lo {
            if let Some(p) = self.at(k) {
                return Some((k, p));
            }
            bit += 1;
            if bit > PARAM_BITS {
                return None;
            }
            k = (j >> bit) << bit;
        }
        None
    }
}

impl<'a> Verifier<'a> {
    /// The certified pieces, each with the blockers its certificates use.
    pub(super) fn sweep(&self, a: DVec2, b: DVec2, stop_at_gap: bool) -> Vec<(Hidden, Vec<u32>)> {
        let mut out: Vec<(Hidden, Vec<u32>)> = Vec::new();
        let len = a.distance(b);
        if !(len > 0.0 && len.is_finite()) {
            return out;
        }
        let par = Param { a, b, d: b - a };
        let steps = |m: f64| ((m / len * END as f64) as u64).clamp(1, END);
        let (min_step, probe) = (steps(self.min_step_m), steps(PROBE_M));
        let max_step = steps(self.max_step_m);
        let mut j = 0u64;
        let mut gap = min_step;
        let mut cache = NearCache {
            span: (1, 0),
            ahead: steps(NEAR_AHEAD_M),
            ids: Vec::new(),
            polys: Vec::new(),
            boxes: Vec::new(),
            along: Vec::new(),
            keyed: Vec::new(),
        };
        // The last point that could not be certified, after which the sweep stepped on.
        let mut failed: Option<u64> = None;
        while j < END {
            let Some(mut q) = par.at(j) else { break };
            let mut found = self.piece_from(&par, (j, q), probe, &mut cache);
            // Stepping on doubles the step, so the first certified point may lie far past the
            // start of the hidden part: bisect back towards the last failure, down to the
            // least step.
            if let (true, Some(mut lo)) = (found.is_some(), failed) {
                while j - lo > min_step {
                    let Some((mid, qm)) = par.at_or_below(lo + (j - lo) / 2, lo) else {
                        break;
                    };
                    match self.piece_from(&par, (mid, qm), probe, &mut cache) {
                        Some(r) => (j, q, found) = (mid, qm, Some(r)),
                        None => lo = mid,
                    }
                }
            }
            failed = None;
            match found {
                Some((e, pe, used)) => {
                    match out.last_mut() {
                        Some((h, all)) if h.p1 == q => {
                            h.t1 = e as f64 / END as f64;
                            h.p1 = pe;
                            all.extend_from_slice(&used);
                        }
                        _ => out.push((
                            Hidden {
                                t0: j as f64 / END as f64,
                                t1: e as f64 / END as f64,
                                p0: q,
                                p1: pe,
                            },
                            used.to_vec(),
                        )),
                    }
                    j = e;
                    gap = min_step;
                }
                None => {
                    if stop_at_gap {
                        break;
                    }
                    // The last probe ahead of `b` is tried too, however long the step.
                    let last = END.saturating_sub(probe);
                    if j >= last {
                        break;
                    }
                    // The next exact point at least a step on (far from the origin, exact
                    // points of a long segment can be sparse: step further until one is found).
                    let mut step = gap;
                    let next = loop {
                        let target = j.saturating_add(step).min(last);
                        if let Some((k, _)) = par.at_or_below(target, j) {
                            break Some(k);
                        }
                        if target == last {
                            break None;
                        }
                        step = step.saturating_mul(2);
                    };
                    let Some(k) = next else { break };
                    failed = Some(j);
                    j = k;
                    gap = gap.saturating_mul(2).min(max_step);
                }
            }
        }
        for (_, used) in &mut out {
            used.sort_unstable();
            used.dedup();
        }
        out
    }

    /// The longest certified piece `[j, e]` the sweep finds from the point `q` at parameter
    /// `j`: its end parameter and point, and the blockers its certificate uses.
    pub(super) fn piece_from(
        &self,
        par: &Param,
        (j, q): (u64, DVec2),
        probe: u64,
        cache: &mut NearCache<'a>,
    ) -> Option<(u64, DVec2, std::rc::Rc<[u32]>)> {
        // The probe point: the next exact point at least `probe` on (further when exact points
        // are sparse, far from the origin).
        let mut step = probe.max(1);
        let (k, p) = loop {
            let target = j.saturating_add(step).min(END);
            if let Some(x) = par.at_or_below(target, j) {
                break x;
            }
            if target == END {
                return None;
            }
            step = step.saturating_mul(2);
        };
        self.extend(par, (j, q), (k, p), cache)
    }

    /// Given the piece `[q, p]` (parameters `j < k`), a certificate for it, extended as far
    /// along the segment as it holds: the end parameter and point.
    pub(super) fn extend(
        &self,
        par: &Param,
        (j, q): (u64, DVec2),
        (k, p): (u64, DVec2),
        cache: &mut NearCache<'a>,
    ) -> Option<(u64, DVec2, std::rc::Rc<[u32]>)> {
        // A certificate found before that holds here (it proves the piece as well as a new one).
        let remaining = q.distance(par.b);
        let cached = self.cache.borrow().find(q, p, par.b);
        // A cached certificate that reaches only a little way: a new one may reach further.
        let cached = cached.filter(|(_, t)| t * remaining >= CACHE_ENOUGH_M);
        // The certificate's conditions: a cached one's copied into a buffer reused from call to
        // call, a new one's as found.
        let mut conds_buf = self.conds.borrow_mut();
        conds_buf.clear();
        let (used, fresh): (std::rc::Rc<[u32]>, bool) = match cached {
            Some((id, _)) => {
                let c = self.cache.borrow();
                conds_buf.extend_from_slice(c.conds_of(id));
                (c.certs[id as usize].2.clone(), false)
            }
            None => {
                let (ids, near, boxes, along) = self.near_cached(par, j, k, cache);
                // Inside one blocker: the piece up to where the segment leaves it.
                let inside = |b: &[DVec2], x| point_in_convex(b, x) != Containment::Outside;
                // The blockers holding q, and (when there are any) those holding p, in the
                // stretch's order (its boxes and polygons lie in that order too).
                let holding = |x: DVec2| -> Vec<u32> {
                    let mut out = Vec::new();
                    for &k in along {
                        let k = k as usize;
                        let (lo, hi) = boxes[k];
                        let in_box = lo.x <= x.x && x.x <= hi.x && lo.y <= x.y && x.y <= hi.y;
                        if in_box && inside(near[k], x) {
                            out.push(ids[k]);
                        }
                    }
                    out
                };
                let at_q = holding(q);
                let at_p = if at_q.is_empty() {
                    Vec::new()
                } else {
                    holding(p)
                };
                if let Some(&i) = at_q.iter().find(|i| at_p.contains(i)) {
                    let blk = self.poly(i);
                    if blk.len() < 3 {
                        let exit = exit_param(blk, par, j);
                        let (e, pe) = self.furthest(par, k, p, exit, &|x| inside(blk, x));
                        return Some((e, pe, [i].into()));
                    }
                    // A polygon is a certificate by itself: on no edge's outer side.
                    let n = blk.len();
                    let conds = (0..n)
                        .map(|e| Cond {
                            u: blk[e],
                            v: blk[(e + 1) % n],
                            strict: false,
                        })
                        .collect::<Vec<Cond>>();
                    *conds_buf = conds;
                    ([i].into(), true)
                } else if let Some((i, j)) = self.across_two(&at_q, &at_p, q, p) {
                    // From one blocker into one it meets: the piece is covered, and the sweep
                    // goes on from p (inside the second).
                    return Some((k, p, [i.min(j), i.max(j)].into()));
                } else {
                    // Leaving a blocker, the chords are read from `p`, beyond its edge.
                    let leaving = !at_q.is_empty();
                    let anchor = if leaving {
                        p
                    } else {
                        exact_midpoint(q, p).unwrap_or(q)
                    };
                    let pts = [anchor, q, p];
                    let valid = |links: &[Link]| {
                        let conds = conditions(links, self.cell);
                        let holds = |x: DVec2| conds.iter().all(|c| c.holds(x));
                        if !(holds(anchor) && holds(p)) {
                            return None;
                        }
                        if holds(q) {
                            return Some(conds);
                        }
                        // Leaving a blocker: `q` inside a link's blocker, `[q, anchor]`
                        // crossing that link's chord, every other condition holding at `q`
                        // (module header, "Leaving a blocker").
                        let bridge = links.iter().find(|k| {
                            inside(near[k.poly], q)
                                && segment_intersection(q, anchor, k.l, k.r)
                                    != SegmentIntersection::Disjoint
                        })?;
                        conds
                            .iter()
                            .all(|c| (c.strict && c.u == bridge.l && c.v == bridge.r) || c.holds(q))
                            .then_some(conds)
                    };
                    // Chords read at the anchor first; near an umbra boundary, from all three
                    // points.
                    let with_used = |links: &[Link]| {
                        let c = valid(links)?;
                        let mut used: Vec<u32> = links.iter().map(|k| ids[k.poly]).collect();
                        used.sort_unstable();
                        used.dedup();
                        Some((c, used))
                    };
                    let search = |near: &[&[DVec2]]| -> Option<(Vec<Cond>, Vec<u32>)> {
                        let first = self.chain(near, boxes, &pts, false)?;
                        match with_used(&first) {
                            Some(c) => Some(c),
                            None => with_used(&self.chain(near, boxes, &pts, true)?),
                        }
                    };
                    // The blockers nearest the point first (the stretch's order, by distance
                    // from its start): they subtend the widest angles, and a few of them often
                    // cover the cell.
                    let (conds, used) = search(near)?;
                    *conds_buf = conds;
                    (used.into(), true)
                }
            }
        };
        // Where the first condition stops holding, estimated from its affine values at q and b.
        let conds: &[Cond] = &conds_buf;
        let t = reach(conds, q, par.b);
        let est = j + ((END - j) as f64 * t) as u64;
        let (e, pe) = self.furthest(par, k, p, est, &|x| conds.iter().all(|c| c.holds(x)));
        if fresh {
            self.cache.borrow_mut().add(conds, used.clone(), q, pe);
        }
        Some((e, pe, used))
    }

    /// The two blockers whose union holds `[q, p]`, if any: `q` in one of `at_q`, `p` in another
    /// of `at_p` (the blockers holding each), and the
    /// segment crosses a segment `[u, v]` between two vertices that both blockers contain (the
    /// shared edge of two pieces of one footprint, or where two blockers overlap). *Proof.* The
    /// crossing `x` lies in `[u, v]`, which lies in both blockers (convex, closed); so `[q, x]`
    /// lies in the first and `[x, p]` in the second, and every point of `[q, p]` is in a
    /// blocker, hence hidden (touching counts). All tests are exact.
    pub(super) fn across_two(
        &self,
        at_q: &[u32],
        at_p: &[u32],
        q: DVec2,
        p: DVec2,
    ) -> Option<(u32, u32)> {
        let inside = |b: &[DVec2], x| point_in_convex(b, x) != Containment::Outside;
        for &i in at_q {
            for &j in at_p {
                if i == j {
                    continue;
                }
                let (bi, bj) = (self.poly(i), self.poly(j));
                let both: Vec<DVec2> = bi
                    .iter()
                    .chain(bj)
                    .copied()
                    .filter(|&v| inside(bi, v) && inside(bj, v))
                    .collect();
                for (n, &u) in both.iter().enumerate() {
                    for &v in &both[n..] {
                        if segment_intersection(q, p, u, v) != SegmentIntersection::Disjoint {
                            return Some((i, j));
                        }
                    }
                }
            }
        }
        None
    }

    /// The largest exact parameter in `[k, est]` whose point passes `ok`, by checking `est` and
    /// then searching back towards `k` (whose point `p` passed).
    pub(super) fn furthest(
        &self,
        par: &Param,
        k: u64,
        p: DVec2,
        est: u64,
        ok: &dyn Fn(DVec2) -> bool,
    ) -> (u64, DVec2) {
        let (mut good, mut gp) = (k, p);
        let mut bad = est.min(END) + 1;
        if est > k {
            if let Some((e, pe)) = par.at_or_below(est.min(END), k) {
                if ok(pe) {
                    return (e, pe);
                }
                bad = e;
            }
        }
        // Binary search between a passing and a failing parameter.
        while bad > good + 1 {
            let mid = good + (bad - good) / 2;
            match par.at_or_below(mid, good) {
                Some((m, pm)) if ok(pm) => {
                    good = m;
                    gp = pm;
                }
                Some((m, _)) => bad = m,
                None => break,
            }
        }
        (good, gp)
    }
}

/// The parameter (along `par`, from `j`) where the segment leaves the convex `blk`, estimated
/// in floating point (the caller checks the point it gets exactly).
pub(super) fn exit_param(blk: &[DVec2], par: &Param, j: u64) -> u64 {
    let t0 = j as f64 / END as f64;
    let mut t1 = 1.0f64;
    let n = blk.len();
    for i in 0..n {
        let (u, v) = (blk[i], blk[(i + 1) % n]);
        let w = v - u;
        // Inside is left of u -> v: w x (x - u) >= 0 along x = a + t d.
        let f0 = w.perp_dot(par.a - u);
        let fd = w.perp_dot(par.d);
        if fd < 0.0 {
            t1 = t1.min(-f0 / fd);
        }
    }
    let t = t1.max(t0);
    ((t * END as f64) as u64).min(END)
}

#[cfg(test)]
mod tests {
    use super::super::oracle::{brute_hidden, rect, v};
    use super::super::tests::slices;
    use super::super::MAX_STEP_M;
    use super::*;
    use crate::testutil::Lcg;

    #[test]
    fn parameters_give_exact_points_of_the_segment_or_none() {
        let mut g = Lcg(43);
        for _ in 0..2000 {
            // Integer ends: the exact point at j is (a 2^30 + j d) / 2^30, in integers.
            let a = v(g.range(-1e5, 1e5).round(), g.range(-1e5, 1e5).round());
            let b = v(g.range(-1e5, 1e5).round(), g.range(-1e5, 1e5).round());
            let par = Param { a, b, d: b - a };
            let j = g.next_u64() % (END + 1);
            let want = |a: f64, d: f64| a as i128 * END as i128 + j as i128 * d as i128;
            if let Some(p) = par.at(j) {
                // p * 2^30 is an integer here (a dyadic of at most 30 bits after the point).
                assert_eq!(
                    (p.x * END as f64) as i128,
                    want(a.x, b.x - a.x),
                    "{a} {b} {j}"
                );
                assert_eq!(
                    (p.y * END as f64) as i128,
                    want(a.y, b.y - a.y),
                    "{a} {b} {j}"
                );
            }
            let lo = j / 2;
            if let Some((k, p)) = par.at_or_below(j, lo) {
                assert!(lo < k && k <= j);
                assert_eq!(par.at(k), Some(p));
            }
        }
        let par = Param {
            a: v(0.0, 0.0),
            b: v(3.0, 1.0),
            d: v(3.0, 1.0),
        };
        assert_eq!(par.at(0), Some(par.a));
        assert_eq!(par.at(END), Some(par.b));
        assert_eq!(par.at(END / 2), Some(v(1.5, 0.5)));
    }

    /// Against the oracle on single blockers, where the hidden part of a segment is one
    /// interval: what is certified is hidden, and misses at most a step at each end of it.
    #[test]
    fn the_sweep_finds_the_hidden_interval_of_one_blocker() {
        let mut g = Lcg(47);
        let cell = rect(0.0, 0.0, 16.0, 16.0);
        let mut seen = 0;
        for _ in 0..60 {
            let (x, y) = (g.range(-30.0, 30.0).floor(), g.range(20.0, 40.0).floor());
            let blk = vec![rect(x, y, x + g.range(8.0, 60.0).floor(), y + 2.0)];
            let (a, b) = (v(-120.0, 70.0), v(140.0, 70.0));
            let ver = Verifier::new(&cell, slices(&blk));
            let parts = ver.hidden_parts(a, b);
            assert!(parts.len() <= 1, "{parts:?}");
            // The oracle's hidden interval, on a 1/16 m raster.
            let n = 260 * 16;
            let hid: Vec<f64> = (0..=n)
                .map(|k| k as f64 / n as f64)
                .filter(|&t| brute_hidden(&cell, &blk, a + (b - a) * t, 200))
                .collect();
            let len = b.distance(a);
            match (parts.first(), hid.first(), hid.last()) {
                (None, None, _) => {}
                (Some(h), Some(&t0), Some(&t1)) => {
                    seen += 1;
                    for k in 0..=32 {
                        let q = h.p0 + (h.p1 - h.p0) * (k as f64 / 32.0);
                        assert!(brute_hidden(&cell, &blk, q, 400), "{q:?} of {h:?}");
                    }
                    let slack = MAX_STEP_M + 2.0 / 16.0;
                    assert!((h.t0 - t0) * len <= slack, "{h:?} from {t0}");
                    assert!((t1 - h.t1) * len <= slack, "{h:?} to {t1}");
                }
                // A sliver of umbra shorter than a step may be missed, never claimed.
                (None, Some(&t0), Some(&t1)) if (t1 - t0) * len <= 2.0 * MAX_STEP_M => {}
                (got, _, _) => panic!("certified {got:?}, the oracle hides {hid:?}"),
            }
        }
        assert!(seen > 20, "{seen}");
    }

    #[test]
    fn the_exit_from_a_blocker_is_on_its_boundary() {
        let blk = rect(0.0, 0.0, 10.0, 4.0);
        let par = Param {
            a: v(2.0, 1.0),
            b: v(42.0, 11.0),
            d: v(40.0, 10.0),
        };
        // The segment leaves through x = 10 at t = 0.2.
        let e = exit_param(&blk, &par, 0);
        assert!((e as f64 / END as f64 - 0.2).abs() < 1e-9);
        // Starting beyond the exit: no earlier than the start.
        assert_eq!(exit_param(&blk, &par, END / 2), END / 2);
    }

    #[test]
    fn furthest_finds_the_last_point_that_passes() {
        let ver = Verifier::new(&[], std::iter::empty());
        let par = Param {
            a: v(0.0, 0.0),
            b: v(64.0, 0.0),
            d: v(64.0, 0.0),
        };
        let ok = |p: DVec2| p.x <= 21.0;
        for est in [END / 8, END / 3, END / 2, END] {
            let (e, p) = ver.furthest(&par, 1, par.at(1).unwrap(), est, &ok);
            assert!(ok(p) && par.at(e) == Some(p));
            if est >= END / 3 {
                // 21 m is at parameter 21 / 64, exact.
                assert_eq!(p.x, 21.0, "from {est}");
            } else {
                assert_eq!(e, est);
            }
        }
    }
}
