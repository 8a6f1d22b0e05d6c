//! The bake as one library job: a loaded scene and bake parameters in; the store's bytes, its
//! `.hashes` bytes, every baked cell and a summary out.
//!
//! Input: a [`Scene`], [`BakeParams`], and optionally: one shard `(index, count)` of the cells,
//! an explicit list of cells, an older store (and its `.hashes` file, as bytes) whose records may
//! be reused, and a thread count. Output: [`BakeOutput`]: the store bytes (`docs/FORMAT.md`), the
//! hashes bytes (`bake::incremental`), the [`CellBake`] of every cell baked here (ascending id)
//! and a [`BakeSummary`] (counts, timings, bytes, and the reuse decision with its reason as
//! data).
//! Invariants:
//! - no printing and no file I/O: the caller reads the inputs and writes the outputs (the CLI
//!   atomically); progress goes through the caller's `Sync` callback as done / total;
//! - the store bytes depend only on the scene, the parameters and the cell selection, never on
//!   the thread count, and a reuse bake gives the same bytes as a full bake (reused cells are
//!   taken only when every global hash and the frame agree, and their cell hash is unchanged;
//!   `bake::incremental`);
//! - a shard bakes the selected cells whose group of cells (`bake::share`, 4 x 4 cells that
//!   share their bytes) is `index` modulo `count`; the shards of one bake merge into the single
//!   bake's bytes (`vocc merge`); a reuse bake bakes again every group with a changed cell.

use std::collections::BTreeMap;
use std::time::Instant;

use serde::Serialize;

use super::incremental::{CellHashes, HashesError};
use super::params::BakeParams;
use super::plan::{bake_cells, records, BakeError, CellBake, Plan};
use crate::runtime::crc::crc32;
use crate::runtime::format::{
    encode_frame, encode_store_with, CellRecord, FormatError, SceneSection, Store,
};
use crate::runtime::grid::CellId;
use crate::scene::Scene;

/// The cells of `cells` to bake given an older bake's hashes `old`: every cell of a group
/// ([`super::share::group_of`]) in which some cell of the grid is hashed differently now (a cell
/// changed, or was selected in one bake and not the other), since a cell's record depends on its
/// group's; the others' records are the old ones.
fn whole_groups(plan: &Plan, now: &CellHashes, old: &CellHashes, cells: &[CellId]) -> Vec<CellId> {
    let changed = now.changed(old, cells);
    if changed.len() == cells.len() {
        return changed;
    }
    let grid = &plan.frame.grid;
    let group = |id: CellId| super::share::group_of(grid, id);
    let mut stale: std::collections::BTreeSet<u64> = changed.iter().map(|&id| group(id)).collect();
    // A cell of the grid baked before and not now (or the other way) changes its group's share.
    for id in 0..grid.cell_count() as CellId {
        let i = id as usize;
        if now.cells.get(i) != old.cells.get(i) {
            stale.insert(group(id));
        }
    }
    cells
        .iter()
        .copied()
        .filter(|&id| stale.contains(&group(id)))
        .collect()
}

/// Where a bake stands: `done` of `total` cells baked. Reported once with `done == 0` before the
/// first cell, then as cells finish (in any order, from any worker thread).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Progress {
    pub done: usize,
    pub total: usize,
}

/// Why a bake job cannot run.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    /// The parameters or the grid are refused ([`Plan::new`]).
    #[error(transparent)]
    Plan(#[from] BakeError),
    #[error("shard index {index} is not below the shard count {count}")]
    Shard { index: u32, count: u32 },
    #[error("cell {id} is outside the grid (cells 0..{cells})")]
    CellOutsideGrid { id: CellId, cells: u64 },
    /// The region (world coordinates) meets no cell of the grid.
    #[error("the region {region:?} meets no cell of the grid, which covers x {:.1}..{:.1}, y {:.1}..{:.1} (world): nothing to bake", grid[0], grid[2], grid[1], grid[3])]
    RegionOutsideGrid { region: [f64; 4], grid: [f64; 4] },
    /// The walkable area meets no cell of the grid.
    #[error("the walkable area meets no cell of the grid, which covers x {:.1}..{:.1}, y {:.1}..{:.1} (world): nothing to bake", grid[0], grid[2], grid[1], grid[3])]
    WalkableOutsideGrid { grid: [f64; 4] },
    #[error("the old store is not a valid vocc store: {0}")]
    OldStore(FormatError),
    #[error("the old store's hashes are damaged: {0}")]
    OldHashes(HashesError),
    #[error("cannot start {threads} worker threads: {message}")]
    Threads { threads: usize, message: String },
    #[error("the records do not encode: {0}")]
    Encode(FormatError),
}

