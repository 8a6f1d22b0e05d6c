//! The far field: long VOs sought once per block of cells, kilometres out, certified hidden from
//! the whole block, and offered to each of its cells.
//!
//! Input: the [`Plan`] and a block (a square of whole cells, [`super::params::FarParams`]).
//! Output: the block's [`FarPiece`]s: segments with a top, each certified hidden (rule 1 and
//! rule 2, the exact verifier) from every eye of every cell of the block, chosen greedily by the
//! occludees they hide from it.
//! Method: the long generator's own stages ([`super::long`]) on the block as one region: its
//! ground is the lowest ground of its cells (the VOs' bottom), its eyes reach from that ground's
//! lowest eye to the highest ground's highest eye; its blockers are taken from `reach_m` around
//! it; its hidden maps and scan lines are coarser (`px`, `spacing_m`), as a far VO needs
//! angular, not metric, precision. A cell takes a piece through
//! [`super::certify::Certifier::store_far`], which quantizes it for the cell and keeps only grid
//! segments lying in the piece's umbra seen from the cell (exact).
//! Why per block: a far VO hides what lies behind it from every neighbouring cell alike, and
//! certifying a kilometre of it costs as much as the cell's own search; sought per block its
//! cost is shared by the block's cells, and the cells' own search keeps its near reach.
//! Sparse blocks split: a block among few blockers ([`super::params::FarParams::split_blockers`])
//! seeks its far field per quarter instead ([`Blocks::quarter`]): a smaller region sees more of
//! the scene hidden from all of it, and there the search costs little. Whether a block splits
//! depends on the blockers around it alone ([`super::plan::Plan::block_splits`]).
//! Invariants: a block's (or quarter's) pieces depend on the plan and its cells alone
//! (deterministic, whatever cell asks first); each piece's quad, from the region's ground to its
//! top, is hidden from the region's whole eye range, which holds the eye range of each of its
//! cells, so a cell's VO standing on the cell's ground (no lower) up to a top no higher is a part
//! of it.

use glam::DVec2;

use super::cell::CellSetup;
use super::certify::{CertifyStats, Piece};
use super::hidden::MapParams;
use super::long::{certifier, proposals};
use super::plan::{CellStats, Plan};
use super::propose::ProposeParams;
use super::select::{select, Candidate, Stage};
use super::spans::Spans;
use crate::geom::verify::BlockerIndex;
use crate::runtime::frame::{CellGround, CellView, VoGeom};
use crate::runtime::grid::{CellId, GridDescriptor};

/// A segment certified hidden from a whole block, standing from `bottom` (the block's lowest
/// ground) up to `top` (metres, local frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FarPiece {
    pub a: DVec2,
    pub b: DVec2,
    pub bottom: f64,
    pub top: f64,
}

/// The blocks of a grid: squares of `side` cells, row-major from the grid's minimum corner
/// (the last ones of a row or column may hold fewer cells).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Blocks {
    /// Cells per block side; 0: no blocks (the far field is off).
    pub side: u32,
    pub nx: u32,
    pub ny: u32,
}

impl Blocks {
    /// The blocks of a grid of `nx` by `ny` cells of `cell_size` metres, about `block_m` metres
    /// on a side.
    pub fn new(nx: u32, ny: u32, cell_size: f64, block_m: f64) -> Blocks {
        if !(block_m > 0.0) {
            return Blocks {
                side: 0,
                nx: 0,
                ny: 0,
            };
        }
        let side = (block_m / cell_size).round().clamp(1.0, 64.0) as u32;
        Blocks {
            side,
            nx: nx.div_ceil(side),
            ny: ny.div_ceil(side),
        }
    }

    pub fn count(&self) -> usize {
        self.nx as usize * self.ny as usize
    }

    /// The block of cell `(i, j)`.
    pub fn of(&self, i: u32, j: u32) -> usize {
        (j / self.side) as usize * self.nx as usize + (i / self.side) as usize
    }

