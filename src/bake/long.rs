//! The long generator (the default, `--generator long`): one cell's VOs from the long hidden
//! runs of lines around it.
//!
//! Input: the [`Plan`] and a cell's `CellSetup` (its near blockers with their rule-2 support,
//! the height levels and the slice levels). Output: the cell's record, at most `max_vos` stored
//! VOs, most effective first, and what it took in [`CellStats`].
//! Per cell: per slice, the boundary edges of the blockers tall enough ([`super::hidden`]'s
//! `EdgeTwins`), the sampled hidden maps of all slices in one pass ([`super::hidden`]), the
//! long hidden runs on them ([`super::propose`]), each weighed by rule 3 against the occludees
//! and trimmed (`trim`) to the part those need; then lazy greedy selection
//! ([`super::select`]) that certifies ([`super::certify`]) only what it is about to pick.
//! Invariants: the hidden maps and proposals are sampled and decide nothing: a stored VO is what
//! the exact verifier certified over its rule-2 supporters, quantized and certified again in its
//! dequantized form (ARCHITECTURE.md invariant 7); at most `budget` certifications per cell;
//! reads only what the setup and the plan's reach hold.

use std::time::Instant;

use glam::DVec2;

use super::cell::CellSetup;
use super::certify::{Certifier, CertifyStats, Piece};
use super::hidden::MapParams;
use super::plan::{CellStats, Plan};
use super::propose::ProposeParams;
use super::select::{select, Candidate, Stage};
use super::spans::Spans;
use crate::geom::verify::BlockerIndex;
use crate::runtime::format::CellRecord;
use crate::runtime::frame::{QVo, VoGeom, HEIGHT_LEVELS};

/// The long generator's VOs of one cell: per slice, the sampled hidden map, its long runs, exact
/// rule-3 weights; with them the far pieces of the cell's block ([`super::far`]); greedy picks,
/// each certified exactly when picked. Returns the cell's record.
pub(super) fn long_vos(plan: &Plan, setup: &CellSetup, stats: &mut CellStats) -> CellRecord {
    long_vos_traced(plan, setup, stats, &mut |_| {})
}

