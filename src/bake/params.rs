//! What a bake is asked for: one struct, [`BakeParams`], with the effort settings and the limits.
//!
//! Input: the caller's choices (the CLI's flags, the Python binding's arguments, a test's
//! values) over [`BakeParams::default`]. Output: [`BakeParams`], which [`super::plan::Plan::new`]
//! validates (the limits below, named in its [`super::plan::BakeError`]) before anything is baked.
//! Every field says what it is, its unit, and which generator reads it: both, only the long one
//! ([`Generator::Long`], the default), or only the growth ([`Generator::Growth`]).
//! Invariants: no field but the cell selection (`region`, `walkable`) changes a cell's record
//! without changing the `.hashes` file's global hash (`super::incremental` hashes all of them, in
//! a fixed layout); the defaults are what `vocc bake` bakes with no option.

use super::growth::GrowParams;
use crate::runtime::frame::MAX_VOS_PER_CELL;

/// The smallest view cell, metres. VO endpoints lie on a grid of at least 2 m at the default
/// search distance, so smaller cells give no finer occluders, only many more cells to bake.
pub const MIN_CELL_SIZE_M: f64 = 1.0;
/// The largest view cell, metres.
pub const MAX_CELL_SIZE_M: f64 = 1e5;
/// How far around a cell the blockers of its VOs are looked for by default, metres
/// ([`BakeParams::search_m`]).
pub const SEARCH_M: f64 = 900.0;
/// The shortest and longest reach a bake accepts, metres ([`BakeParams::with_reach`]): below
/// 100 m a cell finds hardly any fused occlusion; beyond 5 km the far field
/// ([`FarParams::reach_m`]) already serves, and each cell would read a whole district.
pub const MIN_REACH_M: f64 = 100.0;
pub const MAX_REACH_M: f64 = 5000.0;
/// The largest far-field block a bake accepts, metres ([`BakeParams::with_far_block`]): a block
/// holds at most 64 cells a side in any case ([`super::far::Blocks::new`]).
pub const MAX_FAR_BLOCK_M: f64 = 10_000.0;

/// How far a cell's own search reaches past its sides (`vocc bake --reach`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reach {
    /// Chosen from the scene ([`super::reach::auto_reach`]; the default).
    Auto,
    /// This many metres ([`MIN_REACH_M`] to [`MAX_REACH_M`]).
    Metres(f64),
}

/// How many slices a cell gets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slices {
    /// Up to 5, or up to 8 where the cell's blockers stand low ([`super::slice::auto_slices`]);
    /// fewer when the heights around the cell do not spread over that many levels.
    Auto,
    /// Up to this many (1 to [`super::slice::MAX_SLICES`]), fewer when levels coincide.
    Fixed(u8),
}

/// What the bake is asked for.
#[derive(Clone, Debug)]
pub struct BakeParams {
    /// Side of a view cell, metres ([`MIN_CELL_SIZE_M`] to [`MAX_CELL_SIZE_M`]). Both generators.
    pub cell_size: f64,
    /// Eye heights above a cell's ground, lowest and highest, metres (`0 <= low <= high`). Both
    /// generators (rule 2 and rule 3 heights, the frame's eye range).
    pub eye: (f64, f64),
    /// How many slice levels a cell is baked at. Both generators.
    pub slices: Slices,
    /// Most VOs stored per cell, a count (1 to [`MAX_VOS_PER_CELL`]). Both generators.
    pub max_vos: usize,
    /// The store's budget, bytes per cell on average with every byte of the store counted
    /// ([`BYTES_PER_CELL`]; `f64::INFINITY`: none). Each cell keeps the VOs that
    /// [`super::plan::Plan::vo_cap`] allows it, and the bytes its group of 4 x 4 cells leaves
    /// pay for the group's best further VOs ([`super::share`]), so that the whole store stays
    /// within it. Both generators (only the long one's cells take further VOs).
    pub bytes_per_cell: f64,
    /// Bake only the cells meeting this local rectangle `[x0, y0, x1, y1]`, metres (the grid
    /// still covers the whole scene). Cell selection, both generators; not in the global hash.
    pub region: Option<[f64; 4]>,
    /// Bake only the cells meeting this walkable area (outer rings, local frame). Cell
    /// selection, both generators; not in the global hash.
    pub walkable: Option<crate::scene::walkable::Area>,
    /// How far around a cell (per axis, past its sides) the blockers that may support its VOs
    /// are taken from, metres. Both generators; it also bounds the ground level's widening
    /// search, sets the quantization window (the quantum) and, with the cell size, the reach
    /// ([`super::plan::Plan::reaches`]); the growth follows its active lines this far.
    pub search_m: f64,
    /// The growth's own knobs (seeds, chain length, bridges, tries, shortest VO, single-object
    /// chains, the dense set's verification). The growth only.
    pub grow: GrowParams,
    /// Which generator proposes the VOs.
    pub generator: Generator,
    /// Occludees within this distance of a cell's centre (per axis) weigh its VOs, metres
    /// ([`WEIGH_M`]). Both generators.
    pub weigh_m: f64,
    /// The sampled visibility of the cell's boundary: eyes per edge, angular bins, pixel side
    /// (metres) and raster half-side (metres). The long generator only (set by [`Effort`]).
    pub map: super::hidden::MapParams,
    /// The line scan over that raster: directions, line spacing (metres), step (pixels),
    /// farthest line (metres), shortest run (metres), runs kept per direction and band. The long
    /// generator only (set by [`Effort`]).
    pub propose: super::propose::ProposeParams,
    /// Exact certifications the long generator's selection may run per cell, a count
    /// ([`super::select`]). The long generator only (set by [`Effort`]).
    pub budget: usize,
    /// The far field: VOs sought once per block of cells, far beyond `search_m`, certified
    /// hidden from the whole block and offered to each of its cells ([`super::far`]). The long
    /// generator only (its budget set by [`Effort`]).
    pub far: FarParams,
}

