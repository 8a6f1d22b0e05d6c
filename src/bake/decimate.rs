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

use glam::DVec2;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};

use crate::runtime::frame::{CellView, VoGeom};
use crate::runtime::occlusion::{Cover, PreparedVo};

/// Stop when the best remaining gain is below this share of the cost already hidden.
pub const MIN_GAIN_SHARE: f64 = 0.01;

/// The occludees of a scene: boxes in the local frame, with costs, under an R-tree.
pub struct Occludees {
    pub boxes: Vec<[f64; 6]>,
    pub cost: Vec<u64>,
    tree: RTree<GeomWithData<Rectangle<[f64; 2]>, u32>>,
}

impl Occludees {
    pub fn new(boxes: Vec<[f64; 6]>, cost: Vec<u64>) -> Occludees {
        let items = boxes
            .iter()
            .enumerate()
            .map(|(i, b)| {
                GeomWithData::new(
                    Rectangle::from_corners([b[0], b[1]], [b[3], b[4]]),
                    i as u32,
                )
            })
            .collect();
        Occludees {
            boxes,
            cost,
            tree: RTree::bulk_load(items),
        }
    }

    pub fn from_scene(scene: &crate::scene::Scene) -> Occludees {
        let boxes = scene
            .objects
            .iter()
            .map(|o| {
                let (a, b) = (o.bbox.min, o.bbox.max);
                [a.x, a.y, a.z, b.x, b.y, b.z]
            })
            .collect();
        let cost = scene.objects.iter().map(|o| o.cost.max(1)).collect();
        Occludees::new(boxes, cost)
    }

    /// The occludees within `radius` of the cell centre that `vo` hides from the cell (rule 3),
    /// ascending.
    pub fn hidden(&self, view: &CellView, vo: &VoGeom, radius: f64) -> Vec<u32> {
        let p = PreparedVo::new(view, vo);
        let (lo, hi) = umbra_box(view, vo, radius);
        let mut out: Vec<u32> = self
            .tree
            .locate_in_envelope_intersecting(AABB::from_corners(lo.to_array(), hi.to_array()))
            .map(|g| g.data)
            .filter(|&i| p.cover(view, &self.boxes[i as usize]) == Cover::Hidden)
            .collect();
        out.sort_unstable();
        out
    }

    pub fn cost_of(&self, ids: &[u32]) -> u64 {
        ids.iter().map(|&i| self.cost[i as usize]).sum()
    }
}

/// A box around the part within `radius` of the cell centre of the cone from the centre through
/// the VO, which holds the VO's umbra (every segment from the cell, the centre included, to a
/// hidden point meets the VO).
fn umbra_box(view: &CellView, vo: &VoGeom, radius: f64) -> (DVec2, DVec2) {
    let r = view.rect;
    let o = DVec2::new(0.5 * (r[0] + r[2]), 0.5 * (r[1] + r[3]));
    let full = (o - DVec2::splat(radius), o + DVec2::splat(radius));
    let (a, b) = (DVec2::from(vo.a) - o, DVec2::from(vo.b) - o);
    let (la, lb) = (a.length(), b.length());
    if la == 0.0 || lb == 0.0 {
        return full;
    }
    let (ua, ub) = (a / la, b / lb);
    let cos = ua.dot(ub).clamp(-1.0, 1.0);
    let half = 0.5 * cos.acos();
    if half > 1.2 {
        return full;
    }
    // The sector of angle 2*half lies in the triangle o, o + ua R', o + ub R' with
    // R' = radius / cos(half).
    let rr = radius / half.cos() * 1.001;
    let pts = [o, o + ua * rr, o + ub * rr, o + a, o + b];
    let lo = pts.iter().fold(DVec2::INFINITY, |m, p| m.min(*p));
    let hi = pts.iter().fold(DVec2::NEG_INFINITY, |m, p| m.max(*p));
    (lo.max(full.0), hi.min(full.1))
}

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
