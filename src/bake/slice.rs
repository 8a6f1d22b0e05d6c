//! Slices: at which VO heights a cell is baked, and which blockers support each (rule 2).
//!
//! Input: a cell (convex, counter-clockwise), its eye range `[e0, e1]` and ground `g`, and the
//! blockers near it with their base and top. Output: the slice levels (VO height levels of the
//! store's frame), and for each VO the blockers that support it by rule 2.
//! Invariants:
//! - rule 2 (docs/DESIGN.md section 3) decides support: with `lambda` a bound of the fraction of a
//!   ray's 2D length at which it crosses the blocker, `t >= e1 + lambda (h - e1)` and
//!   `b <= min(e0, g)` or `b <= e0 - lambda (e0 - g)`, with
//!   `lambda = min(1, d_far(B) / d_near(s))` (proof in ARCHITECTURE.md, "Rules 2 and 3");
//!   distances are computed in f64 and rounded toward the conservative side (`d_far` up,
//!   `d_near` down, the bounds by [`RULE2_SLACK_M`]), so a blocker admitted here supports the
//!   VO in exact arithmetic;
//! - for one given VO segment `s`, [`Support::supports_beside`] also takes
//!   `lambda <= d_far(B) / (d_far(B) + dist(B, s))` and `lambda <= 1 - d_B / d_line`
//!   ([`line_lambda`], distances from the VO's line; ARCHITECTURE.md, "Rule 2, the tighter
//!   bounds"), never looser than the plain bound;
//! - the slice histogram ranks blockers by their top: the highest VO a blocker supports at any
//!   distance where rule 2 caps `lambda` at 1 (a VO as near as the blocker's far side); every
//!   VO is then checked against rule 2 with its own `d_near(s)`.

use glam::DVec2;

use crate::geom::predicates::{point_in_convex, Containment};

/// Added to rule 2's height bound before comparing, metres: covers float rounding in it.
pub const RULE2_SLACK_M: f64 = 1e-6;
/// Relative rounding allowance of a computed distance.
const DIST_ROUND: f64 = 1e-12;

/// The greatest distance between a point of convex polygon (or segment) `p` and one of convex
/// polygon (or segment) `q`, rounded up. (Distance is convex, so the maximum is at a pair of
/// vertices; a segment's are its two ends.)
pub fn d_far(p: &[DVec2], q: &[DVec2]) -> f64 {
    let mut m: f64 = 0.0;
    for a in p {
        for b in q {
            m = m.max(a.distance_squared(*b));
        }
    }
    m.sqrt() * (1.0 + DIST_ROUND) + DIST_ROUND
}

pub(crate) fn point_segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let l2 = d.length_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(d) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + d * t)
}

/// The least distance between convex polygon `cell` and convex polygon (or segment) `q`, rounded
/// down; 0 when they may meet. For disjoint convex sets the least distance is between a vertex of
/// one and an edge of the other.
pub fn d_near(cell: &[DVec2], q: &[DVec2]) -> f64 {
    // The edges of a polygon, or the one edge of a segment (no allocation: this runs for every
    // blocker near every cell).
    fn edges(p: &[DVec2]) -> impl Iterator<Item = (DVec2, DVec2)> + '_ {
        let n = if p.len() == 2 { 1 } else { p.len() };
        (0..n).map(move |i| (p[i], p[(i + 1) % p.len()]))
    }
    let mut m = f64::INFINITY;
    for &v in q {
        for (a, b) in edges(cell) {
            m = m.min(point_segment_distance(v, a, b));
        }
    }
    for &v in cell {
        for (a, b) in edges(q) {
            m = m.min(point_segment_distance(v, a, b));
        }
    }
    // Segments that cross have no vertex–edge pair at distance 0, and a set inside the other
    // has its vertex–edge distances to the far boundary; callers only pass sets whose interiors
    // are disjoint, and a crossing would make rule 2 fail anyway, but stay safe (exactly).
    let inside =
        |p: &[DVec2], v: DVec2| p.len() >= 2 && point_in_convex(p, v) != Containment::Outside;
    if q.iter().any(|&v| inside(cell, v)) || cell.iter().any(|&v| inside(q, v)) {
        return 0.0;
    }
    for (a, b) in edges(q) {
        for (c, d) in edges(cell) {
            if segments_may_cross(a, b, c, d) {
                return 0.0;
            }
        }
    }
    (m * (1.0 - DIST_ROUND) - DIST_ROUND).max(0.0)
}

