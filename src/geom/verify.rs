//! The exact hidden-interval verifier (DESIGN.md section 6.1): the final gate for every virtual
//! occluder.
//!
//! Input: a convex cell `C` (counter-clockwise), convex blockers (counter-clockwise), and a
//! segment `s = [a, b]` with f64 endpoints. Output: the sub-intervals of `s` hidden from every
//! point of `C`: every closed 2D segment from a point of `C` to a point of such an interval meets
//! some blocker (touching counts).
//!
//! Invariant: an interval is reported only with a proof that is exact for the f64 inputs. It
//! shares no code with the occluder growth except [`super::predicates`].
//!
//! ## The certificate
//! For a point `q` outside `C`, a *certificate* is a chain of blockers `B_1..B_m`, each with a
//! chord `[l_k, r_k]` between two of its vertices and a separating line `L_k` between `B_k` and
//! `C` through two input vertices, plus two window vertices `W`, `X`. It holds at `q` when
//! (every test an exact orientation of `q` against two input vertices):
//! - (S) `q` lies strictly on `B_k`'s side of `L_k`, for every k;
//! - (A) `orient(q, l_k, r_k) = Ccw`: `q` sees the chord under a counter-clockwise angle below a
//!   half-turn, for every k;
//! - (W) `orient(q, W, X) = Ccw` and every chord end and cell vertex `v` has
//!   `orient(q, W, v) != Cw` and `orient(q, v, X) != Cw`: all directions used lie in one
//!   half-turn, where orientation is angle order;
//! - (O) `orient(q, l_{k+1}, r_k) != Cw`: consecutive chord arcs overlap or touch;
//! - (C) every cell vertex `c` has `orient(q, l_1, c) != Cw` and `orient(q, c, r_m) != Cw`.
//!
//! **Lemma 1.** If a certificate holds at `q`, then `q` is hidden. *Proof.* By (W) directions
//! compare as angles. By (O) and induction, the union of the arcs `[l_1, r_k]..` covers
//! `[l_1, r_m]`: if it covers `[l_1, r_k]` and `l_{k+1} <= r_k`, adding `[l_{k+1}, r_{k+1}]`
//! covers `[l_1, max(r_k, r_{k+1})]`. By (C) every cell vertex, hence (C convex, `q` outside it
//! by (S)) every point `c` of `C`, is seen in `[l_1, r_m]`, so in some arc `k`. By (A) the ray
//! from `q` towards `c` crosses the chord `[l_k, r_k]`, which lies in `B_k`, at a point `x`. By
//! (S) `q` is strictly on `B_k`'s side of `L_k` and `c` on the other closed side, so the ray
//! crosses `L_k` once, at or before `c`, and `x` (on `B_k`'s closed side) comes no later. So the
//! segment `[q, c]` contains `x`. ∎
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
//! by breadth-first search; if its extreme chords overshoot a half-turn, the same chain with
//! chords trimmed to the vertices it needs), and checked exactly at both ends.
//! Pieces that cannot be certified count as visible: the output can only be smaller than the true
//! hidden set, never larger.

use glam::DVec2;

use super::predicates::{
    common_tangents, orient, point_in_convex, set_side, tangent_vertices, Containment, Orientation,
    SetSide,
};

