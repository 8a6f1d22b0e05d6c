//! Sharing the store's byte budget within groups of cells: each cell keeps what its own cap
//! allows ([`Plan::vo_cap`]), and the bytes its group leaves unused pay for the group's best
//! further picks.
//!
//! Input: the plan and the cells a bake baked, each record with its greedy's gains
//! ([`CellStats::gains`]; the long generator picks up to `max_vos`, [`Plan::vo_max`]).
//! Output: the same cells, each record cut to the VOs it keeps (its stats' `gains` and
//! `unquantized` cut alike).
//! Rule: the cells are grouped in squares of [`GROUP_SIDE`] x [`GROUP_SIDE`] cells of the grid.
//! A group may take [`Plan::cell_allowance`] bytes (`B - F / N`) for each of its cells the bake
//! holds. Each cell first keeps its first `min(n, cap)` VOs; what the group's allowance has left
//! then pays for further VOs, 6 bytes each, taken by their gains, highest first (ties: the lower
//! cell id, then the earlier VO), each cell's in its stored order, while 6 bytes are left.
//! Invariants:
//! - a cell keeps a prefix of its greedy's picks: every stored VO was certified on its own, so
//!   any prefix is sound, and the first `k` picks are what a cap of `k` gives ([`super::select`]);
//! - a group's records take at most its allowance (or, where the caps alone exceed it, a budget
//!   below one VO a cell, its cells' caps), so the store holds `B N` bytes at most, as before;
//! - a cell's record depends only on the cells of its group baked with it: shards and
//!   incremental rebakes go by whole groups ([`super::job`]) and give a full bake's bytes; a
//!   region or a list of cells that cuts a group shares among the group's cells it holds.

use std::collections::BTreeMap;

use super::plan::{CellBake, Plan};
use crate::runtime::format::{CellRecord, VO_BYTES};
use crate::runtime::frame::Frame;
use crate::runtime::grid::{CellId, GridDescriptor};

/// Cells per side of a group that shares its bytes. Simulated on every Tokyo centre cell
/// (docs/SCALING.md, "The byte budget shared"): groups of 2 x 2, 4 x 4 and 8 x 8 cells and the
/// whole grid add 0.10, 0.29, 0.33 and 0.42 points of culled share; 4 x 4 takes most of it and
/// keeps an edit's reach and a region's cut groups small.
pub const GROUP_SIDE: u32 = 4;

/// The group of cell `id` on `grid`: row-major over squares of [`GROUP_SIDE`] cells.
pub fn group_of(grid: &GridDescriptor, id: CellId) -> u64 {
    let (i, j) = (id % grid.nx, id / grid.nx);
    let across = grid.nx.div_ceil(GROUP_SIDE) as u64;
    (j / GROUP_SIDE) as u64 * across + (i / GROUP_SIDE) as u64
}

/// The bytes a record takes in a store of `frame` (docs/FORMAT.md 5.3 and 5.5,
/// [`CellRecord::stored_len`]).
pub fn record_bytes(frame: &Frame, rec: &CellRecord) -> usize {
    rec.stored_len(frame.per_cell_ground()) as usize
}

/// A record's bytes with `vos` of its VOs, given its bytes besides the VOs when it has some
/// (`header`: index, ground and rise bytes): 1 (the index byte alone) without VOs.
fn bytes_with(header: usize, vos: usize) -> usize {
    if vos == 0 {
        1
    } else {
        header + VO_BYTES * vos
    }
}

/// One cell of a group as [`allot`] sees it.
#[derive(Clone, Debug)]
pub struct Member<'a> {
    /// VOs its greedy picked.
    pub vos: usize,
    /// Its record's bytes besides the VOs when it has some (index, ground, rise).
    pub header: usize,
    /// What it keeps whatever the group does ([`Plan::vo_cap`]).
    pub cap: usize,
    /// Its picks' gains, in order (fewer than `vos`: the rest are never taken beyond the cap).
    pub gains: &'a [u64],
}

/// How many VOs each member keeps when the group may take `allowance` bytes per member (module
/// header). Members in ascending cell id order.
pub fn allot(allowance: f64, members: &[Member]) -> Vec<usize> {
    let mut keep: Vec<usize> = members.iter().map(|m| m.vos.min(m.cap)).collect();
    if !allowance.is_finite() {
        return members.iter().map(|m| m.vos).collect();
    }
    let used: usize = members
        .iter()
        .zip(&keep)
        .map(|(m, &k)| bytes_with(m.header, k))
        .sum();
    let total = allowance * members.len() as f64;
    // Bytes left, with a margin far below a byte against the rounding of `total`.
    let mut left = total - used as f64 - 1e-9 * total.abs();
    while left >= VO_BYTES as f64 {
        let mut best: Option<(u64, usize)> = None;
        for (i, m) in members.iter().enumerate() {
            if keep[i] == 0 || keep[i] >= m.vos {
                continue;
            }
            if let Some(&g) = m.gains.get(keep[i]) {
                if best.is_none_or(|(bg, _)| g > bg) {
                    best = Some((g, i));
                }
            }
        }
        let Some((_, i)) = best else { break };
        keep[i] += 1;
        left -= VO_BYTES as f64;
    }
    keep
}

