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
//! Invariants: a block's pieces depend on the plan and the block alone (deterministic, whatever
//! cell asks first); each piece's quad, from the block's ground to its top, is hidden from the
//! block's whole eye range, which holds the eye range of each of its cells, so a cell's VO
//! standing on the cell's ground (no lower) up to a top no higher is a part of it.

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
use crate::runtime::grid::CellId;

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
}

/// The far pieces of block `block` ([`Plan::far_pieces`] caches them).
pub(super) fn block_pieces(plan: &Plan, block: usize) -> Vec<FarPiece> {
    let far = &plan.params.far;
    let bl = plan.blocks;
    let g = &plan.frame.grid;
    let (bi, bj) = (
        (block % bl.nx as usize) as u32,
        (block / bl.nx as usize) as u32,
    );
    let (i0, j0) = (bi * bl.side, bj * bl.side);
    let (i1, j1) = ((i0 + bl.side).min(g.nx), (j0 + bl.side).min(g.ny));
    if i0 >= i1 || j0 >= j1 {
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
    let rect = [
        g.min_x + i0 as f64 * g.cell_size,
        g.min_y + j0 as f64 * g.cell_size,
        g.min_x + i1 as f64 * g.cell_size,
        g.min_y + j1 as f64 * g.cell_size,
    ];
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
}
