//! The plan of a bake and its cells: a scene and [`BakeParams`] in, one stored record per cell
//! out.
//!
//! Input: a loaded [`Scene`] and [`BakeParams`]. Output: a [`Plan`] (the store's [`Frame`], all
//! blockers with their R-tree and shared edges, the occludees) and, per cell in id order, a
//! [`CellBake`]: its record (skipped, or its ground level and at most `max_vos` quantized VOs,
//! most effective first) and what it took ([`CellStats`]); then the store's records and bytes.
//! Per cell ([`Plan::bake_cell`]): the setup both generators share ([`super::cell`]: ground,
//! eyes, the inside-a-building skip, the near blockers with their rule-2 support, the slice
//! levels), then the generator the parameters name: [`super::long`] (the default) or
//! [`super::growth`]. Both re-check every stored VO in its dequantized form with rule 2 and the
//! exact verifier; a VO that fails is shrunk or dropped and counted.
//! Invariants: the parameters are validated, and the grid's memory checked, before anything is
//! allocated per cell; each cell is baked from the scene alone within [`Plan::reaches`] (no state
//! shared between cells), so the output is the same for any thread count and any order of
//! cells; no cell gets more than [`MAX_VOS_PER_CELL`] VOs.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;
use std::time::Instant;

use glam::DVec2;
use rayon::prelude::*;

use super::cell::CellSetup;
use super::far::{Blocks, FarPiece};
use super::occludees::Occludees;
use super::params::{BakeParams, Generator, Slices, MAX_CELL_SIZE_M, MIN_CELL_SIZE_M};
use super::BlockerSet;
use crate::runtime::format::{encode_store, CellRecord, FormatError};
use crate::runtime::frame::{Frame, VoGeom, HEIGHT_LEVELS, MAX_VOS_PER_CELL};
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

/// Why a bake cannot start.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum BakeError {
    #[error("cell size must be {MIN_CELL_SIZE_M} to {MAX_CELL_SIZE_M} metres, got {0}")]
    CellSize(f64),
    #[error("eye heights must satisfy 0 <= low <= high, got {0}..{1}")]
    Eye(f64, f64),
    #[error("--max-vos must be 1..=10, got {0}")]
    MaxVos(usize),
    #[error("--bytes-per-cell must be a positive number of bytes, got {0}")]
    BytesPerCell(f64),
    #[error("--slices must be 1..={max}, got {0}", max = super::slice::MAX_SLICES)]
    Slices(u8),
    #[error("--reach must be {min} to {max} m, got {0}", min = super::params::MIN_REACH_M, max = super::params::MAX_REACH_M)]
    Reach(f64),
    #[error("--far-block must be 0 (off) or above 0 up to {max} m, got {0}", max = super::params::MAX_FAR_BLOCK_M)]
    FarBlock(f64),
    #[error("the scene has no objects")]
    EmptyScene,
    #[error("the grid would have {0} cells, more than 2^31; use larger cells")]
    TooManyCells(u64),
    /// The grid's per-cell tables would not fit in memory ([`super::budget`]).
    #[error("{0}")]
    Grid(Box<super::budget::GridTooLarge>),
}

/// The long generator's stages, as [`CellStats::stage_ms`] and the bake's summary name them.
pub const STAGES: [&str; 5] = ["maps", "proposals", "weights", "far_field", "selection"];