/// Cuts each baked cell's record to what its group's share keeps (module header). With no
/// budget (`--bytes-per-cell none`) every cell keeps its picks.
pub fn share_bytes(plan: &Plan, baked: &mut [CellBake]) {
    let allowance = plan.cell_allowance();
    let f = &plan.frame;
    let mut groups: BTreeMap<u64, Vec<usize>> = BTreeMap::new();
    for (k, c) in baked.iter().enumerate() {
        groups.entry(group_of(&f.grid, c.id)).or_default().push(k);
    }
    for mut cells in groups.into_values() {
        cells.sort_by_key(|&k| baked[k].id);
        let members: Vec<Member> = cells
            .iter()
            .map(|&k| {
                let c = &baked[k];
                let vos = c.record.vos().len();
                Member {
                    vos,
                    // Its bytes besides the VOs (unused for a cell without VOs).
                    header: record_bytes(f, &c.record) - VO_BYTES * vos,
                    cap: plan.vo_cap(c.id),
                    gains: &c.stats.gains,
                }
            })
            .collect();
        let keep = allot(allowance, &members);
        for (&k, n) in cells.iter().zip(keep) {
            let c = &mut baked[k];
            if n < c.record.vos().len() {
                let (ground, rise) = (c.record.ground(), c.record.rise());
                c.record = CellRecord::new(ground, &c.record.vos()[..n])
                    .expect("a prefix of a valid list")
                    .with_rise(rise);
                c.stats.gains.truncate(n);
                c.stats.unquantized.truncate(n);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn member(vos: usize, cap: usize, gains: &[u64]) -> Member<'_> {
        Member {
            vos,
            header: 1,
            cap,
            gains,
        }
    }

    #[test]
    fn the_bytes_a_group_leaves_go_to_its_best_further_picks_in_order() {
        // Three cells, cap 2 each, 15.2 bytes a cell (45.6 in all). Kept by the caps:
        // 13 + 13 + 1 (an empty cell) = 27; 18.6 left: three more VOs. Each cell's next pick
        // competes: a's 70, b's 65, b's 64 beat a's 60 (b's order is kept as picked).
        let a = [90, 80, 70, 60, 5];
        let b = [100, 50, 65, 64];
        let m = [member(5, 2, &a), member(4, 2, &b), member(0, 2, &[])];
        assert_eq!(allot(15.2, &m), vec![3, 4, 0]);
        // 44.7 in all: 17.7 left, two more VOs, the two best.
        assert_eq!(allot(14.9, &m), vec![3, 3, 0]);
        // An exact fit is refused (the margin against rounding errs low): 45 in all, 18 left.
        assert_eq!(allot(15.0, &m), vec![3, 3, 0]);
        // No budget: every pick.
        assert_eq!(allot(f64::INFINITY, &m), vec![5, 4, 0]);
        // A budget below the caps: the caps still hold, nothing more.
        assert_eq!(allot(2.0, &m), vec![2, 2, 0]);
    }

    #[test]
    fn ties_go_to_the_lower_cell_and_missing_gains_stop_a_cell() {
        let g = [10, 10, 10];
        // 2 cells, cap 1: 7 + 7 bytes kept; 7 left at 10.5 a cell: one more, the first cell's.
        assert_eq!(
            allot(10.5, &[member(3, 1, &g), member(3, 1, &g)]),
            vec![2, 1]
        );
        // A cell without gains (the growth generator) keeps its cap whatever is left.
        assert_eq!(allot(100.0, &[member(3, 1, &[])]), vec![1]);
    }

    #[test]
    fn a_group_stays_within_its_allowance_and_keeps_prefixes() {
        // Random groups: what they keep is within the allowance (or the caps), each between
        // its cap and its picks, and no further pick that would fit is left while a cell has one.
        let mut r = crate::testutil::uniform(11);
        let mut below = |n: u64| r(0.0, n as f64) as u64;
        for _ in 0..2000 {
            let n = 1 + below(16) as usize;
            let gains: Vec<Vec<u64>> = (0..n)
                .map(|_| {
                    let mut g: Vec<u64> = (0..below(11)).map(|_| below(1000)).collect();
                    g.sort_unstable_by(|a, b| b.cmp(a));
                    g
                })
                .collect();
            let members: Vec<Member> = gains
                .iter()
                .map(|g| Member {
                    vos: g.len(),
                    header: 1 + below(3) as usize,
                    cap: 1 + below(9) as usize,
                    gains: g,
                })
                .collect();
            let allowance = 20.0 + below(40) as f64 + 0.5;
            let keep = allot(allowance, &members);
            let bytes: usize = members
                .iter()
                .zip(&keep)
                .map(|(m, &k)| bytes_with(m.header, k))
                .sum();
            let caps: usize = members
                .iter()
                .map(|m| bytes_with(m.header, m.vos.min(m.cap)))
                .sum();
            let total = allowance * n as f64;
            assert!(
                bytes as f64 <= total.max(caps as f64),
                "{bytes} bytes over {allowance} x {n}"
            );
            for (m, &k) in members.iter().zip(&keep) {
                assert!(m.vos.min(m.cap) <= k && k <= m.vos);
            }
            let open = members.iter().zip(&keep).any(|(m, &k)| k > 0 && k < m.vos);
            if open {
                // (An exact fit may be refused: the margin against rounding errs low.)
                assert!(
                    bytes as f64 + VO_BYTES as f64 > total * (1.0 - 1e-9),
                    "6 more bytes fit ({bytes} of {total}) and a cell has a pick left"
                );
            }
        }
    }
}