/// Why the cells of an older store were not reused (every cell was baked).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ReuseRefusal {
    /// No hashes were given with the old store.
    NoHashes,
    /// The hashes' store checksum is not the old store's: they belong to another store.
    OtherStore,
    /// The grid, origin, eyes, ground range or quantization changed.
    FrameChanged,
    /// The options changed, or the old store was baked by another vocc (version or build).
    OptionsChanged,
}

impl std::fmt::Display for ReuseRefusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ReuseRefusal::NoHashes => "the old store has no hashes",
            ReuseRefusal::OtherStore => "the hashes belong to another store",
            ReuseRefusal::FrameChanged => {
                "the grid, origin, eyes, ground range or quantization changed"
            }
            ReuseRefusal::OptionsChanged => {
                "the options changed, or another vocc (version or build) baked the old store"
            }
        })
    }
}

/// What became of the older store given for reuse.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct ReuseDecision {
    /// `None` when its records were reused; else why every cell was baked.
    pub refused: Option<ReuseRefusal>,
    /// Cells of the selection baked anew (all of them when refused).
    pub changed: usize,
    /// Cells whose record was copied from the old store.
    pub reused: usize,
}

/// Quantization of the stored VOs, summed over the baked cells ([`super::plan::CellStats`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Quantization {
    pub tried: usize,
    pub shrunk: usize,
    pub dropped: usize,
    /// Exact verifications of dequantized VOs.
    pub checks: usize,
}

/// Wall-clock seconds of the job's stages.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Timings {
    /// [`Plan::new`]: validation, blocker index, occludee index.
    pub plan_s: f64,
    /// The content hashes of the selected cells.
    pub hashes_s: f64,
    /// Reading the old store and choosing the cells to rebake.
    pub reuse_s: f64,
    /// Baking the cells.
    pub bake_s: f64,
    /// Encoding the store and the hashes.
    pub encode_s: f64,
}

/// What the scene held, from its load report: how many objects were skipped and why.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SceneCounts {
    pub objects: usize,
    pub blockers: usize,
    /// Objects the readers left out (neither occludee nor blocker).
    pub skipped: usize,
    pub skipped_by_reason: BTreeMap<String, usize>,
    /// Objects that gave no blocker (they stay occludees).
    pub no_blocker: usize,
    /// Reasons, one per report entry (an object may have several).
    pub no_blocker_by_reason: BTreeMap<String, usize>,
}

impl SceneCounts {
    pub fn of(scene: &Scene) -> SceneCounts {
        let mut skipped_by_reason = BTreeMap::new();
        for (_, s) in &scene.report.skipped {
            *skipped_by_reason.entry(s.reason.label()).or_insert(0) += 1;
        }
        let mut no_blocker_by_reason = BTreeMap::new();
        for (_, why) in &scene.report.no_blocker {
            *no_blocker_by_reason.entry(why.label()).or_insert(0) += 1;
        }
        let mut has_blocker = vec![false; scene.objects.len()];
        for b in &scene.blockers {
            if let Some(h) = has_blocker.get_mut(b.object as usize) {
                *h = true;
            }
        }
        SceneCounts {
            objects: scene.objects.len(),
            blockers: scene.blockers.len(),
            skipped: scene.report.skipped.len(),
            skipped_by_reason,
            no_blocker: has_blocker.iter().filter(|&&b| !b).count(),
            no_blocker_by_reason,
        }
    }
}

