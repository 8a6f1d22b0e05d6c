//! The bake: from blockers to per-cell virtual occluders. One file per stage, one folder per
//! generator.
//!
//! The frame of a bake: [`params`] (what it is asked for, one documented
//! [`params::BakeParams`]), [`plan`] (the frame, the blocker set, the occludees, one cell's
//! dispatch, all cells in parallel, the records), [`cell`] (the setup both generators share:
//! ground, eyes, the inside-a-building skip, the usable blockers with their rule-2 support, the
//! slice levels; and the record of the VOs picked), [`slice`](mod@slice) (slice heights,
//! area-angle weights and rule 2), [`occludees`] (the boxes and costs both generators weigh
//! with, rule 3), [`quantize`] (a VO to its 5 bytes). [`job`] is the whole bake as one library
//! call (selection, shards, reuse, hashes, encoding, summary), [`incremental`] the per-cell
//! content hashes, [`budget`] the grid's memory check.
//! The long generator (the default), in pipeline order: [`long`] (one cell's VOs, trimming),
//! [`hidden`] (per slice, a raster of what the cell's boundary cannot see, sampled), [`propose`]
//! (the long hidden runs of lines on it), [`certify`] (the exact verifier cuts a proposal into
//! certified pieces; quantization to 5 bytes, re-checked, then the highest level that still
//! holds), [`select`] (lazy greedy by occludee cost hidden, certifying only what it picks),
//! [`share`] (the store's bytes shared within groups of 4 x 4 cells: each keeps its cap, the
//! rest goes to the group's best further picks).
//! The growth generator, kept as a measured baseline: [`growth`] (aggregate umbrae grown from
//! single buildings, the dense set, greedy decimation, the picture of one cell's growth).
//! Invariant: every stored VO passes rule 2 and the exact verifier ([`crate::geom::verify`]) in
//! its dequantized form; a VO that fails is shrunk or dropped and counted. This file holds
//! [`BlockerSet`] (2D blockers, their R-tree and a bucket grid for ray walks) and the mid-height
//! slice of `vocc render --debug`.

pub mod budget;
pub mod cell;
pub mod certify;
pub mod far;
pub mod growth;
pub mod hidden;
pub mod incremental;
pub mod job;
pub mod long;
pub mod merge;
pub mod occludees;
pub mod params;
pub mod plan;
pub mod propose;
pub mod quantize;
pub mod reach;
pub mod select;
pub mod share;
pub mod slice;
pub mod spans;
pub mod terrain;
pub mod trace;

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
    /// The same boxes in a uniform grid, for the many small queries along rays.
    grid: Buckets,
}

/// A uniform grid of buckets over boxes, compressed (bucket `k` holds
/// `ids[start[k]..start[k + 1]]`). A box is listed in every bucket it touches, so a query box
/// meets every box that meets it in at least one shared bucket (bucket indices are one monotone
/// function of the coordinate for both).
struct Buckets {
    lo: DVec2,
    size: f64,
    nx: usize,
    ny: usize,
    start: Vec<u32>,
    ids: Vec<u32>,
    boxes: Vec<(DVec2, DVec2)>,
}

impl Buckets {
    /// Side of a bucket, metres, unless the extent needs more buckets than [`Self::MAX_PER_BOX`]
    /// per box.
    const SIZE_M: f64 = 25.0;
    const MAX_PER_BOX: usize = 8;

    fn new(boxes: Vec<(DVec2, DVec2)>) -> Buckets {
        let (lo, hi) = boxes.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(l, h), b| (l.min(b.0), h.max(b.1)),
        );
        if boxes.is_empty() || !(lo.is_finite() && hi.is_finite()) {
            return Buckets {
                lo: DVec2::ZERO,
                size: 1.0,
                nx: 0,
                ny: 0,
                start: vec![0],
                ids: Vec::new(),
                boxes,
            };
        }
        let ext = hi - lo;
        let budget = (Self::MAX_PER_BOX * boxes.len()).max(1 << 12) as f64;
        let size = Self::SIZE_M.max((ext.x * ext.y / budget).sqrt()).max(1e-9);
        let nx = (ext.x / size) as usize + 1;
        let ny = (ext.y / size) as usize + 1;
        let mut g = Buckets {
            lo,
            size,
            nx,
            ny,
            start: vec![0; nx * ny + 1],
            ids: Vec::new(),
            boxes,
        };
        for b in &g.boxes {
            let (x0, y0, x1, y1) = g.range(b.0, b.1);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    g.start[y * nx + x + 1] += 1;
                }
            }
        }
        for k in 0..nx * ny {
            g.start[k + 1] += g.start[k];
        }
        let mut fill = g.start.clone();
        g.ids = vec![0; g.start[nx * ny] as usize];
        for (i, b) in g.boxes.iter().enumerate() {
            let (x0, y0, x1, y1) = g.range(b.0, b.1);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let k = y * nx + x;
                    g.ids[fill[k] as usize] = i as u32;
                    fill[k] += 1;
                }
            }
        }
        g
    }

    /// Bucket index ranges (inclusive) touched by the box `[lo, hi]`, clamped to the grid.
    fn range(&self, lo: DVec2, hi: DVec2) -> (usize, usize, usize, usize) {
        let ix = |v: f64, n: usize| (((v / self.size).floor().max(0.0)) as usize).min(n - 1);
        let (a, b) = (lo - self.lo, hi - self.lo);
        (
            ix(a.x, self.nx),
            ix(a.y, self.ny),
            ix(b.x, self.nx),
            ix(b.y, self.ny),
        )
    }

    /// Calls `f` with every box id meeting `[lo, hi]`, possibly more than once.
    fn each(&self, lo: DVec2, hi: DVec2, mut f: impl FnMut(u32)) {
        if self.nx == 0 {
            return;
        }
        let (x0, y0, x1, y1) = self.range(lo, hi);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let k = y * self.nx + x;
                for &id in &self.ids[self.start[k] as usize..self.start[k + 1] as usize] {
                    let (bl, bh) = self.boxes[id as usize];
                    if bl.x <= hi.x && bh.x >= lo.x && bl.y <= hi.y && bh.y >= lo.y {
                        f(id);
                    }
                }
            }
        }
    }
}

impl BlockerSet {
    pub fn new(polys: Vec<Vec<DVec2>>, heights: Vec<f64>) -> Self {
        let boxes: Vec<(DVec2, DVec2)> = polys.iter().map(|p| bounds(p)).collect();
        let items = boxes
            .iter()
            .enumerate()
            .map(|(i, (lo, hi))| {
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
            grid: Buckets::new(boxes),
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

    /// [`Self::in_box`] through the bucket grid, faster for small boxes: calls `f` with every
    /// blocker whose bounding box meets `[lo, hi]`, possibly more than once, in no set order.
    pub fn each_in_box(&self, lo: DVec2, hi: DVec2, f: impl FnMut(u32)) {
        self.grid.each(lo, hi, f)
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
