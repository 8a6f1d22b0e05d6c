//! The exact hidden-interval verifier (DESIGN.md section 6.1): the final gate for every virtual
//! occluder.
//!
//! Input: a convex cell `C` (counter-clockwise), convex blockers (counter-clockwise polygons, or
//! segments: 2-vertex blockers, walls seen from above), and a segment `s = [a, b]` with f64
//! endpoints. Output: the sub-intervals of `s` hidden from every
//! point of `C`: every closed 2D segment from a point of `C` to a point of such an interval meets
//! some blocker (touching counts).
//!
//! Invariant: an interval is reported only with a proof that is exact for the f64 inputs. It
//! shares no code with the occluder growth except [`super::predicates`].
//!
//! ## The certificate
//! For a point `q`, a *certificate* is a chain of blockers `B_1..B_m`, each with a chord
//! `[l_k, r_k]` between two of its points (vertices, or a vertex of a neighbour lying in it) and
//! a separating line `L_k` between `B_k` and `C`
//! through two input vertices. It holds at `q` when (every test an exact orientation of `q`
//! against two input vertices):
//! - (S) `q` lies strictly on `B_k`'s side of `L_k`, for every k;
//! - (A) `orient(q, l_k, r_k) = Ccw`: `q` sees the chord under a counter-clockwise angle below a
//!   half-turn (the arc `[l_k, r_k]`), for every k;
//! - (O) `orient(q, l_{k+1}, r_k) != Cw` and `orient(q, r_k, r_{k+1}) != Cw`: the direction of
//!   `r_k` lies in the next arc (exact, as that arc is below a half-turn);
//! - (C) every cell vertex `c` has `orient(q, l_1, c) != Cw` and `orient(q, c, r_m) != Cw`.
//!
//! **Lemma 1.** If a certificate holds at `q`, then `q` is hidden. *Proof.* By (O) and induction
//! the arcs cover the counter-clockwise sweep from `l_1` to `r_m`: if they cover the sweep to
//! `r_k`, and `r_k` lies in `[l_{k+1}, r_{k+1}]`, adding that arc extends it to `r_{k+1}`. Let the
//! sweep turn through `σ`. Each cell vertex lies within a half-turn counter-clockwise of `l_1` and
//! within a half-turn clockwise of `r_m` (C); if `σ >= π` the first puts it in the sweep, and if
//! `σ < π` the two together do. `q` is outside `C` (by (S), `C` is on the other closed side of
//! `L_1`), so `C` is seen within the angular hull of its vertices, hence inside the sweep: the
//! direction to any `c` in `C` lies in some arc `k`. By (A) the ray from `q` towards `c` crosses
//! the chord `[l_k, r_k]`, which lies in `B_k`, at a point `x`. By (S) `q` is strictly on
//! `B_k`'s side of `L_k` and `c` on the other closed side, so the ray crosses `L_k` once, at or
//! before `c`, and `x` (on `B_k`'s closed side) comes no later. So `[q, c]` contains `x`. ∎
//!
//! **Segments.** A 2-vertex blocker (a wall) is the closed segment between its vertices: convex,
//! closed, with an empty interior. Lemma 1 uses of `B_k` only that it is convex and closed, that
//! its chord lies in it, and that it lies on one closed side of `L_k`; all hold for a segment,
//! whose only chord is itself (its two ends, in the order `q` sees them) and whose separating
//! lines may be its own line (the segment lies on it, which is on its closed side). Seen edge-on
//! from `q` its two ends are collinear with `q`, (A) fails, and it is simply not a link there.
//! The predicates answer exactly for segments ([`super::predicates`], module header); in
//! particular a point of the segment's line beyond its ends is outside it, so the search's
//! "both ends in one blocker" shortcut below holds for segments too (the piece then lies on
//! the wall, and a segment from `C` to any point of it meets the wall there).
//!
//! **Lemma 2.** Each condition is `f(q) > 0` or `f(q) >= 0` for an affine `f` (the orientation
//! determinant is affine in `q`), so a certificate that holds at both ends of a segment holds at
//! every point of it. ∎
//!
//! ## The search
//! A piece whose two ends lie in one blocker lies in it (blockers are convex), and is hidden.
//! Other pieces of `s` are bisected at their midpoints, but only where the midpoint is exactly
//! representable (checked; it then lies exactly on `s`), down to [`MIN_PIECE_M`]. For a piece, a
//! candidate certificate is read off at one exact point of it (the tangent vertices of each
//! blocker in front, then the shortest chain of overlapping chords that covers the cell's angle,
//! by breadth-first search, joining blockers that share a vertex through it), and checked exactly
//! at both ends.
//! Pieces that cannot be certified count as visible: the output can only be smaller than the true
//! hidden set, never larger.

