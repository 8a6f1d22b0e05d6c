//! The search for a certificate at a point: the chords of the blockers near it read nearest
//! first until their floating-point angular spans seem to cover the cell, then a chain of them
//! covering the cell's angle (greedy, breadth-first when the greedy is stuck), joined through
//! overlapping arcs or a point two blockers share, with the separating line of each link.
//!
//! Input: the blockers near a piece (in the stretch's order), their boxes, and three points
//! (the anchor, the piece's start and its probe). Output: the links of a chain, which the caller
//! checks with the exact conditions of [`super::certificate`].
//!
//! Invariant: floating point ([`guess`]) only chooses what is tried; a chain is offered, never
//! trusted: the sweep checks every condition exactly before using it.

use glam::DVec2;

use super::certificate::{separating_line, Link, SepLine};
use super::Verifier;
use crate::geom::predicates::{
    orient, point_in_convex, tangent_vertices, Containment, Orientation,
};
use crate::geom::pseudo_angle;

/// A new certificate is first sought among this many blockers nearest the point.
pub const NEAREST_FIRST: usize = 12;

impl<'a> Verifier<'a> {
    /// A chain of blocker chords whose conditions (S), (A), (O) and (C) hold at every point of
    /// `pts`: the chords seen from `pts[0]` are read nearest blocker first until their
    /// floating-point spans cover the cell's angle, then [`Self::cover`] picks a chain among
    /// them and checks every condition exactly. Floating point only chooses what is tried.
    pub(super) fn chain(
        &self,
        near: &[&[DVec2]],
        boxes: &[(DVec2, DVec2)],
        pts: &[DVec2; 3],
        multi: bool,
    ) -> Option<Vec<Link>> {
        use Orientation::*;
        let q = pts[0];
        let (cl, cr) = guess_tangents(q, self.cell)?;
        let (cl, cr) = (self.cell[cl], self.cell[cr]);
        // Directions from q as pseudo-angles unwrapped about the cell's middle direction: the
        // cell spans [ucl, ucr]. Only to decide when enough blockers have been read (the cover
        // is then sought and checked exactly).
        let mid = pseudo_angle((cl + cr) * 0.5 - q);
        let u = |x: DVec2| {
            let d = pseudo_angle(x - q) - mid;
            if d > 2.0 {
                d - 4.0
            } else if d < -2.0 {
                d + 4.0
            } else {
                d
            }
        };
        let (ucl, ucr) = (u(cl), u(cr));
        // Whether the spans read so far cover the cell's angle ([`Sweep`]).
        let mut scratch = self.scratch.borrow_mut();
        let ChainScratch {
            seps,
            arcs,
            usable,
            beyond,
        } = &mut *scratch;
        let mut sweep = Sweep::new(ucl, ucr, beyond);
        seps.clear();
        seps.resize(near.len(), None);
        arcs.clear();
        let mut next = 8usize;
        for (poly, b) in near.iter().enumerate() {
            if let Some((l, r)) = guess_tangents(q, b) {
                // Only arcs that meet the cell's angle from q can be links (a cheap filter
                // before the separating line; the conditions decide).
                if guess(q, cl, b[r]) != Cw && guess(q, b[l], cr) != Cw {
                    sweep.add(u(b[l]).max(ucl), u(b[r]).min(ucr));
                    // Chords from the extreme vertices seen from each test point: near an
                    // umbra boundary, nearly collinear vertices trade places within
                    // millimetres.
                    // (At most one per test point, in a fixed array: this runs for every
                    // blocker read.)
                    let (mut ls, mut nl) = ([b[l]; 3], 1);
                    let (mut rs, mut nr) = ([b[r]; 3], 1);
                    for &p in &pts[1..(if multi { 3 } else { 1 })] {
                        if let Some((l, r)) = guess_tangents(p, b) {
                            if !ls[..nl].contains(&b[l]) {
                                ls[nl] = b[l];
                                nl += 1;
                            }
                            if !rs[..nr].contains(&b[r]) {
                                rs[nr] = b[r];
                                nr += 1;
                            }
                        }
                    }
                    for &l in &ls[..nl] {
                        for &r in &rs[..nr] {
                            // Where the piece leaves this blocker, its chord is not seen
                            // from the start inside it ("Leaving a blocker").
                            let seen = |x: DVec2| {
                                guess(x, l, r) == Ccw
                                    || (x == pts[1]
                                        && point_in_convex(b, x) != Containment::Outside)
                            };
                            if pts.iter().all(|&x| seen(x)) {
                                // The separating line comes later, only for arcs the cover
                                // picks.
                                let sep = SepLine {
                                    a: l,
                                    b: r,
                                    side: Ccw,
                                };
                                arcs.push(Link { l, r, sep, poly });
                            }
                        }
                    }
                }
            }
            // Blockers come nearest first: the cover is sought once the arcs read so far seem
            // to cover the cell's angle, and again after each doubling. Not after the last
            // blocker when they still seem not to: the cover reads the same arcs from `q`, so
            // it could succeed there only where the two floating-point readings disagree at a
            // rounding-sized gap, and trying cost 5% of the bake's instructions for nothing
            // (the stores of every bundled scene and of a generated city came out the same).
            // Skipping a search can only certify less, never more.
            let last = poly + 1 == near.len();
            if poly + 1 >= next || last {
                next *= 2;
                if sweep.covers() && !arcs.is_empty() {
                    if let Some(path) = self.cover(near, boxes, pts, arcs, seps, usable) {
                        return Some(path);
                    }
                }
            }
        }
        None
    }

