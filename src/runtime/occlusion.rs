//! Rule 3 (DESIGN.md section 3): is an occludee box hidden from a cell by one VO?
//!
//! Input: a [`CellView`] (rectangle and eye heights), a [`VoGeom`] and a box
//! `[xmin, ymin, zmin, xmax, ymax, zmax]`, all in the local frame.
//! Output: [`Cover`]: the box is hidden, the box lies wholly outside the VO's 2D umbra (so no
//! box inside it can be hidden by this VO), or neither.
//! Invariants (conservative by construction, plain f64, no geometry stack):
//! - before any test the box and the cell grow by [`MARGIN_M`] and the VO shrinks by it at each
//!   end, so float rounding (below 1e-9 m at the coordinates a store uses) can only make a
//!   hidden box look visible, never the reverse;
//! - a box that touches the (grown) cell is never hidden;
//! - `Hidden` for a box implies `Hidden` for every box inside it (all three conditions are
//!   monotone), which lets the culler cull a whole subtree at once.
//!
//! ## The 2D umbra of a segment from a convex cell
//! Let the cell lie strictly left of the directed line `a -> b` (swap `a` and `b` otherwise; if
//! the line meets the cell the umbra is empty). For a point `p` right of that line, the set of
//! cell points `c` whose segment to `p` meets `a–b` is the cone from `p` through the segment,
//! which is convex; so every segment from the cell to `p` meets the VO exactly when every cell
//! *vertex* `c` sees `p` between its rays to `a` and `b`: `orient(c, a, p) >= 0` and
//! `orient(c, p, b) >= 0`. The umbra is an intersection of half-planes, hence convex, so a box
//! footprint lies in it exactly when its four corners do.
//!
//! ## Heights
//! The box is hidden when its footprint lies in the umbra, `zmin >= g`, `e0 >= g`, and
//! `zmax <= e1 + (h - e1) * max(1, D_near / D_far)`, with `D_near` the least distance between the
//! cell and the footprint and `D_far` the greatest distance between the cell and the VO. The
//! brief's rule 3 has the ratio alone; the ray from an eye to the box crosses the VO's line
//! before it reaches the box, so the ratio can also be taken as at least 1. Proof in
//! ARCHITECTURE.md ("Rules 2 and 3").

use crate::runtime::frame::{CellView, VoGeom};

/// Safety margin of the runtime test, metres: boxes and cells grow by it, VOs shrink by it.
pub const MARGIN_M: f64 = 0.001;

/// How one VO covers a box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cover {
    /// Every point of the box is hidden from every eye of the cell.
    Hidden,
    /// No point of the box's footprint is in the VO's 2D umbra: no box inside it is hidden.
    Outside,
    /// Neither can be shown.
    Partial,
}

#[inline]
fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// A VO prepared for many box tests against one cell.
#[derive(Clone, Copy, Debug)]
pub struct PreparedVo {
    g: f64,
    h: f64,
    /// Greatest distance between the grown cell and the VO.
    d_far: f64,
    /// False when the VO's line meets the cell: its umbra is empty.
    usable: bool,
    /// The umbra's binding half-planes as linear forms `f(p) = k[0] p.x + k[1] p.y + k[2]`,
    /// `f > 0` inside: `-orient(a, b, p)`, `orient(c_a, a, p)` and `orient(c_b, p, b)` (the same
    /// polynomials as the orientation tests, expanded). Of the constraints `orient(c, a, p) >= 0`
    /// over the cell corners `c`, all pass through `a`, so their intersection is the cone at `a`
    /// bounded by the most counter-clockwise direction `a - c`: that corner is `c_a`; likewise
    /// `c_b` is the corner whose `b - c` is most clockwise. (Near-parallel candidates differ by
    /// rounding only, far below [`MARGIN_M`].)
    planes: [[f64; 3]; 3],
    /// The VO's endpoints (shrunk, oriented with the cell on the left of `a -> b`).
    a: [f64; 2],
    b: [f64; 2],
    /// The grown cell's corners.
    cs: [[f64; 2]; 4],
    /// Least distance between the grown cell and the VO (rounded down).
    d_near: f64,
}