use glam::DVec2;

use super::predicates::{
    common_tangents, convex_interiors_disjoint, orient, point_in_convex, segment_meets_convex,
    set_side, tangent_vertices, Containment, Orientation, SetSide,
};

/// Pieces shorter than this are not split further; an uncertified one counts as visible, metres.
pub const MIN_PIECE_M: f64 = 0.01;
/// Deepest bisection.
pub const MAX_DEPTH: u32 = 30;
/// Most bisections of a piece in [`Verifier::is_hidden`] (pieces down to 1/1024 of the segment).
pub const CHECK_DEPTH: u32 = 10;

/// A hidden sub-interval of the verified segment: parameters along `a -> b` and the exact
/// endpoints (each lies exactly on the segment).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hidden {
    pub t0: f64,
    pub t1: f64,
    pub p0: DVec2,
    pub p1: DVec2,
}

/// A line through two input points, and the strict side on which its blocker lies.
#[derive(Clone, Copy, Debug)]
struct SepLine {
    a: DVec2,
    b: DVec2,
    side: Orientation,
}

impl SepLine {
    fn holds(&self, q: DVec2) -> bool {
        orient(self.a, self.b, q) == self.side
    }
}

/// One link of a certificate: a chord `[l, r]` of blocker `poly` (an index into the blockers
/// near the segment) and its separating line.
#[derive(Clone, Copy, Debug)]
struct Link {
    l: DVec2,
    r: DVec2,
    sep: SepLine,
    poly: usize,
}

/// The verifier for one cell and one set of blockers.
pub struct Verifier<'a> {
    cell: &'a [DVec2],
    blockers: Vec<&'a [DVec2]>,
    boxes: Vec<(DVec2, DVec2)>,
}

impl<'a> Verifier<'a> {
    /// `cell`: convex, counter-clockwise, non-degenerate. Every blocker: the same, or a segment
    /// (exactly 2 distinct vertices).
    pub fn new(cell: &'a [DVec2], blockers: impl IntoIterator<Item = &'a [DVec2]>) -> Self {
        let blockers: Vec<&[DVec2]> = blockers.into_iter().collect();
        let boxes = blockers.iter().map(|b| bbox(b)).collect();
        Verifier {
            cell,
            blockers,
            boxes,
        }
    }