/// What baking one cell took. Both generators fill `levels`, `dense`, `tried`, `shrunk`,
/// `dropped`, `checks`, `unquantized` and `hidden_cost`, each in its own sense below;
/// `proposed_m`, `certified_m`, `stage_ms` and `raised` are the long generator's alone (0 under
/// the growth). A cell no generator saw (skipped, or with no blocker that may support a VO)
/// has only `ms` (and `levels` when it had near blockers but no slice).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CellStats {
    /// Slice levels used (height levels of the frame, ascending), chosen before either
    /// generator runs.
    pub levels: Vec<u8>,
    /// Candidates that hide some occludee by rule 3. Long: the proposals over all slices (each
    /// segment once, at its highest level), trimmed. Growth: the dense VOs over all slices,
    /// clipped to the quantization window, at their chain's level.
    pub dense: usize,
    /// Long: proposals sent to the exact verifier to be cut into certified pieces. Growth: dense
    /// VOs the decimation tried to store.
    pub tried: usize,
    /// Stored only after a shorter grid segment or a lower level replaced a failed one. Long: of
    /// the certified pieces stored. Growth: of the VOs tried.
    pub shrunk: usize,
    /// Not stored because no grid segment near them, at their level or the lower ones tried,
    /// passed rule 2 and the verifier. Long: certified pieces sent to quantization. Growth: VOs
    /// tried.
    pub dropped: usize,
    /// Exact verifications run. Long: hidden-part searches of proposals, checks of quantized
    /// candidates and the sweeps that raise a stored VO. Growth: checks of quantized candidates.
    pub checks: usize,
    /// The stored VOs before quantization, in the same order, for measuring what quantization
    /// costs. Long: the certified piece at its level (before quantization and raising). Growth:
    /// the dense VO at its chain's level.
    pub unquantized: Vec<VoGeom>,
    /// Occludee cost hidden by the VOs the cell's greedy picked together (rule 3, within
    /// [`Plan::reaches`]), before its group's share of the bytes cuts them ([`super::share`]).
    /// Both.
    pub hidden_cost: u64,
    /// Long only: length of the proposals sent to the exact verifier, and of the certified
    /// pieces kept from them, metres (the verifier's completeness).
    pub proposed_m: f64,
    pub certified_m: f64,
    /// Long only: time per stage, ms ([`STAGES`]): hidden maps, proposals, rule-3 weights (with
    /// trimming), the block's far field (its search counts in the cell that first asks for it,
    /// the others find it cached), selection with certification.
    pub stage_ms: [f64; STAGES.len()],
    /// Long only: levels the stored VOs were raised by after quantization (rule 2's tighter
    /// bounds for their own segment).
    pub raised: usize,
    /// Long only: each stored VO's gain when the cell's greedy picked it (the occludee cost it
    /// added), in stored order, non-increasing; what [`super::share`] weighs a cell's VOs beyond
    /// its own cap by. Empty for the growth generator (its cells keep their own cap).
    pub gains: Vec<u64>,
    /// Time the whole cell took, ms. Both.
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
    /// Every blocker of the scene (2D), with its R-tree.
    pub(super) set: BlockerSet,
    /// The blockers' shared edges, for each slice's boundary edges (the long generator).
    pub(super) twins: super::hidden::EdgeTwins,
    /// Each blocker's base and top, metres (local frame).
    pub(super) base: Vec<f64>,
    pub(super) top: Vec<f64>,
    pub occludees: Occludees,
    /// On a terrain, every cell's ground level and whether its eyes fit the frame.
    pub ground: Option<super::terrain::GroundTable>,
    /// The blocks of cells the far field is sought for ([`super::far`]); for each block,
    /// whether it splits into quarters, and the far pieces of the whole block and of each
    /// quarter (`FAR_SLOTS` a block), each found when a cell of it first asks.
    pub blocks: Blocks,
    splits: Vec<OnceLock<bool>>,
    far: Vec<OnceLock<Vec<FarPiece>>>,
}