fn segments_may_cross(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let o = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    let (d1, d2) = (o(a, b, c), o(a, b, d));
    let (d3, d4) = (o(c, d, a), o(c, d, b));
    if d1 == 0.0 && d2 == 0.0 {
        // Collinear: they meet only if their boxes do.
        let (lo1, hi1) = (a.min(b), a.max(b));
        let (lo2, hi2) = (c.min(d), c.max(d));
        return lo1.x <= hi2.x && lo2.x <= hi1.x && lo1.y <= hi2.y && lo2.y <= hi1.y;
    }
    d1 * d2 <= 0.0 && d3 * d4 <= 0.0
}

/// An upper bound of the fraction `lambda = |p - y| / |p - x|` at which a ray's 2D segment
/// from a point `p` of `cell` to a point `x` of the VO `a`–`b` crosses the convex polygon (or
/// segment) `poly` at `y`, from the VO's line alone: `1 - d_poly / d_line`, where `d_line` is
/// the greatest distance of a cell corner from the line and `d_poly` the least distance of a
/// point of `poly` from it on the cell's side (0 when `poly` reaches the line). By similar
/// triangles `|y - x| / |p - x|` is the ratio of the distances of `y` and `p` from the line
/// (ARCHITECTURE.md, "Rule 2, the tighter bounds"). 1 when the line meets the cell. Rounded up.
pub fn line_lambda(cell: &[DVec2], poly: &[DVec2], a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let len = d.length();
    if !(len > 0.0) {
        return 1.0;
    }
    // Unit normal pointing to the cell's side.
    let mut n = d.perp() / len;
    let side = |p: DVec2, n: DVec2| n.dot(p - a);
    if side(cell[0], n) < 0.0 {
        n = -n;
    }
    let mut d_line: f64 = 0.0;
    for &c in cell {
        let s = side(c, n);
        if !(s > 0.0) {
            return 1.0;
        }
        d_line = d_line.max(s);
    }
    let d_poly = poly
        .iter()
        .map(|&v| side(v, n))
        .fold(f64::INFINITY, f64::min);
    if !(d_poly > 0.0) {
        return 1.0;
    }
    // Rounding of the distances is relative 1e-15 or so: the allowance covers it many times.
    let lambda = 1.0 - d_poly / d_line + 1e-9;
    lambda.clamp(0.0, 1.0)
}

/// What rule 2 needs to know of a blocker seen from one cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Support {
    pub base: f64,
    pub top: f64,
    /// Greatest distance between the cell and the blocker (rounded up).
    pub d_far: f64,
}

impl Support {
    pub fn new(cell: &[DVec2], poly: &[DVec2], base: f64, top: f64) -> Support {
        Support {
            base,
            top,
            d_far: d_far(cell, poly),
        }
    }

    /// Rule 2 for any bound `lambda` of the fraction of a ray's 2D length at which it crosses
    /// this blocker: the ray's height there lies between `e0 - lambda (e0 - g)` and
    /// `e1 + lambda (h - e1)` (ARCHITECTURE.md, "Rule 2"), which must lie within the blocker's
    /// base and top. Both bounds are rounded toward refusal by [`RULE2_SLACK_M`].
    fn holds(&self, e0: f64, e1: f64, g: f64, h: f64, lambda: f64) -> bool {
        if !(lambda >= 0.0) {
            return false;
        }
        let lambda = lambda.min(1.0);
        self.base_holds(e0, g, lambda) && self.top_holds(e1, h, lambda)
    }

