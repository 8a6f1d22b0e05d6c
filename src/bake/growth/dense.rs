//! The dense set of one cell: every seed's growth, its VOs counted once, and the gate.
//!
//! Input: a convex cell (counter-clockwise), the slice's [`BlockerSet`], [`GrowParams`] and the
//! search distance (`search_m`, metres) the active lines are followed. Output: [`CellVos`]: the
//! dense set of VOs of the cell, each a segment with both endpoints on a 2^-10 m grid and hidden
//! from the whole cell, plus the growth trace for pictures and the VOs the verifier had to cut or
//! drop (the gate; tests require none).
//! Rule: seeds ([`super::seed`]) ranked by area-angle, each grown into chains ([`super::umbra`])
//! unless an earlier seed's cluster already holds it; identical segments from different chains
//! count once; with [`GrowParams::verify`], every VO then passes the exact verifier over the
//! same blockers, which shares nothing with the growth but the predicates (a VO it cuts keeps
//! its longest certified part of at least [`GrowParams::min_vo_m`]).
//! Invariants: deterministic (the hash sets are only tested, never iterated); one
//! [`CellGrower`] shares the tangents and ray queries between a cell's slices.

use glam::DVec2;

use super::umbra::{grower, Grower, HashSet, SeedTrace, Vo};
use super::{seed, GrowParams};
use crate::bake::cell::usable;
use crate::bake::BlockerSet;
use crate::geom::verify::Verifier;

/// Everything the growth gives for one cell.
#[derive(Clone, Debug, Default)]
pub struct CellVos {
    /// The dense set, every VO verified.
    pub vos: Vec<Vo>,
    /// VOs the verifier had to cut or drop (must be none), as the growth emitted them.
    pub rejected_vos: Vec<Vo>,
    pub traces: Vec<SeedTrace>,
}

impl CellVos {
    /// How many VOs the verifier had to cut or drop (tests require 0).
    pub fn rejected(&self) -> usize {
        self.rejected_vos.len()
    }
}

/// Grows from one given seed (for tests and pictures), over the blockers within `search_m`
/// (metres); the VOs are not yet verified.
pub fn grow_seed(
    cell: &[DVec2],
    set: &BlockerSet,
    params: &GrowParams,
    search_m: f64,
    seed: u32,
) -> (Vec<Vo>, SeedTrace) {
    let near = usable(cell, set, search_m);
    grower(cell, set, params, search_m, &near).grow(seed)
}

/// Grows the dense VO set of one cell over the blockers within `search_m` (metres) and passes it
/// through the exact verifier.
pub fn grow_cell(cell: &[DVec2], set: &BlockerSet, params: &GrowParams, search_m: f64) -> CellVos {
    CellGrower::new(cell, set, params, search_m).grow(&usable(cell, set, search_m))
}

/// The growth of one cell over several blocker subsets (the slices), sharing the tangents and
/// ray queries between them: a tangent of two blockers does not depend on the slice.
pub struct CellGrower<'a>(Grower<'a>);

impl<'a> CellGrower<'a> {
    /// The growth of `cell`, its active lines followed `search_m` metres.
    pub fn new(
        cell: &'a [DVec2],
        set: &'a BlockerSet,
        params: &'a GrowParams,
        search_m: f64,
    ) -> Self {
        CellGrower(grower(cell, set, params, search_m, &[]))
    }

    /// The dense set over blockers `near_sorted` (sorted ids, none overlapping the cell).
    pub fn grow(&mut self, near_sorted: &[u32]) -> CellVos {
        self.0.usable = near_sorted.iter().copied().collect();
        let (cell, set, params) = (self.0.cell, self.0.set, self.0.params);
        grow_usable(&mut self.0, cell, set, params, near_sorted)
    }
}

fn grow_usable(
    g: &mut Grower,
    cell: &[DVec2],
    set: &BlockerSet,
    params: &GrowParams,
    near_sorted: &[u32],
) -> CellVos {
    let seeds = seed::seeds(cell, set, near_sorted, params.seeds);
    let mut out = CellVos::default();
    let mut dense: Vec<Vo> = Vec::new();
    let mut grown: HashSet<u32> = HashSet::default();
    for s in seeds {
        // A seed already inside a grown cluster would grow the same cluster again.
        if grown.contains(&s) {
            continue;
        }
        let (vos, trace) = g.grow(s);
        if let Some(last) = trace.steps.last() {
            grown.extend(last.chain.iter().copied());
        }
        dense.extend(vos);
        out.traces.push(trace);
    }
    // Identical segments from different chains count once.
    let mut seen = HashSet::default();
    dense.retain(|v| {
        seen.insert((
            v.a.x.to_bits(),
            v.a.y.to_bits(),
            v.b.x.to_bits(),
            v.b.y.to_bits(),
        ))
    });
    if !params.verify {
        out.vos = dense;
        return out;
    }
    // The gate: the exact verifier, which shares nothing with the growth but the predicates.
    let ver = Verifier::new(
        cell,
        near_sorted
            .iter()
            .map(|&id| set.polys[id as usize].as_slice()),
    );
    for v in dense {
        if ver.is_hidden(v.a, v.b) {
            out.vos.push(v);
            continue;
        }
        out.rejected_vos.push(v.clone());
        let parts = ver.hidden_parts(v.a, v.b);
        if let Some(h) = parts
            .iter()
            .max_by(|x, y| x.p0.distance(x.p1).total_cmp(&y.p0.distance(y.p1)))
        {
            if h.p0.distance(h.p1) >= params.min_vo_m {
                out.vos.push(Vo {
                    a: h.p0,
                    b: h.p1,
                    chain: v.chain,
                });
            }
        }
    }
    out
}