    /// A cover of the cell's angle by `arcs` (module header), greedy first, breadth-first when
    /// the greedy gets stuck, with their separating lines (`seps`, per blocker, found when first
    /// needed).
    pub(super) fn cover(
        &self,
        near: &[&[DVec2]],
        boxes: &[(DVec2, DVec2)],
        pts: &[DVec2; 3],
        arcs: &mut [Link],
        seps: &mut [Option<Option<SepLine>>],
        usable: &mut Vec<bool>,
    ) -> Option<Vec<Link>> {
        use Orientation::*;
        let q = pts[0];
        // (Each test below is spelled out over `pts`, not passed as a `dyn Fn`: they run for
        // every pair of arcs the search weighs, and inline this way.)
        let mut sep_of = |poly: usize| -> Option<SepLine> {
            *seps[poly].get_or_insert_with(|| separating_line(near[poly], self.cell, pts))
        };
        let starts = |k: &Link| {
            pts.iter()
                .all(|&p| self.cell.iter().all(|&c| guess(p, k.l, c) != Cw))
        };
        let ends = |k: &Link| {
            pts.iter()
                .all(|&p| self.cell.iter().all(|&c| guess(p, c, k.r) != Cw))
        };
        let overlaps = |a: &Link, b: &Link| {
            pts.iter()
                .all(|&p| guess(p, b.l, a.r) != Cw && guess(p, a.r, b.r) != Cw)
        };
        // Blockers that share a point `v` (a common vertex, or a vertex of one inside the
        // other) join through it: the chords `[a.l, v]` and `[v, b.r]` lie in their blockers
        // (convexity), are valid by (A), and make (O) hold trivially. Adjacent convex pieces of one footprint, and
        // buildings that share a wall, meet like this; across the line of a shared edge the
        // extreme vertices swap, and only such a join certifies both sides at once.
        // Blockers whose boxes are apart share no point: a cheap test, kept apart so that it
        // inlines where most pairs end.
        let boxes_meet = |a: &Link, b: &Link| {
            let ((al, ah), (bl, bh)) = (boxes[a.poly], boxes[b.poly]);
            !(al.x > bh.x || bl.x > ah.x || al.y > bh.y || bl.y > ah.y)
        };
        let shared = |a: &Link, b: &Link| -> Option<DVec2> {
            if !boxes_meet(a, b) {
                return None;
            }
            let (pa, pb) = (near[a.poly], near[b.poly]);
            let in_both = |v: &DVec2| {
                point_in_convex(pa, *v) != Containment::Outside
                    && point_in_convex(pb, *v) != Containment::Outside
            };
            pa.iter().chain(pb.iter()).copied().find(|v| {
                in_both(v)
                    && pts
                        .iter()
                        .all(|&p| orient(p, a.l, *v) == Ccw && orient(p, *v, b.r) == Ccw)
            })
        };
        let joins =
            |a: &Link, b: &Link| overlaps(a, b) || (boxes_meet(a, b) && shared(a, b).is_some());
        // Greedy cover, as for intervals on a line: from the start arc reaching furthest
        // counter-clockwise (seen from the anchor), repeatedly the joining arc that reaches
        // furthest, while it advances.
        let further = |x: &Link, y: &Link| guess(q, y.r, x.r) == Ccw;
        usable.clear();
        usable.resize(arcs.len(), true);
        let mut path: Vec<Link> = Vec::with_capacity(8);
        let greedy = loop {
            let prev = path.last().copied();
            let mut best: Option<usize> = None;
            for (j, b) in arcs.iter().enumerate() {
                if !usable[j] || best.is_some_and(|k| !further(b, &arcs[k])) {
                    continue;
                }
                let ok = match &prev {
                    None => starts(b),
                    Some(c) => further(b, c) && joins(c, b),
                };
                if ok {
                    best = Some(j);
                }
            }
            let Some(k) = best else {
                break false;
            };
            match sep_of(arcs[k].poly) {
                Some(sep) => {
                    arcs[k].sep = sep;
                    path.push(arcs[k]);
                    if ends(&arcs[k]) {
                        break true;
                    }
                    if path.len() > arcs.len() {
                        break false;
                    }
                }
                None => usable[k] = false,
            }
        };
        if !greedy {
            // The greedy can take an arc that joins nothing further (joins through a shared
            // point do not order like intervals): a breadth-first search over the same arcs
            // finds a chain whenever their joins (as the floating-point guesses see them) hold
            // one, so adding blockers to the set cannot hide a chain from it.
            let n = arcs.len();
            let mut from = vec![usize::MAX; n];
            let mut seen = vec![false; n];
            let mut queue = std::collections::VecDeque::new();
            for j in 0..n {
                if starts(&arcs[j]) {
                    if let Some(sep) = sep_of(arcs[j].poly) {
                        arcs[j].sep = sep;
                        seen[j] = true;
                        queue.push_back(j);
                    }
                }
            }
            let mut end = None;
            while let Some(k) = queue.pop_front() {
                if ends(&arcs[k]) {
                    end = Some(k);
                    break;
                }
                for j in 0..n {
                    if seen[j] || !further(&arcs[j], &arcs[k]) || !joins(&arcs[k], &arcs[j]) {
                        continue;
                    }
                    if let Some(sep) = sep_of(arcs[j].poly) {
                        arcs[j].sep = sep;
                        seen[j] = true;
                        from[j] = k;
                        queue.push_back(j);
                    }
                }
            }
            let mut k = end?;
            path.clear();
            loop {
                path.push(arcs[k]);
                if from[k] == usize::MAX {
                    break;
                }
                k = from[k];
            }
            path.reverse();
        }
        {
            {
                for k in 0..path.len() - 1 {
                    if !overlaps(&path[k], &path[k + 1]) {
                        if let Some(v) = shared(&path[k], &path[k + 1]) {
                            path[k].r = v;
                            path[k + 1].l = v;
                        }
                    }
                }
            }
        }
        Some(path)
    }
}