/// How the far field is sought ([`super::far`]): per block of cells, with the long generator's
/// own stages at the block's scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FarParams {
    /// Side of a block, metres: blocks are squares of whole cells, the nearest count per side
    /// to this (at least 1). 0 turns the far field off.
    pub block_m: f64,
    /// How far around a block (per axis, past its sides) its VOs' blockers are taken from,
    /// and its lines scanned, metres.
    pub reach_m: f64,
    /// Pixel side of the block's hidden maps, metres.
    pub px: f64,
    /// Spacing of the block's scan lines, metres, and the shortest run proposed.
    pub spacing_m: f64,
    pub min_len_m: f64,
    /// Exact certifications per block, and the certified pieces kept for its cells (the
    /// block's own greedy choice by what they hide from it). A block among more than
    /// `full_budget_blockers` blockers certifies fewer, down to half the budget
    /// ([`FarParams::certifications`]).
    pub budget: usize,
    pub keep: usize,
    pub full_budget_blockers: usize,
    /// A block of at least 2 cells a side whose square, grown by `reach_m` each way, meets at
    /// most this many blockers' boxes seeks its far field per quarter instead
    /// ([`super::far::Blocks::quarter`]); 0 never splits. A quarter's pieces are hidden from
    /// a quarter of the block only, so they hide more; its search costs about what a whole
    /// block's does, which among few blockers is little. On Tokyo centre (every block under
    /// 31,000) every cell's 200 m block culled 91.3% against 90.9% for 400 m blocks, for 29%
    /// more bake time; the generated 10^6 city's inner blocks (about 110,000) keep 400 m, where
    /// a block already costs 4 to 6 times as much (docs/SCALING.md).
    pub split_blockers: usize,
}

impl FarParams {
    /// The exact certifications a block reading `blockers` blockers may spend: `budget` up to
    /// `full_budget_blockers` of them, then in inverse proportion to their count, never below
    /// half of `budget` (rounded up). A far proposal's certification sweeps every blocker
    /// between the block and it, so its cost grows with the block's blockers: on Tokyo centre
    /// (about 30,000 a block) a kilometre of far proposal took 2.0 ms to certify, on the
    /// generated 10^6 city (about 112,000) 13 ms (docs/SCALING.md). The count alone decides,
    /// so a block's pieces stay a function of what it reads.
    pub fn certifications(&self, blockers: usize) -> usize {
        if blockers <= self.full_budget_blockers {
            return self.budget;
        }
        // `blockers` is above 0 here.
        let scaled =
            (self.budget as u128 * self.full_budget_blockers as u128 / blockers as u128) as usize;
        scaled.clamp(self.budget.div_ceil(2), self.budget)
    }
}

impl Default for FarParams {
    fn default() -> Self {
        FarParams {
            block_m: 400.0,
            reach_m: 3000.0,
            px: 12.0,
            spacing_m: 64.0,
            min_len_m: 120.0,
            budget: 24,
            keep: 12,
            full_budget_blockers: 40_000,
            split_blockers: 40_000,
        }
    }
}

