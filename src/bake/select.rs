//! Selection: from a cell's proposals to at most `max_vos` stored VOs, most effective first
//! (docs/DESIGN.md section 4.4, the paper's Fig. 6), certifying only what it is about to pick.
//!
//! Input: candidates, each with the occludees it hides on its own (rule 3, the runtime's own
//! test, so a weight is what the runtime will cull) and the occludees' costs; a `refine` step
//! that turns a candidate into what it really is one stage later.
//! Output: the stored candidates in pick order, each with its gain when picked (the cost it
//! added to what the VOs before it hide: non-increasing along the order).
//! Rule: lazy greedy by weight. A candidate's weight is the summed cost of the occludees it
//! hides that no VO picked before hides. The heaviest candidate is popped; if its weight is stale
//! it goes back with the true one. A fresh candidate that is not yet stored is refined: a
//! proposal becomes its certified hidden pieces, a piece its quantized, re-checked VO, each with
//! the occludees it really hides, and they go back into the queue. A fresh stored VO is picked.
//! Picking stops at `max_vos`, or when the best gain falls below [`SELECT_MIN_GAIN_SHARE`] of what is
//! already hidden (five more bytes and a test per box at run time no longer pay).
//! Invariants: deterministic (ties broken by insertion order); only candidates that `refine`
//! returned as stored are ever picked; refining a candidate can only shrink what it hides, and
//! gains only shrink as VOs are picked, so the lazy queue picks what a full rescan would.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::spans::{Costs, Spans};

/// The long generator's selection stops when the best remaining gain is below this share of the
/// cost already hidden. The bytes are held by the store's budget (each cell's cap,
/// `Plan::vo_cap`, 8 VOs on Tokyo's grid, and its group's share, `bake/share.rs`), not by this
/// share: under the cap alone 0.002 stored 7.7 VOs a cell on Tokyo (47.5 bytes, 90.9% culled on
/// 20 cells), 0.001 7.9 (48.8 bytes, 90.9%), 0.004 7.1 (43.9 bytes, 90.6%).
pub const SELECT_MIN_GAIN_SHARE: f64 = 0.002;

/// How far a candidate has come.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Stage {
    /// Proposed, not yet certified.
    Proposed,
    /// Certified hidden, not yet quantized.
    Certified,
    /// Quantized and re-checked from its stored form: may be picked.
    Stored,
}

/// A candidate: its stage, its value, and what it hides.
#[derive(Clone, Debug)]
pub struct Candidate<T> {
    pub stage: Stage,
    pub value: T,
    pub hidden: Spans,
}

#[derive(PartialEq, Eq)]
struct Entry {
    gain: u64,
    /// Insertion order: earlier wins ties.
    idx: usize,
}