    /// The lower half of [`Self::holds`], for `lambda` in `[0, 1]`: it does not depend on the
    /// VO's top.
    fn base_holds(&self, e0: f64, g: f64, lambda: f64) -> bool {
        let low = e0 - lambda * (e0 - g).max(0.0);
        // `b <= min(e0, g)` compares given values, with no arithmetic: exact.
        self.base <= e0.min(g) || self.base <= low - RULE2_SLACK_M * (1.0 + low.abs())
    }

    /// The upper half of [`Self::holds`], for `lambda` in `[0, 1]`.
    fn top_holds(&self, e1: f64, h: f64, lambda: f64) -> bool {
        let high = e1 + lambda * (h - e1).max(0.0);
        self.top >= high + RULE2_SLACK_M * (1.0 + high.abs())
    }

    /// Rule 2 with the ratio at its cap of 1 (`lambda <= 1` always): this blocker supports a VO
    /// of top `h` and bottom `g` wherever the VO stands.
    pub fn supports_anywhere(&self, e0: f64, e1: f64, g: f64, h: f64) -> bool {
        self.holds(e0, e1, g, h, 1.0)
    }

    /// Rule 2: this blocker supports a VO of top `h`, bottom `g`, at least `d_near_s` from the
    /// cell, for eyes in `[e0, e1]`: `lambda <= min(1, d_far(B) / d_near(s))`.
    pub fn supports(&self, e0: f64, e1: f64, g: f64, h: f64, d_near_s: f64) -> bool {
        d_near_s > 0.0 && self.holds(e0, e1, g, h, self.d_far / d_near_s)
    }

    /// Rule 2 with the tighter bounds, for one VO: `lambda <= d_far(B) / (d_far(B) + dist(B, s))`
    /// as well, where `d_bs` is the least distance between this blocker and the VO's segment
    /// (rounded down; 0 when they may meet), and `lambda <= line`, the bound from the VO's line
    /// ([`line_lambda`]). The crossing `y` splits the ray's 2D segment from eye `p` to VO point
    /// `x` into `|p - y| <= d_far(B)` and `|y - x| >= dist(B, s)`, and `u / (u + v)` grows with
    /// `u` and falls with `v` (ARCHITECTURE.md, "Rule 2, the tighter bounds"). They hold for
    /// the VO they were computed for, not for every VO of a distance band.
    #[allow(clippy::too_many_arguments)]
    pub fn supports_beside(
        &self,
        e0: f64,
        e1: f64,
        g: f64,
        h: f64,
        d_near_s: f64,
        d_bs: f64,
        line: f64,
    ) -> bool {
        self.lambda_beside(d_near_s, d_bs, line)
            .is_some_and(|lambda| self.holds(e0, e1, g, h, lambda))
    }

    /// The bound on `lambda` of [`Self::supports_beside`] (before its cap of 1), `None` when
    /// the distances refuse every VO.
    fn lambda_beside(&self, d_near_s: f64, d_bs: f64, line: f64) -> Option<f64> {
        if !(d_near_s > 0.0) || !(d_bs >= 0.0) {
            return None;
        }
        Some(
            (self.d_far / d_near_s)
                .min(self.d_far / (self.d_far + d_bs))
                .min(line),
        )
    }