    /// The cells of block `block` on a grid of `gnx` by `gny` cells, as half-open index ranges
    /// `[i0, i1) x [j0, j1)` (the last blocks of a row or column may be cut by the grid).
    pub fn cells(&self, block: usize, gnx: u32, gny: u32) -> CellRange {
        if self.side == 0 || self.nx == 0 {
            return CellRange::default();
        }
        let (bi, bj) = (
            (block % self.nx as usize) as u32,
            (block / self.nx as usize) as u32,
        );
        let (i0, j0) = (bi * self.side, bj * self.side);
        CellRange {
            i0,
            j0,
            i1: (i0 + self.side).min(gnx),
            j1: (j0 + self.side).min(gny),
        }
    }

    /// Whether blocks can split into quarters: at least 2 cells a side.
    pub fn can_split(&self) -> bool {
        self.side >= 2
    }

    /// The quarter of block `cells` (its cell range, [`Self::cells`]) that holds cell `(i, j)`,
    /// and its number `0..4` (row-major: south-west, south-east, north-west, north-east): the
    /// block cut after its first `ceil(side / 2)` cells each way, the cut parts clipped to the
    /// grid's.
    pub fn quarter(&self, cells: CellRange, i: u32, j: u32) -> (usize, CellRange) {
        let h = self.side.div_ceil(2);
        let (xi, yj) = (cells.i0 + h, cells.j0 + h);
        let (east, north) = (i >= xi, j >= yj);
        let range = CellRange {
            i0: if east { xi } else { cells.i0 },
            i1: if east { cells.i1 } else { xi.min(cells.i1) },
            j0: if north { yj } else { cells.j0 },
            j1: if north { cells.j1 } else { yj.min(cells.j1) },
        };
        (east as usize + 2 * north as usize, range)
    }
}

/// Cells `[i0, i1) x [j0, j1)` of a grid: a block or a quarter of one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CellRange {
    pub i0: u32,
    pub j0: u32,
    pub i1: u32,
    pub j1: u32,
}

impl CellRange {
    pub fn is_empty(&self) -> bool {
        self.i0 >= self.i1 || self.j0 >= self.j1
    }

    /// The region's rectangle on grid `g`, `[x0, y0, x1, y1]` (local frame).
    pub fn rect(&self, g: &GridDescriptor) -> [f64; 4] {
        [
            g.min_x + self.i0 as f64 * g.cell_size,
            g.min_y + self.j0 as f64 * g.cell_size,
            g.min_x + self.i1 as f64 * g.cell_size,
            g.min_y + self.j1 as f64 * g.cell_size,
        ]
    }
}

