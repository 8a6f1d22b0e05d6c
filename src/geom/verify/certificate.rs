//! A certificate of the verifier (module header of [`super`]): its links (a chord of a blocker
//! and a line separating that blocker from the cell) and the conditions (S), (A), (O) and (C)
//! they give at a point, each an exact orientation of the point against two input vertices.
//!
//! Input: links, the cell's vertices, points. Output: the conditions, whether they hold at a
//! point (exact), how far along a segment they seem to hold (floating point, an estimate the
//! sweep then checks exactly), and a separating line for a blocker (exact).
//!
//! Invariant: whether a certificate holds is decided here with the exact [`orient`] alone;
//! floating point only estimates where to check.

use glam::DVec2;

use crate::geom::predicates::{common_tangents, orient, set_side, Orientation, SetSide};

/// A line through two input points, and the strict side on which its blocker lies.
#[derive(Clone, Copy, Debug)]
pub(super) struct SepLine {
    pub(super) a: DVec2,
    pub(super) b: DVec2,
    pub(super) side: Orientation,
}

impl SepLine {
    pub(super) fn holds(&self, q: DVec2) -> bool {
        orient(self.a, self.b, q) == self.side
    }
}

/// One link of a certificate: a chord `[l, r]` of blocker `poly` (an index into the blockers
/// near the segment) and its separating line.
#[derive(Clone, Copy, Debug)]
pub(super) struct Link {
    pub(super) l: DVec2,
    pub(super) r: DVec2,
    pub(super) sep: SepLine,
    pub(super) poly: usize,
}

/// One condition of a certificate at `q`: `orient(q, u, v)` is `Ccw` (strict) or not `Cw`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Cond {
    pub(super) u: DVec2,
    pub(super) v: DVec2,
    pub(super) strict: bool,
}

impl Cond {
    pub(super) fn holds(&self, q: DVec2) -> bool {
        match orient(q, self.u, self.v) {
            Orientation::Ccw => true,
            Orientation::Collinear => !self.strict,
            Orientation::Cw => false,
        }
    }

    /// `orient(q, u, v)` in floating point, an affine function of `q`.
    pub(super) fn value(&self, q: DVec2) -> f64 {
        (self.u - q).perp_dot(self.v - q)
    }
}

/// The conditions (S), (A), (O) and (C) of a chain (module header).
pub(super) fn conditions(links: &[Link], cell: &[DVec2]) -> Vec<Cond> {
    let mut c = Vec::with_capacity(3 * links.len() + 2 * cell.len());
    for k in links {
        let (u, v) = match k.sep.side {
            Orientation::Ccw => (k.sep.a, k.sep.b),
            _ => (k.sep.b, k.sep.a),
        };
        c.push(Cond { u, v, strict: true });
        c.push(Cond {
            u: k.l,
            v: k.r,
            strict: true,
        });
    }
    for p in links.windows(2) {
        c.push(Cond {
            u: p[1].l,
            v: p[0].r,
            strict: false,
        });
        c.push(Cond {
            u: p[0].r,
            v: p[1].r,
            strict: false,
        });
    }
    if let (Some(first), Some(last)) = (links.first(), links.last()) {
        for &v in cell {
            c.push(Cond {
                u: first.l,
                v,
                strict: false,
            });
            c.push(Cond {
                u: v,
                v: last.r,
                strict: false,
            });
        }
    }
    c
}

/// How far along `[q, b]` (as a share of it) every condition of a certificate stays true,
/// estimated in floating point from their affine values at both ends.
pub(super) fn reach(conds: &[Cond], q: DVec2, b: DVec2) -> f64 {
    let mut t = 1.0f64;
    for c in conds {
        let (f0, f1) = (c.value(q), c.value(b));
        // A strict condition fails where f reaches 0, a non-strict one where it goes below
        // (one that is 0 all along, as a join through a shared vertex, never fails).
        let fails = if c.strict { f1 <= 0.0 } else { f1 < 0.0 };
        if fails {
            t = if f0 > 0.0 { t.min(f0 / (f0 - f1)) } else { 0.0 };
        }
    }
    t
}

