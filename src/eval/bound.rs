//! The 2D fusion bound and the 10-VO ceiling: how much occluders built from the blockers outside
//! a cell could cull, estimated by sampling. They tell what limits tightness: the VOs, the
//! generator, or the cell.
//!
//! Input: the scene (objects and blockers, local frame), a cell rectangle, and the sampling
//! density ([`BoundParams`], [`CeilingParams`]).
//! Output:
//! - [`hidden_2d`], the ascending ids of the objects whose sampled footprint points are all cut
//!   off from every sampled point of the cell by blockers whose interiors miss the cell, heights
//!   ignored (every blocker infinitely tall);
//! - [`ceiling_2d`], what `vos` ideal VOs could cull in 2D under the same model: candidate
//!   segments are the long runs of sampled hidden points along lines around the cell; an object
//!   is culled by one when its bounding box lies in the segment's umbra seen from the cell (the
//!   runtime's single-umbra rule, tested here in plain f64 with a 1 mm margin on the side of
//!   culling less); `vos` of them are chosen greedily by the objects they add. It is the ceiling
//!   issue 11 measures (10 ideal VOs), for reports to compare the bake against;
//! - [`ceiling_sliced`], the same once heights count: per slice of VO tops, the runs hidden by
//!   the blockers that support such a VO on their line (rule 2), objects culled when rule 3's
//!   heights hold too.
//!
//! Both ceilings read lines out to `max_offset_m` (600 m, [`CeilingParams::default`], the
//! figures of docs/RESULTS.md), or over the whole scene ([`CeilingParams::scene`], `vocc eval
//! --ceiling`): lines out to the scene's edge, spaced and sampled at the same angle beyond
//! 600 m as at 600 m (a far VO needs angular, not metric, precision), and VO tops up to the
//! scene's tallest blocker.
//!
//! Why [`hidden_2d`] bounds the VO method: a stored VO certifies only a region that blockers
//! disjoint from the cell hide in 2D (rule 1), and rule 3 adds heights, which can only cull less.
//! So an object outside this set can be culled by no VO of this cell. Sampling makes the set
//! optimistic (a visible object may look hidden if no sampled ray finds it), so it is an upper
//! estimate of what VOs could cull: an estimate of the bound, not a certificate, and never used
//! to cull. [`ceiling_2d`] is optimistic the same way (its segments are hidden only at the
//! sampled points, from the sampled cell points) and lower in another (lines and offsets are
//! sampled, the choice is greedy): an estimate of what 10 VOs reach in 2D, never used to cull.
//! Each of its objects has its whole box in the umbra of a segment whose samples are hidden, so
//! it is hidden too, up to sampling: the ceiling lies within [`hidden_2d`] but for sampling.
//!
//! Invariants: no code of the occlusion pipeline (bake, verifier, culler) is used, only the scene
//! and the exact segment predicate; both share one blocker index and one segment test
//! ([`Outside`]); deterministic (rayon only splits work whose results keep their order).

use std::ops::Range;

use glam::DVec2;
use rayon::prelude::*;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};

use crate::geom::predicates::{convex_interiors_disjoint, segment_meets_convex};
use crate::scene::{Blocker, Scene};

/// Sampling density of [`hidden_2d`].
#[derive(Clone, Copy, Debug)]
pub struct BoundParams {
    /// Points on the cell's boundary (a point outside a convex cell seen from the cell is seen
    /// from its boundary, when no blocker meets the cell).
    pub cell_points: usize,
    /// Most points per object: vertices of its blockers, pulled 1 cm towards their centre.
    pub object_points: usize,
}

impl Default for BoundParams {
    fn default() -> Self {
        BoundParams {
            cell_points: 48,
            object_points: 16,
        }
    }
}

/// The blockers whose interiors miss a cell, indexed for segment tests: the model both estimates
/// share (every such blocker infinitely tall, heights ignored).
struct Outside<'a> {
    /// The scene's blockers, then its terrain's (solid ground counts, issue 32).
    blockers: Vec<&'a Blocker>,
    tree: RTree<GeomWithData<Rectangle<[f64; 2]>, u32>>,
}

