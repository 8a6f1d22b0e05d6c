//! The 2D fusion bound: how much any set of occluders built from the blockers outside a cell
//! could cull, estimated by sampling. It tells what limits tightness: the VOs, or the cell.
//!
//! Input: the scene (objects and blockers, local frame), a cell rectangle, and the sampling
//! density (points on the cell's boundary, points per object).
//! Output: [`hidden_2d`], the ascending ids of the objects whose sampled footprint points are all
//! cut off from every sampled point of the cell by blockers whose interiors miss the cell,
//! heights ignored (every blocker infinitely tall).
//! Why it bounds the VO method: a stored VO certifies only a region that blockers disjoint from
//! the cell hide in 2D (rule 1), and rule 3 adds heights, which can only cull less. So an object
//! outside this set can be culled by no VO of this cell. Sampling makes the set optimistic (a
//! visible object may look hidden if no sampled ray finds it), so it is an upper estimate of what
//! VOs could cull: an estimate of the bound, not a certificate, and never used to cull.
//! Invariants: no code of the occlusion pipeline (bake, verifier, culler) is used, only the scene
//! and the exact segment predicate; deterministic.

use glam::DVec2;
use rayon::prelude::*;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};

use crate::geom::predicates::{convex_interiors_disjoint, segment_meets_convex};
use crate::scene::Scene;

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

/// Objects that sampled rays find hidden from the cell `r = [x0, y0, x1, y1]` in 2D, by the
/// blockers outside it (module header). Objects without blockers are counted visible.
pub fn hidden_2d(scene: &Scene, r: [f64; 4], p: &BoundParams) -> Vec<u32> {
    let cell = [
        DVec2::new(r[0], r[1]),
        DVec2::new(r[2], r[1]),
        DVec2::new(r[2], r[3]),
        DVec2::new(r[0], r[3]),
    ];
    let outside: Vec<usize> = (0..scene.blockers.len())
        .filter(|&i| convex_interiors_disjoint(&scene.blockers[i].polygon, &cell))
        .collect();
    let tree: RTree<GeomWithData<Rectangle<[f64; 2]>, u32>> = RTree::bulk_load(
        outside
            .iter()
            .map(|&i| {
                let (lo, hi) = bounds(&scene.blockers[i].polygon);
                GeomWithData::new(Rectangle::from_corners(lo, hi), i as u32)
            })
            .collect(),
    );
    let per = (2.0 * (r[2] - r[0] + r[3] - r[1])) / p.cell_points as f64;
    let centre = (cell[0] + cell[2]) * 0.5;
    let eyes: Vec<DVec2> = (0..p.cell_points)
        .map(|k| {
            let mut d = per * (k as f64 + 0.5);
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
        .collect();
    // Blocker ranges per object (blockers are grouped by object, in object order).
    let mut first = vec![usize::MAX; scene.objects.len()];
    let mut count = vec![0usize; scene.objects.len()];
    for (i, b) in scene.blockers.iter().enumerate() {
        let o = b.object as usize;
        first[o] = first[o].min(i);
        count[o] += 1;
    }
    let blocked = |a: DVec2, b: DVec2, own: std::ops::Range<usize>| -> bool {
        // Step along the segment so the first blocker near the cell ends the search early.
        let len = a.distance(b);
        let steps = (len / 25.0).ceil().max(1.0) as usize;
        for s in 0..steps {
            let p0 = a + (b - a) * (s as f64 / steps as f64);
            let p1 = a + (b - a) * ((s + 1) as f64 / steps as f64);
            let (lo, hi) = (p0.min(p1), p0.max(p1));
            let hit = tree
                .locate_in_envelope_intersecting(AABB::from_corners(lo.to_array(), hi.to_array()))
                .any(|g| {
                    let i = g.data as usize;
                    !own.contains(&i) && segment_meets_convex(a, b, &scene.blockers[i].polygon)
                });
            if hit {
                return true;
            }
        }
        false
    };
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
            pts.iter()
                .step_by(stride)
                .all(|&t| eyes.iter().all(|&e| blocked(e, t, own.clone())))
        })
        .collect()
}

fn bounds(p: &[DVec2]) -> ([f64; 2], [f64; 2]) {
    let (lo, hi) = p.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(l, h), v| (l.min(*v), h.max(*v)),
    );
    (lo.to_array(), hi.to_array())
}
