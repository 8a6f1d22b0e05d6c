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
    /// `1 / d_far` and `1 / d_line` (their rounding changes a height factor by a relative
    /// 1e-16, a top by far less than the margin).
    inv_d_far: f64,
    inv_d_line: f64,
    /// The signed distance beyond the VO's line (the side away from the cell) as a linear form,
    /// `-orient(a, b, p) / |b - a|`.
    beyond_form: [f64; 3],
    /// Greatest distance between the grown cell and the VO's line, rounded down by the margin
    /// (a lower bound of every `D_far'` of [`Self::factor`]; the least positive float when it is
    /// not positive, so that the bound it gives is infinite).
    d_line: f64,
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
    /// The grown cell's corners in the VO's coordinates: `(t, s)`, `t` along `a -> b` from
    /// `a`, `s > 0` the distance from the VO's line.
    ts: [[f64; 2]; 4],
    /// The least and greatest `t` and `s` of [`Self::ts`]: `[t_min, t_max, s_min, s_max]`.
    ts_range: [f64; 4],
    /// `t` of a point as a linear form (unit direction `a -> b`, 0 at `a`).
    along: [f64; 3],
    /// `|b - a|` (shrunk).
    len: f64,
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
        let norm = planes[0][0].hypot(planes[0][1]);
        let beyond_form = if norm > 0.0 {
            planes[0].map(|k| k / norm)
        } else {
            [0.0; 3]
        };
        let u = if norm > 0.0 {
            [(b[0] - a[0]) / norm, (b[1] - a[1]) / norm]
        } else {
            [0.0; 2]
        };
        let along = [u[0], u[1], -(u[0] * a[0] + u[1] * a[1])];
        let ts = cs.map(|c| {
            let k = beyond_form;
            [
                along[0] * c[0] + along[1] * c[1] + along[2],
                -(k[0] * c[0] + k[1] * c[1] + k[2]),
            ]
        });
        let mut d_line: f64 = 0.0;
        for c in cs {
            d_line = d_line.max(orient(a, b, c).abs() / norm);
        }
        let d_line = d_line - MARGIN_M;
        let d_line = if d_line > 0.0 {
            d_line
        } else {
            f64::MIN_POSITIVE
        };
        let d_far = d_far + MARGIN_M;
        PreparedVo {
            inv_d_far: 1.0 / d_far,
            inv_d_line: 1.0 / d_line,
            planes,
            beyond_form,
            g: vo.g,
            h: vo.h,
            d_far,
            d_line,
            usable,
            ts,
            ts_range: [
                ts.iter().map(|c| c[0]).fold(f64::INFINITY, f64::min),
                ts.iter().map(|c| c[0]).fold(f64::NEG_INFINITY, f64::max),
                ts.iter().map(|c| c[1]).fold(f64::INFINITY, f64::min),
                ts.iter().map(|c| c[1]).fold(f64::NEG_INFINITY, f64::max),
            ],
            along,
            len: norm,
        }
    }

    /// The tighter height factor `1 / mu` of rule 3 for a footprint `[x0, y0, x1, y1]` (grown)
    /// lying in the umbra: `max(1, D_near / D_far', 1 + dist(F, line(s)) / D_far')`, where
    /// `D_far'` is the greatest distance from the cell to the part of the VO that segments
    /// from the cell to the footprint can cross (ARCHITECTURE.md, "Rule 3, the tighter bound").
    fn factor(&self, fp: [f64; 4], d_near: f64, dl: f64) -> f64 {
        // In the VO's own coordinates (`t` along `a -> b` from `a`, `s` the distance beyond its
        // line), the segment from a cell corner `(t_c, -s_c)` to a footprint corner
        // `(t_w, s_w)` (`s_c, s_w > 0`) crosses the line at `t = (t_c s_w + t_w s_c) / (s_c +
        // s_w)`. The crossings of the 16 corner pairs bound those of every segment from the
        // cell to the footprint (both convex).
        let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
        for w in [
            [fp[0], fp[1]],
            [fp[2], fp[1]],
            [fp[2], fp[3]],
            [fp[0], fp[3]],
        ] {
            let tw = self.along[0] * w[0] + self.along[1] * w[1] + self.along[2];
            let k = self.beyond_form;
            let sw = k[0] * w[0] + k[1] * w[1] + k[2];
            if !(sw > 0.0) {
                return 1.0;
            }
            for [tc, sc] in self.ts {
                let t = (tc * sw + tw * sc) / (sc + sw);
                t0 = t0.min(t);
                t1 = t1.max(t);
            }
        }
        self.span_factor(t0, t1, d_near, dl)
    }

    /// [`Self::factor`] from a span `[t0, t1]` of the VO's line holding every crossing (the
    /// tighter bound holds for any such span: a wider one only makes `D_far'` larger).
    fn span_factor(&self, t0: f64, t1: f64, d_near: f64, dl: f64) -> f64 {
        let m = MARGIN_M;
        let (t0, t1) = ((t0 - m).max(0.0), (t1 + m).min(self.len));
        if !(t0 <= t1) {
            return 1.0;
        }
        // The greatest distance from a cell corner to the crossings' span `[t0, t1]`.
        let mut df2: f64 = 0.0;
        for [tc, sc] in self.ts {
            let e = (t0 - tc).abs().max((t1 - tc).abs());
            df2 = df2.max(e * e + sc * sc);
        }
        let df = df2.sqrt() + m;
        (d_near / df).max(1.0 + dl / df).max(1.0)
    }

    /// A cheaper [`Self::factor`], from a span that holds the crossings without computing
    /// them: the crossing of the segment from cell corner `(t_c, -s_c)` to footprint point
    /// `(t_w, s_w)` is `t = lam t_w + (1 - lam) t_c` with `lam = s_c / (s_c + s_w)`, which lies
    /// between `lam_min = s_c,min / (s_c,min + s_w,max)` and `lam_max = s_c,max / (s_c,max +
    /// s_w,min)`. For a fixed `lam`, `t >= t_c,min + lam (t_w,min - t_c,min)`, linear in `lam`,
    /// so `t` is at least the lesser of its values at `lam_min` and `lam_max`; likewise for the
    /// greatest `t`. Two divisions instead of sixteen; never above the exact factor by more
    /// than rounding, which the margin covers.
    fn coarse_factor(&self, fp: [f64; 4], d_near: f64, dl: f64) -> f64 {
        let lin = |k: [f64; 3]| {
            let (x0, x1) = (k[0] * fp[0], k[0] * fp[2]);
            let (y0, y1) = (k[1] * fp[1], k[1] * fp[3]);
            (
                x0.min(x1) + y0.min(y1) + k[2],
                x0.max(x1) + y0.max(y1) + k[2],
            )
        };
        let (tw0, tw1) = lin(self.along);
        let (sw0, sw1) = lin(self.beyond_form);
        if !(sw0 > 0.0) {
            return 1.0;
        }
        let [tc0, tc1, sc0, sc1] = self.ts_range;
        let lam0 = sc0 / (sc0 + sw1);
        let lam1 = sc1 / (sc1 + sw0);
        let lo = |lam: f64| tc0 + lam * (tw0 - tc0);
        let hi = |lam: f64| tc1 + lam * (tw1 - tc1);
        let t0 = lo(lam0).min(lo(lam1));
        let t1 = hi(lam0).max(hi(lam1));
        self.span_factor(t0, t1, d_near, dl)
    }

    /// The least distance of the footprint `[x0, y0, x1, y1]` (grown) beyond the VO's line
    /// (the cell is on its left), rounded down by the margin, and not below 0.
    #[inline]
    fn beyond(&self, fp: [f64; 4]) -> f64 {
        let k = self.beyond_form;
        let x = if k[0] >= 0.0 { fp[0] } else { fp[2] };
        let y = if k[1] >= 0.0 { fp[1] } else { fp[3] };
        (k[0] * x + k[1] * y + k[2] - MARGIN_M).max(0.0)
    }

    /// The greatest signed distance of the footprint `fp` beyond the VO's line (not rounded).
    #[inline]
    fn beyond_max(&self, fp: [f64; 4]) -> f64 {
        let k = self.beyond_form;
        let x = if k[0] >= 0.0 { fp[2] } else { fp[0] };
        let y = if k[1] >= 0.0 { fp[3] } else { fp[1] };
        k[0] * x + k[1] * y + k[2]
    }

    /// How this VO covers box `bx = [xmin, ymin, zmin, xmax, ymax, zmax]` seen from `view`.
    pub fn cover(&self, view: &CellView, bx: &[f64; 6]) -> Cover {
        self.cover_probe(view, &Probe::new(view, bx))
    }

    /// [`Self::cover`] of the box that `probe` was made from (with the same `view`).
    #[inline]
    pub fn cover_probe(&self, view: &CellView, probe: &Probe) -> Cover {
        match self.verdict(view, probe) {
            Verdict::Done(c) => c,
            Verdict::Factor { need, dl } => self.settle(probe, need, dl),
        }
    }

    /// Rule 3 up to its exact tighter factor: the cover, or the height ratio `need` a factor
    /// must reach and the box's distance `dl` beyond the VO's line, for [`Self::settle`].
    #[inline]
    pub(crate) fn verdict(&self, view: &CellView, p: &Probe) -> Verdict {
        if !self.usable {
            return Verdict::Done(Cover::Outside);
        }
        if let Some(c) = self.footprint(p.fp) {
            return Verdict::Done(c);
        }
        // Heights. `zmin >= g` compares stored values, with no arithmetic: exact.
        if !(p.zmin >= self.g && view.e0 >= self.g && self.h >= view.e1) {
            return Verdict::Done(Cover::Partial);
        }
        // A box touching the cell (D_near = 0) is refused outright.
        if !p.apart {
            return Verdict::Done(Cover::Partial);
        }
        // Every factor below is at least 1: a box no taller than the VO is hidden.
        if p.z <= self.h {
            return Verdict::Done(Cover::Hidden);
        }
        if !(self.h > view.e1) {
            return Verdict::Done(Cover::Partial);
        }
        // Hidden when `z <= e1 + (h - e1) * F` for a valid factor `F`; the larger of the
        // plain and the tighter bound decides (ARCHITECTURE.md, rule 3). The tighter factor
        // `max(D_near, D_far' + dl) / D_far'` lies between its value at `D_far' = D_far`
        // (`D_far' <= D_far`) and at `D_far' = d_line` (`<= D_far'`): the exact one, with its
        // 16 crossings, is computed only when the top falls between the two.
        let need = (p.z - view.e1) / (self.h - view.e1);
        let dl = self.beyond(p.fp);
        if p.d_near.max(self.d_far + dl) * self.inv_d_far >= need {
            return Verdict::Done(Cover::Hidden);
        }
        if p.d_near.max(self.d_line + dl) * self.inv_d_line < need {
            return Verdict::Done(Cover::Partial);
        }
        Verdict::Factor { need, dl }
    }

    /// The end of [`Self::verdict`]: the tighter factor against `need`, first from the coarse
    /// span ([`Self::coarse_factor`], at most the exact factor), then exact.
    pub(crate) fn settle(&self, p: &Probe, need: f64, dl: f64) -> Cover {
        if self.coarse_factor(p.fp, p.d_near, dl) >= need || self.factor(p.fp, p.d_near, dl) >= need
        {
            Cover::Hidden
        } else {
            Cover::Partial
        }
    }

    /// The footprint test of [`Self::cover`] for the grown footprint `fp`: `Some(Outside)` when
    /// it lies wholly outside one of the umbra's half-planes, `Some(Partial)` when it is not
    /// strictly inside all three, `None` when it is.
    #[inline]
    fn footprint(&self, fp: [f64; 4]) -> Option<Cover> {
        let [x0, y0, x1, y1] = fp;
        // Over the box, each linear form is least and greatest at the corners its coefficients
        // pick. All corners strictly in every half-plane is needed for Hidden; all corners
        // outside one of them (non-strictly) gives Outside.
        // Branch-free: the greater and the lesser of the two products on each axis are the
        // products at those corners, bit for bit.
        let mut all_in = true;
        for k in &self.planes {
            let (px0, px1) = (k[0] * x0, k[0] * x1);
            let (py0, py1) = (k[1] * y0, k[1] * y1);
            let max = px0.max(px1) + py0.max(py1) + k[2];
            if !(max > 0.0) {
                return Some(Cover::Outside);
            }
            let min = px0.min(px1) + py0.min(py1) + k[2];
            all_in &= min > 0.0;
        }
        if all_in {
            None
        } else {
            Some(Cover::Partial)
        }
    }
}