/// A block's cached far pieces: the whole block's, then its four quarters'.
const FAR_SLOTS: usize = 5;

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
        if !(params.bytes_per_cell > 0.0) {
            return Err(BakeError::BytesPerCell(params.bytes_per_cell));
        }
        if let Slices::Fixed(n) = params.slices {
            if n == 0 || n as usize > super::slice::MAX_SLICES {
                return Err(BakeError::Slices(n));
            }
        }
        let reach = params.search_m;
        if !(reach.is_finite()
            && (super::params::MIN_REACH_M..=super::params::MAX_REACH_M).contains(&reach))
        {
            return Err(BakeError::Reach(reach));
        }
        let block = params.far.block_m;
        if !(block == 0.0 || (block > 0.0 && block <= super::params::MAX_FAR_BLOCK_M)) {
            return Err(BakeError::FarBlock(block));
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
        // The objects' blockers, then the terrain's (scene/terrain.rs).
        let all = || scene.blockers.iter().chain(scene.terrain_blockers());
        let base: Vec<f64> = all().map(|b| b.base).collect();
        let top: Vec<f64> = all().map(|b| b.top).collect();
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
        let grid = GridDescriptor {
            min_x,
            min_y,
            cell_size: size,
            nx: nx as u32,
            ny: ny as u32,
        };
        // On a terrain, each cell stands on its least terrain height, and the eyes reach the
        // greatest (bake/terrain.rs).
        let ground = super::terrain::GroundTable::new(scene, &grid);
        let (ground_z0, ground_step) = match &ground {
            Some(t) => (t.ground_z0, t.ground_step),
            None => (ground_z0, ground_step),
        };
        let blocks = if params.generator == Generator::Long {
            Blocks::new(nx as u32, ny as u32, size, params.far.block_m)
        } else {
            Blocks::new(nx as u32, ny as u32, size, 0.0)
        };
        let far_m = if blocks.side > 0 {
            blocks.side as f64 * size + params.far.reach_m
        } else {
            0.0
        };
        // The largest exponent's grid (255 * 128 steps from the centre) reaches as far as a VO
        // may stand from its cell: its own search, or its block's far field.
        let quantum = pow2_at_least((0.5 * size + params.search_m).max(far_m) / (255.0 * 128.0));
        // The highest level stands as tall above the lowest eye as the tallest building (not
        // the terrain: a hill far off does not make every VO's levels coarse).
        let tallest = scene.blockers.iter().fold(0.0f64, |m, b| m.max(b.top));
        let rise = (tallest - (ground_z0 + e1)).max(4.0 * H0_M);
        let h_ratio = (((rise / H0_M + 1.0).ln() / (HEIGHT_LEVELS - 1) as f64).exp() * 1024.0)
            .ceil()
            / 1024.0;
        let frame = Frame {
            origin: scene.origin.to_array(),
            grid,
            quantum,
            eye_lo: e0,
            eye_hi: e1,
            ground_z0,
            ground_step,
            h0: H0_M,
            h_ratio,
        };
        let set = BlockerSet::new(
            all().map(|b| b.polygon.clone()).collect(),
            all().map(|b| b.top - b.base).collect(),
        )
        .with_objects(all().map(|b| b.object).collect());
        Ok(Plan {
            scene,
            frame,
            twins: super::hidden::EdgeTwins::new(&set.polys),
            set,
            base,
            top,
            occludees: Occludees::from_scene(scene),
            splits: (0..blocks.count()).map(|_| OnceLock::new()).collect(),
            far: (0..blocks.count() * FAR_SLOTS)
                .map(|_| OnceLock::new())
                .collect(),
            blocks,
            params,
            ground,
        })
    }

    /// The far pieces of the block of cell `id`, or of its quarter that holds the cell where
    /// the block splits ([`super::far`]): sought when a cell of that region first asks, the
    /// same whatever cell that is; none without blocks.
    pub fn far_pieces(&self, id: CellId) -> &[FarPiece] {
        let Some(b) = self.block_of(id) else {
            return &[];
        };
        let g = &self.frame.grid;
        let cells = self.blocks.cells(b, g.nx, g.ny);
        let (k, region) = if self.block_splits(b) {
            let (q, r) = self.blocks.quarter(cells, id % g.nx, id / g.nx);
            (1 + q, r)
        } else {
            (0, cells)
        };
        match self.far.get(b * FAR_SLOTS + k) {
            Some(slot) => slot.get_or_init(|| super::far::block_pieces(self, region)),
            None => &[],
        }
    }

    /// The far-field searches this plan has run: `[whole blocks, quarters of split blocks]`
    /// (each runs once, when a cell of it first asks).
    pub fn far_searches(&self) -> [usize; 2] {
        let mut n = [0, 0];
        for (k, slot) in self.far.iter().enumerate() {
            if slot.get().is_some() {
                n[usize::from(k % FAR_SLOTS != 0)] += 1;
            }
        }
        n
    }

    /// Whether block `b` seeks its far field per quarter: it has at least 2 cells a side, and
    /// its square grown by the far field's reach each way meets at most
    /// [`super::params::FarParams::split_blockers`] blockers' boxes (the blockers around it
    /// alone decide, so an edit beyond the block's reach never changes it).
    pub fn block_splits(&self, b: usize) -> bool {
        let far = &self.params.far;
        if far.split_blockers == 0 || !self.blocks.can_split() {
            return false;
        }
        let Some(slot) = self.splits.get(b) else {
            return false;
        };
        *slot.get_or_init(|| {
            let g = &self.frame.grid;
            let c = self.blocks.cells(b, g.nx, g.ny);
            if c.is_empty() {
                return false;
            }
            let [x0, y0, x1, y1] = c.rect(g);
            let r = DVec2::splat(far.reach_m);
            self.set
                .in_box(DVec2::new(x0, y0) - r, DVec2::new(x1, y1) + r)
                .take(far.split_blockers + 1)
                .count()
                <= far.split_blockers
        })
    }

    /// The far-field block of cell `id`; none without blocks or outside the grid.
    pub fn block_of(&self, id: CellId) -> Option<usize> {
        let g = &self.frame.grid;
        if self.blocks.side == 0 || g.nx == 0 || id as u64 >= g.cell_count() {
            return None;
        }
        Some(self.blocks.of(id % g.nx, id / g.nx))
    }

    pub fn scene(&self) -> &'s Scene {
        self.scene
    }

    pub fn params(&self) -> &BakeParams {
        &self.params
    }

    /// What a cell's bake reads, in three parts (metres, half-sides of squares; ARCHITECTURE.md
    /// invariant 13): [`Reaches`].
    pub fn reaches(&self) -> Reaches {
        let cell = self.frame.grid.cell_size;
        let p = &self.params;
        // One metre more everywhere, against rounding in the bake's box arithmetic.
        let near = p.search_m + cell + 1.0;
        if self.blocks.side == 0 {
            return Reaches {
                near,
                weigh: p.weigh_m + 1.0,
                block: 0.0,
            };
        }
        let side = self.blocks.side as f64 * cell;
        Reaches {
            near,
            // A block weighs its pieces from its own centre, at most a block's side from the
            // cell's.
            weigh: p.weigh_m + side + 1.0,
            // The block's blockers within `far.reach_m` of it (its hidden maps a square of
            // `far.reach_m` + half its side around its centre), its cells' grounds within
            // `search_m` of them; the block lies within half its side of its centre.
            block: side + p.far.reach_m.max(p.search_m) + 1.0,
        }
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
        if let Some(t) = &self.ground {
            return t.levels.get(id as usize).copied().unwrap_or(0);
        }
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

    /// The bytes each cell may take on average within the store's budget
    /// ([`BakeParams::bytes_per_cell`], `B`): `B - F / N`, where `F` is the store's fixed part
    /// (header, scene section with the CRS name, and the block table's 4 bytes per 64 cells) and
    /// `N` the grid's cells. Over `N` cells the store is within `B N` bytes when the cells take
    /// `N (B - F / N)` at most. Infinite without a budget.
    pub fn cell_allowance(&self) -> f64 {
        let b = self.params.bytes_per_cell;
        if !b.is_finite() {
            return f64::INFINITY;
        }
        let n = self.frame.grid.cell_count().max(1);
        let crs = self
            .scene
            .crs()
            .map_or(0, |c| super::job::crs_field(&c.name).len());
        let fixed = crate::runtime::format::store::fixed_len(n, crs) as f64;
        b - fixed / n as f64
    }

    /// The VOs cell `id` keeps whatever its group does, and never more than `max_vos`: per
    /// cell, 1 index byte, a ground byte when the frame has per-cell ground, a rise byte when
    /// the cell has a rise, and 6 bytes per VO (docs/FORMAT.md sections 5 and 6) within
    /// [`Plan::cell_allowance`], so `floor((B - F / N - 1 - ground - rise) / 6)`. The cap
    /// depends on the grid and the cell alone. It is at least 1: on a grid so small that its
    /// header alone exceeds the budget (a few cells), one VO a cell still goes in. What a group
    /// of cells leaves of its allowance pays for further VOs of its cells ([`super::share`]).
    pub fn vo_cap(&self, id: CellId) -> usize {
        let allowance = self.cell_allowance();
        if !allowance.is_finite() {
            return self.params.max_vos;
        }
        let own = 1.0
            + f64::from(u8::from(self.frame.per_cell_ground()))
            + f64::from(u8::from(self.stand(id).rise > 0));
        let cap = ((allowance - own) / crate::runtime::format::VO_BYTES as f64).floor();
        (cap.max(1.0) as usize).min(self.params.max_vos)
    }

    /// The most VOs the cell's own greedy may pick: [`Plan::vo_cap`] for the growth generator;
    /// for the long generator `max_vos`, of which the group's share of the byte budget keeps
    /// the cap and the best picks beyond it ([`super::share`]).
    pub fn vo_max(&self, id: CellId) -> usize {
        match self.params.generator {
            Generator::Long => self.params.max_vos,
            Generator::Growth => self.vo_cap(id),
        }
    }

    /// Where the cell stands: its ground level and, on a terrain, its rise (bake/terrain.rs).
    pub fn stand(&self, id: CellId) -> crate::runtime::frame::CellGround {
        crate::runtime::frame::CellGround {
            level: self.ground_level(id),
            rise: self
                .ground
                .as_ref()
                .and_then(|t| t.rises.get(id as usize).copied())
                .unwrap_or(0),
        }
    }

    /// Whether a camera anywhere on the cell's ground stands within its stored eye range (always
    /// without a terrain; on one, not for the steepest cells, bake/terrain.rs).
    pub fn eyes_fit(&self, id: CellId) -> bool {
        self.ground
            .as_ref()
            .is_none_or(|t| t.fits.get(id as usize).copied().unwrap_or(false))
    }

    /// Bakes one cell.
    pub fn bake_cell(&self, id: CellId) -> CellBake {
        let t0 = Instant::now();
        let mut stats = CellStats::default();
        let record = self.bake_record(id, &mut stats);
        stats.ms = t0.elapsed().as_secs_f64() * 1e3;
        CellBake { id, record, stats }
    }

    /// The cell's record: its setup, then the generator the parameters name.
    fn bake_record(&self, id: CellId, stats: &mut CellStats) -> CellRecord {
        let c = match CellSetup::new(self, id) {
            Ok(c) => c,
            Err(record) => return record,
        };
        stats.levels = c.slices.clone();
        match self.params.generator {
            Generator::Long => {
                let rec = super::long::long_vos(self, &c, stats);
                // On a terrain, the cell is baked again with deep VOs (bottom at the lowest
                // ground level, bake/terrain.rs); the record that hides more is kept.
                if self.ground.is_none() || c.g <= self.frame.ground_z0 {
                    return rec;
                }
                let Ok(d) = CellSetup::new_with(self, id, true) else {
                    return rec;
                };
                let mut deep = CellStats {
                    levels: d.slices.clone(),
                    ..CellStats::default()
                };
                let drec = super::long::long_vos(self, &d, &mut deep);
                if deep.hidden_cost > stats.hidden_cost {
                    *stats = deep;
                    drec
                } else {
                    rec
                }
            }
            Generator::Growth => super::growth::growth_vos(self, &c, stats),
        }
    }
}