/// A line through two input vertices with the blocker `b` on one closed side and the cell on the
/// other, having every point of `qs` strictly on `b`'s side. Candidates: the cell's edges, the
/// blocker's edges and the two crossing common tangents.
pub(super) fn separating_line(b: &[DVec2], cell: &[DVec2], qs: &[DVec2]) -> Option<SepLine> {
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

#[cfg(test)]
mod tests {
    use super::super::oracle::{brute_hidden, rect, scene, v};
    use super::super::tests::slices;
    use super::super::Verifier;
    use super::*;
    use crate::testutil::Lcg;

    /// Lemma 1 against the oracle: wherever every condition of a certificate the sweep found
    /// holds, at points along the segment and scattered around it, the point is hidden.
    #[test]
    fn wherever_a_found_certificate_holds_the_point_is_hidden() {
        let mut g = Lcg(3);
        let (mut certs, mut points) = (0, 0);
        for _ in 0..40 {
            let (cell, blockers, (a, b)) = scene(&mut g, 12);
            let ver = Verifier::new(&cell, slices(&blockers));
            ver.hidden_parts_by(a, b);
            let cache = ver.cache.borrow();
            for id in 0..cache.certs.len() as u32 {
                let conds = cache.conds_of(id);
                certs += 1;
                for _ in 0..40 {
                    let t = g.next();
                    let q = a + (b - a) * t + v(g.range(-3.0, 3.0), g.range(-3.0, 3.0));
                    if conds.iter().all(|c| c.holds(q)) {
                        points += 1;
                        assert!(brute_hidden(&cell, &blockers, q, 300), "{q:?}");
                    }
                }
            }
        }
        assert!(
            certs > 20 && points > 200,
            "{certs} certificates, {points} points"
        );
    }

    #[test]
    fn the_conditions_of_a_chain_are_its_links_and_the_cell_vertices() {
        let cell = rect(0.0, 0.0, 10.0, 10.0);
        let sep = SepLine {
            a: v(-20.0, 20.0),
            b: v(30.0, 20.0),
            side: Orientation::Ccw,
        };
        let link = |l: DVec2, r: DVec2| Link { l, r, sep, poly: 0 };
        let links = [
            link(v(-20.0, 20.0), v(6.0, 20.0)),
            link(v(5.0, 20.0), v(30.0, 20.0)),
        ];
        let c = conditions(&links, &cell);
        // (S) and (A) per link, (O) twice per join, (C) twice per cell vertex.
        assert_eq!(c.len(), 2 * 2 + 2 + 2 * 4);
        assert_eq!(c.iter().filter(|c| c.strict).count(), 4);
        // Behind the wall the chain holds; in front of it (S) fails.
        assert!(c.iter().all(|k| k.holds(v(5.0, 40.0))));
        assert!(!c.iter().all(|k| k.holds(v(5.0, 15.0))));
    }

    #[test]
    fn reach_is_where_an_affine_condition_turns() {
        // orient(q, (c, -1), (c, 1)) = 2 (c - q.x): holds for q.x < c.
        let cond = |c: f64, strict| Cond {
            u: v(c, -1.0),
            v: v(c, 1.0),
            strict,
        };
        let (q, b) = (v(0.0, 0.0), v(10.0, 0.0));
        assert_eq!(reach(&[cond(4.0, true)], q, b), 0.4);
        assert_eq!(reach(&[cond(4.0, true), cond(2.5, false)], q, b), 0.25);
        // Holding all along: the whole way.
        assert_eq!(reach(&[cond(12.0, true)], q, b), 1.0);
        // Failing already at q: nowhere.
        assert_eq!(reach(&[cond(-1.0, false)], q, b), 0.0);
    }

    #[test]
    fn a_separating_line_has_the_blocker_on_one_side_and_the_cell_on_the_other() {
        let mut g = Lcg(5);
        let cell = rect(0.0, 0.0, 16.0, 16.0);
        let mut found = 0;
        for _ in 0..2000 {
            let (x, y) = (g.range(-40.0, 40.0).floor(), g.range(-40.0, 40.0).floor());
            let b = rect(
                x,
                y,
                x + g.range(1.0, 12.0).floor(),
                y + g.range(1.0, 12.0).floor(),
            );
            let q = b.iter().copied().sum::<DVec2>() / 4.0 + v(0.25, 0.0);
            let Some(s) = separating_line(&b, &cell, &[q]) else {
                continue;
            };
            found += 1;
            assert!(s.holds(q));
            let other = if s.side == Orientation::Ccw {
                Orientation::Cw
            } else {
                Orientation::Ccw
            };
            assert!(
                b.iter().all(|&p| orient(s.a, s.b, p) != other),
                "{b:?} {s:?}"
            );
            assert!(
                cell.iter().all(|&p| orient(s.a, s.b, p) != s.side),
                "{b:?} {s:?}"
            );
        }
        assert!(found > 500, "{found}");
        // Overlapping the cell: none.
        assert!(separating_line(&rect(8.0, 8.0, 20.0, 20.0), &cell, &[v(18.0, 18.0)]).is_none());
    }

    #[test]
    fn exact_midpoints_only() {
        assert_eq!(exact_midpoint(v(1.0, 2.0), v(3.0, 6.0)), Some(v(2.0, 4.0)));
        // 1 + (1 + 2^-52) = 2 + 2^-52 rounds: no exact midpoint.
        let up = 1.0 + f64::EPSILON;
        assert_eq!(exact_midpoint(v(1.0, 0.0), v(up, 0.0)), None);
        // The same point twice has no midpoint apart from its ends.
        assert_eq!(exact_midpoint(v(1.0, 1.0), v(1.0, 1.0)), None);
    }
}
