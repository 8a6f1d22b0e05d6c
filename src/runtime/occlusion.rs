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
    /// Shrunk endpoints, oriented so that the cell lies left of `a -> b`.
    a: [f64; 2],
    b: [f64; 2],
    g: f64,
    h: f64,
    /// Greatest distance between the grown cell and the VO.
    d_far: f64,
    /// False when the VO's line meets the cell: its umbra is empty.
    usable: bool,
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
        let sides: Vec<f64> = cs.iter().map(|&c| orient(a, b, c)).collect();
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
        PreparedVo {
            a,
            b,
            g: vo.g,
            h: vo.h,
            d_far: d_far + MARGIN_M,
            usable,
        }
    }

    /// How this VO covers box `bx = [xmin, ymin, zmin, xmax, ymax, zmax]` seen from `view`.
    pub fn cover(&self, view: &CellView, bx: &[f64; 6]) -> Cover {
        if !self.usable {
            return Cover::Outside;
        }
        let m = MARGIN_M;
        let (x0, y0, x1, y1) = (bx[0] - m, bx[1] - m, bx[3] + m, bx[4] + m);
        let pts = [[x0, y0], [x1, y0], [x1, y1], [x0, y1]];
        let cs = corners(view);
        let (a, b) = (self.a, self.b);
        // Each half-plane of the umbra: all corners in it (strictly) is needed for Hidden; all
        // corners outside one of them (non-strictly) gives Outside.
        let mut all_in = true;
        let mut half_plane = |f: &dyn Fn([f64; 2]) -> f64| -> bool {
            let mut any_in = false;
            for &p in &pts {
                let v = f(p);
                if v > 0.0 {
                    any_in = true;
                } else {
                    all_in = false;
                }
            }
            !any_in
        };
        if half_plane(&|p| -orient(a, b, p)) {
            return Cover::Outside;
        }
        for c in cs {
            if half_plane(&|p| orient(c, a, p)) || half_plane(&|p| orient(c, p, b)) {
                return Cover::Outside;
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
        let top = view.e1 + (self.h - view.e1) * (d_near / self.d_far).max(1.0);
        // `zmin >= g` compares stored values, with no arithmetic: exact.
        let ok = bx[2] >= self.g && view.e0 >= self.g && bx[5] + m <= top && self.h >= view.e1;
        if ok {
            Cover::Hidden
        } else {
            Cover::Partial
        }
    }
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
        // D_near = 15 < D_far = dist((10,0), (-20,20)) = sqrt(1300): the ratio is capped at 1,
        // so the top bound is the VO's own top.
        let v = view();
        let w = wall(10.0);
        let top = 10.0;
        let under = [3.0, 25.0, 0.0, 7.0, 28.0, top - 0.01];
        let over = [3.0, 25.0, 0.0, 7.0, 28.0, top + 0.01];
        assert!(hides(&v, &w, &under));
        assert!(!hides(&v, &w, &over));
        // Below the VO's bottom: visible under it.
        assert!(!hides(&v, &w, &[3.0, 25.0, -1.0, 7.0, 28.0, 1.0]));
        // Far behind (D_near = 90 > D_far), a box may rise above the VO's top.
        let top = 2.0 + 8.0 * (90.0 - 0.002) / (1300f64.sqrt() + 0.002);
        assert!(hides(&v, &w, &[3.0, 100.0, 0.0, 7.0, 101.0, top - 0.01]));
        assert!(!hides(&v, &w, &[3.0, 100.0, 0.0, 7.0, 101.0, top + 0.01]));
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
}
