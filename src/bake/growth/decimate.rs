//! Decimation: from the dense VO set of a cell to at most `max_vos`, most effective first
//! (DESIGN.md section 4.4, the paper's Fig. 6).
//!
//! Input: candidate VOs with the occludees each hides on its own (rule 3, the runtime's own
//! test, so the weight is what the runtime will cull), the occludees' costs, and an `accept`
//! step that quantizes and verifies a VO (it may shrink it, or refuse it).
//! Output: the accepted VOs in pick order.
//! Rule: greedy by weight. The weight of a candidate is the summed cost (triangles) of the
//! occludees it hides that no VO picked before hides (the overlap correction). Pick the heaviest,
//! pass it through `accept`, and recompute its gain from what the accepted VO really hides. Stop
//! at `max_vos`, or when the best gain falls below [`MIN_GAIN_SHARE`] of what is already hidden
//! (the gain no longer pays for five more bytes and a test per box at run time).
//! Invariants: deterministic (ties broken by candidate order); gains only shrink as VOs are
//! picked, so a lazy max-heap gives the same picks as a full rescan.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Stop when the best remaining gain is below this share of the cost already hidden.
pub const MIN_GAIN_SHARE: f64 = 0.01;

/// Sum of the costs of `ids` not in `covered` (both ascending).
fn gain(ids: &[u32], covered: &[u32], cost: &[u64]) -> u64 {
    ids.iter()
        .filter(|i| covered.binary_search(i).is_err())
        .map(|&i| cost[i as usize])
        .sum()
}

fn merge(covered: &mut Vec<u32>, ids: &[u32]) {
    covered.extend_from_slice(ids);
    covered.sort_unstable();
    covered.dedup();
}

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

/// Greedy decimation. `hidden[i]` is what candidate `i` hides on its own (ascending ids);
/// `accept(i)` quantizes and verifies candidate `i`, returning the stored form and what it really
/// hides, or `None` to drop it. Returns the accepted values in pick order.
pub fn greedy<T>(
    hidden: &[Vec<u32>],
    cost: &[u64],
    max_vos: usize,
    mut accept: impl FnMut(usize) -> Option<(T, Vec<u32>)>,
) -> Vec<T> {
    let mut heap: BinaryHeap<Entry> = hidden
        .iter()
        .enumerate()
        .map(|(idx, h)| Entry {
            gain: gain(h, &[], cost),
            idx,
        })
        .filter(|e| e.gain > 0)
        .collect();
    let mut covered: Vec<u32> = Vec::new();
    let mut hidden_cost: u64 = 0;
    let mut out = Vec::new();
    let mut tried = vec![false; hidden.len()];
    while out.len() < max_vos {
        let Some(top) = heap.pop() else { break };
        let g = gain(&hidden[top.idx], &covered, cost);
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
        if (g as f64) < MIN_GAIN_SHARE * hidden_cost as f64 {
            break;
        }
        if tried[top.idx] {
            continue;
        }
        tried[top.idx] = true;
        let Some((value, real)) = accept(top.idx) else {
            continue;
        };
        let rg = gain(&real, &covered, cost);
        if rg == 0 || (rg as f64) < MIN_GAIN_SHARE * hidden_cost as f64 {
            continue;
        }
        hidden_cost += rg;
        merge(&mut covered, &real);
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
        let hidden = vec![vec![0, 1, 2, 3], vec![0, 1, 2, 4], vec![5, 6]];
        let cost = vec![10; 7];
        let picked = greedy(&hidden, &cost, 10, |i| Some((i, hidden[i].clone())));
        assert_eq!(picked, vec![0, 2, 1]);
        assert_eq!(
            greedy(&hidden, &cost, 2, |i| Some((i, hidden[i].clone()))),
            vec![0, 2]
        );
    }

    #[test]
    fn a_refused_candidate_gives_way_to_the_next() {
        let hidden = vec![vec![0, 1, 2], vec![0, 1], vec![3]];
        let cost = vec![1; 4];
        let picked = greedy(&hidden, &cost, 10, |i| {
            (i != 0).then(|| (i, hidden[i].clone()))
        });
        assert_eq!(picked, vec![1, 2]);
    }

    #[test]
    fn diminishing_gain_stops_the_picks() {
        let hidden = vec![vec![0], vec![1]];
        let cost = vec![1000, 5];
        let picked = greedy(&hidden, &cost, 10, |i| Some((i, hidden[i].clone())));
        assert_eq!(picked, vec![0]);
    }
}