/// `orient(u, v, p)` as a linear form in `p`.
fn linear(u: [f64; 2], v: [f64; 2]) -> [f64; 3] {
    // (v - u) x (p - u) = (vx - ux)(py - uy) - (vy - uy)(px - ux)
    let (dx, dy) = (v[0] - u[0], v[1] - u[1]);
    [-dy, dx, dy * u[0] - dx * u[1]]
}

/// The grown cell's corners, counter-clockwise.
fn corners(view: &CellView) -> [[f64; 2]; 4] {
    let [x0, y0, x1, y1] = view.rect;
    let m = MARGIN_M;
    [
        [x0 - m, y0 - m],
        [x1 + m, y0 - m],
        [x1 + m, y1 + m],
        [x0 - m, y1 + m],
    ]
}

impl PreparedVo {
    pub fn new(view: &CellView, vo: &VoGeom) -> PreparedVo {
        let (mut a, mut b) = (vo.a, vo.b);
        let d = [b[0] - a[0], b[1] - a[1]];
        let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
        let mut usable = len.is_finite() && len > 2.0 * MARGIN_M && vo.h.is_finite();
        if usable {
            let s = MARGIN_M / len;
            a = [a[0] + d[0] * s, a[1] + d[1] * s];
            b = [b[0] - d[0] * s, b[1] - d[1] * s];
        }
        let cs = corners(view);
        let sides = cs.map(|c| orient(a, b, c));
        if sides.iter().all(|&s| s < 0.0) {
            std::mem::swap(&mut a, &mut b);
        } else if !sides.iter().all(|&s| s > 0.0) {
            usable = false;
        }
        let mut d_far: f64 = 0.0;
        for c in cs {
            for p in [vo.a, vo.b] {
                d_far = d_far.max(((c[0] - p[0]).powi(2) + (c[1] - p[1]).powi(2)).sqrt());
            }
        }
        let cross = |u: [f64; 2], v: [f64; 2]| u[0] * v[1] - u[1] * v[0];
        let away = |p: [f64; 2], c: [f64; 2]| [p[0] - c[0], p[1] - c[1]];
        let (mut ca, mut cb) = (cs[0], cs[0]);
        for &c in &cs[1..] {
            if cross(away(a, ca), away(a, c)) > 0.0 {
                ca = c;
            }
            if cross(away(b, cb), away(b, c)) < 0.0 {
                cb = c;
            }
        }
        let l = linear(a, b);
        // orient(c, p, b) = orient(b, c, p).
        let planes = [[-l[0], -l[1], -l[2]], linear(ca, a), linear(b, cb)];
        let mut d_near = f64::INFINITY;
        for c in cs {
            d_near = d_near.min(point_segment(c, a, b));
        }
        for p in [a, b] {
            d_near = d_near.min(point_rect(p, view.rect) - MARGIN_M);
        }
        PreparedVo {
            planes,
            g: vo.g,
            h: vo.h,
            d_far: d_far + MARGIN_M,
            usable,
            a,
            b,
            cs,
            d_near: (d_near - MARGIN_M).max(0.0),
        }
    }

    /// The tighter height factor `1 / mu` of rule 3 for a footprint `[x0, y0, x1, y1]` (grown)
    /// lying in the umbra: `max(1, D_near / D_far', 1 + dist(F, line(s)) / D_far')`, where
    /// `D_far'` is the greatest distance from the cell to the part of the VO that segments
    /// from the cell to the footprint can cross (ARCHITECTURE.md, "Rule 3, the tighter bound").
    fn factor(&self, fp: [f64; 4], d_near: f64) -> f64 {
        let m = MARGIN_M;
        let (a, b) = (self.a, self.b);
        let d = [b[0] - a[0], b[1] - a[1]];
        let l2 = d[0] * d[0] + d[1] * d[1];
        let len = l2.sqrt();
        let cross = |u: [f64; 2], v: [f64; 2]| u[0] * v[1] - u[1] * v[0];
        let ws = [
            [fp[0], fp[1]],
            [fp[2], fp[1]],
            [fp[2], fp[3]],
            [fp[0], fp[3]],
        ];
        // Crossings of the segments between corners of the cell and of the footprint with the
        // VO's line: their parameters along a -> b bound those of every such segment.
        let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
        for c in self.cs {
            for w in ws {
                let cw = [w[0] - c[0], w[1] - c[1]];
                let den = cross(cw, d);
                if !(den.abs() > 0.0) {
                    return 1.0;
                }
                let u = cross([a[0] - c[0], a[1] - c[1]], d) / den;
                let x = [c[0] + u * cw[0] - a[0], c[1] + u * cw[1] - a[1]];
                let t = (x[0] * d[0] + x[1] * d[1]) / l2;
                t0 = t0.min(t);
                t1 = t1.max(t);
            }
        }
        let slack = m / len;
        let (t0, t1) = ((t0 - slack).max(0.0), (t1 + slack).min(1.0));
        if !(t0 <= t1) {
            return 1.0;
        }
        let p0 = [a[0] + t0 * d[0], a[1] + t0 * d[1]];
        let p1 = [a[0] + t1 * d[0], a[1] + t1 * d[1]];
        let mut df: f64 = 0.0;
        for c in self.cs {
            for p in [p0, p1] {
                df = df.max(((c[0] - p[0]).powi(2) + (c[1] - p[1]).powi(2)).sqrt());
            }
        }
        let df = df + m;
        // Distance of the footprint beyond the VO's line (the cell is on its left).
        let mut dl = f64::INFINITY;
        for w in ws {
            dl = dl.min(-orient(a, b, w) / len);
        }
        let dl = (dl - m).max(0.0);
        (d_near / df).max(1.0 + dl / df).max(1.0)
    }