    /// The blockers that may block a segment from the cell to `[a, b]`.
    fn near(&self, a: DVec2, b: DVec2) -> Vec<&'a [DVec2]> {
        // Only blockers whose box meets the hull of the cell and the segment can block.
        let (mut lo, mut hi) = bbox(self.cell);
        lo = lo.min(a).min(b);
        hi = hi.max(a).max(b);
        let near: Vec<&[DVec2]> = self
            .blockers
            .iter()
            .zip(&self.boxes)
            .filter(|(_, (bl, bh))| bl.x <= hi.x && bh.x >= lo.x && bl.y <= hi.y && bh.y >= lo.y)
            .map(|(b, _)| *b)
            .collect();
        // Every segment from the cell to [a, b] lies in their convex hull; a polygon whose
        // interior misses the hull can at most touch such segments on its boundary. Leaving it
        // out can only certify less, never more. A wall segment is kept when it meets the closed
        // hull: one lying on the hull's boundary may hold part of [a, b] (a VO along a facade).
        let hull = convex_hull(self.cell.iter().copied().chain([a, b]));
        if hull.len() >= 3 {
            near.into_iter()
                .filter(|b| match b.len() {
                    2 => segment_meets_convex(b[0], b[1], &hull),
                    _ => !convex_interiors_disjoint(&hull, b),
                })
                .collect()
        } else {
            near
        }
    }

    /// The certified hidden sub-intervals of `[a, b]`, in order, merged where they touch.
    pub fn hidden_parts(&self, a: DVec2, b: DVec2) -> Vec<Hidden> {
        let near = self.near(a, b);
        let mut out: Vec<Hidden> = Vec::new();
        let mut stack = vec![(0.0f64, 1.0f64, a, b, 0u32)];
        // Depth-first, left piece first, so pieces come out in order.
        while let Some((t0, t1, p0, p1, depth)) = stack.pop() {
            if self.certify(&near, p0, p1) {
                match out.last_mut() {
                    Some(h) if h.p1 == p0 => {
                        h.t1 = t1;
                        h.p1 = p1;
                    }
                    _ => out.push(Hidden { t0, t1, p0, p1 }),
                }
                continue;
            }
            if depth >= MAX_DEPTH || p0.distance(p1) < 2.0 * MIN_PIECE_M {
                continue;
            }
            if let Some(m) = exact_midpoint(p0, p1) {
                let tm = 0.5 * (t0 + t1);
                stack.push((tm, t1, m, p1, depth + 1));
                stack.push((t0, tm, p0, m, depth + 1));
            }
        }
        out
    }

    /// True when the whole closed segment `[a, b]` is certified hidden. Same certificates as
    /// [`Self::hidden_parts`], but it stops at the first piece that cannot be certified, and
    /// splits at most [`CHECK_DEPTH`] times: a yes/no answer for the bake's final gate.
    pub fn is_hidden(&self, a: DVec2, b: DVec2) -> bool {
        let near = self.near(a, b);
        let mut stack = vec![(a, b, 0u32)];
        while let Some((p0, p1, depth)) = stack.pop() {
            if self.certify(&near, p0, p1) {
                continue;
            }
            if depth >= CHECK_DEPTH || p0.distance(p1) < 2.0 * MIN_PIECE_M {
                return false;
            }
            match exact_midpoint(p0, p1) {
                Some(m) => {
                    stack.push((m, p1, depth + 1));
                    stack.push((p0, m, depth + 1));
                }
                None => return false,
            }
        }
        true
    }

    /// Looks for a certificate that holds at both ends of `[p0, p1]` (and at an exact point
    /// between), with chords read off at that point.
    fn certify(&self, near: &[&[DVec2]], p0: DVec2, p1: DVec2) -> bool {
        // A piece inside one (convex) blocker: every segment to it meets that blocker.
        let inside = |b: &[DVec2], p| point_in_convex(b, p) != Containment::Outside;
        if near.iter().any(|b| inside(b, p0) && inside(b, p1)) {
            return true;
        }
        let anchor = exact_midpoint(p0, p1).unwrap_or(p0);
        let pts = [anchor, p0, p1];
        match self.chain(near, &pts) {
            Some(links) => pts.iter().all(|&q| self.holds(&links, q)),
            None => false,
        }
    }

    /// The shortest chain of blocker chords whose conditions (S), (A), (O) and (C) hold at every
    /// point of `pts`, by breadth-first search over the chords seen from `pts[0]`. Any chain
    /// that is valid with fewer blockers is still found with more, so adding a blocker never
    /// loses a certificate.
    fn chain(&self, near: &[&[DVec2]], pts: &[DVec2; 3]) -> Option<Vec<Link>> {
        use Orientation::*;
        let q = pts[0];
        let (cl, cr) = tangent_vertices(q, self.cell)?;
        let (cl, cr) = (self.cell[cl], self.cell[cr]);
        let all = |f: &dyn Fn(DVec2) -> bool| pts.iter().all(|&p| f(p));
        let mut arcs: Vec<Link> = Vec::new();
        for (poly, b) in near.iter().enumerate() {
            let Some((l, r)) = tangent_vertices(q, b) else {
                continue;
            };
            // Only arcs that meet the cell's angle from q can be links (a cheap filter before
            // the separating line; the conditions below decide).
            if orient(q, cl, b[r]) == Cw || orient(q, b[l], cr) == Cw {
                continue;
            }
            // Chords from the extreme vertices seen from each test point: near an umbra
            // boundary, nearly collinear vertices trade places within millimetres.
            let mut ls = vec![b[l]];
            let mut rs = vec![b[r]];
            for &p in &pts[1..] {
                if let Some((l, r)) = tangent_vertices(p, b) {
                    if !ls.contains(&b[l]) {
                        ls.push(b[l]);
                    }
                    if !rs.contains(&b[r]) {
                        rs.push(b[r]);
                    }
                }
            }
            let mut sep = None;
            for &l in &ls {
                for &r in &rs {
                    if !all(&|p| orient(p, l, r) == Ccw) {
                        continue;
                    }
                    if sep.is_none() {
                        sep = Some(separating_line(b, self.cell, pts));
                    }
                    if let Some(Some(sep)) = sep {
                        arcs.push(Link { l, r, sep, poly });
                    }
                }
            }
        }
        let starts = |k: &Link| all(&|p| self.cell.iter().all(|&c| orient(p, k.l, c) != Cw));
        let ends = |k: &Link| all(&|p| self.cell.iter().all(|&c| orient(p, c, k.r) != Cw));
        let overlaps =
            |a: &Link, b: &Link| all(&|p| orient(p, b.l, a.r) != Cw && orient(p, a.r, b.r) != Cw);
        // Blockers that share a point `v` (a common vertex, or a vertex of one inside the
        // other) join through it: the chords `[a.l, v]` and `[v, b.r]` lie in their blockers
        // (convexity), are valid by (A), and make (O) hold trivially. Adjacent convex pieces of one footprint, and
        // buildings that share a wall, meet like this; across the line of a shared edge the
        // extreme vertices swap, and only such a join certifies both sides at once.
        let boxes: Vec<(DVec2, DVec2)> = near.iter().map(|p| bbox(p)).collect();
        let shared = |a: &Link, b: &Link| -> Option<DVec2> {
            let ((al, ah), (bl, bh)) = (boxes[a.poly], boxes[b.poly]);
            if al.x > bh.x || bl.x > ah.x || al.y > bh.y || bl.y > ah.y {
                return None;
            }
            let (pa, pb) = (near[a.poly], near[b.poly]);
            let in_both = |v: &DVec2| {
                point_in_convex(pa, *v) != Containment::Outside
                    && point_in_convex(pb, *v) != Containment::Outside
            };
            pa.iter().chain(pb.iter()).copied().find(|v| {
                in_both(v) && all(&|p| orient(p, a.l, *v) == Ccw && orient(p, *v, b.r) == Ccw)
            })
        };
        let joins = |a: &Link, b: &Link| overlaps(a, b) || shared(a, b).is_some();
        // Breadth-first from every start arc; `prev` records the path.
        let n = arcs.len();
        let mut prev: Vec<Option<usize>> = vec![None; n];
        let mut seen = vec![false; n];
        let mut queue = std::collections::VecDeque::new();
        for (i, a) in arcs.iter().enumerate() {
            if starts(a) {
                seen[i] = true;
                queue.push_back(i);
            }
        }
        while let Some(i) = queue.pop_front() {
            if ends(&arcs[i]) {
                let mut path = vec![arcs[i]];
                let mut k = i;
                while let Some(j) = prev[k] {
                    path.push(arcs[j]);
                    k = j;
                }
                path.reverse();
                for k in 0..path.len() - 1 {
                    if !overlaps(&path[k], &path[k + 1]) {
                        if let Some(v) = shared(&path[k], &path[k + 1]) {
                            path[k].r = v;
                            path[k + 1].l = v;
                        }
                    }
                }
                return Some(path);
            }
            for j in 0..n {
                if !seen[j] && joins(&arcs[i], &arcs[j]) {
                    seen[j] = true;
                    prev[j] = Some(i);
                    queue.push_back(j);
                }
            }
        }
        None
    }

    /// Checks the certificate's conditions (module header) at `q`.
    fn holds(&self, links: &[Link], q: DVec2) -> bool {
        use Orientation::*;
        let o = |u: DVec2, v: DVec2| orient(q, u, v);
        if links.is_empty() || links.iter().any(|k| !k.sep.holds(q) || o(k.l, k.r) != Ccw) {
            return false;
        }
        // (O): each chord's end lies in the next arc.
        if links
            .windows(2)
            .any(|p| o(p[1].l, p[0].r) == Cw || o(p[0].r, p[1].r) == Cw)
        {
            return false;
        }
        // (C): every cell vertex inside the sweep from l_1 to r_m.
        let (l1, rm) = (links[0].l, links[links.len() - 1].r);
        self.cell.iter().all(|&c| o(l1, c) != Cw && o(c, rm) != Cw)
    }
}