/// What the long generator did for one cell, told as it happens to [`long_vos_traced`]'s
/// observer (for pictures, [`super::trace`]); telling decides nothing.
pub enum Traced<'a> {
    /// A slice's hidden map, with the slice's height level.
    Map(u8, &'a super::hidden::HiddenMap),
    /// A proposal as weighed, trimmed: its level and ends.
    Proposal(u8, DVec2, DVec2),
    /// The certified pieces of a proposal the selection certified.
    Certified(&'a [Piece]),
    /// A VO stored (certified again in its dequantized form): as the runtime reads it.
    Stored(&'a VoGeom),
}

/// [`long_vos`], telling `observe` what it does: the maps, the proposals, what the selection
/// certified and stored (the bake passes an observer that does nothing).
pub(super) fn long_vos_traced(
    plan: &Plan,
    setup: &CellSetup,
    stats: &mut CellStats,
    observe: &mut impl FnMut(Traced),
) -> CellRecord {
    let f = &plan.frame;
    let (g, e1, view) = (setup.g, setup.view.e1, setup.view);
    let radius = plan.params.weigh_m;
    let mut t = Instant::now();
    let (cands, hidden) = proposals(
        plan,
        setup,
        &plan.params.map,
        &plan.params.propose,
        plan.params.weigh_m,
        &mut t,
        stats,
        observe,
    );
    for &(level, a, b) in &cands {
        observe(Traced::Proposal(level, a, b));
    }
    stats.dense = cands.len();
    let index = BlockerIndex::new(
        setup
            .near
            .iter()
            .map(|&i| plan.set.polys[i as usize].as_slice()),
    );
    let certifier = certifier(plan, setup, &index);
    // The far field: pieces certified hidden from the cell's whole block.
    stats.stage_ms[4] += clock(&mut t);
    let far = plan.far_pieces(setup.id);
    stats.stage_ms[3] += clock(&mut t);
    let mut cs = CertifyStats::default();
    #[derive(Clone)]
    enum Vo {
        Piece(Piece),
        Far(usize),
        Stored(QVo, VoGeom),
    }
    let geom = |level: u8, a: DVec2, b: DVec2| VoGeom {
        a: a.to_array(),
        b: b.to_array(),
        g,
        h: f.vo_top(e1, level),
    };
    let mut start: Vec<Candidate<Vo>> = cands
        .iter()
        .zip(hidden)
        .map(|(&(level, a, b), hidden)| Candidate {
            stage: Stage::Proposed,
            value: Vo::Piece(Piece {
                level,
                a,
                b,
                used: Vec::new(),
            }),
            hidden,
        })
        .collect();
    for (i, p) in far.iter().enumerate() {
        let Some(level) = certifier.far_level(p) else {
            continue;
        };
        let hidden = plan.occludees.hidden(&view, &geom(level, p.a, p.b), radius);
        if !hidden.is_empty() {
            start.push(Candidate {
                stage: Stage::Certified,
                value: Vo::Far(i),
                hidden,
            });
        }
    }
    let picked = select(
        start,
        &plan.occludees.costs,
        Spans::new(),
        plan.vo_max(setup.id),
        plan.params.budget,
        |c| match &c.value {
            Vo::Piece(p) if c.stage == Stage::Proposed => {
                let pieces = certifier.pieces(p.level, p.a, p.b, &mut cs);
                observe(Traced::Certified(&pieces));
                pieces
                    .into_iter()
                    .map(|p| Candidate {
                        stage: Stage::Certified,
                        hidden: plan.occludees.hidden(
                            &view,
                            &geom(p.level, p.a, p.b),
                            plan.params.weigh_m,
                        ),
                        value: Vo::Piece(p),
                    })
                    .collect()
            }
            Vo::Piece(p) => certifier
                .store(p, &mut cs)
                .inspect(|s| observe(Traced::Stored(&s.geom)))
                .map(|s| Candidate {
                    stage: Stage::Stored,
                    value: Vo::Stored(s.q, geom(p.level, p.a, p.b)),
                    hidden: plan.occludees.hidden(&view, &s.geom, radius),
                })
                .into_iter()
                .collect(),
            Vo::Far(i) => certifier
                .store_far(&far[*i], &mut cs)
                .inspect(|s| observe(Traced::Stored(&s.geom)))
                .map(|s| Candidate {
                    stage: Stage::Stored,
                    value: Vo::Stored(s.q, s.geom),
                    hidden: plan.occludees.hidden(&view, &s.geom, radius),
                })
                .into_iter()
                .collect(),
            Vo::Stored(..) => Vec::new(),
        },
    );
    let (vos, gains): (Vec<(QVo, VoGeom)>, Vec<u64>) = picked
        .into_iter()
        .filter_map(|(v, gain)| match v {
            Vo::Stored(q, g) => Some(((q, g), gain)),
            _ => None,
        })
        .unzip();
    stats.gains = gains;
    stats.stage_ms[4] += clock(&mut t);
    stats.tried = cs.tried;
    stats.raised = cs.raised;
    stats.shrunk = cs.shrunk;
    stats.dropped = cs.stores - cs.stored;
    stats.checks = cs.checks;
    stats.proposed_m = cs.proposed_m;
    stats.certified_m = cs.certified_m;
    setup.finish(plan, vos, stats)
}

/// Milliseconds since `t`, which restarts.
fn clock(t: &mut Instant) -> f64 {
    let e = t.elapsed().as_secs_f64() * 1e3;
    *t = Instant::now();
    e
}

/// The first stages of the long generator for a region's setup (a cell's, or a block's): per
/// slice the hidden map and its long runs, each weighed by rule 3 from the region and trimmed
/// to what its occludees need. Proposals `(level, a, b)` with what each hides, in a fixed order;
/// stage times go to `stats` (maps, proposals, weights); each map is shown to `observe`.
#[allow(clippy::too_many_arguments)]
pub(super) fn proposals(
    plan: &Plan,
    setup: &CellSetup,
    map: &MapParams,
    propose: &ProposeParams,
    radius: f64,
    t: &mut Instant,
    stats: &mut CellStats,
    observe: &mut impl FnMut(Traced),
) -> (Vec<(u8, DVec2, DVec2)>, Vec<Spans>) {
    let CellSetup {
        view,
        g,
        ref cell,
        ref near,
        ref support,
        ref levels,
        ..
    } = *setup;
    let mut cands: Vec<(u8, DVec2, DVec2)> = Vec::new();
    let mut hidden: Vec<Spans> = Vec::new();
    let mut all_props: Vec<(u8, DVec2, DVec2)> = Vec::new();
    // Every slice's boundary edges, each edge once with the slices it belongs to: the maps
    // are built together (8 slices at a time), each edge's hit distances computed once for
    // all its slices.
    for chunk in setup.slices.chunks(8) {
        let slices: Vec<Vec<u32>> = chunk
            .iter()
            .map(|&k| {
                let h = levels[k as usize];
                near.iter()
                    .zip(support)
                    .filter(|(_, s)| s.top >= h)
                    .map(|(&i, _)| i)
                    .collect()
            })
            .collect();
        let (edges, member) = plan.twins.slice_edges(&plan.set.polys, &slices);
        let maps = super::hidden::HiddenMap::build_slices(cell, &edges, &member, chunk.len(), map);
        stats.stage_ms[0] += clock(t);
        for (&k, map) in chunk.iter().zip(&maps) {
            observe(Traced::Map(k, map));
            let props = super::propose::runs(cell, map, propose);
            all_props.extend(props.into_iter().map(|p| (k, p.a, p.b)));
        }
        stats.stage_ms[1] += clock(t);
    }
    // The same segment proposed at several levels: the highest (its map says hidden
    // there, and a taller VO hides at least as much).
    let key = |p: &(u8, DVec2, DVec2)| {
        (
            p.1.x.to_bits(),
            p.1.y.to_bits(),
            p.2.x.to_bits(),
            p.2.y.to_bits(),
        )
    };
    all_props.sort_by(|x, y| key(x).cmp(&key(y)).then(y.0.cmp(&x.0)));
    all_props.dedup_by(|x, y| key(x) == key(y));
    for (k, a, b) in all_props {
        let geom = crate::runtime::frame::VoGeom {
            a: a.to_array(),
            b: b.to_array(),
            g,
            h: levels[k as usize],
        };
        let mut bounds: Vec<[f64; 6]> = Vec::new();
        let hid = plan
            .occludees
            .hidden_bounds(&view, &geom, radius, |b| bounds.push(*b));
        if hid.is_empty() {
            continue;
        }
        // Trimmed to the part that the objects it hides need: the exact certification then
        // sweeps only that. A box lies in the umbra of a sub-segment exactly when every
        // segment from the cell to it crosses the line within that sub-segment, and rule 3's
        // heights depend on the line only, so the trimmed segment hides what this one does
        // (up to rounding; it is weighed again).
        let (a, b, hid) = match trim(cell, a, b, bounds.iter()) {
            Some((ta, tb)) if (ta, tb) != (a, b) => {
                let g = crate::runtime::frame::VoGeom {
                    a: ta.to_array(),
                    b: tb.to_array(),
                    ..geom
                };
                (ta, tb, plan.occludees.hidden(&view, &g, radius))
            }
            _ => (a, b, hid),
        };
        if hid.is_empty() {
            continue;
        }
        cands.push((k, a, b));
        hidden.push(hid);
    }
    stats.stage_ms[2] += clock(t);
    (cands, hidden)
}

/// The certification context of a region's setup: its blockers with their rule-2 support,
/// indexed once in `index` for all its verifiers.
pub(super) fn certifier<'a>(
    plan: &'a Plan,
    setup: &'a CellSetup,
    index: &'a BlockerIndex<'a>,
) -> Certifier<'a> {
    Certifier {
        index,
        frame: &plan.frame,
        id: setup.id,
        ground: setup.ground,
        cell: &setup.cell,
        heights: (setup.view.e0, setup.view.e1, setup.g),
        blockers: setup
            .near
            .iter()
            .zip(&setup.support)
            .map(|(&i, s)| (plan.set.polys[i as usize].as_slice(), *s))
            .collect(),
        verifiers: (0..HEIGHT_LEVELS as usize * super::certify::BANDS)
            .map(|_| Default::default())
            .collect(),
    }
}