/// The grid of a bake.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct GridSummary {
    pub nx: u32,
    pub ny: u32,
    pub cell_size: f64,
    pub cells: u64,
    /// World rectangle `[x0, y0, x1, y1]` the grid covers.
    pub world: [f64; 4],
}

/// What a bake did, as data (the CLI prints it; `bake --json` writes it).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BakeSummary {
    pub grid: GridSummary,
    /// `[index, count]` when the job baked one shard.
    pub shard: Option<[u32; 2]>,
    /// Cells this job covers: the region, walkable area, explicit list and shard applied.
    pub cells_selected: usize,
    /// Of those, baked here.
    pub cells_baked: usize,
    /// Of those, copied from the old store.
    pub cells_reused: usize,
    /// Selected cells marked skipped (inside a building).
    pub cells_skipped: usize,
    /// Selected cells with at least one VO.
    pub cells_with_vos: usize,
    /// VOs in the store.
    pub vos: usize,
    /// VOs per selected cell (0 when none is selected).
    pub vos_per_cell: f64,
    /// The most VOs of one cell.
    pub max_vos: usize,
    /// Per baked cell, ms (`None` when no cell was baked here).
    pub ms_per_cell_median: Option<f64>,
    pub ms_per_cell_p95: Option<f64>,
    pub quantization: Quantization,
    /// CPU seconds of the long generator's stages, summed over the baked cells, by name
    /// ([`super::plan::STAGES`]): where a bake spends its time (empty under the growth).
    pub stages_s: BTreeMap<String, f64>,
    /// The far field's searches: `[whole blocks, quarters of blocks split among few blockers]`
    /// (`Plan::far_searches`; README, "How far a cell reaches").
    pub far_searches: [usize; 2],
    /// Worker threads the cells were baked on.
    pub threads: usize,
    pub timings: Timings,
    pub store_bytes: usize,
    pub hashes_bytes: usize,
    /// Store bytes per grid cell.
    pub bytes_per_cell: f64,
    /// Present when an older store was given for reuse.
    pub reuse: Option<ReuseDecision>,
    pub scene: SceneCounts,
    /// On a terrain: how far the ground rises across the selected cells that stand on it
    /// (metres, from each cell's stored ground level to its highest ground): the median and the
    /// most. A cell's eyes span that rise plus the eye range, and a cell whose eyes span more
    /// culls less (README, "Low-rise ground on a slope").
    pub ground_rise_m: Option<[f64; 2]>,
}

/// What a bake job returns.
#[derive(Clone, Debug)]
pub struct BakeOutput {
    /// The store file's bytes.
    pub store: Vec<u8>,
    /// The `.hashes` file's bytes (its store checksum is the store's).
    pub hashes: Vec<u8>,
    /// Every cell baked by this job, ascending id (reused cells are not here).
    pub cells: Vec<CellBake>,
    pub summary: BakeSummary,
}

/// One bake: build it with [`BakeJob::new`], narrow it with the builder methods, then
/// [`BakeJob::run`].
pub struct BakeJob<'s> {
    plan: Plan<'s>,
    plan_s: f64,
    shard: Option<(u32, u32)>,
    cells: Option<Vec<CellId>>,
    reuse: Option<(Vec<u8>, Option<Vec<u8>>)>,
    threads: Option<usize>,
}

impl<'s> BakeJob<'s> {
    /// Validates the parameters and the grid and builds the plan (the blocker and occludee
    /// indices); nothing is baked yet.
    pub fn new(scene: &'s Scene, params: BakeParams) -> Result<BakeJob<'s>, JobError> {
        let t = Instant::now();
        let plan = Plan::new(scene, params)?;
        Ok(BakeJob {
            plan,
            plan_s: t.elapsed().as_secs_f64(),
            shard: None,
            cells: None,
            reuse: None,
            threads: None,
        })
    }

    /// Bake only shard `index` of `count`: the selected cells whose group
    /// ([`super::share::group_of`]) is `index` modulo `count`.
    pub fn shard(mut self, index: u32, count: u32) -> Result<BakeJob<'s>, JobError> {
        if count == 0 || index >= count {
            return Err(JobError::Shard { index, count });
        }
        self.shard = Some((index, count));
        Ok(self)
    }

