//! One cell's setup, what both generators start from, and the record they end with.
//!
//! Input: the [`Plan`] and a cell id. Output: a `CellSetup`: the cell's polygon, ground level
//! and eyes ([`CellView`]), the blockers near it that may support its VOs with their rule-2
//! [`Support`] and their adjusted heights and weights, the VO top of every height level, and
//! the slice levels ([`choose_levels`]); or, for a cell no generator needs to see, its record:
//! empty (no blocker that may support a VO) or skipped (wholly inside a blocker standing above
//! the eyes). [`usable`] is the blocker query both generators use; `CellSetup::finish` turns
//! the VOs a generator picked into the cell's record. [`VO_GRID_M`] is the grid both generators'
//! VO endpoints lie on.
//! Invariants: a cell's setup reads only the blockers whose boxes meet `cell ± search_m` (within
//! the reach, ARCHITECTURE.md invariant 13) and compares ids only; `near` is ascending, and
//! `support` and `adjusted` are parallel to it; a record holds a ground byte only with VOs.

use glam::DVec2;

use super::params::Slices;
use super::plan::{CellStats, Plan};
use super::slice::{area_angle, auto_slices, choose_levels, Support};
use super::{bounds, BlockerSet};
use crate::geom::predicates::{convex_interiors_disjoint, point_in_convex, Containment};
use crate::runtime::format::CellRecord;
use crate::runtime::frame::{CellGround, CellView, QVo, VoGeom, HEIGHT_LEVELS};
use crate::runtime::grid::CellId;

/// Both generators' VO endpoints (the long one's proposals, the growth's clipped VOs) lie on this
/// grid, metres (2^-10 m): dyadic, so the verifier's bisection midpoints are exact and lie
/// exactly on the segment (ARCHITECTURE.md invariant 8).
pub const VO_GRID_M: f64 = 1.0 / 1024.0;

/// The blockers the VOs of a cell may use: those whose boxes meet the cell grown by `search_m`
/// (metres) on every side, not overlapping it; ascending ids.
pub fn usable(cell: &[DVec2], set: &BlockerSet, search_m: f64) -> Vec<u32> {
    let (lo, hi) = bounds(cell);
    let r = DVec2::splat(search_m);
    let mut near: Vec<u32> = set
        .in_box(lo - r, hi + r)
        .filter(|&id| {
            // A blocker whose box misses the cell's is apart from it (the exact test decides
            // the others).
            let (blo, bhi) = bounds(&set.polys[id as usize]);
            bhi.x < lo.x
                || blo.x > hi.x
                || bhi.y < lo.y
                || blo.y > hi.y
                || convex_interiors_disjoint(&set.polys[id as usize], cell)
        })
        .collect();
    near.sort_unstable();
    near
}

/// What both generators know of a cell before they propose anything.
pub(super) struct CellSetup {
    pub(super) id: CellId,
    /// The cell's polygon, counter-clockwise, local frame.
    pub(super) cell: [DVec2; 4],
    /// The cell's ground level (the frame's ground byte), and its eyes as rule 3 sees them.
    pub(super) ground: CellGround,
    pub(super) view: CellView,
    /// The height of that ground level, metres (local frame).
    pub(super) g: f64,
    /// The cell's centre.
    pub(super) centre: DVec2,
    /// The blockers that may support a VO, ascending ids: near ([`usable`]), apart from the
    /// cell, standing from below the lowest eye (rule 2: `base <= e0 - lambda (e0 - g)`) to
    /// above the eyes.
    pub(super) near: Vec<u32>,
    /// Rule 2's view of each of them from this cell.
    pub(super) support: Vec<Support>,
    /// Each one's adjusted height (metres) and area-angle weight, for the slices.
    pub(super) adjusted: Vec<(f64, f64)>,
    /// The VO top of every height level of the frame above these eyes, metres.
    pub(super) levels: Vec<f64>,
    /// The slice levels chosen for the cell, ascending (indices into `levels`).
    pub(super) slices: Vec<u8>,
}

impl CellSetup {
    /// The setup of cell `id`, or (as `Err`) its record when no generator has anything to do:
    /// empty when it has no eyes or no blocker that may support a VO, skipped when it lies
    /// wholly inside one blocker that stands above the eyes.
    // The record (an inline list of 10 VOs) is the answer, not an error: no boxing.
    #[allow(clippy::result_large_err)]
    pub(super) fn new(plan: &Plan, id: CellId) -> Result<CellSetup, CellRecord> {
        Self::new_with(plan, id, false)
    }