impl<'a> Outside<'a> {
    fn new(scene: &'a Scene, cell: &[DVec2; 4]) -> Self {
        Self::with(scene, cell, |_| true)
    }

    /// The blockers outside the cell that `keep` accepts.
    fn with(scene: &'a Scene, cell: &[DVec2; 4], keep: impl Fn(&Blocker) -> bool) -> Self {
        let blockers: Vec<&Blocker> = scene
            .blockers
            .iter()
            .chain(scene.terrain_blockers())
            .collect();
        let tree = RTree::bulk_load(
            (0..blockers.len())
                .filter(|&i| {
                    keep(blockers[i]) && convex_interiors_disjoint(&blockers[i].polygon, cell)
                })
                .map(|i| {
                    let (lo, hi) = bounds(&blockers[i].polygon);
                    GeomWithData::new(Rectangle::from_corners(lo, hi), i as u32)
                })
                .collect(),
        );
        Outside { blockers, tree }
    }

    fn is_empty(&self) -> bool {
        self.tree.size() == 0
    }

    /// Whether the closed segment `[a, b]` meets a blocker outside the cell, other than those in
    /// `own`. `hint` is a blocker that blocked a nearby segment: it is tried first, and set to
    /// the blocker found. The answer does not depend on the hint.
    fn blocked(&self, a: DVec2, b: DVec2, own: Range<usize>, hint: &mut Option<u32>) -> bool {
        self.blocked_by(a, b, own, hint, &|_| true)
    }

    /// [`Self::blocked`] by the blockers that `keep` accepts.
    fn blocked_by(
        &self,
        a: DVec2,
        b: DVec2,
        own: Range<usize>,
        hint: &mut Option<u32>,
        keep: &dyn Fn(&Blocker) -> bool,
    ) -> bool {
        let meets = |i: usize| {
            !own.contains(&i)
                && keep(self.blockers[i])
                && segment_meets_convex(a, b, &self.blockers[i].polygon)
        };
        if let Some(h) = *hint {
            if meets(h as usize) {
                return true;
            }
        }
        // Step along the segment so the first blocker near the cell ends the search early.
        let len = a.distance(b);
        let steps = (len / 25.0).ceil().max(1.0) as usize;
        for s in 0..steps {
            let p0 = a + (b - a) * (s as f64 / steps as f64);
            let p1 = a + (b - a) * ((s + 1) as f64 / steps as f64);
            let (lo, hi) = (p0.min(p1), p0.max(p1));
            let hit = self
                .tree
                .locate_in_envelope_intersecting(AABB::from_corners(lo.to_array(), hi.to_array()))
                .find(|g| meets(g.data as usize));
            if let Some(g) = hit {
                *hint = Some(g.data);
                return true;
            }
        }
        false
    }
}

/// The corners of the cell `r = [x0, y0, x1, y1]`, counter-clockwise from `(x0, y0)`.
fn cell_corners(r: [f64; 4]) -> [DVec2; 4] {
    [
        DVec2::new(r[0], r[1]),
        DVec2::new(r[2], r[1]),
        DVec2::new(r[2], r[3]),
        DVec2::new(r[0], r[3]),
    ]
}

/// `n` points evenly spread along the cell's boundary, the first `phase` spacings from corner 0
/// (0: the corners are among them when `n` is a multiple of 4 on a square), each pulled a
/// relative 1e-9 towards the centre so that none lies on a blocker touching the cell.
fn boundary_points(cell: &[DVec2; 4], n: usize, phase: f64) -> Vec<DVec2> {
    let per = 2.0 * (cell[2].x - cell[0].x + cell[2].y - cell[0].y) / n as f64;
    let centre = (cell[0] + cell[2]) * 0.5;
    (0..n)
        .map(|k| {
            let mut d = per * (k as f64 + phase);
            let mut at = cell[0];
            for i in 0..4 {
                let (a, b) = (cell[i], cell[(i + 1) % 4]);
                let len = a.distance(b);
                if d <= len {
                    at = a + (b - a) * (d / len);
                    break;
                }
                d -= len;
            }
            centre + (at - centre) * (1.0 - 1e-9)
        })
        .collect()
}