/// The buffers [`Verifier::chain`] reuses between calls: the separating lines found per blocker,
/// the arcs read, the cover's usable flags and the sweep's spans beyond its reach.
#[derive(Default)]
pub(super) struct ChainScratch {
    pub(super) seps: Vec<Option<Option<SepLine>>>,
    pub(super) arcs: Vec<Link>,
    pub(super) usable: Vec<bool>,
    pub(super) beyond: Vec<(f64, f64)>,
}

/// The sweep of the chain search's angular spans (floating point, to decide when enough
/// blockers have been read): the spans sorted by their starts and swept from `from`, each span
/// that starts at or before the reach so far extending it, the answer true as soon as the reach
/// is at least `to` and false at the first gap. When `from < to` that is whether the least point
/// from `from` on that no span starting at or before it passes is at least `to`, whatever order
/// the spans come in, so it is kept up to date as spans are read, with no sort: `reach`, and
/// the spans that start beyond it, taken in when the reach passes their start. (When
/// `from >= to`, the sorted sweep answers at its first span: true when there is none or when
/// one starts at or before `from`.)
pub(super) struct Sweep<'s> {
    pub(super) from: f64,
    pub(super) to: f64,
    pub(super) reach: f64,
    /// Some span read so far starts at or before `from`.
    pub(super) at_from: bool,
    /// No span read so far.
    pub(super) empty: bool,
    pub(super) beyond: &'s mut Vec<(f64, f64)>,
}

