//! The bake: from blockers to per-cell virtual occluders. One file per pipeline stage.
//!
//! Stages so far: [`seed`] (which blockers start a cluster) and [`umbra`] (aggregate umbrae grown
//! from a seed, and the dense set of 2D virtual occluders behind them). [`svg`] draws one cell.
//! Every VO any stage emits passes the exact verifier ([`crate::geom::verify`]) before it
//! leaves the stage; a VO it had to cut or drop is counted, and tests require that count be 0.

pub mod seed;
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
            tree: RTree::bulk_load(items),
        }
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
