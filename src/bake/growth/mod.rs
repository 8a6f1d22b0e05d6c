//! The growth generator (`--generator growth`, the default before 0.2, kept as a measured
//! baseline): aggregate umbrae grown from single buildings (paper 002, section 3).
//!
//! Input: the [`Plan`] and a cell's `CellSetup` (its near blockers with their rule-2 support
//! and adjusted heights, the height levels and the slice levels), [`GrowParams`] and the shared
//! `search_m`. Output: the cell's record, at most `max_vos` stored VOs, most effective first,
//! and what it took in [`CellStats`].
//! Per cell: per slice, the dense set ([`dense`]: seeds ([`seed`]) grown into chains and their
//! VOs ([`umbra`])), each VO clipped to the quantization window, given the highest level its
//! chain supports by rule 2 and weighed by rule 3; then the greedy decimation ([`decimate`])
//! whose accept step quantizes ([`super::quantize`]) and re-checks the *dequantized* VO with
//! rule 2 and the exact verifier, at up to [`LEVEL_FALLBACKS`] levels. A VO that fails is shrunk
//! or dropped and counted. [`svg`] draws one cell's growth (`vocc render --debug`).
//! Invariants: every VO the growth emits is hidden by its chain certificate ([`umbra`]); every
//! stored VO passes rule 2 and the exact verifier in its dequantized form; the growth's hash
//! maps are only looked up, never iterated, so the output does not depend on their order.

pub mod decimate;
pub mod dense;
pub mod seed;
pub mod svg;
pub mod umbra;

use glam::DVec2;

use self::decimate::greedy;
use self::dense::CellGrower;
use super::cell::CellSetup;
use super::certify::LEVEL_FALLBACKS;
use super::plan::{CellStats, Plan};
use super::quantize::{clip, quantize, window, Refused};
use super::slice::{d_near, Support};
use super::BlockerSet;
use crate::geom::verify::Verifier;
use crate::runtime::format::CellRecord;
use crate::runtime::frame::HEIGHT_LEVELS;

/// Parameters of the growth.
#[derive(Clone, Debug)]
pub struct GrowParams {
    /// Seeds ranked by area-angle (the direction rule may add more).
    pub seeds: usize,
    /// Longest chain.
    pub max_chain: usize,
    /// Bridges (case 2) in a row on one side.
    pub max_bridges: usize,
    /// Candidates tried per side and step.
    pub tries: usize,
    /// Shortest VO kept, metres.
    pub min_vo_m: f64,
    /// No fusion: a chain holds the convex pieces of one object only (the single-building
    /// baseline of the paper's Fig. 7).
    pub single_object: bool,
    /// Pass every dense VO through the exact verifier before returning it (the gate). The bake
    /// turns it off: it verifies the few VOs it keeps after quantization instead, from their
    /// stored bytes, with rule 2's blockers.
    pub verify: bool,
}

impl Default for GrowParams {
    fn default() -> Self {
        GrowParams {
            seeds: 8,
            max_chain: 24,
            max_bridges: 2,
            tries: 6,
            min_vo_m: 1.0,
            single_object: false,
            verify: true,
        }
    }
}

