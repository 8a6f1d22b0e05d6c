//! Rule 3 (docs/DESIGN.md section 3): is an occludee box hidden from a cell by one VO?
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
//! - the culler's box test, [`PreparedVo::hides_lanes`], tests up to [`LANES`] boxes at once
//!   ([`Lanes`]) and answers `cover == Hidden` for each, with the same arithmetic lane by lane,
//!   only cheaper (each form's least value alone); tests check it box by box against `cover`
//!   and against the one-box form kept for them (`hides_probe`). Its group and box tests that
//!   skip the half-planes an enclosing group lies strictly inside
//!   ([`PreparedVo::cover_group_planes`], and `todo` in `hides_lanes`) answer as the full tests,
//!   bit for bit (monotone rounding; a test checks them too), and so does the probe of a box
//!   inside a box found apart from the cell, which is taken as apart without a test
//!   ([`Probe::within`]).
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
//! With `F = 1 + dl / d_line`, where `dl` is the least distance of the footprint beyond the
//! VO's line and `d_line` the greatest distance of a cell point from that line, the box is hidden
//! when its footprint lies in the umbra, `e0 >= g`, `h >= e1`, `zmax <= e1 + (h - e1) F` and
//! `zmin >= min(g, e0 - (e0 - g) F)`. By similar triangles a ray from an eye to a box point
//! crosses the VO's line at the fraction `mu = s_eye / (s_eye + s_box)` of its length (distances
//! from the line), and `1 / mu >= F`; the ray's height there then lies in `[g, h]`. This factor
//! is never below the brief's `max(1, D_near / D_far)`. Proof in ARCHITECTURE.md ("Rules 2
//! and 3").

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
    /// `1 / d_line`, with `d_line` the greatest distance between the grown cell and the VO's
    /// line, rounded up by the margin: the height factor of a box is `1 + dl / d_line`.
    inv_d_line: f64,
    /// `1 / d_line` with `d_line` rounded down by the margin (the least positive float when it
    /// is not positive): an upper bound of every box's factor, for groups.
    inv_d_line_lo: f64,
    /// The signed distance beyond the VO's line (the side away from the cell) as a linear form,
    /// `-orient(a, b, p) / |b - a|`.
    beyond_form: [f64; 3],
    /// False when the VO's line meets the cell: its umbra is empty.
    usable: bool,
    /// `e0 >= g` and `h >= e1` for the view it was prepared for: without both, rule 3 hides
    /// no box (its first test, the same for every box).
    heights_ok: bool,
    /// The umbra's binding half-planes as linear forms `f(p) = k[0] p.x + k[1] p.y + k[2]`,
    /// `f > 0` inside: `-orient(a, b, p)`, `orient(c_a, a, p)` and `orient(c_b, p, b)` (the same
    /// polynomials as the orientation tests, expanded). Of the constraints `orient(c, a, p) >= 0`
    /// over the cell corners `c`, all pass through `a`, so their intersection is the cone at `a`
    /// bounded by the most counter-clockwise direction `a - c`: that corner is `c_a`; likewise
    /// `c_b` is the corner whose `b - c` is most clockwise. (Near-parallel candidates differ by
    /// rounding only, far below [`MARGIN_M`].)
    planes: [[f64; 3]; 3],
}