/// The store's default budget, bytes per cell on average, every byte of the store counted
/// (header, scene section, index, block table, records): the budget the format was sized for
/// (docs/FORMAT.md section 10). A cell's VO cap follows from it ([`super::plan::Plan::vo_cap`]):
/// 8 VOs on a large grid, 7 on one with per-cell ground and rise bytes or a small grid, and
/// never more than `max_vos`; what a group of cells leaves under its caps goes to its cells'
/// best further VOs, up to `max_vos` ([`super::share`]).
pub const BYTES_PER_CELL: f64 = 52.0;

/// Occludees within this distance of a cell's centre (per axis) weigh its VOs, metres: far
/// enough for the far field of a large city (its VOs hide objects kilometres behind them),
/// and cheap, since a VO's hidden occludees are found whole subtrees at a time
/// ([`super::spans`]).
pub const WEIGH_M: f64 = 10_000.0;

/// How hard the long generator looks, from fast to tight: how many eyes sample the cell's
/// boundary, how many runs per direction are proposed, how many certifications a cell may run.
/// Every setting is as safe as the others (only the exact verifier decides what is stored);
/// they trade bake time for culled share (docs/RESULTS.md, "Speed against culling").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Effort {
    Fast,
    #[default]
    Default,
    Tight,
}

impl Effort {
    /// The parameters of this effort, over `p`.
    pub fn apply(self, p: &mut BakeParams) {
        let (eyes, per_direction, budget, far) = match self {
            Effort::Fast => (1, 1, 12, 12),
            Effort::Default => (3, 1, 25, 24),
            Effort::Tight => (7, 2, 60, 48),
        };
        p.map.edge_eyes = eyes;
        p.propose.per_direction = per_direction;
        p.budget = budget;
        p.far.budget = far;
    }
}

/// Which generator proposes a cell's VOs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Generator {
    /// Aggregate umbrae grown from seeds (paper 002, section 3; [`super::growth`]).
    Growth,
    /// Long hidden runs of lines from sampled from-region visibility ([`super::long`]).
    Long,
}

impl Default for BakeParams {
    fn default() -> Self {
        BakeParams {
            cell_size: 100.0,
            eye: (1.5, 2.0),
            slices: Slices::Auto,
            max_vos: MAX_VOS_PER_CELL,
            bytes_per_cell: BYTES_PER_CELL,
            region: None,
            walkable: None,
            search_m: SEARCH_M,
            grow: GrowParams {
                verify: false,
                ..GrowParams::default()
            },
            generator: Generator::Long,
            weigh_m: WEIGH_M,
            map: super::hidden::MapParams::default(),
            propose: super::propose::ProposeParams::default(),
            budget: 0,
            far: FarParams::default(),
        }
        .with_effort(Effort::Default)
    }
}

impl std::str::FromStr for Effort {
    type Err = String;
    fn from_str(s: &str) -> Result<Effort, String> {
        match s {
            "fast" => Ok(Effort::Fast),
            "default" => Ok(Effort::Default),
            "tight" => Ok(Effort::Tight),
            _ => Err(format!("expected fast, default or tight, got {s:?}")),
        }
    }
}

impl std::str::FromStr for Generator {
    type Err = String;
    fn from_str(s: &str) -> Result<Generator, String> {
        match s {
            "long" => Ok(Generator::Long),
            "growth" => Ok(Generator::Growth),
            _ => Err(format!("expected long or growth, got {s:?}")),
        }
    }
}

impl BakeParams {
    /// These parameters with the long generator's settings of `effort`.
    pub fn with_effort(mut self, effort: Effort) -> BakeParams {
        effort.apply(&mut self);
        self
    }

    /// These parameters with a cell's own search reaching `reach_m` metres past its sides
    /// (`vocc bake --reach`): its blockers (`search_m`), its hidden maps' half-side (the reach
    /// plus the default's margin of 124 m) and its scan lines (`propose.max_offset`). The maps
    /// keep their pixel count (256 per half-side), so their pixels grow with the reach: a VO
    /// kilometres away needs angular, not metric, precision. [`SEARCH_M`] (900 m) gives the
    /// defaults exactly. A longer reach finds VOs farther out, which close the wedges that the
    /// near VOs' ends leave open along streets seen end-on, for more bake time (README, "How far
    /// a cell reaches"). Checked by [`super::plan::Plan::new`] ([`MIN_REACH_M`] to
    /// [`MAX_REACH_M`]).
    pub fn with_reach(mut self, reach_m: f64) -> BakeParams {
        let d = super::hidden::MapParams::default();
        self.search_m = reach_m;
        self.map.half = reach_m + (d.half - SEARCH_M);
        self.map.px = d.px * self.map.half / d.half;
        self.propose.max_offset = reach_m;
        self
    }

