//! Decimation: from the dense VO set of a cell to at most `max_vos`, most effective first
//! (docs/DESIGN.md section 4.4, the paper's Fig. 6).
//!
//! Input: candidate VOs with the occludees each hides on its own (rule 3, the runtime's own
//! test, so the weight is what the runtime will cull), the occludees' costs, and an `accept`
//! step that quantizes and verifies a VO (it may shrink it, or refuse it).
//! Output: the accepted VOs in pick order.
//! Rule: greedy by weight. The weight of a candidate is the summed cost (triangles) of the
//! occludees it hides that no VO picked before hides (the overlap correction). Pick the heaviest,
//! pass it through `accept`, and recompute its gain from what the accepted VO really hides. Stop
//! at `max_vos`, or when the best gain falls below [`DECIMATE_MIN_GAIN_SHARE`] of what is already hidden
//! (the gain no longer pays for five more bytes and a test per box at run time).
//! Invariants: deterministic (ties broken by candidate order); gains only shrink as VOs are
//! picked, so a lazy max-heap gives the same picks as a full rescan.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use crate::bake::spans::{Costs, Spans};

/// The growth's decimation stops when the best remaining gain is below this share (1%) of the
/// occludee cost already hidden. Not the long generator's [`crate::bake::select::SELECT_MIN_GAIN_SHARE`]
/// (0.4%): the growth's dense sets hold many near-duplicates whose small gains it drops.
pub const DECIMATE_MIN_GAIN_SHARE: f64 = 0.01;

#[derive(PartialEq, Eq)]
struct Entry {
    gain: u64,
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

/// Greedy decimation. `hidden[i]` is what candidate `i` hides on its own;
/// `accept(i)` quantizes and verifies candidate `i`, returning the stored form and what it really
/// hides, or `None` to drop it. Returns the accepted values in pick order.
pub fn greedy<T>(
    hidden: &[Spans],
    cost: &Costs,
    max_vos: usize,
    mut accept: impl FnMut(usize) -> Option<(T, Spans)>,
) -> Vec<T> {
    let mut heap: BinaryHeap<Entry> = hidden
        .iter()
        .enumerate()
        .map(|(idx, h)| Entry {
            gain: cost.of(h),
            idx,
        })
        .filter(|e| e.gain > 0)
        .collect();
    let mut covered = Spans::new();
    let mut hidden_cost: u64 = 0;
    let mut out = Vec::new();
    let mut tried = vec![false; hidden.len()];
    while out.len() < max_vos {
        let Some(top) = heap.pop() else { break };
        let g = cost.gain(&hidden[top.idx], &covered);
        if g < top.gain {
            // Stale: re-queue with the true gain.
            if g > 0 {
                heap.push(Entry {
                    gain: g,
                    idx: top.idx,
                });
            }
            continue;
        }
        if (g as f64) < DECIMATE_MIN_GAIN_SHARE * hidden_cost as f64 {
            break;
        }
        if tried[top.idx] {
            continue;
        }
        tried[top.idx] = true;
        let Some((value, real)) = accept(top.idx) else {
            continue;
        };
        let rg = cost.gain(&real, &covered);
        if rg == 0 || (rg as f64) < DECIMATE_MIN_GAIN_SHARE * hidden_cost as f64 {
            continue;
        }
        hidden_cost += rg;
        covered = covered.union(&real);
        out.push(value);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn greedy_corrects_for_overlap_and_keeps_order() {
        // 0 and 1 overlap almost wholly; 2 is smaller but disjoint: after 0, 2 beats 1.
        let hidden: Vec<Spans> = [&[0, 1, 2, 3][..], &[0, 1, 2, 4], &[5, 6]]
            .map(Spans::from_ids)
            .to_vec();
        let cost = Costs::new(&[10; 7]);
        let picked = greedy(&hidden, &cost, 10, |i| Some((i, hidden[i].clone())));
        assert_eq!(picked, vec![0, 2, 1]);
        assert_eq!(
            greedy(&hidden, &cost, 2, |i| Some((i, hidden[i].clone()))),
            vec![0, 2]
        );
    }

    #[test]
    fn a_refused_candidate_gives_way_to_the_next() {
        let hidden: Vec<Spans> = [&[0, 1, 2][..], &[0, 1], &[3]]
            .map(Spans::from_ids)
            .to_vec();
        let cost = Costs::new(&[1; 4]);
        let picked = greedy(&hidden, &cost, 10, |i| {
            (i != 0).then(|| (i, hidden[i].clone()))
        });
        assert_eq!(picked, vec![1, 2]);
    }

    #[test]
    fn diminishing_gain_stops_the_picks() {
        let hidden: Vec<Spans> = [&[0][..], &[1]].map(Spans::from_ids).to_vec();
        let cost = Costs::new(&[1000, 5]);
        let picked = greedy(&hidden, &cost, 10, |i| Some((i, hidden[i].clone())));
        assert_eq!(picked, vec![0]);
    }
}
