//! The orchestrator: a scene and bake parameters in, one stored record per cell out.
//!
//! Input: a loaded [`Scene`] and [`BakeParams`]. Output: the store's [`Frame`] and, per cell in
//! id order, a [`CellBake`]: its record (skipped, or its ground level and at most `max_vos`
//! quantized VOs, most effective first) and what it took.
//! Per cell: ground and eyes, then the slices ([`super::slice`]), the dense set per slice
//! ([`super::umbra`]), the decimation ([`super::decimate`]) whose accept step quantizes
//! ([`super::quantize`]) and then re-checks the *dequantized* VO with rule 2 and the exact
//! verifier. A VO that fails is shrunk or dropped and counted.
//! Invariants: each cell is baked from the scene alone (no state shared between cells), so the
//! output is the same for any thread count and any order of cells; no cell gets more than
//! [`MAX_VOS_PER_CELL`] VOs.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use glam::DVec2;
use rayon::prelude::*;

use super::growth::decimate::greedy;
use super::growth::umbra::{self, CellGrower};
use super::occludees::Occludees;
use super::params::{BakeParams, Generator, Slices, MAX_CELL_SIZE_M, MIN_CELL_SIZE_M};
use super::quantize::{clip, quantize, window, Refused};
use super::slice::{area_angle, choose_levels, d_near, Support};
use super::BlockerSet;
use crate::geom::predicates::{point_in_convex, Containment};
use crate::geom::verify::Verifier;
use crate::runtime::format::{encode_store, CellRecord, FormatError};
use crate::runtime::frame::{Frame, QVo, HEIGHT_LEVELS, MAX_VOS_PER_CELL, QUANT_STEPS};
use crate::runtime::grid::{CellId, GridDescriptor};
use crate::scene::Scene;

/// Step between ground levels when the ground is not flat, metres (at least).
pub const GROUND_STEP_M: f64 = 0.25;
/// Blockers within this distance of a cell decide its ground, metres. When none stands that
/// near (a square, a field, the water beside a city), the radius doubles until some blocker is
/// within it, up to the search radius of the VOs' blockers (`BakeParams::search_m`): the cell
/// then stands on the ground of the nearest buildings, not on the scene's lowest.
pub const GROUND_RADIUS_M: f64 = 50.0;
/// The cell's ground is this percentile of the bases of the blockers near it, so that most of
/// them stand on or below it (rule 2 needs a blocker's base at or below the VO's bottom).
pub const GROUND_QUANTILE_PCT: usize = 90;
/// VO top of level k above the eyes: `H0_M * (H_RATIO^k - 1)`.
pub const H0_M: f64 = 2.0;
pub const H_RATIO: f64 = 1.25;
/// Height levels tried for one VO before it is dropped: its own, then each lower one.
pub const LEVEL_FALLBACKS: usize = 3;

/// Why a bake cannot start.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum BakeError {
    #[error("cell size must be {MIN_CELL_SIZE_M} to {MAX_CELL_SIZE_M} metres, got {0}")]
    CellSize(f64),
    #[error("eye heights must satisfy 0 <= low <= high, got {0}..{1}")]
    Eye(f64, f64),
    #[error("--max-vos must be 1..=10, got {0}")]
    MaxVos(usize),
    #[error("--slices must be 1..=5, got {0}")]
    Slices(u8),
    #[error("the scene has no objects")]
    EmptyScene,
    #[error("the grid would have {0} cells, more than 2^31; use larger cells")]
    TooManyCells(u64),
    /// The grid's per-cell tables would not fit in memory ([`super::budget`]).
    #[error("{0}")]
    Grid(Box<super::budget::GridTooLarge>),
}