    /// These parameters with the reach `vocc bake --reach auto` (the default) picks for `scene`
    /// ([`super::reach::auto_reach`]: 16 mean free paths of a sight line among its buildings,
    /// 900 to 1800 m; 900 in a low-rise scene): exactly
    /// [`with_reach`](Self::with_reach)`(`[`SEARCH_M`]`)` in a compact or low-rise city,
    /// further among free-standing towers or wide streets.
    pub fn with_auto_reach(self, scene: &crate::scene::Scene) -> BakeParams {
        self.with_reach(super::reach::auto_reach(scene))
    }

    /// These parameters with `reach` ([`Self::with_auto_reach`] or [`Self::with_reach`]).
    pub fn with_reach_for(self, reach: Reach, scene: &crate::scene::Scene) -> BakeParams {
        match reach {
            Reach::Auto => self.with_auto_reach(scene),
            Reach::Metres(m) => self.with_reach(m),
        }
    }

    /// These parameters with far-field blocks of about `block_m` metres a side, every one of
    /// them (`vocc bake --far-block M`; 0: no far field): no block splits into quarters, as the
    /// default's sparse blocks do ([`FarParams::split_blockers`]). A block's far VOs are
    /// certified hidden from the whole block, so a smaller block gets larger umbrae and culls
    /// more, for a search per block that costs about as much as a large block's: 1-cell blocks
    /// on Tokyo centre cull 0.6 points more than the default for about twice the bake time
    /// (README, "How far a cell reaches"). Checked by
    /// [`super::plan::Plan::new`] (0, or above 0 up to [`MAX_FAR_BLOCK_M`]).
    pub fn with_far_block(mut self, block_m: f64) -> BakeParams {
        self.far.block_m = block_m;
        self.far.split_blockers = 0;
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default reach is the defaults, field for field (so `--reach 900` bakes the default's
    /// bytes); another reach moves the search, the maps and the scan lines together and keeps
    /// the maps' pixel count.
    #[test]
    fn reach_900_is_the_default_and_a_reach_keeps_the_maps_pixel_count() {
        let d = BakeParams::default();
        let r = BakeParams::default().with_reach(SEARCH_M);
        assert_eq!(
            (r.search_m, r.map, r.propose),
            (d.search_m, d.map, d.propose)
        );
        let r = BakeParams::default().with_reach(2500.0);
        assert_eq!(r.search_m, 2500.0);
        assert_eq!(r.propose.max_offset, 2500.0);
        assert_eq!(r.map.half, 2624.0);
        assert_eq!(r.map.half / r.map.px, d.map.half / d.map.px);
        assert_eq!((r.map.edge_eyes, r.map.bins), (d.map.edge_eyes, d.map.bins));
        // The effort's settings are left alone, whichever comes first.
        let t = BakeParams::default()
            .with_effort(Effort::Tight)
            .with_reach(2500.0);
        assert_eq!((t.budget, t.map.edge_eyes), (60, 7));
    }

    /// A block's certifications: the whole budget among few blockers (Tokyo centre's blocks
    /// read about 30,000), half of it among as many as a block of the generated 10^6 city reads
    /// (about 112,000: the 12 of the bake before the budget grew), and in between in inverse
    /// proportion, never rising with the count.
    #[test]
    fn a_block_among_more_blockers_certifies_fewer_down_to_half() {
        let f = FarParams::default();
        assert_eq!(f.certifications(0), 24);
        assert_eq!(f.certifications(29_838), 24);
        assert_eq!(f.certifications(40_000), 24);
        assert_eq!(f.certifications(48_000), 20);
        assert_eq!(f.certifications(60_000), 16);
        assert_eq!(f.certifications(111_743), 12);
        assert_eq!(f.certifications(usize::MAX), 12);
        let mut last = usize::MAX;
        for n in (0..400_000).step_by(997) {
            let c = f.certifications(n);
            assert!((12..=24).contains(&c) && c <= last, "{n} blockers: {c}");
            last = c;
        }
        // Fast and tight scale the same way from their own budgets.
        let mut p = BakeParams::default();
        Effort::Fast.apply(&mut p);
        assert_eq!(
            (p.far.certifications(1), p.far.certifications(200_000)),
            (12, 6)
        );
        Effort::Tight.apply(&mut p);
        assert_eq!(
            (p.far.certifications(1), p.far.certifications(200_000)),
            (48, 24)
        );
    }
}