    /// An estimate of the greatest VO top `h` for which [`Self::supports_beside`] holds with
    /// these arguments: minus infinity when it holds for none (the distances refuse, or the
    /// blocker's base stands too high: neither depends on `h`); else rule 2's upper bound `top >=
    /// high + RULE2_SLACK_M (1 + |high|)`, with `high = e1 + lambda (h - e1)`, solved for `h`
    /// (infinite when `lambda` is 0 and it holds). An estimate only, rounded either way: a caller
    /// checks the answer with `supports_beside` itself ([`super::certify`]'s `levels_beside`
    /// checks the level it points to and the next).
    pub fn top_beside_estimate(
        &self,
        e0: f64,
        e1: f64,
        g: f64,
        d_near_s: f64,
        d_bs: f64,
        line: f64,
    ) -> f64 {
        let Some(lambda) = self.lambda_beside(d_near_s, d_bs, line) else {
            return f64::NEG_INFINITY;
        };
        if !(lambda >= 0.0) {
            return f64::NEG_INFINITY;
        }
        let lambda = lambda.min(1.0);
        if !self.base_holds(e0, g, lambda) {
            return f64::NEG_INFINITY;
        }
        let high = (self.top - RULE2_SLACK_M) / (1.0 + RULE2_SLACK_M);
        if lambda > 0.0 {
            e1 + (high - e1) / lambda
        } else if self.top_holds(e1, e1, 0.0) {
            f64::INFINITY
        } else {
            f64::NEG_INFINITY
        }
    }

    /// The height this blocker ranks by in the slice histogram: the VO top it supports where
    /// rule 2 caps `lambda` at 1, its own top (0 when it cannot support a VO above the eyes).
    pub fn adjusted_height(&self, e1: f64) -> f64 {
        if self.top <= e1 {
            return 0.0;
        }
        self.top
    }
}

/// Slices a cell gets with `--slices auto` where its blockers stand tall ([`auto_slices`]).
pub const AUTO_SLICES: usize = 5;
/// Slices a cell gets with `--slices auto` where its blockers stand low ([`auto_slices`]), and
/// the most any cell gets (the hidden maps are built 8 slices at a time).
pub const MAX_SLICES: usize = 8;
/// Below this weighted median height of its blockers above the top eye, metres (about four
/// storeys), a cell is low-rise and gets [`MAX_SLICES`] slices with `--slices auto`.
pub const LOW_RISE_M: f64 = 12.0;

/// How many slices `--slices auto` gives a cell whose blockers are `adjusted` (the slice
/// histogram's (adjusted height, weight) pairs, [`Support::adjusted_height`]) with top eye
/// `e1`: [`MAX_SLICES`] when the weighted median of `height - e1` over the blockers that stand
/// above the eyes is below [`LOW_RISE_M`], else [`AUTO_SLICES`].
///
/// Why: where blockers stand only a few metres above the eyes, what a VO hides changes sharply
/// with its top (rule 3 lets an occludee rise `(h - e1) dl / d_line` above it), and five
/// quantile slices are too coarse there: 8 slices took Den Haag (every cell) from 22.2% to
/// 23.6% culled and Salt River with its DEM (every cell) from 5.4% to 6.3%. Among tall blockers
/// the extra slices add little (Tokyo centre, every cell: 90.0% against 89.9%) for 5 to 8% more
/// bake time. Which slices are baked decides nothing about safety: every VO is certified.
pub fn auto_slices(adjusted: &[(f64, f64)], e1: f64) -> usize {
    let mut above: Vec<(f64, f64)> = adjusted
        .iter()
        .filter(|&&(h, w)| h > e1 && w > 0.0)
        .map(|&(h, w)| (h - e1, w))
        .collect();
    let total: f64 = above.iter().map(|x| x.1).sum();
    if !(total > 0.0) {
        return AUTO_SLICES;
    }
    above.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut acc = 0.0;
    for &(h, w) in &above {
        acc += w;
        if acc >= 0.5 * total {
            return if h < LOW_RISE_M {
                MAX_SLICES
            } else {
                AUTO_SLICES
            };
        }
    }
    AUTO_SLICES
}