/// Margin kept beyond the crossings [`trim`] finds, metres.
const TRIM_MARGIN_M: f64 = 0.05;
/// Share of the trimmed length kept on either side beyond it.
const TRIM_EXTRA: f64 = 0.25;
/// Relative bound, far above the rounding of a crossing's float value, under which [`trim`]
/// skips a box that cannot move either end.
const TRIM_SKIP_EPS: f64 = 1e-9;

/// The part of the segment `a`–`b` that segments from the rectangle `cell` to the footprints of
/// `boxes` (lying beyond its line) cross, with [`TRIM_MARGIN_M`] on each side and its ends
/// snapped outwards to the VO grid; `None` when the line meets the cell or a box is not wholly
/// beyond it. The crossings of the segments between corners bound all others (the cell and the
/// footprints are convex, and the crossing point moves monotonically along each).
fn trim<'b>(
    cell: &[DVec2; 4],
    a: DVec2,
    b: DVec2,
    boxes: impl Iterator<Item = &'b [f64; 6]>,
) -> Option<(DVec2, DVec2)> {
    let len = a.distance(b);
    if !(len > 0.0) {
        return None;
    }
    let u = (b - a) / len;
    let mut n = u.perp();
    if n.dot(cell[0] - a) > 0.0 {
        n = -n;
    }
    // Cell corners at (t, s) with s < 0 on the cell's side.
    let cs: Vec<(f64, f64)> = cell.iter().map(|&c| (u.dot(c - a), n.dot(c - a))).collect();
    if cs.iter().any(|&(_, s)| !(s < 0.0)) {
        return None;
    }
    let boxes = boxes.map(|bx| {
        [
            DVec2::new(bx[0], bx[1]),
            DVec2::new(bx[3], bx[1]),
            DVec2::new(bx[3], bx[4]),
            DVec2::new(bx[0], bx[4]),
        ]
        .map(|w| (u.dot(w - a), n.dot(w - a)))
    });
    let (t0, t1) = crossing_span(&cs, boxes)?;
    let extra = TRIM_EXTRA * (t1 - t0) + TRIM_MARGIN_M;
    let (t0, t1) = ((t0 - extra).max(0.0), (t1 + extra).min(len));
    if !(t0 < t1) {
        return None;
    }
    let out = |t: f64, toward: f64| {
        if t <= 0.0 {
            a
        } else if t >= len {
            b
        } else {
            // Snapped along the segment, away from its middle.
            let g = super::cell::VO_GRID_M;
            let p = a + u * (t + toward * g);
            (p / g).round() * g
        }
    };
    Some((out(t0, -1.0), out(t1, 1.0)))
}