impl<'s> Sweep<'s> {
    /// The sweep from `from` to `to`, with `beyond` as its buffer (cleared).
    pub(super) fn new(from: f64, to: f64, beyond: &'s mut Vec<(f64, f64)>) -> Self {
        beyond.clear();
        Sweep {
            from,
            to,
            reach: from,
            at_from: false,
            empty: true,
            beyond,
        }
    }

    /// Whether the spans read so far cover `[from, to]` (the sorted sweep's answer).
    pub(super) fn covers(&self) -> bool {
        if self.from < self.to {
            self.reach >= self.to
        } else {
            self.empty || self.at_from
        }
    }

    /// Adds the span `[a, b]`.
    pub(super) fn add(&mut self, a: f64, b: f64) {
        self.empty = false;
        self.at_from |= !(a > self.from);
        if a > self.reach {
            self.beyond.push((a, b));
            return;
        }
        if !(b > self.reach) {
            return;
        }
        self.reach = b;
        loop {
            let before = self.reach;
            let reach = &mut self.reach;
            self.beyond.retain(|&(a, b)| {
                if a > *reach {
                    return true;
                }
                if b > *reach {
                    *reach = b;
                }
                false
            });
            if !(self.reach > before) {
                break;
            }
        }
    }
}

/// Orientation in plain floating point. The search uses it only to choose candidates (tangent
/// vertices, which arcs join, which reaches furthest); every condition of a certificate is then
/// checked with the exact [`orient`], so a wrong guess can only lose a certificate.
#[inline]
pub(super) fn guess(a: DVec2, b: DVec2, c: DVec2) -> Orientation {
    sign((b - a).perp_dot(c - a))
}

/// The orientation a floating-point determinant `d` stands for (NaN: collinear).
#[inline]
pub(super) fn sign(d: f64) -> Orientation {
    if d > 0.0 {
        Orientation::Ccw
    } else if d < 0.0 {
        Orientation::Cw
    } else {
        Orientation::Collinear
    }
}