impl PreparedVo {
    /// How this VO covers a group of boxes with bounds `bounds` whose least top is `min_top`:
    /// [`Self::cover`] of the bounds, except that `Partial` becomes `Outside` when no box of the
    /// group can meet rule 3's height bound. For a box inside the bounds, `D_near` and its
    /// distance `dl` beyond the VO's line are at most those of the bounds' farthest points
    /// (`d_max`, `dl_max`), and both of rule 3's factors are at most
    /// `max(1, d_max / d_line, 1 + dl_max / d_line)`, as `D_far >= D_far' >= d_line`; a group
    /// whose every top exceeds the top that factor allows has no box this VO hides.
    pub fn cover_group(&self, view: &CellView, bounds: &[f64; 6], min_top: f64) -> Cover {
        self.cover_group_probe(view, &GroupProbe::new(view, bounds, min_top))
    }

    /// [`Self::cover_group`] of the group that `g` was made from (with the same `view`).
    #[inline]
    pub fn cover_group_probe(&self, view: &CellView, g: &GroupProbe) -> Cover {
        match self.cover_probe(view, &g.probe) {
            Cover::Partial => self.group_partial(view, g),
            c => c,
        }
    }

    /// The end of [`Self::cover_group_probe`] once the bounds are `Partial`: `Outside` when
    /// every top of the group is above what rule 3 allows, else `Partial`.
    #[inline]
    pub(crate) fn group_partial(&self, view: &CellView, g: &GroupProbe) -> Cover {
        let m = MARGIN_M;
        let dl_max = self.beyond_max(g.probe.fp) + m;
        let f_max = (g.d_max.max(self.d_line + dl_max) * self.inv_d_line).max(1.0);
        let top_max = view.e1 + (self.h - view.e1).max(0.0) * f_max;
        if g.min_top > top_max + m {
            Cover::Outside
        } else {
            Cover::Partial
        }
    }
}