/// Objects that sampled rays find hidden from the cell `r = [x0, y0, x1, y1]` in 2D, by the
/// blockers outside it (module header). Objects without blockers are counted visible.
pub fn hidden_2d(scene: &Scene, r: [f64; 4], p: &BoundParams) -> Vec<u32> {
    let cell = cell_corners(r);
    let outside = Outside::new(scene, &cell);
    let eyes = boundary_points(&cell, p.cell_points, 0.5);
    // Blocker ranges per object (blockers are grouped by object, in object order).
    let mut first = vec![usize::MAX; scene.objects.len()];
    let mut count = vec![0usize; scene.objects.len()];
    for (i, b) in scene.blockers.iter().enumerate() {
        let o = b.object as usize;
        first[o] = first[o].min(i);
        count[o] += 1;
    }
    (0..scene.objects.len() as u32)
        .into_par_iter()
        .filter(|&o| {
            let o = o as usize;
            if count[o] == 0 {
                return false;
            }
            let own = first[o]..first[o] + count[o];
            let bb = scene.objects[o].bbox;
            if bb.min.x <= r[2] && bb.max.x >= r[0] && bb.min.y <= r[3] && bb.max.y >= r[1] {
                return false;
            }
            let pts: Vec<DVec2> = own
                .clone()
                .flat_map(|i| {
                    let poly = &scene.blockers[i].polygon;
                    let c = poly.iter().copied().sum::<DVec2>() / poly.len() as f64;
                    poly.iter()
                        .map(move |&v| v + (c - v).normalize_or_zero() * 0.01)
                })
                .collect();
            let stride = pts.len().div_ceil(p.object_points).max(1);
            let mut hint = None;
            pts.iter().step_by(stride).all(|&t| {
                eyes.iter()
                    .all(|&e| outside.blocked(e, t, own.clone(), &mut hint))
            })
        })
        .collect()
}

/// Sampling of [`ceiling_2d`].
#[derive(Clone, Copy, Debug)]
pub struct CeilingParams {
    /// Normal directions of the candidate lines, evenly over the full turn.
    pub directions: usize,
    /// Metres between parallel candidate lines; the nearest lies `step_m` clear of the cell.
    pub spacing_m: f64,
    /// Farthest line from the cell centre, metres (infinite: the scene's edge, [`Self::scene`]).
    pub max_offset_m: f64,
    /// Metres between sampled points along a line.
    pub step_m: f64,
    /// Points on the cell's boundary, corners included, that a sampled point must be hidden from.
    pub cell_points: usize,
    /// Shortest candidate segment, metres.
    pub min_len_m: f64,
    /// How many segments are chosen.
    pub vos: usize,
    /// Beyond this distance from the cell centre the spacing of lines and the step along them
    /// grow in proportion to the distance (a far VO needs angular, not metric, precision):
    /// `spacing_m` and `step_m` at `near_m`, twice that at twice the distance. Infinite: fixed.
    pub near_m: f64,
    /// Besides [`SLICES_ABOVE_EYE_M`], the taller VO tops of [`TALL_SLICES_ABOVE_EYE_M`] up to
    /// the scene's tallest blocker ([`ceiling_sliced`]).
    pub tall: bool,
}

impl Default for CeilingParams {
    fn default() -> Self {
        CeilingParams {
            directions: 24,
            spacing_m: 24.0,
            max_offset_m: 600.0,
            step_m: 4.0,
            cell_points: 16,
            min_len_m: 20.0,
            vos: 10,
            near_m: f64::INFINITY,
            tall: false,
        }
    }
}

impl CeilingParams {
    /// The ceiling over the whole scene: lines out to the scene's edge, sampled at the default
    /// density within 600 m of the cell centre and at the same angle beyond, and VO tops up to
    /// the scene's tallest blocker.
    pub fn scene() -> Self {
        CeilingParams {
            max_offset_m: f64::INFINITY,
            near_m: 600.0,
            tall: true,
            ..CeilingParams::default()
        }
    }