/// A line through two input vertices with the blocker `b` on one closed side and the cell on the
/// other, having every point of `qs` strictly on `b`'s side. Candidates: the cell's edges, the
/// blocker's edges and the two crossing common tangents.
fn separating_line(b: &[DVec2], cell: &[DVec2], qs: &[DVec2]) -> Option<SepLine> {
    let ok = |s: SepLine| qs.iter().all(|&q| s.holds(q));
    // An edge of one polygon (counter-clockwise, so itself on the left) with the other wholly
    // on the right: the blocker's side is right of a cell edge, left of a blocker edge.
    fn edges<'a>(
        poly: &'a [DVec2],
        other: &'a [DVec2],
        side: Orientation,
    ) -> impl Iterator<Item = SepLine> + 'a {
        let n = poly.len();
        (0..n).filter_map(move |i| {
            let (u, v) = (poly[i], poly[(i + 1) % n]);
            (set_side(u, v, other) == SetSide::Right).then_some(SepLine { a: u, b: v, side })
        })
    }
    if let Some(s) = edges(cell, b, Orientation::Cw)
        .chain(edges(b, cell, Orientation::Ccw))
        .find(|&s| ok(s))
    {
        return Some(s);
    }
    let t = common_tangents(cell, b);
    // cross_left: cell on the left, blocker on the right; cross_right: the reverse.
    let cands = [
        t.cross_left.map(|t| (t, Orientation::Cw)),
        t.cross_right.map(|t| (t, Orientation::Ccw)),
    ];
    for (t, side) in cands.into_iter().flatten() {
        let s = SepLine {
            a: cell[t.i],
            b: b[t.j],
            side,
        };
        if ok(s) {
            return Some(s);
        }
    }
    None
}

