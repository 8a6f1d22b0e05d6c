//! The occludees both generators weigh their VOs with: every object's box and cost, on the
//! runtime's own box hierarchy.
//!
//! Input: a [`Scene`](crate::scene::Scene) (or boxes and costs). Output: [`Occludees`]: boxes and
//! costs by position in the hierarchy, and, for a VO seen from a cell, the occludees it hides
//! (rule 3, the runtime's own test, so a weight is what the runtime will cull), as [`Spans`] of
//! positions found whole subtrees at a time, so weighing against a whole city costs about what
//! weighing against a neighbourhood does.
//! Invariants: a cost is at least 1; the hidden set of a VO holds only occludees within the given
//! radius of the cell centre (per axis), which is what keeps a cell's bake within its reach
//! (ARCHITECTURE.md invariant 13).

use super::spans::{Costs, Spans};
use crate::runtime::culler::{BoxTree, Coarse};
use crate::runtime::frame::{CellView, VoGeom};
use crate::runtime::occlusion::PreparedVo;

/// Subtrees partly hidden by a VO that look smaller than this from the cell, radians, are
/// passed over whole when a VO is weighed (`BoxTree::hidden_runs`): a subtree of buildings
/// 2 km away on the edge of an umbra, 20 m across, weighs nothing rather than being walked box
/// by box. It only lowers weights, and decides nothing.
pub const WEIGH_MIN_ANGLE: f64 = 0.01;
/// Beyond this distance from the cell's centre, metres (past a cell's own reach and its block's
/// far field), subtrees partly hidden are passed over below [`WEIGH_FAR_MIN_ANGLE`] instead:
/// there the edges of a VO's umbra are kilometres long, and walking them at the near angle was
/// most of the weighing's cost in a city 25 km wide (docs/SCALING.md), for weights that chose the
/// same VOs as well. A city narrower than this is weighed as before.
pub const WEIGH_FAR_M: f64 = 3000.0;
pub const WEIGH_FAR_MIN_ANGLE: f64 = 0.05;

/// The occludees of a scene: boxes in the local frame, with costs, under the runtime's box
/// hierarchy. Occludees are named by their position in the hierarchy (each subtree a
/// contiguous range), so the hidden sets of rule 3 come out whole subtrees at a time.
pub struct Occludees {
    /// Boxes and costs, by position.
    pub boxes: Vec<[f64; 6]>,
    pub cost: Vec<u64>,
    /// The same costs as prefix sums.
    pub costs: Costs,
    /// Which subtrees partly hidden are passed over whole when weighing
    /// (`BoxTree::hidden_runs`): [`Coarse::EXACT`] weighs exactly.
    pub(crate) coarse: Coarse,
    tree: BoxTree,
}

impl Occludees {
    /// `boxes[i]` and `cost[i]` of object `i`.
    pub fn new(boxes: Vec<[f64; 6]>, cost: Vec<u64>) -> Occludees {
        let tree = BoxTree::new(&boxes);
        let by_pos = (0..tree.positions() as u32).map(|p| tree.id_at(p) as usize);
        let cost: Vec<u64> = by_pos.clone().map(|i| cost[i]).collect();
        Occludees {
            boxes: by_pos.map(|i| boxes[i]).collect(),
            costs: Costs::new(&cost),
            cost,
            coarse: Coarse {
                angle: WEIGH_MIN_ANGLE,
                far_m: WEIGH_FAR_M,
                far_angle: WEIGH_FAR_MIN_ANGLE,
            },
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
    /// from the cell (rule 3).
    pub fn hidden(&self, view: &CellView, vo: &VoGeom, radius: f64) -> Spans {
        let mut out = Spans::new();
        self.hidden_with(view, vo, radius, |s, e, _| out.push(s, e));
        out
    }

    /// [`Self::hidden`], also calling `bounds(b)` with the box of each subtree or occludee found
    /// hidden whole: together they hold every hidden occludee's box.
    pub fn hidden_bounds(
        &self,
        view: &CellView,
        vo: &VoGeom,
        radius: f64,
        mut bounds: impl FnMut(&[f64; 6]),
    ) -> Spans {
        let mut out = Spans::new();
        self.hidden_with(view, vo, radius, |s, e, b| {
            out.push(s, e);
            bounds(b);
        });
        out
    }

    fn hidden_with(
        &self,
        view: &CellView,
        vo: &VoGeom,
        radius: f64,
        found: impl FnMut(u32, u32, &[f64; 6]),
    ) {
        let p = PreparedVo::new(view, vo);
        let r = view.rect;
        let (cx, cy) = (0.5 * (r[0] + r[2]), 0.5 * (r[1] + r[3]));
        self.tree.hidden_runs(
            view,
            &p,
            [cx - radius, cy - radius, cx + radius, cy + radius],
            &self.boxes,
            self.coarse,
            found,
        );
    }

    /// The object at position `pos`.
    pub fn object(&self, pos: u32) -> u32 {
        self.tree.id_at(pos)
    }

    /// The summed cost of `s`.
    pub fn cost_of(&self, s: &Spans) -> u64 {
        self.costs.of(s)
    }
}