    /// The spacing of lines, or the step along one, at `dist` metres from the cell centre.
    fn at_distance(&self, metres: f64, dist: f64) -> f64 {
        if dist > self.near_m {
            metres * dist / self.near_m
        } else {
            metres
        }
    }
}

/// What [`ceiling_2d`] found for one cell.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Ceiling {
    /// Ascending ids of the objects culled by the chosen segments.
    pub culled: Vec<u32>,
    /// The chosen segments in the order picked, `[a.x, a.y, b.x, b.y]`, local frame.
    pub vos: Vec<[f64; 4]>,
    /// `by_count[k - 1]`: objects culled by the first `k` segments, `k = 1..=vos` (the last
    /// count repeats when fewer segments add anything).
    pub by_count: Vec<usize>,
}

/// Margin of the umbra test, metres: every side test must pass by this much.
const UMBRA_MARGIN_M: f64 = 1e-3;

/// Sampled points stay within this far beyond `max_offset_m` of the cell centre (per axis), and,
/// when lines reach the scene's edge, within this far of the scene's bounds.
const LINE_REACH_M: f64 = 200.0;

/// What `p.vos` ideal VOs could cull from the cell `r = [x0, y0, x1, y1]` in 2D (module header):
/// the hidden runs of the candidate lines as segments, the objects whose boxes lie in each one's
/// umbra, and a greedy choice.
pub fn ceiling_2d(scene: &Scene, r: [f64; 4], p: &CeilingParams) -> Ceiling {
    ceiling(scene, r, None, p)
}

/// Heights of a cell for [`ceiling_sliced`]: its ground (the VOs' bottom) and its eyes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Heights {
    pub g: f64,
    pub e0: f64,
    pub e1: f64,
}

/// VO tops of [`ceiling_sliced`]'s slices, metres above the highest eye.
pub const SLICES_ABOVE_EYE_M: [f64; 7] = [1.0, 2.0, 4.0, 6.0, 10.0, 16.0, 24.0];

/// The taller VO tops of [`ceiling_sliced`] with [`CeilingParams::tall`], metres above the
/// highest eye: those up to the scene's tallest blocker.
pub const TALL_SLICES_ABOVE_EYE_M: [f64; 6] = [40.0, 64.0, 100.0, 160.0, 250.0, 400.0];

/// What `p.vos` ideal VOs could cull from the cell `r` in 2.5D, sliced: at each VO top `t` of
/// [`SLICES_ABOVE_EYE_M`] above the eyes, the candidate runs of a line are those hidden by the
/// blockers that support a VO of top `t` on that line by rule 2, with its bound from the line
/// (`lambda <= 1 - d_B / d_line`, distances from the line: `top >= e1 + lambda (t - e1)`, and
/// `base <= min(e0, g)` or `base <= e0 - lambda (e0 - g)`; ARCHITECTURE.md); a candidate culls
/// an object when its box lies in the segment's umbra and rule 3's heights hold for a VO of top
/// `t` (written here apart from the runtime's: `zmax <= e1 + (t - e1) F` and
/// `zmin >= min(g, e0 - (e0 - g) F)`, `F = 1 + dist(box, line) / d_line`); the greedy choice
/// runs across the slices. An estimate of what 10 VOs reach once heights count: optimistic by
/// sampling like [`ceiling_2d`], lower where tops between the slices would do better.
pub fn ceiling_sliced(scene: &Scene, r: [f64; 4], h: Heights, p: &CeilingParams) -> Ceiling {
    ceiling(scene, r, Some(h), p)
}