    /// How this VO covers box `bx = [xmin, ymin, zmin, xmax, ymax, zmax]` seen from `view`.
    pub fn cover(&self, view: &CellView, bx: &[f64; 6]) -> Cover {
        if !self.usable {
            return Cover::Outside;
        }
        let m = MARGIN_M;
        let (x0, y0, x1, y1) = (bx[0] - m, bx[1] - m, bx[3] + m, bx[4] + m);
        // Over the box, each linear form is least and greatest at the corners its coefficients
        // pick. All corners strictly in every half-plane is needed for Hidden; all corners
        // outside one of them (non-strictly) gives Outside.
        let mut all_in = true;
        for k in &self.planes {
            let (lo_x, hi_x) = if k[0] >= 0.0 { (x0, x1) } else { (x1, x0) };
            let (lo_y, hi_y) = if k[1] >= 0.0 { (y0, y1) } else { (y1, y0) };
            let max = k[0] * hi_x + k[1] * hi_y + k[2];
            if !(max > 0.0) {
                return Cover::Outside;
            }
            let min = k[0] * lo_x + k[1] * lo_y + k[2];
            if !(min > 0.0) {
                all_in = false;
            }
        }
        if !all_in {
            return Cover::Partial;
        }
        // Heights. A box touching the cell has D_near = 0 and fails the top test unless the
        // VO does not rise above the eyes; it is also refused outright.
        let [cx0, cy0, cx1, cy1] = view.rect;
        let dx = (x0 - (cx1 + m)).max((cx0 - m) - x1).max(0.0);
        let dy = (y0 - (cy1 + m)).max((cy0 - m) - y1).max(0.0);
        let d_near = (dx * dx + dy * dy).sqrt();
        if d_near <= 0.0 {
            return Cover::Partial;
        }
        let mut top = view.e1 + (self.h - view.e1) * (d_near / self.d_far).max(1.0);
        if bx[5] + m > top && self.h > view.e1 {
            // Both bounds hold (ARCHITECTURE.md, rule 3): the larger one decides.
            top = top.max(view.e1 + (self.h - view.e1) * self.factor([x0, y0, x1, y1], d_near));
        }
        // `zmin >= g` compares stored values, with no arithmetic: exact.
        let ok = bx[2] >= self.g && view.e0 >= self.g && bx[5] + m <= top && self.h >= view.e1;
        if ok {
            Cover::Hidden
        } else {
            Cover::Partial
        }
    }
}