/// Picks up to `n` slice levels among `levels` (ascending VO tops, level index = position) from
/// blockers given as (adjusted height, weight): the level at which the weight of blockers still
/// tall enough falls to each of the fractions `1 - (i + 1/2) / n` of the total. Levels come out
/// ascending and distinct; none when no blocker reaches the lowest level above 0.
pub fn choose_levels(levels: &[f64], blockers: &[(f64, f64)], n: usize) -> Vec<u8> {
    let total: f64 = blockers
        .iter()
        .filter(|(h, _)| *h >= levels.get(1).copied().unwrap_or(f64::INFINITY))
        .map(|(_, w)| w)
        .sum();
    if n == 0 || !(total > 0.0) {
        return Vec::new();
    }
    // Weight still standing at each level.
    let standing: Vec<f64> = levels
        .iter()
        .map(|&l| {
            blockers
                .iter()
                .filter(|(h, _)| *h >= l)
                .map(|(_, w)| w)
                .sum()
        })
        .collect();
    let mut out: Vec<u8> = Vec::new();
    for i in 0..n {
        let f = 1.0 - (i as f64 + 0.5) / n as f64;
        // The highest level (above 0) at which at least that share still stands.
        if let Some(k) = (1..levels.len())
            .rev()
            .find(|&k| standing[k] >= f * total && standing[k] > 0.0)
        {
            if !out.contains(&(k as u8)) {
                out.push(k as u8);
            }
        }
    }
    out.sort_unstable();
    out
}