/// The part of rule 3 that depends on a box and the cell but not on the VO, computed once per
/// box for every VO of the cell: the grown footprint, the top, and `D_near`.
#[derive(Clone, Copy, Debug)]
pub struct Probe {
    /// The footprint grown by the margin, `[x0, y0, x1, y1]`.
    fp: [f64; 4],
    zmin: f64,
    /// The top grown by the margin.
    z: f64,
    /// The least distance between the grown footprint and the grown cell.
    d_near: f64,
    /// The grown footprint and the grown cell are apart (`D_near > 0`).
    apart: bool,
}

impl Probe {
    /// The probe of box `bx = [xmin, ymin, zmin, xmax, ymax, zmax]` seen from `view`.
    #[inline]
    pub fn new(view: &CellView, bx: &[f64; 6]) -> Probe {
        let m = MARGIN_M;
        let fp = [bx[0] - m, bx[1] - m, bx[3] + m, bx[4] + m];
        let [cx0, cy0, cx1, cy1] = view.rect;
        let dx = (fp[0] - (cx1 + m)).max((cx0 - m) - fp[2]).max(0.0);
        let dy = (fp[1] - (cy1 + m)).max((cy0 - m) - fp[3]).max(0.0);
        Probe {
            fp,
            zmin: bx[2],
            z: bx[5] + m,
            d_near: (dx * dx + dy * dy).sqrt(),
            apart: dx > 0.0 || dy > 0.0,
        }
    }
}