    /// Bake only these cells (instead of the plan's region and walkable selection); an empty
    /// list gives a store of empty cells on the plan's grid.
    pub fn cells(mut self, ids: &[CellId]) -> Result<BakeJob<'s>, JobError> {
        let n = self.plan.frame.grid.cell_count();
        if let Some(&id) = ids.iter().find(|&&id| id as u64 >= n) {
            return Err(JobError::CellOutsideGrid { id, cells: n });
        }
        let mut ids = ids.to_vec();
        ids.sort_unstable();
        ids.dedup();
        self.cells = Some(ids);
        Ok(self)
    }

    /// Reuse the records of an older store (its bytes, and its `.hashes` file's bytes when it
    /// has one) for the cells whose content hash did not change.
    pub fn reuse(mut self, store: Vec<u8>, hashes: Option<Vec<u8>>) -> BakeJob<'s> {
        self.reuse = Some((store, hashes));
        self
    }

    /// Bake on a pool of `n` worker threads (default: the current rayon pool). The output does
    /// not depend on it.
    pub fn threads(mut self, n: usize) -> BakeJob<'s> {
        self.threads = Some(n);
        self
    }

    pub fn plan(&self) -> &Plan<'s> {
        &self.plan
    }

    /// The scene section the store records (`docs/FORMAT.md` 5.2): the objects baked for, the
    /// scene's fingerprint and its coordinate reference system's name (empty when unknown; cut
    /// to the section's 255 bytes).
    pub fn scene_section(&self) -> SceneSection<'_> {
        let scene = self.plan.scene;
        SceneSection {
            // Object indices are `u32`, so the count fits (saturated, never reached).
            objects: u32::try_from(scene.objects.len()).unwrap_or(u32::MAX),
            scene: scene.fingerprint(),
            crs: scene.crs().map_or("", |c| crs_field(&c.name)),
        }
    }

    /// The world rectangle of the grid.
    fn grid_world(&self) -> [f64; 4] {
        let g = &self.plan.frame.grid;
        let o = self.plan.frame.origin;
        [
            g.min_x + o[0],
            g.min_y + o[1],
            g.min_x + g.cell_size * g.nx as f64 + o[0],
            g.min_y + g.cell_size * g.ny as f64 + o[1],
        ]
    }

    /// The cells this job covers, ascending: the explicit list, or the plan's selection (region,
    /// walkable area), then the shard.
    pub fn selected(&self) -> Result<Vec<CellId>, JobError> {
        let mut cells = match &self.cells {
            Some(c) => c.clone(),
            None => {
                let c = self.plan.cells();
                let p = self.plan.params();
                if c.is_empty() {
                    if let Some(r) = p.region {
                        let o = self.plan.frame.origin;
                        return Err(JobError::RegionOutsideGrid {
                            region: [r[0] + o[0], r[1] + o[1], r[2] + o[0], r[3] + o[1]],
                            grid: self.grid_world(),
                        });
                    }
                    if p.walkable.is_some() {
                        return Err(JobError::WalkableOutsideGrid {
                            grid: self.grid_world(),
                        });
                    }
                }
                c
            }
        };
        if let Some((i, n)) = self.shard {
            // By whole groups: a cell's record depends on its group's (bake/share.rs).
            let grid = &self.plan.frame.grid;
            cells.retain(|&id| super::share::group_of(grid, id) % n as u64 == i as u64);
        }
        Ok(cells)
    }

    /// Runs the bake. `progress` is called with done / total as cells finish, from the worker
    /// threads.
    pub fn run(&self, progress: &(dyn Fn(Progress) + Sync)) -> Result<BakeOutput, JobError> {
        match self.threads {
            None => self.run_here(progress),
            Some(n) => {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .map_err(|e| JobError::Threads {
                        threads: n,
                        message: e.to_string(),
                    })?;
                pool.install(|| self.run_here(progress))
            }
        }
    }

    fn run_here(&self, progress: &(dyn Fn(Progress) + Sync)) -> Result<BakeOutput, JobError> {
        let plan = &self.plan;
        let mut timings = Timings {
            plan_s: self.plan_s,
            ..Timings::default()
        };
        let cells = self.selected()?;
        let t = Instant::now();
        let hashes = CellHashes::new(plan, &cells);
        timings.hashes_s = t.elapsed().as_secs_f64();

        let t = Instant::now();
        let mut reuse = None;
        let mut reused: Vec<(CellId, CellRecord)> = Vec::new();
        let mut to_bake = cells.clone();
        if let Some((old_bytes, old_hashes)) = &self.reuse {
            let old = Store::parse(old_bytes).map_err(JobError::OldStore)?;
            let refused = match old_hashes {
                None => Some(ReuseRefusal::NoHashes),
                Some(b) => {
                    let h = CellHashes::decode(b).map_err(JobError::OldHashes)?;
                    if h.store_crc != crc32(old_bytes) {
                        Some(ReuseRefusal::OtherStore)
                    } else if encode_frame(old.frame()) != encode_frame(&plan.frame) {
                        Some(ReuseRefusal::FrameChanged)
                    } else if h.global != hashes.global {
                        Some(ReuseRefusal::OptionsChanged)
                    } else {
                        to_bake = whole_groups(plan, &hashes, &h, &cells);
                        for &id in &cells {
                            if to_bake.binary_search(&id).is_err() {
                                reused.push((id, old.cell(id).map_err(JobError::OldStore)?));
                            }
                        }
                        None
                    }
                }
            };
            reuse = Some(ReuseDecision {
                refused,
                changed: to_bake.len(),
                reused: reused.len(),
            });
        }
        timings.reuse_s = t.elapsed().as_secs_f64();

        let t = Instant::now();
        let total = to_bake.len();
        progress(Progress { done: 0, total });
        let baked = bake_cells(plan, &to_bake, &|done| progress(Progress { done, total }));
        timings.bake_s = t.elapsed().as_secs_f64();
        let threads = rayon::current_num_threads();

        let t = Instant::now();
        let mut recs = records(&plan.frame, &baked);
        for (id, rec) in reused {
            recs[id as usize] = rec;
        }
        let store = encode_store_with(&plan.frame, &recs, &self.scene_section())
            .map_err(JobError::Encode)?;
        let hashes = CellHashes {
            store_crc: crc32(&store),
            shard: self.shard,
            ..hashes
        }
        .encode();
        timings.encode_s = t.elapsed().as_secs_f64();

        let selected: Vec<&CellRecord> = cells.iter().map(|&id| &recs[id as usize]).collect();
        let vos: usize = recs.iter().map(|r| r.vos().len()).sum();
        let mut ms: Vec<f64> = baked.iter().map(|c| c.stats.ms).collect();
        ms.sort_by(f64::total_cmp);
        let pct =
            |p: f64| (!ms.is_empty()).then(|| ms[((ms.len() - 1) as f64 * p).round() as usize]);
        let quantization = baked
            .iter()
            .fold(Quantization::default(), |q, c| Quantization {
                tried: q.tried + c.stats.tried,
                shrunk: q.shrunk + c.stats.shrunk,
                dropped: q.dropped + c.stats.dropped,
                checks: q.checks + c.stats.checks,
            });
        let mut stages_s = BTreeMap::new();
        if plan.params.generator == super::params::Generator::Long {
            for (k, name) in super::plan::STAGES.iter().enumerate() {
                let ms: f64 = baked.iter().map(|c| c.stats.stage_ms[k]).sum();
                stages_s.insert(name.to_string(), ms * 1e-3);
            }
        }
        let g = plan.frame.grid;
        let summary = BakeSummary {
            grid: GridSummary {
                nx: g.nx,
                ny: g.ny,
                cell_size: g.cell_size,
                cells: g.cell_count(),
                world: self.grid_world(),
            },
            shard: self.shard.map(|(i, n)| [i, n]),
            cells_selected: cells.len(),
            cells_baked: baked.len(),
            cells_reused: cells.len() - baked.len(),
            cells_skipped: selected
                .iter()
                .filter(|r| matches!(r, CellRecord::Skipped))
                .count(),
            cells_with_vos: selected.iter().filter(|r| !r.vos().is_empty()).count(),
            vos,
            vos_per_cell: vos as f64 / cells.len().max(1) as f64,
            max_vos: recs.iter().map(|r| r.vos().len()).max().unwrap_or(0),
            ms_per_cell_median: pct(0.5),
            ms_per_cell_p95: pct(0.95),
            quantization,
            stages_s,
            far_searches: plan.far_searches(),
            threads,
            timings,
            store_bytes: store.len(),
            hashes_bytes: hashes.len(),
            bytes_per_cell: store.len() as f64 / recs.len().max(1) as f64,
            reuse,
            scene: SceneCounts::of(plan.scene()),
            ground_rise_m: plan.ground.as_ref().and_then(|t| {
                let mut r: Vec<f64> = cells
                    .iter()
                    .filter(|&&id| t.fits.get(id as usize).copied().unwrap_or(false))
                    .filter_map(|&id| t.rises.get(id as usize))
                    .map(|&r| r as f64 * t.ground_step)
                    .collect();
                r.sort_by(f64::total_cmp);
                Some([*r.get((r.len().checked_sub(1)?) / 2)?, *r.last()?])
            }),
        };
        Ok(BakeOutput {
            store,
            hashes,
            cells: baked,
            summary,
        })
    }
}