/// Pieces shorter than this are not split further; an uncertified one counts as visible, metres.
pub const MIN_PIECE_M: f64 = 0.01;
/// Deepest bisection.
pub const MAX_DEPTH: u32 = 30;

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
    /// `cell` and every blocker: convex, counter-clockwise, non-degenerate.
    pub fn new(cell: &'a [DVec2], blockers: impl IntoIterator<Item = &'a [DVec2]>) -> Self {
        let blockers: Vec<&[DVec2]> = blockers.into_iter().collect();
        let boxes = blockers.iter().map(|b| bbox(b)).collect();
        Verifier {
            cell,
            blockers,
            boxes,
        }
    }

    /// The certified hidden sub-intervals of `[a, b]`, in order, merged where they touch.
    pub fn hidden_parts(&self, a: DVec2, b: DVec2) -> Vec<Hidden> {
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

    /// True when the whole closed segment `[a, b]` is certified hidden.
    pub fn is_hidden(&self, a: DVec2, b: DVec2) -> bool {
        let parts = self.hidden_parts(a, b);
        parts.len() == 1 && parts[0].p0 == a && parts[0].p1 == b
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
        let Some(links) = self.chain(near, &pts) else {
            return false;
        };
        if pts.iter().all(|&q| self.holds(&links, q)) {
            return true;
        }
        // Extreme chords can overshoot the cell's angle so far that the directions used span
        // more than a half-turn (W fails); chords trimmed to what is needed may not.
        let trimmed = self.trim(near, &links, anchor);
        pts.iter().all(|&q| self.holds(&trimmed, q))
    }

    /// Shrinks each chord of a chain, seen from `q`, to the blocker vertices it needs: the first
    /// chord starts at the last vertex not past the cell's first direction, each next chord at
    /// its last vertex not past the previous chord's end, and ends are pulled back the same way.
    /// A heuristic choice of vertices only: the result is checked exactly by the caller.
    fn trim(&self, near: &[&[DVec2]], links: &[Link], q: DVec2) -> Vec<Link> {
        use Orientation::*;
        let Some((cl, cr)) = tangent_vertices(q, self.cell) else {
            return links.to_vec();
        };
        let (cl, cr) = (self.cell[cl], self.cell[cr]);
        let cw_of = |a: DVec2, b: DVec2| orient(q, a, b) != Cw; // a at or clockwise of b
                                                                // The most counter-clockwise vertex of `poly` at or clockwise of `limit`, else `keep`.
        let last_before = |poly: &[DVec2], limit: DVec2, keep: DVec2| {
            poly.iter()
                .copied()
                .filter(|&v| cw_of(v, limit))
                .fold(None, |best: Option<DVec2>, v| match best {
                    Some(b) if orient(q, b, v) != Ccw => Some(b),
                    _ => Some(v),
                })
                .unwrap_or(keep)
        };
        // The most clockwise vertex of `poly` at or counter-clockwise of `limit`, else `keep`.
        let first_after = |poly: &[DVec2], limit: DVec2, keep: DVec2| {
            poly.iter()
                .copied()
                .filter(|&v| cw_of(limit, v))
                .fold(None, |best: Option<DVec2>, v| match best {
                    Some(b) if orient(q, v, b) != Ccw => Some(b),
                    _ => Some(v),
                })
                .unwrap_or(keep)
        };
        let mut out = links.to_vec();
        let m = out.len();
        out[0].l = last_before(near[out[0].poly], cl, out[0].l);
        for k in 1..m {
            out[k].l = last_before(near[out[k].poly], out[k - 1].r, out[k].l);
        }
        out[m - 1].r = first_after(near[out[m - 1].poly], cr, out[m - 1].r);
        for k in (0..m - 1).rev() {
            out[k].r = first_after(near[out[k].poly], out[k + 1].l, out[k].r);
        }
        for (t, o) in out.iter_mut().zip(links) {
            if orient(q, t.l, t.r) != Ccw {
                *t = *o;
            }
        }
        out
    }

    /// The shortest chain of blocker chords whose conditions (S), (A), (O) and (C) hold at every
    /// point of `pts`, by breadth-first search over the chords seen from `pts[0]`. Any chain
    /// that is valid with fewer blockers is still found with more, so adding a blocker never
    /// loses a certificate (up to the window condition (W), checked afterwards).
    fn chain(&self, near: &[&[DVec2]], pts: &[DVec2; 3]) -> Option<Vec<Link>> {
        use Orientation::*;
        let q = pts[0];
        tangent_vertices(q, self.cell)?;
        let all = |f: &dyn Fn(DVec2) -> bool| pts.iter().all(|&p| f(p));
        let mut arcs: Vec<Link> = Vec::new();
        for (poly, b) in near.iter().enumerate() {
            let Some((l, r)) = tangent_vertices(q, b) else {
                continue;
            };
            let (l, r) = (b[l], b[r]);
            if !all(&|p| orient(p, l, r) == Ccw) {
                continue;
            }
            let Some(sep) = separating_line(b, self.cell, pts) else {
                continue;
            };
            arcs.push(Link { l, r, sep, poly });
        }
        let starts = |k: &Link| all(&|p| self.cell.iter().all(|&c| orient(p, k.l, c) != Cw));
        let ends = |k: &Link| all(&|p| self.cell.iter().all(|&c| orient(p, c, k.r) != Cw));
        let overlaps = |a: &Link, b: &Link| all(&|p| orient(p, b.l, a.r) != Cw);
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
                return Some(path);
            }
            for j in 0..n {
                if !seen[j] && overlaps(&arcs[i], &arcs[j]) {
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
        // (W): window from the most clockwise to the most counter-clockwise direction used.
        let pts = links
            .iter()
            .flat_map(|k| [k.l, k.r])
            .chain(self.cell.iter().copied());
        let (mut w, mut x) = (links[0].l, links[0].r);
        for p in pts.clone() {
            if o(w, p) == Cw {
                w = p;
            }
            if o(x, p) == Ccw {
                x = p;
            }
        }
        if o(w, x) != Ccw || pts.clone().any(|p| o(w, p) == Cw || o(p, x) == Cw) {
            return false;
        }
        // (O): consecutive arcs overlap or touch.
        if links.windows(2).any(|p| o(p[1].l, p[0].r) == Cw) {
            return false;
        }
        // (C): every cell vertex inside [l_1, r_m].
        let (l1, rm) = (links[0].l, links[links.len() - 1].r);
        self.cell.iter().all(|&c| o(l1, c) != Cw && o(c, rm) != Cw)
    }
}

/// A line through two input vertices with the blocker `b` on one closed side and the cell on the
/// other, having every point of `qs` strictly on `b`'s side. Candidates: the cell's edges, the
/// blocker's edges and the two crossing common tangents.
fn separating_line(b: &[DVec2], cell: &[DVec2], qs: &[DVec2]) -> Option<SepLine> {
    let ok = |s: SepLine| qs.iter().all(|&q| s.holds(q));
    for i in 0..cell.len() {
        let (u, v) = (cell[i], cell[(i + 1) % cell.len()]);
        if set_side(u, v, b) == SetSide::Right {
            let s = SepLine {
                a: u,
                b: v,
                side: Orientation::Cw,
            };
            if ok(s) {
                return Some(s);
            }
        }
    }
    for i in 0..b.len() {
        let (u, v) = (b[i], b[(i + 1) % b.len()]);
        if set_side(u, v, cell) == SetSide::Right {
            let s = SepLine {
                a: u,
                b: v,
                side: Orientation::Ccw,
            };
            if ok(s) {
                return Some(s);
            }
        }
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

fn bbox(p: &[DVec2]) -> (DVec2, DVec2) {
    p.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), &v| (lo.min(v), hi.max(v)),
    )
}