/// The growth generator's VOs of one cell: the dense set per slice, then the decimation, each
/// pick quantized and re-checked from its dequantized form. Returns the cell's record.
pub(super) fn growth_vos(plan: &Plan, setup: &CellSetup, stats: &mut CellStats) -> CellRecord {
    let f = &plan.frame;
    let CellSetup {
        id,
        ground,
        view,
        g,
        centre,
        cell,
        ref near,
        ref support,
        ref adjusted,
        ref levels,
        ..
    } = *setup;
    let (e0, e1) = (view.e0, view.e1);
    // The dense set, per slice.
    let radius = plan.params.weigh_m;
    let mut cands: Vec<(u8, DVec2, DVec2)> = Vec::new();
    let mut hidden: Vec<crate::bake::spans::Spans> = Vec::new();
    let mut grower = CellGrower::new(&cell, &plan.set, &plan.params.grow, plan.params.search_m);
    let win = {
        let (lo, hi) = window(f, centre);
        let step = DVec2::splat(f.quantum);
        (lo + step, hi - step)
    };
    // A proposed VO `a`–`b` certified by the blockers `chain`: clipped to the window, given
    // its own level, weighed by what it hides; kept if it hides anything.
    let consider = |a: DVec2,
                    b: DVec2,
                    chain: &[u32],
                    cands: &mut Vec<(u8, DVec2, DVec2)>,
                    hidden: &mut Vec<crate::bake::spans::Spans>| {
        // Only the part inside the quantization window (less a grid step) can be stored.
        let Some((a, b)) = clip(a, b, win.0, win.1) else {
            return;
        };
        if a.distance(b) < 2.0 * f.quantum {
            return;
        }
        // The VO's own level: the highest at which every blocker of the chain that
        // certified it supports it by rule 2 (at least the slice's, usually).
        let dn = d_near(&cell, &[a, b]);
        let chain: Vec<&Support> = chain
            .iter()
            .filter_map(|id| near.binary_search(id).ok().map(|p| &support[p]))
            .collect();
        let Some(level) = (1..HEIGHT_LEVELS).rev().find(|&l| {
            chain
                .iter()
                .all(|s| s.supports(e0, e1, g, levels[l as usize], dn))
        }) else {
            return;
        };
        let geom = crate::runtime::frame::VoGeom {
            a: a.to_array(),
            b: b.to_array(),
            g,
            h: levels[level as usize],
        };
        let h = plan.occludees.hidden(&view, &geom, radius);
        if !h.is_empty() {
            cands.push((level, a, b));
            hidden.push(h);
        }
    };
    let mut previous: Option<Vec<u32>> = None;
    for &k in &setup.slices {
        let ids: Vec<u32> = near
            .iter()
            .zip(adjusted)
            .filter(|(_, (h, _))| *h >= levels[k as usize])
            .map(|(&i, _)| i)
            .collect();
        // The same blockers grow the same dense set (each VO's level comes from its chain,
        // not from the slice).
        if previous.as_ref() == Some(&ids) {
            continue;
        }
        let dense = grower.grow(&ids);
        previous = Some(ids);
        for v in dense.vos {
            consider(v.a, v.b, &v.chain, &mut cands, &mut hidden);
        }
    }
    stats.dense = cands.len();

    // Decimation; each pick is quantized and re-checked from its dequantized form.
    let mut tried = 0;
    let mut shrunk = 0;
    let mut dropped = 0;
    let mut all_checks = 0;
    let all: Vec<(u32, Support)> = near.iter().copied().zip(support.iter().copied()).collect();
    let vos = greedy(&hidden, &plan.occludees.costs, plan.vo_cap(setup.id), |i| {
        let (k, a, b) = cands[i];
        tried += 1;
        // At the slice's level first; when rule 2 leaves too few blockers for the verifier
        // (a chain member nearer than the VO's own nearest point), at lower levels.
        let mut first = true;
        for level in (1..=k).rev().take(LEVEL_FALLBACKS) {
            let mut checks = 0;
            let r = quantize(f, id, ground.level, level, a, b, |qa, qb| {
                checks += 1;
                all_checks += 1;
                let h = f.vo_top(e1, level);
                rule2_and_verify(&plan.set, &cell, &all, (e0, e1, g), h, qa, qb)
            });
            if let Ok(q) = r {
                if checks > 1 || !first {
                    shrunk += 1;
                }
                let geom = f.dequantize(id, ground, &q)?;
                let before = crate::runtime::frame::VoGeom {
                    a: a.to_array(),
                    b: b.to_array(),
                    g,
                    h: f.vo_top(e1, k),
                };
                return Some(((q, before), plan.occludees.hidden(&view, &geom, radius)));
            }
            if r == Err(Refused::OutsideWindow) {
                break;
            }
            first = false;
        }
        dropped += 1;
        None
    });
    stats.tried = tried;
    stats.shrunk = shrunk;
    stats.dropped = dropped;
    stats.checks = all_checks;
    setup.finish(plan, vos, stats)
}

/// Rule 2 then rule 1 for a dequantized VO `a`–`b` of top `h`: the blockers of `set` that
/// support it, and the exact verifier over them alone.
fn rule2_and_verify(
    set: &BlockerSet,
    cell: &[DVec2],
    blockers: &[(u32, Support)],
    (e0, e1, g): (f64, f64, f64),
    h: f64,
    a: DVec2,
    b: DVec2,
) -> bool {
    let dn = d_near(cell, &[a, b]);
    let used = blockers
        .iter()
        .filter(|(_, s)| s.supports(e0, e1, g, h, dn))
        .map(|&(i, _)| set.polys[i as usize].as_slice());
    Verifier::new(cell, used).is_hidden(a, b)
}