/// A CRS name as the store's scene section holds it: at most 255 bytes, cut at a character
/// boundary (a name that long is a description read from a file, whose start names it).
pub(crate) fn crs_field(name: &str) -> &str {
    let mut end = name.len().min(255);
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    &name[..end]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::share;
    use crate::scene::{gencity, ReadOptions};

    /// A generated city of `n` buildings, loaded from its GeoJSON bytes.
    fn city(n: usize) -> Scene {
        let c = gencity::generate(&gencity::CityParams {
            buildings: n,
            seed: 5,
        });
        let mut bytes = Vec::new();
        gencity::write_geojson(&mut bytes, &c).unwrap();
        crate::scene::load_bytes(
            &[("city.geojson".into(), &bytes)],
            &ReadOptions {
                height_attr: Some("height".into()),
                ..ReadOptions::default()
            },
        )
        .unwrap()
    }

    /// 50 m cells over a part of the city (local coordinates), where it stores VOs.
    fn params() -> BakeParams {
        BakeParams {
            cell_size: 50.0,
            region: Some([150.0, 100.0, 400.0, 250.0]),
            ..BakeParams::default()
        }
    }

    /// The regression: the selection's gain threshold alone set the bytes, and a district of
    /// towers (Tokyo's 1,207 buildings of 40 m and more) stored 9.6 VOs a cell, 58.6 bytes a
    /// cell over the 52 allowed. Now a budget caps each cell: the whole store, every byte
    /// counted, stays within it, and the cap binds (without it the same bake is over).
    #[test]
    fn a_district_of_towers_stored_more_than_its_bytes_per_cell() {
        let s = city(300);
        let bake = |bytes_per_cell: f64| {
            let p = BakeParams {
                bytes_per_cell,
                ..BakeParams::default()
            };
            let out = BakeJob::new(&s, p).unwrap().run(&|_| {}).unwrap();
            let n = out.summary.grid.cells as f64;
            (out.store.len() as f64 / n, out.summary.vos, out)
        };
        let (free, free_vos, _) = bake(f64::INFINITY);
        let budget = 24.0;
        assert!(
            free > budget,
            "without a budget the store is over it: {free}"
        );
        let (capped, vos, out) = bake(budget);
        assert!(capped <= budget, "{capped} bytes a cell over {budget}");
        assert!(
            0 < vos && vos < free_vos,
            "{vos} VOs, {free_vos} without the budget"
        );
        // Each group of cells within its allowance (bake/share.rs), which the store's sum then
        // respects; the bytes a group's cells leave under their own caps (Plan::vo_cap) go to
        // further VOs of other cells of the group, so some cell stores more than its cap.
        let plan = Plan::new(
            &s,
            BakeParams {
                bytes_per_cell: budget,
                ..BakeParams::default()
            },
        )
        .unwrap();
        let st = Store::parse(&out.store).unwrap();
        let grid = &plan.frame.grid;
        let mut groups: BTreeMap<u64, (usize, usize)> = BTreeMap::new();
        let mut over_cap = 0;
        for id in 0..out.summary.grid.cells as CellId {
            let rec = st.cell(id).unwrap();
            let n = rec.vos().len();
            assert!(n <= plan.params().max_vos, "cell {id}: {n} VOs");
            over_cap += usize::from(n > plan.vo_cap(id));
            let g = groups.entry(share::group_of(grid, id)).or_default();
            g.0 += share::record_bytes(&plan.frame, &rec);
            g.1 += 1;
        }
        // The records' bytes, as the format counts them, are the store's beside its fixed part
        // (the generated city has no CRS).
        let records: usize = groups.values().map(|g| g.0).sum();
        let fixed = crate::runtime::format::store::fixed_len(out.summary.grid.cells, 0);
        assert_eq!(fixed as usize + records, out.store.len());
        for (g, (bytes, cells)) in groups {
            let allowance = plan.cell_allowance() * cells as f64;
            assert!(
                bytes as f64 <= allowance,
                "group {g}: {bytes} bytes over {allowance}"
            );
        }
        assert!(over_cap > 0, "no cell stored more than its own cap");
        // A budget that is no number is refused by name.
        let bad = BakeParams {
            bytes_per_cell: f64::NAN,
            ..BakeParams::default()
        };
        assert!(matches!(
            BakeJob::new(&s, bad).err(),
            Some(JobError::Plan(BakeError::BytesPerCell(_)))
        ));
    }

    #[test]
    fn shards_threads_and_reuse_give_the_full_bakes_bytes() {
        let s = city(300);
        let full = BakeJob::new(&s, params())
            .unwrap()
            .threads(1)
            .run(&|_| {})
            .unwrap();
        let sum = &full.summary;
        assert!(sum.vos > 0, "the city stores VOs: {sum:?}");
        assert_eq!(sum.cells_baked, sum.cells_selected);
        assert!(0 < sum.cells_selected && (sum.cells_selected as u64) < sum.grid.cells);
        assert_eq!(sum.store_bytes, full.store.len());
        assert_eq!(sum.scene.objects, 300);
        // The store records the scene it was baked from (FORMAT.md 5.2); no CRS yet.
        let st = Store::parse(&full.store).unwrap();
        assert_eq!(st.major(), 2);
        assert_eq!(
            (st.objects(), st.scene(), st.crs()),
            (300, s.fingerprint(), "")
        );
        assert_ne!(st.scene(), city(301).fingerprint());
        CellHashes::decode(&full.hashes).unwrap();
        // Two threads: the same bytes; progress counts every cell once, from 0.
        let seen = std::sync::Mutex::new(Vec::new());
        let two = BakeJob::new(&s, params())
            .unwrap()
            .threads(2)
            .run(&|p| seen.lock().unwrap().push(p))
            .unwrap();
        assert_eq!(two.store, full.store);
        assert_eq!(two.hashes, full.hashes);
        let mut seen = seen.into_inner().unwrap();
        seen.sort_by_key(|p| p.done);
        let total = sum.cells_baked;
        assert_eq!(seen.len(), total + 1);
        assert!(seen
            .iter()
            .enumerate()
            .all(|(k, p)| p.done == k && p.total == total));
        // Three shards cover the cells once each, by whole groups of cells (bake/share.rs).
        let mut covered = 0;
        let grid = BakeJob::new(&s, params()).unwrap().plan.frame.grid;
        for i in 0..3 {
            let sh = BakeJob::new(&s, params()).unwrap().shard(i, 3).unwrap();
            let out = sh.run(&|_| {}).unwrap();
            assert!(out
                .cells
                .iter()
                .all(|c| share::group_of(&grid, c.id) % 3 == i as u64));
            assert_eq!(out.summary.shard, Some([i, 3]));
            covered += out.summary.cells_baked;
        }
        assert_eq!(covered, total);
        // Reusing its own output bakes nothing and gives the same bytes.
        let again = BakeJob::new(&s, params())
            .unwrap()
            .reuse(full.store.clone(), Some(full.hashes.clone()))
            .run(&|_| {})
            .unwrap();
        assert_eq!(again.store, full.store);
        assert_eq!(
            again.summary.reuse,
            Some(ReuseDecision {
                refused: None,
                changed: 0,
                reused: total
            })
        );
        assert_eq!(again.summary.ms_per_cell_median, None);
        assert_eq!(again.summary.vos, sum.vos);
        // Without hashes, or with another option, every cell is baked, and the reason says why.
        let no_hashes = BakeJob::new(&s, params())
            .unwrap()
            .reuse(full.store.clone(), None)
            .run(&|_| {})
            .unwrap();
        assert_eq!(no_hashes.store, full.store);
        let r = no_hashes.summary.reuse.unwrap();
        assert_eq!(
            (r.refused, r.changed),
            (Some(ReuseRefusal::NoHashes), total)
        );
        let other = BakeJob::new(
            &s,
            BakeParams {
                max_vos: 3,
                ..params()
            },
        )
        .unwrap()
        .reuse(full.store.clone(), Some(full.hashes.clone()))
        .run(&|_| {})
        .unwrap();
        assert_eq!(
            other.summary.reuse.unwrap().refused,
            Some(ReuseRefusal::OptionsChanged)
        );
        // Damaged hashes are an error, not a silent full bake.
        let mut bad = full.hashes.clone();
        bad[30] ^= 1;
        let e = BakeJob::new(&s, params())
            .unwrap()
            .reuse(full.store.clone(), Some(bad))
            .run(&|_| {})
            .unwrap_err();
        assert!(matches!(e, JobError::OldHashes(_)), "{e}");
    }

    #[test]
    fn bad_shards_cells_and_regions_are_refused() {
        let s = city(20);
        let job = || BakeJob::new(&s, params()).unwrap();
        assert!(matches!(
            job().shard(3, 3),
            Err(JobError::Shard { index: 3, count: 3 })
        ));
        assert!(matches!(job().shard(0, 0), Err(JobError::Shard { .. })));
        let n = job().plan().frame.grid.cell_count() as u32;
        assert!(matches!(
            job().cells(&[0, n]),
            Err(JobError::CellOutsideGrid { .. })
        ));
        // An explicit empty list is a store of empty cells on the grid.
        let empty = job().cells(&[]).unwrap().run(&|_| {}).unwrap();
        assert_eq!(empty.summary.vos, 0);
        assert_eq!(Store::parse(&empty.store).unwrap().cell_count(), n);
        // A region that meets no cell is an error naming the grid, not an empty bake.
        let far = BakeJob::new(
            &s,
            BakeParams {
                region: Some([1e6, 1e6, 1e6 + 10.0, 1e6 + 10.0]),
                ..params()
            },
        )
        .unwrap();
        let e = far.run(&|_| {}).unwrap_err();
        assert!(matches!(e, JobError::RegionOutsideGrid { .. }), "{e}");
        assert!(e.to_string().contains("meets no cell of the grid"), "{e}");
    }
}