/// The least and greatest `t` where segments from the cell's corners `cs` to the corners of
/// each box (all as `(t, s)`: along the line and beyond it, the cell at `s < 0`) cross the line
/// `s = 0`; `None` when a box corner is not strictly beyond it.
fn crossing_span(
    cs: &[(f64, f64)],
    boxes: impl Iterator<Item = [(f64, f64); 4]>,
) -> Option<(f64, f64)> {
    let (tc_lo, tc_hi) = cs
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &(tc, _)| {
            (l.min(tc), h.max(tc))
        });
    let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
    for ws in boxes {
        if ws.iter().any(|&(_, sw)| !(sw > 0.0)) {
            return None;
        }
        // Each crossing lies between `tc` and `tw` (`-sc / (sw - sc)` is in (0, 1)), and its
        // float value within a few units in the last place of that: a box whose corners' `tw`
        // and the cell's `tc` all lie inside `[t0, t1]` by [`TRIM_SKIP_EPS`] (relative, far
        // above that rounding) moves neither end, so its crossings are not computed (the same
        // ends, bit for bit).
        let (tw_lo, tw_hi) = ws
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &(tw, _)| {
                (l.min(tw), h.max(tw))
            });
        let eps = TRIM_SKIP_EPS * (1.0 + t0.abs().max(t1.abs()));
        if tw_lo.min(tc_lo) > t0 + eps && tw_hi.max(tc_hi) < t1 - eps {
            continue;
        }
        for (tw, sw) in ws {
            for &(tc, sc) in cs {
                let t = tc + (tw - tc) * (-sc) / (sw - sc);
                t0 = t0.min(t);
                t1 = t1.max(t);
            }
        }
    }
    Some((t0, t1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`crossing_span`] without its skip: every crossing computed.
    fn crossing_span_plain(cs: &[(f64, f64)], boxes: &[[(f64, f64); 4]]) -> Option<(f64, f64)> {
        let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
        for ws in boxes {
            for &(tw, sw) in ws {
                if !(sw > 0.0) {
                    return None;
                }
                for &(tc, sc) in cs {
                    let t = tc + (tw - tc) * (-sc) / (sw - sc);
                    t0 = t0.min(t);
                    t1 = t1.max(t);
                }
            }
        }
        Some((t0, t1))
    }

    #[test]
    fn skipped_boxes_move_no_end_of_the_crossing_span() {
        let mut next = crate::testutil::uniform(5);
        let mut inside = 0;
        for round in 0..300 {
            let x = next(-60.0, 900.0);
            let cs = [
                (x, -130.0),
                (x + 100.0, -130.0),
                (x + 100.0, -30.0),
                (x, -30.0),
            ];
            let boxes: Vec<[(f64, f64); 4]> = (0..40)
                .map(|_| {
                    // Half of them close to the line, where a crossing lies near the box's
                    // own `t`: the ends then move by small steps, which a wrong skip misses.
                    let s = if next(0.0, 1.0) < 0.5 {
                        next(0.01, 2.0)
                    } else {
                        next(0.5, 300.0)
                    };
                    let t = next(-200.0, 1200.0);
                    let (w, d) = (next(0.5, 40.0), next(0.5, 40.0));
                    // Now and then a corner on the line or the cell's side: refused.
                    let s = if round % 50 == 0 { s - 100.0 } else { s };
                    [(t, s), (t + w, s), (t + w, s + d), (t, s + d)]
                })
                .collect();
            let got = crossing_span(&cs, boxes.iter().copied());
            let want = crossing_span_plain(&cs, &boxes);
            assert_eq!(
                got.map(|(a, b)| (a.to_bits(), b.to_bits())),
                want.map(|(a, b)| (a.to_bits(), b.to_bits())),
                "round {round}"
            );
            if let Some((t0, t1)) = got {
                inside += boxes
                    .iter()
                    .filter(|ws| ws.iter().all(|&(tw, _)| tw > t0 && tw < t1))
                    .count();
            }
        }
        assert!(inside > 1000, "boxes inside the span: {inside}");
    }
}
