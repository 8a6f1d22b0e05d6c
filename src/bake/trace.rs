//! The long generator's trace of one cell, for its debug picture (`vocc render --debug`): what
//! the bake itself does for the cell, told by [`super::long::long_vos_traced`].
//!
//! Input: the bake's own [`Plan`] (its grid, frame and parameters, so the cell and its maps are
//! the bake's) and a cell id. Output: a [`CellTrace`]: the cell, its blockers, each slice's hidden map, the
//! proposals as weighed, the pieces the selection certified, the VOs it stored, and the record.
//! Invariant: observing decides nothing: the record is the one the long generator gives the
//! cell's setup on its own ground (a deep bake on a terrain, [`Plan::bake_cell`], may keep
//! another), with all its picks: a bake keeps a prefix of them, what its group's share of the
//! byte budget allows (`bake/share.rs`).

use glam::DVec2;

use super::cell::CellSetup;
use super::hidden::HiddenMap;
use super::long::{long_vos_traced, Traced};
use super::plan::{CellStats, Plan};
use crate::runtime::frame::VoGeom;
use crate::runtime::grid::CellId;

/// What the long generator did for one cell. Segments are `(top, a, b)`, local frame, metres.
#[derive(Clone, Debug)]
pub struct CellTrace {
    pub id: CellId,
    pub cell: [DVec2; 4],
    /// The blockers that may support the cell's VOs (its setup's near blockers), outlines.
    pub blockers: Vec<Vec<DVec2>>,
    /// Per slice, its VO top and its hidden map.
    pub maps: Vec<(f64, HiddenMap)>,
    /// The proposals, trimmed and weighed (those that hide something).
    pub proposals: Vec<(f64, DVec2, DVec2)>,
    /// The certified pieces of the proposals the selection certified.
    pub certified: Vec<(f64, DVec2, DVec2)>,
    /// Every VO stored along the way, as the runtime reads it (the record keeps the picked).
    pub stored: Vec<VoGeom>,
    /// The record's VOs, most effective first, as the runtime reads them.
    pub picked: Vec<VoGeom>,
    pub stats: CellStats,
}

/// The trace of cell `id` of the plan, or `None` when the long generator has nothing to do
/// there (no eyes, no blocker that may support a VO, inside a building).
pub fn trace_cell(plan: &Plan, id: CellId) -> Option<CellTrace> {
    let setup = CellSetup::new(plan, id).ok()?;
    let top = |k: u8| setup.levels[k as usize];
    let mut t = CellTrace {
        id,
        cell: setup.cell,
        blockers: setup
            .near
            .iter()
            .map(|&i| plan.set.polys[i as usize].clone())
            .collect(),
        maps: Vec::new(),
        proposals: Vec::new(),
        certified: Vec::new(),
        stored: Vec::new(),
        picked: Vec::new(),
        stats: CellStats::default(),
    };
    let mut stats = CellStats::default();
    let record = long_vos_traced(plan, &setup, &mut stats, &mut |e| match e {
        Traced::Map(k, m) => t.maps.push((top(k), m.clone())),
        Traced::Proposal(k, a, b) => t.proposals.push((top(k), a, b)),
        Traced::Certified(pieces) => t
            .certified
            .extend(pieces.iter().map(|p| (top(p.level), p.a, p.b))),
        Traced::Stored(g) => t.stored.push(*g),
    });
    t.picked = record
        .vos()
        .iter()
        .filter_map(|q| plan.frame.dequantize(id, record.stand(), q))
        .collect();
    t.stats = stats;
    Some(t)
}