/// Area-angle of a blocker `poly` seen from `centre`, with walls `height` tall (paper 001, Coorg
/// and Teller), summed over the walls that face the centre: `a (N . V^) / |V|^2`, with `a` the
/// wall's area up to the slice (length times height), `N` its outward unit normal, `V` the
/// vector from the centre to the wall's midpoint and `V^` its direction. The slices' weights
/// ([`choose_levels`]) and the growth's seeds rank blockers by it.
pub fn area_angle(poly: &[DVec2], height: f64, centre: DVec2) -> f64 {
    let n = poly.len();
    let mut sum = 0.0;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let edge = b - a;
        let len = edge.length();
        if len == 0.0 {
            continue;
        }
        // Counter-clockwise polygon: the outward normal is the edge turned clockwise.
        let normal = DVec2::new(edge.y, -edge.x) / len;
        let v = (a + b) * 0.5 - centre;
        let d2 = v.length_squared();
        if d2 == 0.0 {
            continue;
        }
        let facing = -normal.dot(v / d2.sqrt());
        if facing > 0.0 {
            sum += len * height * facing / d2;
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sq(x0: f64, y0: f64, s: f64) -> Vec<DVec2> {
        vec![
            DVec2::new(x0, y0),
            DVec2::new(x0 + s, y0),
            DVec2::new(x0 + s, y0 + s),
            DVec2::new(x0, y0 + s),
        ]
    }

    #[test]
    fn distances_between_cell_and_blocker() {
        let cell = sq(0.0, 0.0, 10.0);
        let b = sq(20.0, 0.0, 10.0);
        assert!((d_near(&cell, &b) - 10.0).abs() < 1e-9 && d_near(&cell, &b) <= 10.0);
        let far = d_far(&cell, &b);
        assert!(far >= (900.0f64 + 100.0).sqrt() && far < (1000.0f64).sqrt() + 1e-9);
        let seg = [DVec2::new(5.0, 30.0), DVec2::new(50.0, 30.0)];
        assert!((d_near(&cell, &seg) - 20.0).abs() < 1e-9);
    }

    #[test]
    fn support_of_a_segment_blocker() {
        let cell = sq(0.0, 0.0, 10.0);
        let wall = [DVec2::new(-5.0, 30.0), DVec2::new(25.0, 40.0)];
        let s = Support::new(&cell, &wall, 0.0, 12.0);
        // Nearest: cell corner (0,10) to the wall's end (-5,30) (the foot of the perpendicular
        // on the wall's line falls just outside the wall).
        let near = 425.0f64.sqrt();
        let dn = d_near(&cell, &wall);
        assert!(dn <= near && dn > near - 1e-9, "{dn}");
        // Farthest: cell corner (0,0) to the wall's end (25,40).
        let far = (25.0f64 * 25.0 + 40.0 * 40.0).sqrt();
        assert!(s.d_far >= far && s.d_far < far + 1e-9, "{s:?}");
        assert_eq!((s.base, s.top), (0.0, 12.0));
        // A wall through the cell, one inside it, one touching it: 0.
        for w in [
            [DVec2::new(-5.0, 5.0), DVec2::new(15.0, 6.0)],
            [DVec2::new(2.0, 2.0), DVec2::new(3.0, 8.0)],
            [DVec2::new(10.0, 5.0), DVec2::new(20.0, 5.0)],
            [DVec2::new(12.0, 5.0), DVec2::new(10.0, 5.0)],
        ] {
            assert_eq!(d_near(&cell, &w), 0.0, "{w:?}");
        }
        // Edge-on, on the line of a cell edge past its corner.
        let w = [DVec2::new(10.0, 13.0), DVec2::new(10.0, 20.0)];
        assert!((d_near(&cell, &w) - 3.0).abs() < 1e-9);
        // A polygon holding the whole cell: 0 (no vertex-edge pair says so).
        assert_eq!(d_near(&cell, &sq(-10.0, -10.0, 40.0)), 0.0);
    }

    #[test]
    fn rule_2_tighter_bound() {
        // The blocker of `rule_2_bound`, 10 to 30 m from the cell, and a VO 20 m from the cell
        // but 15 m from the blocker (off to its side): lambda <= 30 / 45 instead of 1.
        let s = Support {
            base: 0.0,
            top: 12.0,
            d_far: 30.0,
        };
        // Bound: 2 + (h - 2) * 30 / 45 <= 12 <=> h <= 17.
        assert!(s.supports_beside(1.5, 2.0, 0.0, 16.99, 20.0, 15.0, 1.0));
        assert!(!s.supports_beside(1.5, 2.0, 0.0, 17.01, 20.0, 15.0, 1.0));
        // Touching the VO it gives the plain rule; never less than the plain rule.
        assert!(s.supports_beside(1.5, 2.0, 0.0, 11.99, 20.0, 0.0, 1.0));
        assert!(!s.supports_beside(1.5, 2.0, 0.0, 12.01, 20.0, 0.0, 1.0));
        assert!(s.supports_beside(1.5, 2.0, 0.0, 15.3, 40.0, 0.0, 1.0));
        // The line's bound, when lower, decides: 2 + (h - 2) / 2 <= 12 <=> h <= 22.
        assert!(s.supports_beside(1.5, 2.0, 0.0, 21.99, 20.0, 15.0, 0.5));
        assert!(!s.supports_beside(1.5, 2.0, 0.0, 22.01, 20.0, 15.0, 0.5));
        // A base above the VO's bottom: the lowest crossing is e0 - lambda (e0 - g) = 1.5 - 1.5
        // lambda, 0.5 at lambda = 2/3 and 0.75 at lambda = 1/2.
        let raised = Support { base: 0.6, ..s };
        assert!(!raised.supports_beside(1.5, 2.0, 0.0, 3.0, 40.0, 15.0, 1.0));
        assert!(raised.supports_beside(1.5, 2.0, 0.0, 3.0, 40.0, 15.0, 0.5));
    }

    #[test]
    fn line_lambda_is_the_ratio_of_distances_from_the_line() {
        let cell = sq(0.0, 0.0, 10.0);
        // The VO's line y = 30: the cell's far edge is 30 m from it, the blocker (y 10..20)
        // 10 m at its nearest: lambda <= 1 - 10 / 30.
        let (a, b) = (DVec2::new(-50.0, 30.0), DVec2::new(50.0, 30.0));
        let l = line_lambda(&cell, &sq(0.0, 10.0, 10.0), a, b);
        assert!((2.0 / 3.0..2.0 / 3.0 + 1e-6).contains(&l), "{l}");
        // Either orientation of the VO.
        assert_eq!(line_lambda(&cell, &sq(0.0, 10.0, 10.0), b, a), l);
        // A blocker reaching the line, or a line through the cell: 1.
        assert_eq!(line_lambda(&cell, &sq(0.0, 25.0, 10.0), a, b), 1.0);
        let through = (DVec2::new(-50.0, 5.0), DVec2::new(50.0, 6.0));
        assert_eq!(
            line_lambda(&cell, &sq(0.0, 20.0, 5.0), through.0, through.1),
            1.0
        );
    }

    /// Rule 2's tighter bounds against 3D rays: on random cells, blockers (some standing above
    /// the VO's bottom) and VOs, whenever the blocker supports the VO by
    /// [`Support::supports_beside`], every sampled ray from an eye to a point of the VO passes,
    /// over each sampled point of its 2D segment inside the blocker, between the blocker's base
    /// and top. The ray heights and the inside test are computed here
    /// from the points alone.
    #[test]
    fn rule_2_tighter_bound_holds_for_3d_rays() {
        let mut g = crate::testutil::Lcg(7);
        let mut rnd = move || g.next();
        let (e0, e1, g) = (1.5, 2.0, 0.0);
        let cell = [
            DVec2::new(0.0, 0.0),
            DVec2::new(50.0, 0.0),
            DVec2::new(50.0, 50.0),
            DVec2::new(0.0, 50.0),
        ];
        let (mut supported, mut tighter_only, mut raised, mut crossings) = (0, 0, 0, 0);
        for _ in 0..3000 {
            // A square blocker in front of the cell, a VO beyond it.
            let (bx, by, w) = (
                60.0 + 80.0 * rnd(),
                -60.0 + 170.0 * rnd(),
                4.0 + 20.0 * rnd(),
            );
            let poly = [
                DVec2::new(bx, by),
                DVec2::new(bx + w, by),
                DVec2::new(bx + w, by + w),
                DVec2::new(bx, by + w),
            ];
            let a = DVec2::new(bx + w + 1.0 + 100.0 * rnd(), -100.0 + 250.0 * rnd());
            let b = a + DVec2::new(-30.0 + 60.0 * rnd(), 20.0 + 150.0 * rnd());
            let top = 3.0 + 30.0 * rnd();
            let h = e1 + (top - e1) * (1.0 + 2.0 * rnd());
            // Half the blockers stand above the VO's bottom, up to the lowest eye.
            let base = if rnd() < 0.5 { g } else { g + (e0 - g) * rnd() };
            let sup = Support::new(&cell, &poly, base, top);
            let dn = d_near(&cell, &[a, b]);
            let dbs = d_near(&poly, &[a, b]);
            let line = line_lambda(&cell, &poly, a, b);
            if !sup.supports_beside(e0, e1, g, h, dn, dbs, line) {
                continue;
            }
            supported += 1;
            if !sup.supports(e0, e1, g, h, dn) {
                tighter_only += 1;
            }
            raised += (base > g) as usize;
            for _ in 0..40 {
                let p = DVec2::new(50.0 * rnd(), 50.0 * rnd());
                let (e, t) = (e0 + (e1 - e0) * rnd(), rnd());
                let x = a + (b - a) * t;
                // The VO's bottom and top edges too.
                let z = match t {
                    t if t < 0.1 => g,
                    t if t > 0.9 => h,
                    _ => g + (h - g) * rnd(),
                };
                let e = if rnd() < 0.2 { e0 } else { e };
                for k in 1..200 {
                    let f = k as f64 / 200.0;
                    let y = p + (x - p) * f;
                    if y.x >= bx && y.x <= bx + w && y.y >= by && y.y <= by + w {
                        crossings += 1;
                        let zy = e + (z - e) * f;
                        assert!(
                            zy <= top + 1e-9 && zy >= base - 1e-9,
                            "ray at {zy} over {y}: blocker {poly:?} base {base} top {top}, \
                             VO {a}-{b} top {h}"
                        );
                    }
                }
            }
        }
        // Many of them supported by the tighter bounds alone, many standing above the VO's
        // bottom.
        assert!(
            supported > 100 && tighter_only > 50 && raised > 50 && crossings > 1000,
            "{supported} {tighter_only} {raised} {crossings}"
        );
    }

    #[test]
    fn rule_2_bound() {
        // A blocker 10 to 30 m from a 10 m cell; a VO 40 m away; eyes at 2 m.
        let s = Support {
            base: 0.0,
            top: 12.0,
            d_far: 30.0,
        };
        // Bound: 2 + (h - 2) * 30 / 40 <= 12 <=> h <= 15.33.
        assert!(s.supports(1.5, 2.0, 0.0, 15.3, 40.0));
        assert!(!s.supports(1.5, 2.0, 0.0, 15.4, 40.0));
        // A VO nearer than the blocker's far side: lambda <= 1 caps the ratio, h <= t.
        assert!(s.supports(1.5, 2.0, 0.0, 11.99, 20.0));
        assert!(!s.supports(1.5, 2.0, 0.0, 12.01, 20.0));
        // A raised base does not support a VO down to the ground.
        let raised = Support { base: 0.5, ..s };
        assert!(!raised.supports(1.5, 2.0, 0.0, 3.0, 40.0));
        // The histogram ranks it by its top; not at all when it is no taller than the eyes.
        assert_eq!(s.adjusted_height(2.0), 12.0);
        assert_eq!(s.adjusted_height(12.0), 0.0);
    }

    #[test]
    fn levels_split_the_weight() {
        let levels = [2.0, 3.0, 5.0, 8.0, 13.0];
        // Half the weight reaches 5, the other half reaches 13.
        let b = [(6.0, 1.0), (6.0, 1.0), (20.0, 1.0), (20.0, 1.0)];
        // One slice: the highest level that half the weight still reaches.
        assert_eq!(choose_levels(&levels, &b, 1), vec![4]);
        assert_eq!(choose_levels(&levels, &b, 2), vec![2, 4]);
        assert_eq!(choose_levels(&levels, &[], 3), Vec::<u8>::new());
    }

    #[test]
    fn low_rise_cells_get_eight_slices_and_tall_ones_five() {
        let e1 = 10.0;
        // Houses 4 m above the eyes, weighted alike: low-rise.
        let houses: Vec<(f64, f64)> = (0..20).map(|i| (e1 + 3.0 + 0.1 * i as f64, 1.0)).collect();
        assert_eq!(auto_slices(&houses, e1), MAX_SLICES);
        // Towers 40 m above: tall.
        let towers: Vec<(f64, f64)> = (0..20).map(|i| (e1 + 40.0 + i as f64, 1.0)).collect();
        assert_eq!(auto_slices(&towers, e1), AUTO_SLICES);
        // The weights decide, not the count: three heavy towers among twenty light houses.
        let mut mixed = houses.clone();
        mixed.extend((0..3).map(|i| (e1 + 30.0 + i as f64, 10.0)));
        assert_eq!(auto_slices(&mixed, e1), AUTO_SLICES);
        // Blockers not above the eyes (adjusted height 0) count for nothing.
        let mut low = towers.clone();
        low.extend((0..100).map(|_| (0.0, 5.0)));
        assert_eq!(auto_slices(&low, e1), AUTO_SLICES);
        // Just under and at the threshold.
        assert_eq!(
            auto_slices(&[(e1 + LOW_RISE_M - 0.01, 1.0)], e1),
            MAX_SLICES
        );
        assert_eq!(auto_slices(&[(e1 + LOW_RISE_M, 1.0)], e1), AUTO_SLICES);
        // No blocker at all: the default.
        assert_eq!(auto_slices(&[], e1), AUTO_SLICES);
        // And choose_levels gives the low-rise cell more distinct levels with it.
        let levels: Vec<f64> = (0..32).map(|k| e1 + 0.25 * k as f64).collect();
        let five = choose_levels(&levels, &houses, AUTO_SLICES);
        let eight = choose_levels(&levels, &houses, MAX_SLICES);
        assert!(eight.len() > five.len(), "{five:?} {eight:?}");
    }
}