/// The far pieces of the region of cells `cells`, a block or a quarter of one
/// ([`Plan::far_pieces`] caches them).
pub(super) fn block_pieces(plan: &Plan, cells: CellRange) -> Vec<FarPiece> {
    let far = &plan.params.far;
    let g = &plan.frame.grid;
    let CellRange { i0, j0, i1, j1 } = cells;
    if cells.is_empty() {
        return Vec::new();
    }
    // The block's ground: the lowest of its cells' grounds, and the highest of their eyes'.
    let mut lo = u8::MAX;
    let mut hi = 0u8;
    for j in j0..j1 {
        for i in i0..i1 {
            let id = j * g.nx + i;
            if !plan.eyes_fit(id) {
                continue;
            }
            let s = plan.stand(id);
            lo = lo.min(s.level);
            hi = hi.max(s.level.saturating_add(s.rise));
        }
    }
    if lo > hi {
        return Vec::new();
    }
    let f = &plan.frame;
    let rect = cells.rect(g);
    let poly = [
        DVec2::new(rect[0], rect[1]),
        DVec2::new(rect[2], rect[1]),
        DVec2::new(rect[2], rect[3]),
        DVec2::new(rect[0], rect[3]),
    ];
    let view = CellView {
        rect,
        e0: f.ground_z(lo) + f.eye_lo,
        e1: f.ground_z(hi) + f.eye_hi,
    };
    // Named by its first cell, which it is not: the block is never quantized.
    let first: CellId = j0 * g.nx + i0;
    let ground = CellGround {
        level: lo,
        rise: hi - lo,
    };
    let bottom = f.ground_z(lo);
    let Ok(setup) = CellSetup::of_region(plan, first, poly, ground, view, bottom, far.reach_m)
    else {
        return Vec::new();
    };
    let half = far.reach_m + 0.5 * (rect[2] - rect[0]).max(rect[3] - rect[1]);
    let map = MapParams {
        px: far.px,
        half,
        ..plan.params.map
    };
    let propose = ProposeParams {
        spacing: far.spacing_m,
        max_offset: half,
        min_len: far.min_len_m,
        ..plan.params.propose
    };
    let mut stats = CellStats::default();
    let mut t = std::time::Instant::now();
    let (cands, hidden) = proposals(
        plan,
        &setup,
        &map,
        &propose,
        plan.params.weigh_m,
        &mut t,
        &mut stats,
        &mut |_| {},
    );
    let index = BlockerIndex::new(
        setup
            .near
            .iter()
            .map(|&i| plan.set.polys[i as usize].as_slice()),
    );
    let certifier = certifier(plan, &setup, &index);
    let radius = plan.params.weigh_m;
    let top = |level: u8| f.vo_top(view.e1, level);
    let geom = |p: &Piece| VoGeom {
        a: p.a.to_array(),
        b: p.b.to_array(),
        g: setup.g,
        h: top(p.level),
    };
    let start: Vec<Candidate<Piece>> = cands
        .iter()
        .zip(hidden)
        .map(|(&(level, a, b), hidden)| Candidate {
            stage: Stage::Proposed,
            value: Piece {
                level,
                a,
                b,
                used: Vec::new(),
            },
            hidden,
        })
        .collect();
    let mut cs = CertifyStats::default();
    // The block's own greedy: a proposal becomes its certified pieces, a piece is final.
    let picked = select(
        start,
        &plan.occludees.costs,
        Spans::new(),
        far.keep,
        far.certifications(setup.near.len()),
        |c| match c.stage {
            Stage::Proposed => certifier
                .pieces(c.value.level, c.value.a, c.value.b, &mut cs)
                .into_iter()
                .map(|p| Candidate {
                    stage: Stage::Certified,
                    hidden: plan.occludees.hidden(&view, &geom(&p), radius),
                    value: p,
                })
                .collect(),
            // Raised as high as its blockers support it for this very segment (a far piece's
            // height is what hides the towers behind it).
            Stage::Certified => {
                let p = &c.value;
                let level = certifier.raise(p.level, p.a, p.b, &p.used, &mut cs);
                let p = Piece { level, ..p.clone() };
                vec![Candidate {
                    stage: Stage::Stored,
                    hidden: plan.occludees.hidden(&view, &geom(&p), radius),
                    value: p,
                }]
            }
            Stage::Stored => Vec::new(),
        },
    );
    picked
        .into_iter()
        .map(|(p, _)| FarPiece {
            a: p.a,
            b: p.b,
            bottom,
            top: top(p.level),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_tile_the_grid_with_whole_cells() {
        let b = Blocks::new(19, 12, 100.0, 400.0);
        assert_eq!((b.side, b.nx, b.ny), (4, 5, 3));
        assert_eq!(b.of(0, 0), 0);
        assert_eq!(b.of(3, 3), 0);
        assert_eq!(b.of(4, 3), 1);
        assert_eq!(b.of(18, 11), 14);
        assert_eq!(b.count(), 15);
        // Cells larger than a block: one cell each.
        let b = Blocks::new(3, 2, 500.0, 400.0);
        assert_eq!((b.side, b.nx, b.ny), (1, 3, 2));
        // Off.
        assert_eq!(Blocks::new(3, 2, 100.0, 0.0).side, 0);
    }

    #[test]
    fn a_block_s_quarters_tile_its_cells_clipped_to_the_grid() {
        // 4-cell blocks on a 6 x 5 grid: block 1 is cut to cells 4..6 by 0..4.
        let b = Blocks::new(6, 5, 100.0, 400.0);
        let r = |i0, j0, i1, j1| CellRange { i0, j0, i1, j1 };
        assert_eq!(b.cells(0, 6, 5), r(0, 0, 4, 4));
        assert_eq!(b.cells(1, 6, 5), r(4, 0, 6, 4));
        assert_eq!(b.cells(3, 6, 5), r(4, 4, 6, 5));
        let whole = b.cells(0, 6, 5);
        assert_eq!(b.quarter(whole, 0, 0), (0, r(0, 0, 2, 2)));
        assert_eq!(b.quarter(whole, 3, 1), (1, r(2, 0, 4, 2)));
        assert_eq!(b.quarter(whole, 1, 2), (2, r(0, 2, 2, 4)));
        assert_eq!(b.quarter(whole, 3, 3), (3, r(2, 2, 4, 4)));
        // Every cell of a cut block lies in exactly the quarter it names, and the quarters
        // that hold cells cover the block.
        for block in 0..b.count() {
            let c = b.cells(block, 6, 5);
            let mut cells = 0;
            for q in 0..4 {
                let mut seen = None;
                for j in c.j0..c.j1 {
                    for i in c.i0..c.i1 {
                        let (k, range) = b.quarter(c, i, j);
                        if k == q {
                            assert!((range.i0..range.i1).contains(&i));
                            assert!((range.j0..range.j1).contains(&j));
                            assert!(seen.is_none_or(|s| s == range), "one range per quarter");
                            seen = Some(range);
                            cells += 1;
                        }
                    }
                }
                if let Some(s) = seen {
                    assert!(!s.is_empty());
                }
            }
            assert_eq!(cells, (c.i1 - c.i0) * (c.j1 - c.j0));
        }
        // An odd side: the first part takes the larger half.
        let b = Blocks::new(3, 3, 100.0, 300.0);
        assert_eq!(b.quarter(b.cells(0, 3, 3), 1, 1), (0, r(0, 0, 2, 2)));
        assert_eq!(b.quarter(b.cells(0, 3, 3), 2, 0), (1, r(2, 0, 3, 2)));
        // One-cell blocks do not split.
        assert!(!Blocks::new(3, 3, 100.0, 100.0).can_split());
    }

    /// A block splits when the blockers around it (its square grown by the far field's reach)
    /// number at most `split_blockers`; a fixed side (`--far-block M`) never splits; a cell's
    /// far pieces then come from its quarter.
    #[test]
    fn a_block_splits_where_few_blockers_lie_around_it() {
        use crate::bake::params::BakeParams;
        // 30 m squares every 40 m over 1,200 by 800 m, 20 m tall: 600 blockers.
        let items: Vec<([f64; 3], f64, f64)> = (0..600)
            .map(|k| {
                (
                    [(k % 30) as f64 * 40.0, (k / 30) as f64 * 40.0, 30.0],
                    0.0,
                    20.0,
                )
            })
            .collect();
        let scene = crate::testutil::squares(&items);
        let with = |split: usize| {
            let mut p = BakeParams {
                search_m: 300.0,
                weigh_m: 1500.0,
                ..BakeParams::default()
            };
            p.far.split_blockers = split;
            p
        };
        let plan = Plan::new(&scene, with(600)).unwrap();
        assert!(plan.blocks.count() > 1);
        assert!((0..plan.blocks.count()).all(|b| plan.block_splits(b)));
        let plan = Plan::new(&scene, with(599)).unwrap();
        assert!((0..plan.blocks.count()).all(|b| !plan.block_splits(b)));
        let plan = Plan::new(&scene, with(600).with_far_block(400.0)).unwrap();
        assert!((0..plan.blocks.count()).all(|b| !plan.block_splits(b)));
        // Split: two cells of one quarter share their pieces, which the quarter's own search
        // gives; cells of another quarter get that quarter's.
        let plan = Plan::new(&scene, with(600)).unwrap();
        let g = &plan.frame.grid;
        let cells = plan.blocks.cells(0, g.nx, g.ny);
        let (_, q) = plan.blocks.quarter(cells, 0, 0);
        assert!(!plan.far_pieces(0).is_empty());
        assert_eq!(plan.far_pieces(0), block_pieces(&plan, q).as_slice());
        assert_eq!(plan.far_pieces(1), plan.far_pieces(0));
        let (_, q2) = plan.blocks.quarter(cells, 2, 0);
        assert_ne!(q, q2);
        assert_eq!(plan.far_pieces(2), block_pieces(&plan, q2).as_slice());
    }
}