impl Ord for Entry {
    fn cmp(&self, o: &Self) -> Ordering {
        self.gain.cmp(&o.gain).then(o.idx.cmp(&self.idx))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// Lazy greedy selection (module header). `refine(c)` returns what candidate `c` (not yet
/// stored) becomes one stage later: any number of candidates, each at a later stage. At most
/// `budget` proposals are refined (certification is what a bake spends most on). Returns the
/// picks with their gains; the first `k` picks are what `max_vos = k` would give.
pub fn select<T>(
    candidates: Vec<Candidate<T>>,
    cost: &Costs,
    mut covered: Spans,
    max_vos: usize,
    budget: usize,
    mut refine: impl FnMut(&Candidate<T>) -> Vec<Candidate<T>>,
) -> Vec<(T, u64)> {
    let mut all: Vec<Option<Candidate<T>>> = Vec::new();
    let mut heap = BinaryHeap::new();
    let push =
        |c: Candidate<T>, all: &mut Vec<Option<Candidate<T>>>, heap: &mut BinaryHeap<Entry>| {
            let g = cost.of(&c.hidden);
            if g > 0 {
                heap.push(Entry {
                    gain: g,
                    idx: all.len(),
                });
                all.push(Some(c));
            }
        };
    for c in candidates {
        push(c, &mut all, &mut heap);
    }
    let mut hidden_cost: u64 = cost.of(&covered);
    let mut out = Vec::new();
    let mut spent = 0;
    while out.len() < max_vos {
        let Some(top) = heap.pop() else { break };
        let Some(c) = all[top.idx].as_ref() else {
            continue;
        };
        let g = cost.gain(&c.hidden, &covered);
        if g < top.gain {
            if g > 0 {
                heap.push(Entry {
                    gain: g,
                    idx: top.idx,
                });
            }
            continue;
        }
        if (g as f64) < SELECT_MIN_GAIN_SHARE * hidden_cost as f64 {
            break;
        }
        let c = all[top.idx].take().expect("checked above");
        if c.stage == Stage::Proposed {
            // At most `budget` proposals are certified; the rest are dropped.
            if spent == budget {
                continue;
            }
            spent += 1;
        }
        if c.stage == Stage::Stored {
            hidden_cost += g;
            covered = covered.union(&c.hidden);
            out.push((c.value, g));
            continue;
        }
        let rs = refine(&c);
        for r in rs {
            debug_assert!(r.stage > c.stage);
            push(r, &mut all, &mut heap);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stored(v: usize, hidden: Vec<u32>) -> Candidate<usize> {
        Candidate {
            stage: Stage::Stored,
            value: v,
            hidden: Spans::from_ids(&hidden),
        }
    }

    #[test]
    fn greedy_corrects_for_overlap_and_keeps_order() {
        // 0 and 1 overlap almost wholly; 2 is smaller but disjoint: after 0, 2 beats 1.
        let c = vec![
            stored(0, vec![0, 1, 2, 3]),
            stored(1, vec![0, 1, 2, 4]),
            stored(2, vec![5, 6]),
        ];
        let cost = Costs::new(&[10; 7]);
        // Gains: 4 x 10, then 2's two new ids, then 1's one new id.
        assert_eq!(
            select(c.clone(), &cost, Spans::new(), 10, 100, |_| vec![]),
            vec![(0, 40), (2, 20), (1, 10)]
        );
        assert_eq!(
            select(c, &cost, Spans::new(), 2, 100, |_| vec![]),
            vec![(0, 40), (2, 20)]
        );
    }

    #[test]
    fn a_refined_candidate_competes_with_what_it_really_hides() {
        // Proposal 0 looks best, but certifies into a piece hiding only {0}; 1 then wins.
        let c = vec![
            Candidate {
                stage: Stage::Proposed,
                value: 0,
                hidden: Spans::from_ids(&[0, 1, 2, 3]),
            },
            stored(1, vec![1, 2]),
        ];
        let cost = Costs::new(&[1; 4]);
        let mut refined = 0;
        let picked = select(c, &cost, Spans::new(), 10, 100, |p| {
            refined += 1;
            assert_eq!(p.value, 0);
            vec![stored(10, vec![0]), stored(11, vec![3])]
        });
        assert_eq!(refined, 1);
        assert_eq!(picked, vec![(1, 2), (10, 1), (11, 1)]);
    }

    #[test]
    fn diminishing_gain_stops_the_picks() {
        let c = vec![stored(0, vec![0]), stored(1, vec![1])];
        // 1 more after 1000 is below SELECT_MIN_GAIN_SHARE (0.4%); 5 more is above it.
        let cost = Costs::new(&[1000, 1]);
        assert_eq!(
            select(c.clone(), &cost, Spans::new(), 10, 100, |_| vec![]),
            vec![(0, 1000)]
        );
        let cost = Costs::new(&[1000, 5]);
        assert_eq!(
            select(c, &cost, Spans::new(), 10, 100, |_| vec![]),
            vec![(0, 1000), (1, 5)]
        );
    }
}
