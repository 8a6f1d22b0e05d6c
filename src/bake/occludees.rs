//! The occludees both generators weigh their VOs with: every object's box and cost, on the
//! runtime's own box hierarchy.
//!
//! Input: a [`Scene`](crate::scene::Scene) (or boxes and costs). Output: [`Occludees`]: boxes and
//! costs by position in the hierarchy, and, for a VO seen from a cell, the occludees it hides
//! (rule 3, the runtime's own test, so a weight is what the runtime will cull).
//! Invariants: a cost is at least 1; the hidden set of a VO is ascending and holds only
//! occludees within the given radius of the cell centre (per axis), which is what keeps a cell's
//! bake within its reach (ARCHITECTURE.md invariant 13).

use crate::runtime::culler::BoxTree;
use crate::runtime::frame::{CellView, VoGeom};
use crate::runtime::occlusion::PreparedVo;

/// The occludees of a scene: boxes in the local frame, with costs, under the runtime's box
/// hierarchy. Occludees are named by their position in the hierarchy (each subtree a
/// contiguous range), so the hidden sets of rule 3 come out whole subtrees at a time.
pub struct Occludees {
    /// Boxes and costs, by position.
    pub boxes: Vec<[f64; 6]>,
    pub cost: Vec<u64>,
    tree: BoxTree,
}

impl Occludees {
    /// `boxes[i]` and `cost[i]` of object `i`.
    pub fn new(boxes: Vec<[f64; 6]>, cost: Vec<u64>) -> Occludees {
        let tree = BoxTree::new(&boxes);
        let by_pos = (0..tree.positions() as u32).map(|p| tree.id_at(p) as usize);
        Occludees {
            boxes: by_pos.clone().map(|i| boxes[i]).collect(),
            cost: by_pos.map(|i| cost[i]).collect(),
            tree,
        }
    }

    pub fn from_scene(scene: &crate::scene::Scene) -> Occludees {
        let boxes = scene
            .objects
            .iter()
            .map(|o| {
                let (a, b) = (o.bbox.min, o.bbox.max);
                [a.x, a.y, a.z, b.x, b.y, b.z]
            })
            .collect();
        let cost = scene.objects.iter().map(|o| o.cost.max(1)).collect();
        Occludees::new(boxes, cost)
    }

    /// The occludees (positions) within `radius` of the cell centre (per axis) that `vo` hides
    /// from the cell (rule 3), ascending.
    pub fn hidden(&self, view: &CellView, vo: &VoGeom, radius: f64) -> Vec<u32> {
        let p = PreparedVo::new(view, vo);
        let r = view.rect;
        let (cx, cy) = (0.5 * (r[0] + r[2]), 0.5 * (r[1] + r[3]));
        let mut out = Vec::new();
        self.tree.hidden_positions(
            view,
            &p,
            [cx - radius, cy - radius, cx + radius, cy + radius],
            &self.boxes,
            &mut out,
        );
        out
    }

    /// The object at position `pos`.
    pub fn object(&self, pos: u32) -> u32 {
        self.tree.id_at(pos)
    }

    pub fn cost_of(&self, ids: &[u32]) -> u64 {
        ids.iter().map(|&i| self.cost[i as usize]).sum()
    }
}