/// [`Probe`] for a group of boxes (a subtree of the culler): the probe of its bounds, the
/// greatest distance `d_max` between the cell and the bounds (grown by the margin), and the
/// least top of the group.
#[derive(Clone, Copy, Debug)]
pub struct GroupProbe {
    pub(crate) probe: Probe,
    d_max: f64,
    min_top: f64,
}

impl GroupProbe {
    #[inline]
    pub fn new(view: &CellView, bounds: &[f64; 6], min_top: f64) -> GroupProbe {
        let m = MARGIN_M;
        let [cx0, cy0, cx1, cy1] = view.rect;
        let dx = (bounds[3] - cx0).abs().max((cx1 - bounds[0]).abs());
        let dy = (bounds[4] - cy0).abs().max((cy1 - bounds[1]).abs());
        GroupProbe {
            probe: Probe::new(view, bounds),
            d_max: (dx * dx + dy * dy).sqrt() + 2.0 * m,
            min_top,
        }
    }
}

/// What [`PreparedVo::verdict`] leaves: a cover, or the exact factor to compute.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Verdict {
    Done(Cover),
    Factor { need: f64, dl: f64 },
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
    fn the_coarse_factor_never_exceeds_the_exact_one() {
        // Boxes whose footprints lie in the umbra of random VOs: the coarse span holds the
        // exact crossings, so its factor is at most the exact factor (up to rounding).
        let mut x: u64 = 777;
        let mut r = |lo: f64, hi: f64| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            lo + (hi - lo) * ((x >> 11) as f64 / (1u64 << 53) as f64)
        };
        let v = view();
        let (mut tried, mut equal) = (0, 0);
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
                let bx = [cx, cy, 0.0, cx + w, cy + d, 5.0];
                let probe = Probe::new(&v, &bx);
                if !p.usable || p.footprint(probe.fp).is_some() {
                    continue;
                }
                let dl = p.beyond(probe.fp);
                let coarse = p.coarse_factor(probe.fp, probe.d_near, dl);
                let exact = p.factor(probe.fp, probe.d_near, dl);
                assert!(coarse >= 1.0, "{vo:?} {bx:?}");
                assert!(
                    coarse <= exact * (1.0 + 1e-12),
                    "{coarse} > {exact}: {vo:?} {bx:?}"
                );
                tried += 1;
                equal += (coarse >= exact * (1.0 - 1e-12)) as usize;
            }
        }
        // Enough boxes in umbrae to mean something, and the coarse factor often not the exact.
        assert!(tried > 500, "{tried} boxes in umbrae");
        assert!(equal < tried, "the coarse factor is always the exact one");
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