/// What baking one cell took.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CellStats {
    /// Slice levels used.
    pub levels: Vec<u8>,
    /// Dense VOs over all slices.
    pub dense: usize,
    /// VOs the decimation tried to store.
    pub tried: usize,
    /// Of those, stored only after a shorter grid segment or a lower level replaced a failed
    /// one.
    pub shrunk: usize,
    /// Of those, dropped: no grid segment near them passed rule 2 and the verifier.
    pub dropped: usize,
    /// Exact verifications run on dequantized VOs.
    pub checks: usize,
    /// The stored VOs before quantization (the growth's segment at its chain's level), in the
    /// same order: for measuring what quantization costs.
    pub unquantized: Vec<crate::runtime::frame::VoGeom>,
    /// Occludee cost hidden by the stored VOs (rule 3, within the weighting radius).
    pub hidden_cost: u64,
    /// Length of the proposals sent to the exact verifier, and of the certified pieces kept
    /// from them, metres (the verifier's completeness).
    pub proposed_m: f64,
    pub certified_m: f64,
    /// Time per stage of the long generator, ms: hidden maps, proposals, rule-3 weights,
    /// selection with certification.
    pub stage_ms: [f64; 4],
    /// Levels the stored VOs were raised by after quantization (rule 2's perspective bonus).
    pub raised: usize,
    pub ms: f64,
}

/// One baked cell.
#[derive(Clone, Debug, PartialEq)]
pub struct CellBake {
    pub id: CellId,
    /// What the store holds for the cell: skipped (inside a building), or its ground and VOs.
    pub record: CellRecord,
    pub stats: CellStats,
}

/// Everything shared by the cells of one bake.
pub struct Plan<'s> {
    pub scene: &'s Scene,
    pub params: BakeParams,
    pub frame: Frame,
    set: BlockerSet,
    /// The blockers' shared edges, for each slice's boundary edges.
    twins: super::hidden::EdgeTwins,
    base: Vec<f64>,
    top: Vec<f64>,
    pub occludees: Occludees,
}

fn pow2_at_least(x: f64) -> f64 {
    let mut q = 1.0f64 / 1024.0;
    while q < x {
        q *= 2.0;
    }
    q
}

impl<'s> Plan<'s> {
    pub fn new(scene: &'s Scene, params: BakeParams) -> Result<Plan<'s>, BakeError> {
        let size = params.cell_size;
        if !(size.is_finite() && (MIN_CELL_SIZE_M..=MAX_CELL_SIZE_M).contains(&size)) {
            return Err(BakeError::CellSize(size));
        }
        let (e0, e1) = params.eye;
        if !(e0.is_finite() && e1.is_finite() && 0.0 <= e0 && e0 <= e1) {
            return Err(BakeError::Eye(e0, e1));
        }
        if params.max_vos == 0 || params.max_vos > MAX_VOS_PER_CELL {
            return Err(BakeError::MaxVos(params.max_vos));
        }
        if let Slices::Fixed(n) = params.slices {
            if n == 0 || n > 5 {
                return Err(BakeError::Slices(n));
            }
        }
        let ext = scene.extent();
        if ext.is_empty() {
            return Err(BakeError::EmptyScene);
        }
        // Grid corners on whole metres, so cell centres and the quantization grid are dyadic.
        let (min_x, min_y) = (ext.min.x.floor(), ext.min.y.floor());
        let nx = ((ext.max.x - min_x) / size).floor() as u64 + 1;
        let ny = ((ext.max.y - min_y) / size).floor() as u64 + 1;
        // Before anything is allocated per cell: the grid's tables must fit in memory.
        super::budget::check(scene, nx, ny, size).map_err(BakeError::Grid)?;
        if nx * ny > 1 << 31 {
            return Err(BakeError::TooManyCells(nx * ny));
        }
        let base: Vec<f64> = scene.blockers.iter().map(|b| b.base).collect();
        let top: Vec<f64> = scene.blockers.iter().map(|b| b.top).collect();
        let (bmin, bmax) = base
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &b| {
                (l.min(b), h.max(b))
            });
        let (ground_z0, ground_step) = if base.is_empty() {
            (ext.min.z, 0.0)
        } else if bmin == bmax {
            (bmin, 0.0)
        } else {
            (
                bmin,
                pow2_at_least(((bmax - bmin) / 255.0).max(GROUND_STEP_M)),
            )
        };
        let quantum = pow2_at_least((0.5 * size + params.search_m) / (QUANT_STEPS / 2) as f64);
        let frame = Frame {
            origin: scene.origin.to_array(),
            grid: GridDescriptor {
                min_x,
                min_y,
                cell_size: size,
                nx: nx as u32,
                ny: ny as u32,
            },
            quantum,
            eye_lo: e0,
            eye_hi: e1,
            ground_z0,
            ground_step,
            h0: H0_M,
            h_ratio: H_RATIO,
        };
        let set = BlockerSet::new(
            scene.blockers.iter().map(|b| b.polygon.clone()).collect(),
            scene.blockers.iter().map(|b| b.top - b.base).collect(),
        )
        .with_objects(scene.blockers.iter().map(|b| b.object).collect());
        Ok(Plan {
            scene,
            frame,
            twins: super::hidden::EdgeTwins::new(&set.polys),
            set,
            base,
            top,
            occludees: Occludees::from_scene(scene),
            params,
        })
    }