    /// [`CellSetup::new`], with the VOs' bottom at the frame's lowest ground level when `deep`
    /// (format 2.1's deep VOs, bake/terrain.rs): rule 2 then takes that bottom, so only
    /// blockers reaching that low support them, and rule 3 hides what lies below the cell.
    #[allow(clippy::result_large_err)]
    pub(super) fn new_with(plan: &Plan, id: CellId, deep: bool) -> Result<CellSetup, CellRecord> {
        let f = &plan.frame;
        let cell = plan.cell_polygon(id);
        if !plan.eyes_fit(id) {
            return Err(CellRecord::EMPTY);
        }
        let ground = plan.stand(id);
        let Some(view) = f.cell_view(id, ground) else {
            return Err(CellRecord::EMPTY);
        };
        let g = if deep {
            f.ground_z0
        } else {
            f.ground_z(ground.level)
        };
        CellSetup::of_region(plan, id, cell, ground, view, g, plan.params.search_m)
    }

    /// The setup of any rectangle `cell` (counter-clockwise corners) with eyes `view` standing
    /// on `ground`, its VOs' bottom at `g`, whose VOs' blockers lie within `search_m`: a
    /// cell's, or a block of cells' for the far field ([`super::far`]), then named `id`.
    #[allow(clippy::result_large_err)]
    pub(super) fn of_region(
        plan: &Plan,
        id: CellId,
        cell: [DVec2; 4],
        ground: CellGround,
        view: CellView,
        g: f64,
        search_m: f64,
    ) -> Result<CellSetup, CellRecord> {
        let f = &plan.frame;
        let (e0, e1) = (view.e0, view.e1);
        // A cell wholly inside one blocker that stands above the eyes holds no eye.
        let inside = plan.set.in_box(cell[0], cell[2]).any(|i| {
            let p = &plan.set.polys[i as usize];
            plan.base[i as usize] <= e0
                && plan.top[i as usize] >= e1
                && cell
                    .iter()
                    .all(|&c| point_in_convex(p, c) != Containment::Outside)
        });
        if inside {
            return Err(CellRecord::Skipped);
        }
        // Blockers that may support a VO: near, apart from the cell, standing from below the
        // lowest eye (rule 2: base <= e0 - lambda (e0 - g)) to above the eyes.
        let near: Vec<u32> = usable(&cell, &plan.set, search_m)
            .into_iter()
            .filter(|&i| plan.base[i as usize] <= e0 && plan.top[i as usize] > e1)
            .collect();
        if near.is_empty() {
            return Err(CellRecord::EMPTY);
        }
        let centre = (cell[0] + cell[2]) * 0.5;
        let support: Vec<Support> = near
            .iter()
            .map(|&i| {
                let i = i as usize;
                Support::new(&cell, &plan.set.polys[i], plan.base[i], plan.top[i])
            })
            .collect();
        let adjusted: Vec<(f64, f64)> = near
            .iter()
            .zip(&support)
            .map(|(&i, s)| {
                let i = i as usize;
                let w = area_angle(&plan.set.polys[i], plan.top[i] - plan.base[i], centre);
                (s.adjusted_height(e1), w)
            })
            .collect();
        let levels: Vec<f64> = (0..HEIGHT_LEVELS).map(|k| f.vo_top(e1, k)).collect();
        let n = match plan.params.slices {
            Slices::Auto => auto_slices(&adjusted, e1),
            Slices::Fixed(n) => n as usize,
        };
        let slices = choose_levels(&levels, &adjusted, n);
        Ok(CellSetup {
            id,
            cell,
            ground,
            view,
            g,
            centre,
            near,
            support,
            adjusted,
            levels,
            slices,
        })
    }

    /// The record of the cell's picked VOs (stored form, and the form before quantization,
    /// most effective first), with the occludee cost they hide in `stats`.
    pub(super) fn finish(
        &self,
        plan: &Plan,
        vos: Vec<(QVo, VoGeom)>,
        stats: &mut CellStats,
    ) -> CellRecord {
        let (id, ground, view) = (self.id, self.ground, &self.view);
        let f = &plan.frame;
        let (vos, before): (Vec<QVo>, Vec<VoGeom>) = vos.into_iter().unzip();
        stats.unquantized = before;
        let mut all = super::spans::Spans::new();
        for q in &vos {
            if let Some(geom) = f.dequantize(id, ground, q) {
                all = all.union(&plan.occludees.hidden(view, &geom, plan.params.weigh_m));
            }
        }
        stats.hidden_cost = plan.occludees.cost_of(&all);
        // A cell without VOs stores no ground byte: its ground is 0 in the record.
        let ground = if vos.is_empty() {
            CellGround::default()
        } else {
            ground
        };
        CellRecord::new(ground.level, &vos)
            .expect("greedy stops at max_vos, checked <= 10 in Plan::new")
            .with_rise(ground.rise)
    }
}