impl PreparedVo {
    /// How this VO covers a group of boxes with bounds `bounds` whose least top is `min_top`:
    /// [`Self::cover`] of the bounds, except that `Partial` becomes `Outside` when no box of the
    /// group can meet rule 3's height bound. A box inside the bounds is at most `d_max` (the
    /// greatest distance between the cell and the bounds' footprint) from the cell, so its
    /// `D_near <= d_max` and its top bound is at most `e1 + (h - e1) max(1, d_max / D_far)`; a
    /// group whose every top exceeds that has no box this VO hides.
    pub fn cover_group(&self, view: &CellView, bounds: &[f64; 6], min_top: f64) -> Cover {
        let c = self.cover(view, bounds);
        if c != Cover::Partial {
            return c;
        }
        let [cx0, cy0, cx1, cy1] = view.rect;
        let dx = (bounds[3] - cx0).abs().max((cx1 - bounds[0]).abs());
        let dy = (bounds[4] - cy0).abs().max((cy1 - bounds[1]).abs());
        let d_max = (dx * dx + dy * dy).sqrt() + 2.0 * MARGIN_M;
        // Every factor of a box inside is at most 1 + d_max / d_near(s): its D_near and its
        // distance beyond the VO's line are at most d_max, and D_far' >= d_near(s).
        let top_max = if self.d_near > 0.0 {
            view.e1 + (self.h - view.e1).max(0.0) * (1.0 + d_max / self.d_near)
        } else {
            f64::INFINITY
        };
        if min_top > top_max + MARGIN_M {
            Cover::Outside
        } else {
            Cover::Partial
        }
    }
}

/// Least distance from `p` to the segment `[a, b]`.
fn point_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    let l2 = d[0] * d[0] + d[1] * d[1];
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((p[0] - a[0] - t * d[0]).powi(2) + (p[1] - a[1] - t * d[1]).powi(2)).sqrt()
}

/// Least distance from `p` to the rectangle `[x0, y0, x1, y1]`.
fn point_rect(p: [f64; 2], r: [f64; 4]) -> f64 {
    let dx = (r[0] - p[0]).max(p[0] - r[2]).max(0.0);
    let dy = (r[1] - p[1]).max(p[1] - r[3]).max(0.0);
    (dx * dx + dy * dy).sqrt()
}

