//! The bake: from blockers to per-cell virtual occluders. One file per pipeline stage.
//!
//! Stages, in pipeline order: [`slice`] (slice heights and rule 2), [`seed`] (which blockers
//! start a cluster), [`umbra`] (aggregate umbrae grown from a seed, and the dense set of 2D
//! virtual occluders behind them), [`decimate`] (the few most effective), [`quantize`] (5 bytes,
//! conservatively). [`pipeline`] orchestrates them per cell and over cells; [`svg`] draws one
//! cell. Every stored VO passes rule 2 and the exact verifier ([`crate::geom::verify`]) in its
//! dequantized form; a VO that fails is shrunk or dropped and counted.

pub mod decimate;
pub mod incremental;
pub mod pipeline;
pub mod quantize;
pub mod seed;
pub mod slice;
pub mod svg;
pub mod umbra;

use glam::DVec2;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};

/// The 2D blockers of one slice, with a spatial index.
pub struct BlockerSet {
    /// Convex, counter-clockwise polygons, local frame.
    pub polys: Vec<Vec<DVec2>>,
    /// Height of the wall that stands above the slice's base, per blocker, metres (for seeding).
    pub heights: Vec<f64>,
    /// The object each blocker comes from (empty when unknown; then every blocker counts as its
    /// own object).
    pub objects: Vec<u32>,
    tree: RTree<GeomWithData<Rectangle<[f64; 2]>, u32>>,
}

impl BlockerSet {
    pub fn new(polys: Vec<Vec<DVec2>>, heights: Vec<f64>) -> Self {
        let items = polys
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let (lo, hi) = bounds(p);
                GeomWithData::new(
                    Rectangle::from_corners(lo.to_array(), hi.to_array()),
                    i as u32,
                )
            })
            .collect();
        BlockerSet {
            polys,
            heights,
            objects: Vec::new(),
            tree: RTree::bulk_load(items),
        }
    }

    /// The same set, knowing which object each blocker comes from.
    pub fn with_objects(mut self, objects: Vec<u32>) -> Self {
        self.objects = objects;
        self
    }

    /// Whether blockers `a` and `b` come from one object.
    pub fn same_object(&self, a: u32, b: u32) -> bool {
        a == b
            || (!self.objects.is_empty()
                && self.objects.get(a as usize) == self.objects.get(b as usize))
    }

    /// Blockers whose bounding box meets the axis-aligned box `[lo, hi]`.
    pub fn in_box(&self, lo: DVec2, hi: DVec2) -> impl Iterator<Item = u32> + '_ {
        self.tree
            .locate_in_envelope_intersecting(AABB::from_corners(lo.to_array(), hi.to_array()))
            .map(|g| g.data)
    }

    pub fn len(&self) -> usize {
        self.polys.len()
    }

    pub fn is_empty(&self) -> bool {
        self.polys.is_empty()
    }
}

/// Bounding box of a point set.
pub fn bounds(p: &[DVec2]) -> (DVec2, DVec2) {
    p.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), &v| (lo.min(v), hi.max(v)),
    )
}

/// The 2D blockers of a scene cut by the horizontal plane at height `z` (local frame): every
/// blocker with `base <= z <= top`. Each counts with the height from its base to `z` for seeding.
pub fn slice_blockers(scene: &crate::scene::Scene, z: f64) -> BlockerSet {
    let (polys, heights) = scene
        .blockers
        .iter()
        .filter(|b| b.base <= z && b.top >= z)
        .map(|b| (b.polygon.clone(), z - b.base))
        .unzip();
    BlockerSet::new(polys, heights)
}

/// A single slice at mid height: half the median object height above the lowest object base.
pub fn mid_slice(scene: &crate::scene::Scene) -> f64 {
    let mut h: Vec<f64> = scene
        .objects
        .iter()
        .map(|o| o.bbox.max.z - o.bbox.min.z)
        .collect();
    if h.is_empty() {
        return 0.0;
    }
    h.sort_by(f64::total_cmp);
    let ground = scene
        .objects
        .iter()
        .map(|o| o.bbox.min.z)
        .fold(f64::INFINITY, f64::min);
    ground + 0.5 * h[h.len() / 2]
}

/// The square cell of side `size` that holds local point `p`, on the grid anchored at the scene
/// extent's minimum corner; counter-clockwise.
pub fn grid_cell(scene: &crate::scene::Scene, p: DVec2, size: f64) -> [DVec2; 4] {
    let ext = scene.extent();
    let o = DVec2::new(ext.min.x, ext.min.y);
    let k = ((p - o) / size).floor();
    let a = o + k * size;
    [
        a,
        a + DVec2::new(size, 0.0),
        a + DVec2::new(size, size),
        a + DVec2::new(0.0, size),
    ]
}