/// The greater of `a` and `b` (either when they are equal or one is NaN): one `maxsd`.
#[inline(always)]
fn max(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

/// The lesser of `a` and `b` (either when they are equal or one is NaN): one `minsd`.
#[inline(always)]
fn min(a: f64, b: f64) -> f64 {
    if a < b {
        a
    } else {
        b
    }
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
    /// A VO that hides nothing (its umbra is empty): a placeholder.
    pub const UNUSABLE: PreparedVo = PreparedVo {
        g: 0.0,
        h: 0.0,
        inv_d_line: 0.0,
        inv_d_line_lo: 0.0,
        beyond_form: [0.0; 3],
        usable: false,
        heights_ok: false,
        planes: [[0.0; 3]; 3],
    };

    /// False when the VO's umbra is empty (its line meets the cell, or it is degenerate): then
    /// [`Self::cover`] is `Outside` for every box.
    pub fn is_usable(&self) -> bool {
        self.usable
    }

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
        let mut d_line: f64 = 0.0;
        for c in cs {
            d_line = d_line.max(orient(a, b, c).abs() / norm);
        }
        let lo = d_line - MARGIN_M;
        PreparedVo {
            inv_d_line: 1.0 / (d_line + MARGIN_M),
            inv_d_line_lo: 1.0 / if lo > 0.0 { lo } else { f64::MIN_POSITIVE },
            planes,
            beyond_form,
            g: vo.g,
            h: vo.h,
            usable: usable && d_line.is_finite(),
            heights_ok: view.e0 >= vo.g && vo.h >= view.e1,
        }
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
    pub fn cover_probe(&self, view: &CellView, p: &Probe) -> Cover {
        if !self.usable {
            return Cover::Outside;
        }
        if let Some(c) = self.footprint(p.fp) {
            return c;
        }
        if self.heights_hide(view, p) {
            Cover::Hidden
        } else {
            Cover::Partial
        }
    }

    /// The height part of rule 3, for a probe whose footprint is strictly inside the umbra.
    #[inline]
    fn heights_hide(&self, view: &CellView, p: &Probe) -> bool {
        // Heights (ARCHITECTURE.md, rule 3): with the factor `F = 1 + dl / d_line >= 1`, the
        // box is hidden when `zmax <= e1 + (h - e1) F` and `zmin >= e0 - (e0 - g) F`.
        if !self.heights_ok {
            return false;
        }
        // A box touching the cell is refused outright.
        if !p.apart {
            return false;
        }
        // `zmin >= g` compares stored values, with no arithmetic: exact. Then `F >= 1` makes a
        // box no taller than the VO hidden.
        if p.zmin >= self.g && p.z <= self.h {
            return true;
        }
        let f = 1.0 + self.beyond(p.fp) * self.inv_d_line;
        let top = view.e1 + (self.h - view.e1) * f;
        let bottom_ok = p.zmin >= self.g || p.zlo >= view.e0 - (view.e0 - self.g) * f;
        p.z <= top && bottom_ok
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
        // products at those corners, bit for bit (for `k >= 0` and `x0 <= x1`, `k x0 <= k x1`
        // after rounding too). [`max`] and [`min`] rather than `f64::max`, whose NaN handling
        // costs instructions here: no NaN reaches this point (finite boxes, and a VO whose forms
        // are not finite is not usable).
        let mut all_in = true;
        for k in &self.planes {
            let (px0, px1) = (k[0] * x0, k[0] * x1);
            let (py0, py1) = (k[1] * y0, k[1] * y1);
            let max = max(px0, px1) + max(py0, py1) + k[2];
            if !(max > 0.0) {
                return Some(Cover::Outside);
            }
            let min = min(px0, px1) + min(py0, py1) + k[2];
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
    /// group can meet rule 3's height bound. A box inside the bounds lies at most `dl_max`
    /// beyond the VO's line, the bounds' farthest distance, so its factor `1 + dl / d_line` is
    /// at most `1 + dl_max / d_line` (with `d_line` rounded down); a group whose every top
    /// exceeds the top that factor allows has no box this VO hides.
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
        let dl_max = (self.beyond_max(g.probe.fp) + m).max(0.0);
        let f_max = 1.0 + dl_max * self.inv_d_line_lo;
        let top_max = view.e1 + (self.h - view.e1).max(0.0) * f_max;
        if g.min_top > top_max + m {
            Cover::Outside
        } else {
            Cover::Partial
        }
    }
}

/// The umbra's three half-planes as bits (bit `k`: the `k`-th linear form), all still to test:
/// where the culler starts each VO ([`PreparedVo::cover_group_planes`]).
pub const ALL_PLANES: u8 = 0b111;

impl PreparedVo {
    /// [`Self::cover_group_probe`] for a group lying inside a group that was found strictly
    /// inside the half-planes missing from `todo` (bit `k`: the `k`-th form): only those of
    /// `todo` are tested. Also returned: the half-planes that its own subgroups must still
    /// test, `todo` less those this group lies strictly inside. The answer is the same as
    /// testing all three, bit for bit: a form's least value over a footprint, computed as here,
    /// can only grow when the footprint shrinks (each product, `min` and sum is rounded
    /// monotonically, and a grown sub-footprint lies inside the grown footprint), so a subgroup
    /// of a group strictly inside a half-plane is strictly inside it too, and that half-plane
    /// can make it neither `Outside` nor `Partial`. (The frustum culler's plane masking.)
    #[inline]
    pub fn cover_group_planes(&self, view: &CellView, g: &GroupProbe, todo: u8) -> (Cover, u8) {
        if !self.usable {
            return (Cover::Outside, 0);
        }
        let [x0, y0, x1, y1] = g.probe.fp;
        let todo = todo & ALL_PLANES;
        let mut left = todo;
        for (k, f) in self.open_planes(todo) {
            let (px0, px1) = (f[0] * x0, f[0] * x1);
            let (py0, py1) = (f[1] * y0, f[1] * y1);
            // The same sums, in the same order, as in [`Self::footprint`].
            if !(max(px0, px1) + max(py0, py1) + f[2] > 0.0) {
                return (Cover::Outside, 0);
            }
            if min(px0, px1) + min(py0, py1) + f[2] > 0.0 {
                left &= !(1 << k);
            }
        }
        if left == 0 && self.heights_hide(view, &g.probe) {
            return (Cover::Hidden, 0);
        }
        (self.group_partial(view, g), left)
    }

    /// The umbra's forms whose bits are set in `todo`, with their bits. Over the set bits only:
    /// a loop over all three forms that skipped the others ran 10% more of the culler's
    /// instructions.
    #[inline(always)]
    fn open_planes(&self, todo: u8) -> impl Iterator<Item = (usize, &[f64; 3])> {
        let mut t = todo & ALL_PLANES;
        std::iter::from_fn(move || {
            let k = (t != 0).then(|| t.trailing_zeros() as usize)?;
            t &= t - 1;
            Some((k, self.planes.get(k)?))
        })
    }
}

/// The one-box form of [`PreparedVo::hides_lanes`], which the culler used before its leaves
/// went into lanes: kept for the tests as the lane test's reference.
#[cfg(test)]
impl PreparedVo {
    /// Whether [`Self::cover_probe`] is `Hidden`. Cheaper: `Hidden` needs every corner strictly
    /// inside each half-plane, so only each form's least value over the footprint is computed,
    /// and the test stops at the first form that fails (where [`Self::footprint`] also finds the
    /// greatest value, to tell `Outside` from `Partial`).
    fn hides_probe(&self, view: &CellView, p: &Probe) -> bool {
        self.hides_probe_planes(view, p, ALL_PLANES)
    }

    /// [`Self::hides_probe`] for a box lying inside a group found strictly inside the
    /// half-planes missing from `todo` ([`Self::cover_group_planes`]): only those of `todo` are
    /// tested, with the same answer.
    fn hides_probe_planes(&self, view: &CellView, p: &Probe, todo: u8) -> bool {
        if !self.usable {
            return false;
        }
        let [x0, y0, x1, y1] = p.fp;
        for (_, f) in self.open_planes(todo) {
            let (px0, px1) = (f[0] * x0, f[0] * x1);
            let (py0, py1) = (f[1] * y0, f[1] * y1);
            // The same sum, in the same order, as `min` in [`Self::footprint`].
            if !(min(px0, px1) + min(py0, py1) + f[2] > 0.0) {
                return false;
            }
        }
        self.heights_hide(view, p)
    }
}

/// Boxes side by side, the culler's leaves, held as the VO-independent part of rule 3 that
/// [`Probe`] computes for one box, grown once when the tree is built rather than at every
/// query: box `j` has the grown footprint `[fp[0][j], fp[1][j], fp[2][j], fp[3][j]]`, the
/// bottom `zmin[j]` and the grown top `z[j]`, grown as [`Probe::within`] grows them ([`grown`]),
/// so the same bits. Lanes past the boxes given hold a grown zero box: whoever reads the
/// answers masks them out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lanes {
    /// The grown footprints, `[x0, y0, x1, y1]`, by lane.
    fp: [[f64; LANES]; 4],
    zmin: [f64; LANES],
    /// The tops grown by the margin.
    z: [f64; LANES],
}

/// Boxes per [`Lanes`]. The lane tests are loops over fixed arrays, which the compiler turns
/// into vector instructions (two lanes at once on the baseline x86-64, SSE2).
pub const LANES: usize = 8;

impl Lanes {
    /// The first [`LANES`] boxes of `boxes` in lanes, the lanes past them zero boxes.
    pub fn new(boxes: &[[f64; 6]]) -> Lanes {
        let mut l = Lanes {
            fp: [[0.0; LANES]; 4],
            zmin: [0.0; LANES],
            z: [0.0; LANES],
        };
        for j in 0..LANES {
            let b = boxes.get(j).unwrap_or(&[0.0; 6]);
            let (fp, z) = grown(b);
            for (lane, v) in l.fp.iter_mut().zip(fp) {
                lane[j] = v;
            }
            l.zmin[j] = b[2];
            l.z[j] = z;
        }
        l
    }

    /// Bit `j`: box `j` is apart from the cell of `view` ([`Probe::is_apart`]); every bit when
    /// `inside_apart`, the boxes lying inside a group found apart ([`Probe::within`]).
    #[inline]
    pub fn apart(&self, view: &CellView, inside_apart: bool) -> u32 {
        if inside_apart {
            return u32::MAX;
        }
        let mut a = [false; LANES];
        for (j, a) in a.iter_mut().enumerate() {
            *a = apart_from(view, self.fp.map(|lane| lane[j]));
        }
        lane_bits(&a)
    }
}

/// The footprint of `bx` grown by the margin, `[x0, y0, x1, y1]`, and its top grown by it: what
/// rule 3 tests of a box, whether one at a time ([`Probe`]) or side by side ([`Lanes`]), so
/// both hold the same bits.
#[inline(always)]
fn grown(bx: &[f64; 6]) -> ([f64; 4], f64) {
    let m = MARGIN_M;
    ([bx[0] - m, bx[1] - m, bx[3] + m, bx[4] + m], bx[5] + m)
}

/// Whether the grown footprint `fp` and the cell of `view`, grown by the margin, are apart on
/// some axis: rule 3 refuses a box without it.
#[inline(always)]
fn apart_from(view: &CellView, fp: [f64; 4]) -> bool {
    let m = MARGIN_M;
    let [cx0, cy0, cx1, cy1] = view.rect;
    (fp[0] > cx1 + m) | (fp[2] < cx0 - m) | (fp[1] > cy1 + m) | (fp[3] < cy0 - m)
}

/// Bit `j` set for each true `v[j]`.
#[inline(always)]
fn lane_bits(v: &[bool; LANES]) -> u32 {
    let mut m = 0;
    for (j, &b) in v.iter().enumerate() {
        m |= u32::from(b) << j;
    }
    m
}

impl PreparedVo {
    /// Whether each box of `p` is hidden ([`Self::cover_probe`] is `Hidden`) once the
    /// half-planes missing from `todo` are known to hold ([`Self::cover_group_planes`]), for
    /// the boxes of `apart` ([`Lanes::apart`]; the others touch the cell): bit `j` is set when
    /// box `j` is hidden. The same arithmetic lane by lane, so the same answers bit for bit:
    /// - a form's least value over a footprint is its value at the corner its coefficients'
    ///   signs pick, which is the lesser of the two products on each axis in
    ///   [`Self::footprint`] (for `k >= 0` and `x0 <= x1`, `k x0 <= k x1` after rounding;
    ///   equal products can differ in the sign of a zero only, which no sum or `> 0` test
    ///   tells apart), summed in the same order;
    /// - the height part is [`Self::heights_hide`] without its early returns: its shortcut
    ///   (`zmin >= g` and `z <= h`) is or-ed with the full test, which it implies anyway.
    #[inline]
    pub fn hides_lanes(&self, view: &CellView, p: &Lanes, apart: u32, todo: u8) -> u32 {
        if !self.usable || !self.heights_ok {
            return 0;
        }
        let mut inside = [true; LANES];
        for (_, f) in self.open_planes(todo) {
            let xs = if f[0] >= 0.0 { &p.fp[0] } else { &p.fp[2] };
            let ys = if f[1] >= 0.0 { &p.fp[1] } else { &p.fp[3] };
            for j in 0..LANES {
                inside[j] &= f[0] * xs[j] + f[1] * ys[j] + f[2] > 0.0;
            }
        }
        // [`Self::beyond`], lane by lane.
        let k = self.beyond_form;
        let bx = if k[0] >= 0.0 { &p.fp[0] } else { &p.fp[2] };
        let by = if k[1] >= 0.0 { &p.fp[1] } else { &p.fp[3] };
        let mut hid = [false; LANES];
        for j in 0..LANES {
            let low = p.zmin[j] >= self.g;
            let short = low & (p.z[j] <= self.h);
            let beyond = max(k[0] * bx[j] + k[1] * by[j] + k[2] - MARGIN_M, 0.0);
            let f = 1.0 + beyond * self.inv_d_line;
            let top = view.e1 + (self.h - view.e1) * f;
            // `zlo` of [`Probe::within`].
            let zlo = p.zmin[j] - MARGIN_M;
            let bottom_ok = low | (zlo >= view.e0 - (view.e0 - self.g) * f);
            hid[j] = inside[j] & (short | ((p.z[j] <= top) & bottom_ok));
        }
        lane_bits(&hid) & apart
    }
}

/// The part of rule 3 that depends on a box and the cell but not on the VO, computed once per
/// box for every VO of the cell: the grown footprint, the bottom and the top, and whether the
/// footprint is apart from the cell.
#[derive(Clone, Copy, Debug)]
pub struct Probe {
    /// The footprint grown by the margin, `[x0, y0, x1, y1]`.
    fp: [f64; 4],
    zmin: f64,
    /// The bottom lowered by the margin.
    zlo: f64,
    /// The top grown by the margin.
    z: f64,
    /// The grown footprint and the grown cell are apart (on some axis): rule 3 refuses a box
    /// without it.
    apart: bool,
}

impl Probe {
    /// The probe of box `bx = [xmin, ymin, zmin, xmax, ymax, zmax]` seen from `view`.
    #[inline]
    pub fn new(view: &CellView, bx: &[f64; 6]) -> Probe {
        Probe::within(view, bx, false)
    }

    /// [`Probe::new`] of a box lying inside a box whose probe was found apart from the cell
    /// when `inside_apart`: then this one is apart too, with no test. The answer is the same
    /// as testing, bit for bit: each grown bound is rounded monotonically, so a bound of a box
    /// inside is on the same side of the grown cell's bound (the culler's walk carries the
    /// flag down, as it does the half-planes).
    #[inline]
    pub fn within(view: &CellView, bx: &[f64; 6], inside_apart: bool) -> Probe {
        let (fp, z) = grown(bx);
        Probe {
            fp,
            zmin: bx[2],
            zlo: bx[2] - MARGIN_M,
            z,
            apart: inside_apart || apart_from(view, fp),
        }
    }

    /// The grown footprint and the grown cell are apart.
    #[inline]
    pub fn is_apart(&self) -> bool {
        self.apart
    }
}

/// [`Probe`] for a group of boxes (a subtree of the culler): the probe of its bounds and the
/// least top of the group.
#[derive(Clone, Copy, Debug)]
pub struct GroupProbe {
    pub(crate) probe: Probe,
    min_top: f64,
}

impl GroupProbe {
    #[inline]
    pub fn new(view: &CellView, bounds: &[f64; 6], min_top: f64) -> GroupProbe {
        GroupProbe::within(view, bounds, min_top, false)
    }

    /// [`GroupProbe::new`] of a group inside a group found apart from the cell when
    /// `inside_apart` ([`Probe::within`]).
    #[inline]
    pub fn within(view: &CellView, bounds: &[f64; 6], min_top: f64, inside_apart: bool) -> Self {
        GroupProbe {
            probe: Probe::within(view, bounds, inside_apart),
            min_top,
        }
    }
}

/// Whether `vo` hides box `bx` from `view` (rule 3).
pub fn hides(view: &CellView, vo: &VoGeom, bx: &[f64; 6]) -> bool {
    PreparedVo::new(view, vo).cover(view, bx) == Cover::Hidden
}

#[cfg(test)]
mod tests;