/// The midpoint of `[p, q]` when it is exactly representable (so lies exactly on the segment).
pub fn exact_midpoint(p: DVec2, q: DVec2) -> Option<DVec2> {
    fn exact_sum(a: f64, b: f64) -> Option<f64> {
        // Knuth's TwoSum: the rounding error of a + b, which must be zero.
        let s = a + b;
        let bb = s - a;
        let err = (a - (s - bb)) + (b - bb);
        (err == 0.0 && s.is_finite()).then_some(s)
    }
    let (sx, sy) = (exact_sum(p.x, q.x)?, exact_sum(p.y, q.y)?);
    let m = DVec2::new(sx * 0.5, sy * 0.5);
    // Halving is exact unless it underflows.
    (m.x * 2.0 == sx && m.y * 2.0 == sy && m != p && m != q).then_some(m)
}

/// Convex hull, counter-clockwise, without collinear points (Andrew's monotone chain with exact
/// orientation tests).
fn convex_hull(pts: impl Iterator<Item = DVec2>) -> Vec<DVec2> {
    let mut p: Vec<DVec2> = pts.collect();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let mut h: Vec<DVec2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = h.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while h.len() >= start + 2
                && orient(h[h.len() - 2], h[h.len() - 1], q) != Orientation::Ccw
            {
                h.pop();
            }
            h.push(q);
        }
        h.pop();
    }
    h
}

fn bbox(p: &[DVec2]) -> (DVec2, DVec2) {
    p.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), &v| (lo.min(v), hi.max(v)),
    )
}