/// Whether `vo` hides box `bx` from `view` (rule 3).
pub fn hides(view: &CellView, vo: &VoGeom, bx: &[f64; 6]) -> bool {
    PreparedVo::new(view, vo).cover(view, bx) == Cover::Hidden
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view() -> CellView {
        CellView {
            rect: [0.0, 0.0, 10.0, 10.0],
            e0: 1.5,
            e1: 2.0,
        }
    }

    fn wall(h: f64) -> VoGeom {
        VoGeom {
            a: [-20.0, 20.0],
            b: [30.0, 20.0],
            g: 0.0,
            h,
        }
    }

    #[test]
    fn a_low_box_right_behind_a_wide_wall_is_hidden() {
        let bx = [3.0, 25.0, 0.0, 7.0, 28.0, 2.0];
        assert_eq!(
            PreparedVo::new(&view(), &wall(10.0)).cover(&view(), &bx),
            Cover::Hidden
        );
        // Either orientation of the VO.
        let mut w = wall(10.0);
        std::mem::swap(&mut w.a, &mut w.b);
        assert!(hides(&view(), &w, &bx));
    }

    #[test]
    fn the_top_bound_follows_rule_3() {
        // D_near = 15 < D_far = dist((10,0), (-20,20)) = sqrt(1300): the plain ratio is capped
        // at 1. The tighter bound: segments from the cell to the box x 3..7, y 25..28 cross the
        // VO's line y = 20 between x = 5/3 and 25/3, so D_far' = dist((0,0), (25/3, 20)) =
        // 65/3, and the box lies 5 m beyond the line: the factor is 1 + 5 / (65/3) = 16/13, the
        // top 2 + 8 * 16/13 = 11.846 (less the margins).
        let v = view();
        let w = wall(10.0);
        let top = 2.0 + 8.0 * 16.0 / 13.0;
        let under = [3.0, 25.0, 0.0, 7.0, 28.0, top - 0.02];
        let over = [3.0, 25.0, 0.0, 7.0, 28.0, top + 0.02];
        assert!(hides(&v, &w, &under));
        assert!(!hides(&v, &w, &over));
        // Below the VO's bottom: visible under it.
        assert!(!hides(&v, &w, &[3.0, 100.0, -1.0, 7.0, 101.0, 1.0]));
        // Far behind: D_near = 90, the plain bound 2 + 8 * 90 / sqrt(1300) = 21.97; the tighter
        // one, with crossings between x = 0.330 and 9.670 and the box 80 m beyond the line, is
        // 2 + 8 * (1 + 80 / 22.215) = 38.81: the larger decides.
        let top = 38.809;
        assert!(hides(&v, &w, &[3.0, 100.0, 0.0, 7.0, 101.0, top - 0.02]));
        assert!(!hides(&v, &w, &[3.0, 100.0, 0.0, 7.0, 101.0, top + 0.02]));
    }

    #[test]
    fn boxes_beside_in_front_or_touching_are_not_hidden() {
        let v = view();
        let w = wall(10.0);
        // Beside the umbra: the cone from cell corner (10, 0) through (30, 20) leaves x = 40 at
        // y = 30.
        assert_eq!(
            PreparedVo::new(&v, &w).cover(&v, &[45.0, 25.0, 0.0, 50.0, 30.0, 1.0]),
            Cover::Outside
        );
        // In front of the VO.
        assert_eq!(
            PreparedVo::new(&v, &w).cover(&v, &[3.0, 12.0, 0.0, 7.0, 15.0, 1.0]),
            Cover::Outside
        );
        // Straddling the umbra's edge.
        assert_eq!(
            PreparedVo::new(&v, &w).cover(&v, &[25.0, 25.0, 0.0, 45.0, 30.0, 1.0]),
            Cover::Partial
        );
        // A VO whose line crosses the cell hides nothing.
        let crossing = VoGeom {
            a: [5.0, -10.0],
            b: [5.0, 40.0],
            g: 0.0,
            h: 50.0,
        };
        assert_eq!(
            PreparedVo::new(&v, &crossing).cover(&v, &[20.0, 0.0, 0.0, 22.0, 2.0, 1.0]),
            Cover::Outside
        );
    }

    #[test]
    fn hidden_is_monotone_under_inclusion() {
        let v = view();
        let p = PreparedVo::new(&v, &wall(10.0));
        let outer = [0.0, 22.0, 0.0, 10.0, 40.0, 3.0];
        assert_eq!(p.cover(&v, &outer), Cover::Hidden);
        for inner in [
            [1.0, 23.0, 0.5, 9.0, 39.0, 2.5],
            [4.0, 30.0, 1.0, 5.0, 31.0, 2.0],
        ] {
            assert_eq!(p.cover(&v, &inner), Cover::Hidden);
        }
    }

    /// Rule 3 written out plainly: every grown corner strictly inside all nine umbra
    /// half-planes (the beyond-line plane and both planes of each cell corner), then heights.
    fn plain_hidden(v: &CellView, vo: &VoGeom, bx: &[f64; 6]) -> bool {
        let m = MARGIN_M;
        let d = [vo.b[0] - vo.a[0], vo.b[1] - vo.a[1]];
        let len = d[0].hypot(d[1]);
        let s = m / len;
        let (mut a, mut b) = (
            [vo.a[0] + d[0] * s, vo.a[1] + d[1] * s],
            [vo.b[0] - d[0] * s, vo.b[1] - d[1] * s],
        );
        let cs = corners(v);
        if cs.iter().all(|&c| orient(a, b, c) < 0.0) {
            std::mem::swap(&mut a, &mut b);
        } else if !cs.iter().all(|&c| orient(a, b, c) > 0.0) {
            return false;
        }
        let (x0, y0, x1, y1) = (bx[0] - m, bx[1] - m, bx[3] + m, bx[4] + m);
        for p in [[x0, y0], [x1, y0], [x1, y1], [x0, y1]] {
            if !(orient(a, b, p) < 0.0) {
                return false;
            }
            for c in cs {
                if !(orient(c, a, p) > 0.0 && orient(c, p, b) > 0.0) {
                    return false;
                }
            }
        }
        let [cx0, cy0, cx1, cy1] = v.rect;
        let dx = (x0 - (cx1 + m)).max((cx0 - m) - x1).max(0.0);
        let dy = (y0 - (cy1 + m)).max((cy0 - m) - y1).max(0.0);
        let d_near = dx.hypot(dy);
        let mut d_far: f64 = 0.0;
        for c in cs {
            for q in [vo.a, vo.b] {
                d_far = d_far.max((c[0] - q[0]).hypot(c[1] - q[1]));
            }
        }
        let top = v.e1 + (vo.h - v.e1) * (d_near / (d_far + m)).max(1.0);
        d_near > 0.0 && bx[2] >= vo.g && bx[5] + m <= top && vo.h >= v.e1
    }

    /// Whether the 3D segment from eye `p` to point `w` passes through the VO's quad (the 2D
    /// segments cross and the ray's height over the crossing lies in `[g, h]`): a brute-force
    /// ray, written apart from the rule.
    fn ray_meets_quad(vo: &VoGeom, p: [f64; 3], w: [f64; 3]) -> bool {
        let (a, b) = (vo.a, vo.b);
        let r = [w[0] - p[0], w[1] - p[1]];
        let d = [b[0] - a[0], b[1] - a[1]];
        let den = r[0] * d[1] - r[1] * d[0];
        if den == 0.0 {
            return false;
        }
        let ap = [a[0] - p[0], a[1] - p[1]];
        let t = (ap[0] * d[1] - ap[1] * d[0]) / den; // along p -> w
        let u = (ap[0] * r[1] - ap[1] * r[0]) / den; // along a -> b
        if !((0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u)) {
            return false;
        }
        let z = p[2] + t * (w[2] - p[2]);
        vo.g <= z && z <= vo.h
    }

    #[test]
    fn rule_3_with_the_tighter_bound_hides_only_what_3d_rays_show_hidden() {
        // A fixed linear congruential sequence: VOs around a 10 m cell, boxes around them.
        let mut x: u64 = 12345;
        let mut r = |lo: f64, hi: f64| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            lo + (hi - lo) * ((x >> 11) as f64 / (1u64 << 53) as f64)
        };
        let v = view();
        let (mut hidden, mut outside, mut gained) = (0, 0, 0);
        for _ in 0..4000 {
            let vo = VoGeom {
                a: [r(-60.0, 70.0), r(-60.0, 70.0)],
                b: [r(-60.0, 70.0), r(-60.0, 70.0)],
                g: 0.0,
                h: r(2.0, 30.0),
            };
            let p = PreparedVo::new(&v, &vo);
            for _ in 0..10 {
                let (cx, cy, w, d) = (
                    r(-150.0, 160.0),
                    r(-150.0, 160.0),
                    r(0.5, 30.0),
                    r(0.5, 30.0),
                );
                let bx = [cx, cy, 0.0, cx + w, cy + d, r(0.5, 80.0)];
                let c = p.cover(&v, &bx);
                // The plain rule (three planes, the D_near / D_far bound) is implied.
                if plain_hidden(&v, &vo, &bx) {
                    assert_eq!(c, Cover::Hidden, "{vo:?} {bx:?}");
                }
                if c == Cover::Hidden {
                    hidden += 1;
                    gained += !plain_hidden(&v, &vo, &bx) as usize;
                    // Rays from eyes of the cell (corners, centre, random; lowest and highest
                    // eye) to points of the box (corners, random) all pass through the quad.
                    for k in 0..40 {
                        let (ex, ey) = match k {
                            0 => (0.0, 0.0),
                            1 => (10.0, 0.0),
                            2 => (10.0, 10.0),
                            3 => (0.0, 10.0),
                            4 => (5.0, 5.0),
                            _ => (r(0.0, 10.0), r(0.0, 10.0)),
                        };
                        let e = [ex, ey, if k % 2 == 0 { v.e0 } else { v.e1 }];
                        let wp = if k < 8 {
                            [
                                bx[3 * (k & 1)],
                                bx[1 + 3 * ((k >> 1) & 1)],
                                bx[2 + 3 * ((k >> 2) & 1)],
                            ]
                        } else {
                            [r(bx[0], bx[3]), r(bx[1], bx[4]), r(bx[2], bx[5])]
                        };
                        assert!(ray_meets_quad(&vo, e, wp), "{vo:?} {bx:?} {e:?} {wp:?}");
                    }
                }
                if c == Cover::Outside {
                    outside += 1;
                    // No sub-box is hidden.
                    for k in 0..4 {
                        let f = k as f64 / 4.0;
                        let sub = [
                            cx + f * w,
                            cy + f * d,
                            0.0,
                            cx + f * w + 0.1,
                            cy + f * d + 0.1,
                            0.1,
                        ];
                        assert_ne!(p.cover(&v, &sub), Cover::Hidden, "{vo:?} {sub:?}");
                    }
                }
            }
        }
        assert!(
            hidden > 100 && outside > 1000 && gained > 10,
            "{hidden} hidden ({gained} by the tighter bound alone), {outside} outside"
        );
    }
}