/// [`ceiling_2d`] (no heights) or [`ceiling_sliced`].
fn ceiling(scene: &Scene, r: [f64; 4], heights: Option<Heights>, p: &CeilingParams) -> Ceiling {
    let cell = cell_corners(r);
    let mut out = Ceiling::default();
    if p.directions == 0 || p.cell_points == 0 || !(p.step_m > 0.0) {
        out.by_count = vec![0; p.vos];
        return out;
    }
    let eyes = boundary_points(&cell, p.cell_points, 0.0);
    let centre = (cell[0] + cell[2]) * 0.5;
    let half = (cell[2] - cell[0]) * 0.5;
    // Where sampled points may lie: the square of `max_offset_m` (and a margin) around the
    // centre, cut to the scene's bounds (and a margin) when lines reach its edge.
    // (Relative to the centre.)
    let rect = if p.max_offset_m.is_finite() {
        let reach = p.max_offset_m + LINE_REACH_M;
        (DVec2::splat(-reach), DVec2::splat(reach))
    } else {
        let (slo, shi) = scene_bounds(scene);
        (
            slo.min(cell[0]) - centre - DVec2::splat(LINE_REACH_M),
            shi.max(cell[2]) - centre + DVec2::splat(LINE_REACH_M),
        )
    };
    // Every line: its normal and offset from the centre, in direction-then-offset order.
    let lines: Vec<(DVec2, f64)> = (0..p.directions)
        .flat_map(|k| {
            let th = std::f64::consts::TAU * k as f64 / p.directions as f64;
            let n = DVec2::new(th.cos(), th.sin());
            let clear = n.x.abs() * half.x + n.y.abs() * half.y + p.step_m;
            let mut offsets = Vec::new();
            if p.max_offset_m.is_finite() && !p.near_m.is_finite() {
                let count = if p.spacing_m > 0.0 && clear <= p.max_offset_m {
                    ((p.max_offset_m - clear) / p.spacing_m).floor() as usize + 1
                } else {
                    0
                };
                offsets.extend((0..count).map(|j| clear + j as f64 * p.spacing_m));
            } else if p.spacing_m > 0.0 {
                // Out to the farthest corner of the sampled rectangle along the normal.
                let far = [
                    rect.0,
                    DVec2::new(rect.1.x, rect.0.y),
                    rect.1,
                    DVec2::new(rect.0.x, rect.1.y),
                ]
                .iter()
                .map(|&c| n.dot(c))
                .fold(0.0, f64::max)
                .min(p.max_offset_m);
                let mut d = clear;
                while d <= far {
                    offsets.push(d);
                    d += p.at_distance(p.spacing_m, d);
                }
            }
            offsets.into_iter().map(move |d| (n, d))
        })
        .collect();
    // The slices' VO tops (none: heights ignored).
    let tops: Vec<Option<f64>> = match heights {
        None => vec![None],
        Some(h) => {
            let tallest = scene
                .blockers
                .iter()
                .chain(scene.terrain_blockers())
                .map(|b| b.top)
                .fold(f64::NEG_INFINITY, f64::max);
            let tall: &[f64] = if p.tall {
                &TALL_SLICES_ABOVE_EYE_M
            } else {
                &[]
            };
            SLICES_ABOVE_EYE_M
                .iter()
                .chain(tall.iter().filter(|&&d| h.e1 + d <= tallest))
                .map(|d| Some(h.e1 + d))
                .collect()
        }
    };
    // Blockers low enough at their base and taller than the eyes; per line and slice, those
    // that support a VO of the slice's top on it by rule 2 with the line's bound of lambda.
    let outside = Outside::with(scene, &cell, |b| match heights {
        Some(h) => b.base <= h.e0 && b.top > h.e1,
        None => true,
    });
    let mut candidates: Vec<([DVec2; 2], Option<f64>)> = Vec::new();
    if !outside.is_empty() {
        let cs = &cell;
        // Per line, the runs of each slice. A taller top keeps a subset of the blockers (rule
        // 2's bound only grows with the top, in floating point too; the tops ascend), so the
        // slices that hide a point are the lowest ones up to some top, found by bisection.
        debug_assert!(tops.windows(2).all(|w| w[0] <= w[1]));
        let per_line: Vec<Vec<Vec<[DVec2; 2]>>> = lines
            .par_iter()
            .map(|&(n, d)| {
                let at = |v: DVec2| d - n.dot(v - centre);
                let d_line = cs.iter().map(|&c| at(c)).fold(0.0, f64::max);
                let keep = |top: Option<f64>, b: &Blocker| match (top, heights) {
                    (Some(t), Some(h)) => {
                        let d_b = b
                            .polygon
                            .iter()
                            .map(|&v| at(v))
                            .fold(f64::INFINITY, f64::min);
                        let lambda = if d_b > 0.0 {
                            1.0 - d_b / d_line + 1e-9
                        } else {
                            1.0
                        };
                        let lambda = lambda.clamp(0.0, 1.0);
                        b.top >= h.e1 + lambda * (t - h.e1)
                            && (b.base <= h.g.min(h.e0) || b.base <= h.e0 - lambda * (h.e0 - h.g))
                    }
                    _ => true,
                };
                let keep_in = |k: usize, b: &Blocker| keep(tops[k], b);
                let line = Line::new(centre, n, d, rect, p);
                let hiding = line.hiding_slices(&outside, tops.len(), &keep_in, &eyes);
                (0..tops.len()).map(|k| line.runs(&hiding, k, p)).collect()
            })
            .collect();
        for (k, &top) in tops.iter().enumerate() {
            for runs in &per_line {
                candidates.extend(runs[k].iter().map(|&s| (s, top)));
            }
        }
    }
    // The objects each candidate culls.
    let boxes: Vec<[DVec2; 4]> = scene
        .objects
        .iter()
        .map(|o| {
            let (lo, hi) = (o.bbox.min.truncate(), o.bbox.max.truncate());
            [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)]
        })
        .collect();
    let culls: Vec<Vec<u32>> = candidates
        .par_iter()
        .map(|&([a, b], top)| {
            // A box in the umbra lies wholly across the segment's line from the cell: the part
            // of `crosses` for the first cell corner, read first for every corner (the same
            // operations as `side`, so the same bits; it only skips boxes that fail anyway).
            let (ab, l) = (b - a, a.distance(b));
            let sc = ab.perp_dot(cell[0] - a) / l;
            let m = UMBRA_MARGIN_M;
            let across = |w: DVec2| {
                let sw = ab.perp_dot(w - a) / l;
                (sc >= m && sw <= -m) || (sc <= -m && sw >= m)
            };
            (0..boxes.len() as u32)
                .filter(|&o| {
                    let bx = &boxes[o as usize];
                    bx.iter().all(|&w| across(w))
                        && box_in_umbra(&cell, bx, a, b)
                        && match (top, heights) {
                            (Some(t), Some(h)) => {
                                let z = &scene.objects[o as usize].bbox;
                                heights_hold(&cell, bx, (z.min.z, z.max.z), a, b, t, h)
                            }
                            _ => true,
                        }
                })
                .collect()
        })
        .collect();
    // Greedy: each pick adds the most objects not yet culled; ties go to the first candidate.
    let mut taken = vec![false; scene.objects.len()];
    let mut total = 0usize;
    for _ in 0..p.vos {
        let best = culls
            .iter()
            .enumerate()
            .map(|(i, c)| (i, c.iter().filter(|&&o| !taken[o as usize]).count()))
            .fold(None, |best: Option<(usize, usize)>, (i, g)| match best {
                Some((_, bg)) if bg >= g => best,
                _ => Some((i, g)),
            });
        if let Some((i, gain)) = best.filter(|&(_, g)| g > 0) {
            for &o in &culls[i] {
                taken[o as usize] = true;
            }
            total += gain;
            let ([a, b], _) = candidates[i];
            out.vos.push([a.x, a.y, b.x, b.y]);
        }
        out.by_count.push(total);
    }
    out.culled = (0..scene.objects.len() as u32)
        .filter(|&o| taken[o as usize])
        .collect();
    out
}