/// Bakes `cells` in parallel on the current rayon pool; `progress(done)` is called as cells
/// finish. Results come in the order of `cells`.
pub fn bake_cells(
    plan: &Plan,
    cells: &[CellId],
    progress: &(dyn Fn(usize) + Sync),
) -> Vec<CellBake> {
    let done = AtomicUsize::new(0);
    let mut baked: Vec<CellBake> = cells
        .par_iter()
        .map(|&id| {
            let r = plan.bake_cell(id);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            r
        })
        .collect();
    super::share::share_bytes(plan, &mut baked);
    baked
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

/// What a cell's bake reads of the scene, as half-sides of squares (metres), beside the frame
/// and the options ([`Plan::reaches`]; `bake/incremental.rs` hashes each part).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reaches {
    /// Around the cell's centre: the objects whose blockers, order and all, its own search
    /// reads (usable blockers within `cell ± search_m`, the ground level).
    pub near: f64,
    /// Around the cell's centre: the occludees its VOs and its block's far pieces are weighed
    /// against, as boxes and costs (rule 3); their order does not matter (weights are sums of
    /// costs over sets).
    pub weigh: f64,
    /// Around the centre of the cell's far-field block: what the block's own search reads,
    /// order and all; 0 without blocks.
    pub block: f64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::squares;

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
}