/// [`tangent_vertices`] with [`guess`]: the extreme vertices of `poly` seen from `q`, or `None`
/// when `q` seems to be inside or on it.
///
/// This runs for every blocker the search reads, so it computes each `poly[i] - q` once:
/// `guess(q, poly[l], poly[i])` is `(poly[l] - q).perp_dot(poly[i] - q)`, the same operations
/// on the same values, so the same bits and the same answers.
pub(super) fn guess_tangents(q: DVec2, poly: &[DVec2]) -> Option<(usize, usize)> {
    let n = poly.len();
    if n >= 3 {
        // Inside or on: no edge has q strictly on its outer (right) side.
        let mut prev = poly[n - 1];
        let mut outside = false;
        for &v in poly {
            if guess(prev, v, q) == Orientation::Cw {
                outside = true;
                break;
            }
            prev = v;
        }
        if !outside {
            return None;
        }
    }
    if n == 2 && guess(poly[0], poly[1], q) == Orientation::Collinear {
        return tangent_vertices(q, poly);
    }
    let Some(&first) = poly.first() else {
        return Some((0, 0));
    };
    let d0 = first - q;
    let (mut l, mut r) = (0, 0);
    let (mut dl, mut dr) = (d0, d0);
    for (i, &v) in poly.iter().enumerate().skip(1) {
        let di = v - q;
        match sign(dl.perp_dot(di)) {
            Orientation::Cw => (l, dl) = (i, di),
            Orientation::Collinear if di.length_squared() < dl.length_squared() => {
                (l, dl) = (i, di)
            }
            _ => {}
        }
        match sign(dr.perp_dot(di)) {
            Orientation::Ccw => (r, dr) = (i, di),
            Orientation::Collinear if di.length_squared() < dr.length_squared() => {
                (r, dr) = (i, di)
            }
            _ => {}
        }
    }
    Some((l, r))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sweep as first written: sort the spans by start, sweep from `from`.
    fn sorted_reaches(spans: &[(f64, f64)], from: f64, to: f64) -> bool {
        let mut s = spans.to_vec();
        s.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut reach = from;
        for &(a, b) in &s {
            if a > reach {
                return false;
            }
            reach = reach.max(b);
            if reach >= to {
                return true;
            }
        }
        reach >= to
    }

    #[test]
    fn the_incremental_span_sweep_answers_as_the_sorted_one() {
        let mut g = crate::testutil::Lcg(11);
        let mut next = move || ((g.next_u64() >> 33) % 64) as f64 / 16.0 - 1.0;
        for _ in 0..20000 {
            let (from, to) = (next(), next());
            let n = (next() * 8.0 + 8.0) as usize;
            // Some spans empty or reversed, many sharing ends (coarse values).
            let spans: Vec<(f64, f64)> = (0..n).map(|_| (next(), next())).collect();
            let mut buffer = vec![(9.0, 9.0)];
            let mut sweep = Sweep::new(from, to, &mut buffer);
            assert_eq!(sweep.covers(), sorted_reaches(&[], from, to));
            for (k, &(a, b)) in spans.iter().enumerate() {
                sweep.add(a, b);
                assert_eq!(
                    sweep.covers(),
                    sorted_reaches(&spans[..=k], from, to),
                    "{spans:?} from {from} to {to}, after {k}"
                );
            }
        }
    }

    /// On integer coordinates the floating-point determinants are exact, so the guessed
    /// tangents are the exact ones.
    #[test]
    fn guessed_tangents_are_the_exact_ones_where_floats_are_exact() {
        let mut g = crate::testutil::Lcg(53);
        let mut r = move |lo: f64, hi: f64| g.range(lo, hi).round();
        for _ in 0..5000 {
            let (x, y) = (r(-50.0, 50.0), r(-50.0, 50.0));
            let poly = if r(0.0, 3.0) == 0.0 {
                vec![
                    DVec2::new(x, y),
                    DVec2::new(x + r(1.0, 9.0), y + r(-9.0, 9.0)),
                ]
            } else {
                let (w, h) = (r(1.0, 20.0), r(1.0, 20.0));
                vec![
                    DVec2::new(x, y),
                    DVec2::new(x + w, y),
                    DVec2::new(x + w, y + h),
                    DVec2::new(x, y + h),
                ]
            };
            let q = DVec2::new(r(-80.0, 80.0), r(-80.0, 80.0));
            let want = tangent_vertices(q, &poly);
            match guess_tangents(q, &poly) {
                Some((l, r)) => assert_eq!(want, Some((l, r)), "{q:?} {poly:?}"),
                None => assert!(
                    point_in_convex(&poly, q) != Containment::Outside,
                    "{q:?} {poly:?}"
                ),
            }
        }
    }

    /// The chain offered at a point behind a wall wider than the cell is that wall, and its
    /// conditions hold at the three points it was read from.
    #[test]
    fn a_chain_behind_a_wide_wall_is_that_wall() {
        let v = DVec2::new;
        let cell = vec![v(0.0, 0.0), v(10.0, 0.0), v(10.0, 10.0), v(0.0, 10.0)];
        let far = vec![
            v(100.0, 200.0),
            v(110.0, 200.0),
            v(110.0, 202.0),
            v(100.0, 202.0),
        ];
        let wall = vec![v(-40.0, 20.0), v(50.0, 20.0), v(50.0, 22.0), v(-40.0, 22.0)];
        let blockers = [far.as_slice(), wall.as_slice()];
        let boxes: Vec<(DVec2, DVec2)> = blockers
            .iter()
            .map(|b| super::super::index::bbox(b))
            .collect();
        let ver = Verifier::new(&cell, blockers.iter().copied());
        let q = v(5.0, 40.0);
        let pts = [q, v(5.0, 39.5), v(5.0, 40.5)];
        let links = ver.chain(&blockers, &boxes, &pts, false).unwrap();
        assert_eq!(links.len(), 1);
        assert_eq!(links[0].poly, 1);
        let conds = super::super::certificate::conditions(&links, &cell);
        assert!(pts.iter().all(|&p| conds.iter().all(|c| c.holds(p))));
        // In front of the wall nothing is offered that holds.
        let pts = [v(5.0, 15.0), v(5.0, 14.5), v(5.0, 15.5)];
        if let Some(links) = ver.chain(&blockers, &boxes, &pts, true) {
            let conds = super::super::certificate::conditions(&links, &cell);
            assert!(!conds.iter().all(|c| c.holds(pts[0])));
        }
    }
}