/// The sampled points of the line `{x : n . (x - centre) = d}`: every `step_m` (growing beyond
/// `near_m` from the centre, [`CeilingParams::near_m`]) within the rectangle `centre + rect`
/// (its corners relative to the centre), as parameters `t` of `foot + t u`.
struct Line {
    foot: DVec2,
    u: DVec2,
    d: f64,
    ts: Vec<f64>,
}

impl Line {
    fn new(centre: DVec2, n: DVec2, d: f64, rect: (DVec2, DVec2), p: &CeilingParams) -> Line {
        let u = n.perp();
        let foot = centre + n * d;
        let mut line = Line {
            foot,
            u,
            d,
            ts: Vec::new(),
        };
        // The parameter range of the line inside the rectangle: lo.i <= n.i d + u.i t <= hi.i
        // per axis.
        let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
        for (ni, ui, lo, hi) in [
            (n.x, u.x, rect.0.x, rect.1.x),
            (n.y, u.y, rect.0.y, rect.1.y),
        ] {
            if ui.abs() > 1e-12 {
                let (e0, e1) = ((lo - ni * d) / ui, (hi - ni * d) / ui);
                t0 = t0.max(e0.min(e1));
                t1 = t1.min(e0.max(e1));
            } else if ni * d < lo || ni * d > hi {
                return line;
            }
        }
        if !(t1 >= t0) {
            return line;
        }
        // Every `step_m` from `t0` (fixed steps: `t0 + k step_m`, as written before the steps
        // could grow), or steps growing with the distance from the centre.
        if p.near_m.is_finite() {
            let mut t = t0;
            while t <= t1 {
                line.ts.push(t);
                t += line.step(t, p);
            }
        } else {
            let samples = ((t1 - t0) / p.step_m).floor() as usize + 1;
            line.ts = (0..samples).map(|k| t0 + k as f64 * p.step_m).collect();
        }
        line
    }