    pub fn scene(&self) -> &'s Scene {
        self.scene
    }

    pub fn params(&self) -> &BakeParams {
        &self.params
    }

    /// How far from a cell's centre its bake reads the scene (metres, per axis): the growth's
    /// search distance past the cell, and the occludees weighed within this distance.
    pub fn reach(&self) -> f64 {
        (self.params.search_m + self.frame.grid.cell_size).max(self.params.weigh_m)
    }

    /// The cells to bake, ascending: those meeting the region and the walkable area, when
    /// given (the others stay empty in the store: no VOs, so the culler keeps everything).
    pub fn cells(&self) -> Vec<CellId> {
        let g = &self.frame.grid;
        (0..g.cell_count() as u32)
            .filter(|&id| match (self.params.region, g.cell_rect(id)) {
                (Some(r), Some(c)) => c[0] <= r[2] && c[2] >= r[0] && c[1] <= r[3] && c[3] >= r[1],
                _ => true,
            })
            .filter(|&id| match (&self.params.walkable, g.cell_rect(id)) {
                (Some(area), Some(c)) => crate::scene::walkable::rect_meets_area(c, area),
                _ => true,
            })
            .collect()
    }

    /// The cell's polygon, counter-clockwise.
    pub fn cell_polygon(&self, id: CellId) -> [DVec2; 4] {
        let [x0, y0, x1, y1] = self.frame.grid.cell_rect(id).unwrap_or([0.0; 4]);
        [
            DVec2::new(x0, y0),
            DVec2::new(x1, y0),
            DVec2::new(x1, y1),
            DVec2::new(x0, y1),
        ]
    }

    /// The ground level of a cell: the [`GROUND_QUANTILE_PCT`] percentile of the bases of the
    /// blockers within [`GROUND_RADIUS_M`] (or the least multiple of it by a power of two that
    /// holds a blocker, up to the search radius), rounded up to a level; level 0 on flat
    /// ground, and where no blocker stands within the search radius.
    pub fn ground_level(&self, id: CellId) -> u8 {
        let f = &self.frame;
        if !f.per_cell_ground() {
            return 0;
        }
        let cell = self.cell_polygon(id);
        let mut radius = GROUND_RADIUS_M;
        let mut bases: Vec<f64> = Vec::new();
        // Within the cell's reach (ARCHITECTURE.md invariant 13): `cell ± search_m` lies in
        // `centre ± (search_m + cell size)`.
        while bases.is_empty() && radius <= self.params.search_m.max(GROUND_RADIUS_M) {
            let r = DVec2::splat(radius);
            bases = self
                .set
                .in_box(cell[0] - r, cell[2] + r)
                .map(|i| self.base[i as usize])
                .collect();
            radius *= 2.0;
        }
        if bases.is_empty() {
            return 0;
        }
        bases.sort_by(f64::total_cmp);
        let m = bases[(bases.len() - 1) * GROUND_QUANTILE_PCT / 100];
        ((m - f.ground_z0) / f.ground_step).ceil().clamp(0.0, 255.0) as u8
    }

    /// Bakes one cell.
    pub fn bake_cell(&self, id: CellId) -> CellBake {
        let t0 = Instant::now();
        let mut stats = CellStats::default();
        let record = self.bake_record(id, &mut stats);
        stats.ms = t0.elapsed().as_secs_f64() * 1e3;
        CellBake { id, record, stats }
    }

    fn bake_record(&self, id: CellId, stats: &mut CellStats) -> CellRecord {
        let f = &self.frame;
        let cell = self.cell_polygon(id);
        let ground = self.ground_level(id);
        let Some(view) = f.cell_view(id, ground) else {
            return CellRecord::EMPTY;
        };
        let (g, e0, e1) = (f.ground_z(ground), view.e0, view.e1);
        // A cell wholly inside one blocker that stands above the eyes holds no eye.
        let inside = self.set.in_box(cell[0], cell[2]).any(|i| {
            let p = &self.set.polys[i as usize];
            self.base[i as usize] <= e0
                && self.top[i as usize] >= e1
                && cell
                    .iter()
                    .all(|&c| point_in_convex(p, c) != Containment::Outside)
        });
        if inside {
            return CellRecord::Skipped;
        }
        // Blockers that may support a VO: near, apart from the cell, standing from below the
        // lowest eye (rule 2: base <= e0 - lambda (e0 - g)) to above the eyes.
        let near: Vec<u32> = umbra::usable(&cell, &self.set, self.params.search_m)
            .into_iter()
            .filter(|&i| self.base[i as usize] <= e0 && self.top[i as usize] > e1)
            .collect();
        if near.is_empty() {
            return CellRecord::EMPTY;
        }
        let centre = (cell[0] + cell[2]) * 0.5;
        let support: Vec<Support> = near
            .iter()
            .map(|&i| {
                let i = i as usize;
                Support::new(&cell, &self.set.polys[i], self.base[i], self.top[i])
            })
            .collect();
        let adjusted: Vec<(f64, f64)> = near
            .iter()
            .zip(&support)
            .map(|(&i, s)| {
                let i = i as usize;
                let w = area_angle(&self.set.polys[i], self.top[i] - self.base[i], centre);
                (s.adjusted_height(e1), w)
            })
            .collect();
        let levels: Vec<f64> = (0..HEIGHT_LEVELS).map(|k| f.vo_top(e1, k)).collect();
        let n = match self.params.slices {
            Slices::Auto => 5,
            Slices::Fixed(n) => n as usize,
        };
        stats.levels = choose_levels(&levels, &adjusted, n);
        if self.params.generator == Generator::Long {
            return self.long_vos(id, ground, &cell, &near, &support, &levels, stats);
        }

        // The dense set, per slice.
        let radius = self.reach();
        let mut cands: Vec<(u8, DVec2, DVec2)> = Vec::new();
        let mut hidden: Vec<Vec<u32>> = Vec::new();
        let mut grower = CellGrower::new(&cell, &self.set, &self.params.grow, self.params.search_m);
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
                        hidden: &mut Vec<Vec<u32>>| {
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
            let h = self.occludees.hidden(&view, &geom, radius);
            if !h.is_empty() {
                cands.push((level, a, b));
                hidden.push(h);
            }
        };
        let mut previous: Option<Vec<u32>> = None;
        for &k in &stats.levels {
            let ids: Vec<u32> = near
                .iter()
                .zip(&adjusted)
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
        let vos = greedy(&hidden, &self.occludees.cost, self.params.max_vos, |i| {
            let (k, a, b) = cands[i];
            tried += 1;
            // At the slice's level first; when rule 2 leaves too few blockers for the verifier
            // (a chain member nearer than the VO's own nearest point), at lower levels.
            let mut first = true;
            for level in (1..=k).rev().take(LEVEL_FALLBACKS) {
                let mut checks = 0;
                let r = quantize(f, id, ground, level, a, b, |qa, qb| {
                    checks += 1;
                    all_checks += 1;
                    let h = f.vo_top(e1, level);
                    self.rule2_and_verify(&cell, &all, (e0, e1, g), h, qa, qb)
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
                    return Some(((q, before), self.occludees.hidden(&view, &geom, radius)));
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
        self.finish(id, ground, &view, vos, stats)
    }

    /// The record of a cell's picked VOs (stored form, and the form before quantization), with
    /// the occludee cost they hide in `stats`.
    fn finish(
        &self,
        id: CellId,
        ground: u8,
        view: &crate::runtime::frame::CellView,
        vos: Vec<(QVo, crate::runtime::frame::VoGeom)>,
        stats: &mut CellStats,
    ) -> CellRecord {
        let f = &self.frame;
        let (vos, before): (Vec<QVo>, Vec<crate::runtime::frame::VoGeom>) = vos.into_iter().unzip();
        stats.unquantized = before;
        let mut all: Vec<u32> = Vec::new();
        for q in &vos {
            if let Some(geom) = f.dequantize(id, ground, q) {
                all.extend(self.occludees.hidden(view, &geom, self.reach()));
            }
        }
        all.sort_unstable();
        all.dedup();
        stats.hidden_cost = self.occludees.cost_of(&all);
        // A cell without VOs stores no ground byte: its ground is 0 in the record.
        let ground = if vos.is_empty() { 0 } else { ground };
        CellRecord::new(ground, &vos).expect("greedy stops at max_vos, checked <= 10 in Plan::new")
    }

    /// The long generator: per slice, the sampled hidden map, its long runs, exact rule-3
    /// weights; greedy picks, each certified exactly when picked.
    #[allow(clippy::too_many_arguments)]
    fn long_vos(
        &self,
        id: CellId,
        ground: u8,
        cell: &[DVec2; 4],
        near: &[u32],
        support: &[Support],
        levels: &[f64],
        stats: &mut CellStats,
    ) -> CellRecord {
        let f = &self.frame;
        let Some(view) = f.cell_view(id, ground) else {
            return CellRecord::EMPTY;
        };
        let (g, e0, e1) = (f.ground_z(ground), view.e0, view.e1);
        let radius = self.reach();
        let mut cands: Vec<(u8, DVec2, DVec2)> = Vec::new();
        let mut hidden: Vec<Vec<u32>> = Vec::new();
        let clock = |t: &mut Instant| {
            let e = t.elapsed().as_secs_f64() * 1e3;
            *t = Instant::now();
            e
        };
        let mut t = Instant::now();
        let mut all_props: Vec<(u8, DVec2, DVec2)> = Vec::new();
        // Every slice's boundary edges, each edge once with the slices it belongs to: the maps
        // are built together (8 slices at a time), each edge's hit distances computed once for
        // all its slices.
        for chunk in stats.levels.clone().chunks(8) {
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
            let (edges, member) = self.twins.slice_edges(&self.set.polys, &slices);
            let maps = super::hidden::HiddenMap::build_slices(
                cell,
                &edges,
                &member,
                chunk.len(),
                &self.params.map,
            );
            stats.stage_ms[0] += clock(&mut t);
            for (&k, map) in chunk.iter().zip(&maps) {
                let props = super::propose::runs(cell, map, &self.params.propose);
                all_props.extend(props.into_iter().map(|p| (k, p.a, p.b)));
            }
            stats.stage_ms[1] += clock(&mut t);
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
            let hid = self.occludees.hidden(&view, &geom, radius);
            if hid.is_empty() {
                continue;
            }
            // Trimmed to the part that the objects it hides need: the exact certification then
            // sweeps only that. A box lies in the umbra of a sub-segment exactly when every
            // segment from the cell to it crosses the line within that sub-segment, and rule 3's
            // heights depend on the line only, so the trimmed segment hides what this one does
            // (up to rounding; it is weighed again).
            let (a, b, hid) = match trim(
                cell,
                a,
                b,
                hid.iter().map(|&o| &self.occludees.boxes[o as usize]),
            ) {
                Some((ta, tb)) if (ta, tb) != (a, b) => {
                    let g = crate::runtime::frame::VoGeom {
                        a: ta.to_array(),
                        b: tb.to_array(),
                        ..geom
                    };
                    (ta, tb, self.occludees.hidden(&view, &g, radius))
                }
                _ => (a, b, hid),
            };
            if hid.is_empty() {
                continue;
            }
            cands.push((k, a, b));
            hidden.push(hid);
        }
        stats.stage_ms[2] += clock(&mut t);
        stats.dense = cands.len();
        let index = crate::geom::verify::BlockerIndex::new(
            near.iter().map(|&i| self.set.polys[i as usize].as_slice()),
        );
        let certifier = super::certify::Certifier {
            index: &index,
            frame: f,
            id,
            ground,
            cell,
            heights: (e0, e1, g),
            blockers: near
                .iter()
                .zip(support)
                .map(|(&i, s)| (self.set.polys[i as usize].as_slice(), *s))
                .collect(),
            verifiers: (0..HEIGHT_LEVELS as usize * super::certify::BANDS)
                .map(|_| Default::default())
                .collect(),
        };
        let mut cs = super::certify::CertifyStats::default();
        use super::certify::Piece;
        use super::select::{select, Candidate, Stage};
        #[derive(Clone)]
        enum Vo {
            Piece(Piece),
            Stored(QVo, crate::runtime::frame::VoGeom),
        }
        let geom = |level: u8, a: DVec2, b: DVec2| crate::runtime::frame::VoGeom {
            a: a.to_array(),
            b: b.to_array(),
            g,
            h: f.vo_top(e1, level),
        };
        let start: Vec<Candidate<Vo>> = cands
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
        let picked = select(
            start,
            &self.occludees.cost,
            self.params.max_vos,
            self.params.budget,
            |c| match &c.value {
                Vo::Piece(p) if c.stage == Stage::Proposed => certifier
                    .pieces(p.level, p.a, p.b, &mut cs)
                    .into_iter()
                    .map(|p| Candidate {
                        stage: Stage::Certified,
                        hidden: self
                            .occludees
                            .hidden(&view, &geom(p.level, p.a, p.b), radius),
                        value: Vo::Piece(p),
                    })
                    .collect(),
                Vo::Piece(p) => certifier
                    .store(p, &mut cs)
                    .map(|s| Candidate {
                        stage: Stage::Stored,
                        value: Vo::Stored(s.q, geom(p.level, p.a, p.b)),
                        hidden: self.occludees.hidden(&view, &s.geom, radius),
                    })
                    .into_iter()
                    .collect(),
                Vo::Stored(..) => Vec::new(),
            },
        );
        let vos: Vec<(QVo, crate::runtime::frame::VoGeom)> = picked
            .into_iter()
            .filter_map(|v| match v {
                Vo::Stored(q, g) => Some((q, g)),
                Vo::Piece(_) => None,
            })
            .collect();
        stats.stage_ms[3] += clock(&mut t);
        stats.tried = cs.tried;
        stats.raised = cs.raised;
        stats.shrunk = cs.shrunk;
        stats.dropped = cs.stores - cs.stored;
        stats.checks = cs.checks;
        stats.proposed_m = cs.proposed_m;
        stats.certified_m = cs.certified_m;
        self.finish(id, ground, &view, vos, stats)
    }

    /// Rule 2 then rule 1 for a dequantized VO `a`–`b` of top `h`: the blockers that support it,
    /// and the exact verifier over them alone.
    fn rule2_and_verify(
        &self,
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
            .map(|&(i, _)| self.set.polys[i as usize].as_slice());
        Verifier::new(cell, used).is_hidden(a, b)
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
            let g = super::propose::VO_GRID_M;
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

/// Bakes `cells` in parallel on the current rayon pool; `progress(done)` is called as cells
/// finish. Results come in the order of `cells`.
pub fn bake_cells(
    plan: &Plan,
    cells: &[CellId],
    progress: &(dyn Fn(usize) + Sync),
) -> Vec<CellBake> {
    let done = AtomicUsize::new(0);
    cells
        .par_iter()
        .map(|&id| {
            let r = plan.bake_cell(id);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            r
        })
        .collect()
}

/// The stored record of every cell of the grid, in id order: baked cells from `baked`, the rest
/// empty.
pub fn records(frame: &Frame, baked: &[CellBake]) -> Vec<CellRecord> {
    let mut out = vec![CellRecord::EMPTY; frame.grid.cell_count() as usize];
    for c in baked {
        if let Some(slot) = out.get_mut(c.id as usize) {
            *slot = c.record;
        }
    }
    out
}

/// The store's bytes for a bake: [`records`], encoded.
pub fn encode(frame: &Frame, baked: &[CellBake]) -> Result<Vec<u8>, FormatError> {
    encode_store(frame, &records(frame, baked))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Square footprints `[x, y, side]` (world metres) with bases and heights, as GeoJSON.
    fn squares(items: &[([f64; 3], f64, f64)]) -> Scene {
        let feats: Vec<String> = items
            .iter()
            .map(|&([x, y, d], base, h)| {
                format!(
                    r#"{{"type":"Feature","properties":{{"h":{h},"b":{base}}},"geometry":{{"type":"Polygon","coordinates":[[[{x},{y}],[{},{y}],[{},{}],[{x},{}],[{x},{y}]]]}}}}"#,
                    x + d,
                    x + d,
                    y + d,
                    y + d
                )
            })
            .collect();
        let text = format!(
            r#"{{"type":"FeatureCollection","features":[{}]}}"#,
            feats.join(",")
        );
        let opts = crate::scene::ReadOptions {
            height_attr: Some("h".into()),
            base_attr: Some("b".into()),
            ..Default::default()
        };
        crate::scene::load_bytes(&[("squares.geojson".into(), text.as_bytes())], &opts).unwrap()
    }

    /// The regression: a cell with no building within 50 m stood on the scene's lowest ground
    /// (level 0), under the bases of the buildings around it, whose VOs then failed rule 2's base
    /// test (Den Haag's empty cells beside its raised streets got no VO). It now takes the ground
    /// of the nearest buildings, within the first radius of 100, 200, 400, 800 m that holds one.
    #[test]
    fn a_cell_with_no_building_near_stands_on_the_ground_of_the_nearest() {
        // A building on low ground (base 0) at the west end; buildings on ground 6 m higher
        // from 80 m east of the empty cell x in [200, 300) on; the scene starts at x = 0.
        let s = squares(&[
            ([0.0, 0.0, 20.0], 0.0, 10.0),
            ([380.0, 0.0, 20.0], 6.0, 10.0),
            ([380.0, 40.0, 20.0], 6.0, 10.0),
            ([380.0, 80.0, 20.0], 6.0, 10.0),
        ]);
        let plan = Plan::new(&s, BakeParams::default()).unwrap();
        let f = &plan.frame;
        assert!(f.per_cell_ground());
        let at = |x: f64| {
            let local = x - s.origin.x;
            f.grid.cell_at(local, 10.0 - s.origin.y).unwrap()
        };
        // Beside the low building: its own ground. Beside the raised ones: theirs.
        assert_eq!(f.ground_z(plan.ground_level(at(10.0))), 0.0);
        let raised = plan.ground_level(at(390.0));
        assert!(
            (f.ground_z(raised) - 6.0).abs() < f.ground_step,
            "{}",
            f.ground_z(raised)
        );
        // The empty cell: nothing within 50 m; within 100 m, the raised buildings alone.
        assert_eq!(plan.ground_level(at(250.0)), raised);
    }

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