    /// The step along the line at parameter `t`.
    fn step(&self, t: f64, p: &CeilingParams) -> f64 {
        p.at_distance(p.step_m, self.d.hypot(t))
    }

    /// For each sampled point, how many of the `slices` hide it from every eye: slice `s` by
    /// the blockers `keep(s, _)` accepts, each slice's blockers a subset of the one before, so
    /// the slices hiding a point are the first ones, and their count is found by bisection.
    fn hiding_slices(
        &self,
        outside: &Outside,
        slices: usize,
        keep: &dyn Fn(usize, &Blocker) -> bool,
        eyes: &[DVec2],
    ) -> Vec<usize> {
        // Coherence along the line: per slice, the eye that last saw a point is tried first,
        // and each eye tries first the blocker that last blocked it (answers do not depend on
        // either).
        let mut hints: Vec<Vec<Option<u32>>> = vec![vec![None; eyes.len()]; slices];
        let mut seer = vec![0usize; slices];
        let mut hidden = |q: DVec2, s: usize| -> bool {
            let keep_s = |b: &Blocker| keep(s, b);
            for j in 0..eyes.len() {
                let e = (seer[s] + j) % eyes.len();
                if !outside.blocked_by(eyes[e], q, 0..0, &mut hints[s][e], &keep_s) {
                    seer[s] = e;
                    return false;
                }
            }
            true
        };
        self.ts
            .iter()
            .map(|&t| {
                let q = self.foot + self.u * t;
                // Slices below `lo` hide it, those from `hi` on do not.
                let (mut lo, mut hi) = (0, slices);
                while lo < hi {
                    let mid = lo + (hi - lo) / 2;
                    if hidden(q, mid) {
                        lo = mid + 1;
                    } else {
                        hi = mid;
                    }
                }
                lo
            })
            .collect()
    }

    /// The candidate segments of slice `s`: the maximal runs of sampled points it hides
    /// (`hiding[k] > s`), each shortened by one step at both ends and kept when at least
    /// `min_len_m` long; in order along the line.
    fn runs(&self, hiding: &[usize], s: usize, p: &CeilingParams) -> Vec<[DVec2; 2]> {
        let (foot, u, ts) = (self.foot, self.u, &self.ts);
        let mut runs = Vec::new();
        let mut start: Option<usize> = None;
        for k in 0..=ts.len() {
            let h = k < ts.len() && hiding[k] > s;
            match (h, start) {
                (true, None) => start = Some(k),
                (false, Some(k0)) => {
                    let (ta, tb) = (
                        ts[k0] + self.step(ts[k0], p),
                        ts[k - 1] - self.step(ts[k - 1], p),
                    );
                    if tb - ta >= p.min_len_m {
                        runs.push([foot + u * ta, foot + u * tb]);
                    }
                    start = None;
                }
                _ => {}
            }
        }
        runs
    }
}

/// The bounds of the scene's blockers (its terrain's included) and objects, `(min, max)`.
fn scene_bounds(scene: &Scene) -> (DVec2, DVec2) {
    let inf = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    let (lo, hi) = scene
        .blockers
        .iter()
        .chain(scene.terrain_blockers())
        .flat_map(|b| b.polygon.iter().copied())
        .chain(
            scene
                .objects
                .iter()
                .flat_map(|o| [o.bbox.min.truncate(), o.bbox.max.truncate()]),
        )
        .fold(inf, |(l, h), v| (l.min(v), h.max(v)));
    if lo.x > hi.x {
        (DVec2::ZERO, DVec2::ZERO)
    } else {
        (lo, hi)
    }
}

/// Signed distance of `x` from the line through `p` and `q` (`p != q`), positive to the left.
fn side(p: DVec2, q: DVec2, x: DVec2) -> f64 {
    (q - p).perp_dot(x - p) / p.distance(q)
}

/// Whether the segment `[c, w]` crosses the segment `[a, b]` with [`UMBRA_MARGIN_M`] to spare:
/// `c` and `w` on opposite sides of the line `ab`, and `a` and `b` on opposite sides of the line
/// `cw`, each at least the margin away (so rounding cannot turn a miss into a crossing).
fn crosses(c: DVec2, w: DVec2, a: DVec2, b: DVec2) -> bool {
    let m = UMBRA_MARGIN_M;
    let apart = |x: f64, y: f64| (x >= m && y <= -m) || (x <= -m && y >= m);
    c.distance(w) > m && apart(side(a, b, c), side(a, b, w)) && apart(side(c, w, a), side(c, w, b))
}

/// Whether the box (its corners) lies in the umbra of the segment `[a, b]` seen from the cell
/// (its corners): every segment from a cell corner to a box corner crosses `[a, b]`. The umbra
/// seen from one point is convex, and so is the set of points that see a given point through
/// the segment, so corners decide for the whole cell and the whole box.
fn box_in_umbra(cell: &[DVec2; 4], bx: &[DVec2; 4], a: DVec2, b: DVec2) -> bool {
    bx.iter()
        .all(|&w| cell.iter().all(|&c| crosses(c, w, a, b)))
}

/// Rule 3's heights for a box (corners `bx`, heights `z = (zmin, zmax)`) in the umbra of a VO
/// `[a, b]` of top `t` standing on the ground `h.g`: with `F = 1 + dist(box, line) / d_line`
/// (`d_line` the greatest distance of a cell corner from the VO's line), `zmax <= e1 + (t - e1)
/// F` and `zmin >= min(g, e0 - (e0 - g) F)`, each with [`UMBRA_MARGIN_M`] to spare.
fn heights_hold(
    cell: &[DVec2; 4],
    bx: &[DVec2; 4],
    (zmin, zmax): (f64, f64),
    a: DVec2,
    b: DVec2,
    t: f64,
    h: Heights,
) -> bool {
    let m = UMBRA_MARGIN_M;
    let d_line = cell
        .iter()
        .map(|&c| side(a, b, c).abs())
        .fold(0.0, f64::max)
        + m;
    let dl = (bx
        .iter()
        .map(|&w| side(a, b, w).abs())
        .fold(f64::INFINITY, f64::min)
        - m)
        .max(0.0);
    let f = 1.0 + dl / d_line;
    let top = h.e1 + (t - h.e1).max(0.0) * f;
    let bottom = h.g.min(h.e0 - (h.e0 - h.g).max(0.0) * f);
    h.e0 >= h.g && zmax + m <= top && zmin - m >= bottom
}

fn bounds(p: &[DVec2]) -> ([f64; 2], [f64; 2]) {
    let (lo, hi) = p.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(l, h), v| (l.min(*v), h.max(*v)),
    );
    (lo.to_array(), hi.to_array())
}

#[cfg(test)]
mod tests;
