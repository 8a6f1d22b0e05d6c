//! Footprint repair: rings as read in, valid polygon rings or a typed rejection out.
//!
//! Input: the rings of one polygon as a reader gives them (ring 0 the exterior, the rest holes;
//! GeoJSON rings repeat their first point at the end), local coordinates.
//! Output: open rings (no closing repeat), no repeated consecutive points, exterior
//! counter-clockwise and holes clockwise, together with the list of repairs made; or the first
//! ring that cannot be repaired and why.
//! Invariants of an accepted polygon, all decided by exact predicates:
//! - every ring has at least 3 points and non-zero area;
//! - no two edges of any rings meet except consecutive edges of one ring at their shared vertex
//!   (no crossings, no touching, no spikes that double back);
//! - every hole lies strictly inside the exterior and outside every other hole.
//!
//! Cost: above 64 edges, edge pairs and hole-in-ring tests come from an R-tree of the edges'
//! boxes, so ordinary footprints cost O(n log n). Long edges that pass near many others (a star
//! with 10^6 spikes) give far more candidate pairs; validation examines at most
//! [`WORK_PER_EDGE`] candidates per edge (plus [`WORK_BASE`]) and otherwise rejects the polygon
//! as [`RingRejection::TooComplex`], so no footprint costs more than linear work in the checks.
//!
//! Repairs (closing, repeated points, orientation) do not move any point, so they cannot add solid
//! area. Anything else is rejected: a rejected polygon gives no blocker, which is conservative,
//! and its object still counts as an occludee.

use glam::DVec2;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};

use super::{Ring, RingRejection, RingRepair};
use crate::geom::predicates::{
    orient, point_in_ring, ring_orientation, segment_intersection, Containment, Orientation,
    SegmentIntersection,
};

/// Below this many edges, all pairs are tested directly instead of through an R-tree.
const BRUTE_FORCE_EDGES: usize = 64;

/// Candidate edge pairs and ray candidates the validation of one polygon may examine per edge,
/// beyond [`WORK_BASE`]. Real footprints need a few per edge (Lyon: at most 3.5, over its 42
/// footprints of more than 64 edges).
pub const WORK_PER_EDGE: u64 = 64;
/// Candidates any polygon may examine, whatever its size.
pub const WORK_BASE: u64 = 1 << 20;

/// What validation may still examine; `spend` is false once it is used up.
struct Budget(u64);

impl Budget {
    fn for_edges(edges: usize) -> Budget {
        Budget(WORK_BASE.saturating_add(WORK_PER_EDGE.saturating_mul(edges as u64)))
    }
    fn spend(&mut self) -> bool {
        let ok = self.0 > 0;
        self.0 = self.0.saturating_sub(1);
        ok
    }
}

/// Validation gave up: see [`WORK_PER_EDGE`].
struct TooComplex;

type EdgeTree = RTree<GeomWithData<Rectangle<[f64; 2]>, usize>>;

/// The outcome of repairing one polygon.
#[derive(Clone, Debug, PartialEq)]
pub struct RepairedPolygon {
    /// (ring index, repair) for each repair made.
    pub repairs: Vec<(usize, RingRepair)>,
    /// The valid rings, or (ring index, reason) for the first ring rejected.
    pub result: Result<Vec<Ring>, (usize, RingRejection)>,
}

/// Repairs or rejects one polygon's rings.
pub fn repair_polygon(rings: &[Ring]) -> RepairedPolygon {
    let mut repairs = Vec::new();
    let result = repair_inner(rings, &mut repairs);
    RepairedPolygon { repairs, result }
}

fn repair_inner(
    rings: &[Ring],
    repairs: &mut Vec<(usize, RingRepair)>,
) -> Result<Vec<Ring>, (usize, RingRejection)> {
    let mut out: Vec<Ring> = Vec::with_capacity(rings.len());
    for (ri, ring) in rings.iter().enumerate() {
        let mut r = ring.clone();
        if r.len() >= 2 && r.first() == r.last() {
            r.pop();
        } else if !r.is_empty() {
            repairs.push((ri, RingRepair::Closed));
        }
        let before = r.len();
        r.dedup();
        while r.len() > 1 && r.first() == r.last() {
            r.pop();
        }
        if r.len() != before {
            repairs.push((ri, RingRepair::RepeatedPoints));
        }
        if r.len() < 3 {
            return Err((ri, RingRejection::TooFewPoints));
        }
        out.push(r);
    }
    if out.is_empty() {
        return Err((0, RingRejection::TooFewPoints));
    }
    let edges = edges_of(&out);
    let mut budget = Budget::for_edges(edges.len());
    let tree = (edges.len() > BRUTE_FORCE_EDGES).then(|| edge_tree(&edges));
    match first_self_intersecting_ring(&out, &edges, tree.as_ref(), &mut budget) {
        Err(TooComplex) => return Err((0, RingRejection::TooComplex)),
        Ok(Some(ri)) => return Err((ri, RingRejection::SelfIntersection)),
        Ok(None) => {}
    }
    for (ri, r) in out.iter_mut().enumerate() {
        let want = if ri == 0 {
            Orientation::Ccw
        } else {
            Orientation::Cw
        };
        match ring_orientation(r) {
            Orientation::Collinear => return Err((ri, RingRejection::ZeroArea)),
            o if o != want => {
                r.reverse();
                repairs.push((ri, RingRepair::Reoriented));
            }
            _ => {}
        }
    }
    // No edges meet, so one vertex decides where a whole hole lies.
    let Some(tree) = tree else {
        for hi in 1..out.len() {
            let p = out[hi][0];
            if point_in_ring(&out[0], p) != Containment::Inside {
                return Err((hi, RingRejection::HoleOutside));
            }
            for (hj, ring) in out.iter().enumerate().skip(1) {
                if hj != hi && point_in_ring(ring, p) != Containment::Outside {
                    return Err((hi, RingRejection::HoleOutside));
                }
            }
        }
        return Ok(out);
    };
    // Many edges: the parity of every ring at once, from the edges whose boxes meet the ray from
    // the hole's vertex towards +x (the same half-open rule as `point_in_ring`; the vertex lies
    // on no other ring's edge, which validation has checked).
    let x_max = edges.iter().fold(f64::NEG_INFINITY, |m, e| m.max(e.a.x));
    let mut crossed: Vec<usize> = Vec::new();
    for (hi, hole) in out.iter().enumerate().skip(1) {
        let p = hole[0];
        crossed.clear();
        let ray = AABB::from_corners([p.x, p.y], [x_max.max(p.x), p.y]);
        for cand in tree.locate_in_envelope_intersecting(ray) {
            if !budget.spend() {
                return Err((0, RingRejection::TooComplex));
            }
            let e = &edges[cand.data];
            if e.ring != hi && crosses_right(e.a, e.b, p) {
                crossed.push(e.ring);
            }
        }
        crossed.sort_unstable();
        let odd = |ring: usize| crossed.iter().filter(|&&r| r == ring).count() % 2 == 1;
        if !odd(0) {
            return Err((hi, RingRejection::HoleOutside));
        }
        let mut k = 0;
        while k < crossed.len() {
            let r = crossed[k];
            let run = crossed[k..].iter().take_while(|&&x| x == r).count();
            if r != 0 && run % 2 == 1 {
                return Err((hi, RingRejection::HoleOutside));
            }
            k += run;
        }
    }
    Ok(out)
}

/// Whether edge `a -> b` crosses the horizontal ray from `p` towards +x, with the half-open rule
/// of [`point_in_ring`] (exact).
fn crosses_right(a: DVec2, b: DVec2, p: DVec2) -> bool {
    if (a.y > p.y) == (b.y > p.y) {
        return false;
    }
    let o = orient(a, b, p);
    let upward = b.y > a.y;
    (upward && o == Orientation::Ccw) || (!upward && o == Orientation::Cw)
}

/// An edge: ring index, index of its first vertex in the ring, endpoints.
#[derive(Clone, Copy)]
struct Edge {
    ring: usize,
    i: usize,
    a: DVec2,
    b: DVec2,
}

/// Every edge of every ring, ring by ring.
fn edges_of(rings: &[Ring]) -> Vec<Edge> {
    let mut edges = Vec::with_capacity(rings.iter().map(Vec::len).sum());
    for (ring, r) in rings.iter().enumerate() {
        for i in 0..r.len() {
            edges.push(Edge {
                ring,
                i,
                a: r[i],
                b: r[(i + 1) % r.len()],
            });
        }
    }
    edges
}

fn edge_box(e: &Edge) -> ([f64; 2], [f64; 2]) {
    (
        [e.a.x.min(e.b.x), e.a.y.min(e.b.y)],
        [e.a.x.max(e.b.x), e.a.y.max(e.b.y)],
    )
}

fn edge_tree(edges: &[Edge]) -> EdgeTree {
    RTree::bulk_load(
        edges
            .iter()
            .enumerate()
            .map(|(k, e)| {
                let (lo, hi) = edge_box(e);
                GeomWithData::new(Rectangle::from_corners(lo, hi), k)
            })
            .collect(),
    )
}

/// The ring of the first offending edge pair, if any two edges meet where they must not; pairs
/// come from `tree` when there is one, else every pair is tested.
fn first_self_intersecting_ring(
    rings: &[Ring],
    edges: &[Edge],
    tree: Option<&EdgeTree>,
    budget: &mut Budget,
) -> Result<Option<usize>, TooComplex> {
    let len_of = |ring: usize| rings[ring].len();
    let bad = |e: &Edge, f: &Edge| edges_conflict(e, f, len_of(e.ring));
    let Some(tree) = tree else {
        for (k, e) in edges.iter().enumerate() {
            for f in &edges[k + 1..] {
                if bad(e, f) {
                    return Ok(Some(e.ring.min(f.ring)));
                }
            }
        }
        return Ok(None);
    };
    let mut worst: Option<usize> = None;
    for (k, e) in edges.iter().enumerate() {
        let (lo, hi) = edge_box(e);
        for cand in tree.locate_in_envelope_intersecting(AABB::from_corners(lo, hi)) {
            if !budget.spend() {
                return Err(TooComplex);
            }
            let j = cand.data;
            if j > k && bad(e, &edges[j]) {
                let r = e.ring.min(edges[j].ring);
                worst = Some(worst.map_or(r, |w| w.min(r)));
            }
        }
    }
    Ok(worst)
}

/// True when edges `e` and `f` meet in a way a simple polygon does not allow.
fn edges_conflict(e: &Edge, f: &Edge, ring_len: usize) -> bool {
    if e.ring == f.ring {
        let n = ring_len;
        let next = |i: usize| (i + 1) % n;
        // Consecutive edges share a vertex; they conflict only when they double back.
        if next(e.i) == f.i {
            return doubles_back(e.a, e.b, f.b);
        }
        if next(f.i) == e.i {
            return doubles_back(f.a, f.b, e.b);
        }
    }
    segment_intersection(e.a, e.b, f.a, f.b) != SegmentIntersection::Disjoint
}

/// For consecutive edges a->b->c: true when c turns back onto the first edge's line (a spike).
fn doubles_back(a: DVec2, b: DVec2, c: DVec2) -> bool {
    orient(a, b, c) == Orientation::Collinear && (b - a).dot(c - b) < 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring(pts: &[(f64, f64)]) -> Ring {
        pts.iter().map(|&(x, y)| DVec2::new(x, y)).collect()
    }

    const SQUARE_CLOSED: &[(f64, f64)] = &[(0., 0.), (4., 0.), (4., 4.), (0., 4.), (0., 0.)];

    #[test]
    fn valid_square_needs_no_repair() {
        let r = repair_polygon(&[ring(SQUARE_CLOSED)]);
        assert_eq!(r.repairs, vec![]);
        assert_eq!(r.result.unwrap()[0].len(), 4);
    }

    #[test]
    fn unclosed_repeated_and_clockwise_are_repaired() {
        let r = repair_polygon(&[ring(&[(0., 0.), (0., 4.), (0., 4.), (4., 4.), (4., 0.)])]);
        assert_eq!(
            r.repairs,
            vec![
                (0, RingRepair::Closed),
                (0, RingRepair::RepeatedPoints),
                (0, RingRepair::Reoriented)
            ]
        );
        let rings = r.result.unwrap();
        assert_eq!(ring_orientation(&rings[0]), Orientation::Ccw);
        assert_eq!(rings[0].len(), 4);
    }

    #[test]
    fn hole_is_oriented_clockwise() {
        let hole = ring(&[(1., 1.), (2., 1.), (2., 2.), (1., 2.), (1., 1.)]);
        let r = repair_polygon(&[ring(SQUARE_CLOSED), hole]);
        assert_eq!(r.repairs, vec![(1, RingRepair::Reoriented)]);
        assert_eq!(ring_orientation(&r.result.unwrap()[1]), Orientation::Cw);
    }

    #[test]
    fn bowtie_is_rejected() {
        let r = repair_polygon(&[ring(&[(0., 0.), (4., 4.), (4., 0.), (0., 4.), (0., 0.)])]);
        assert_eq!(r.result, Err((0, RingRejection::SelfIntersection)));
    }

    #[test]
    fn spike_is_rejected() {
        let r = repair_polygon(&[ring(&[
            (0., 0.),
            (4., 0.),
            (6., 0.),
            (4., 0.),
            (4., 4.),
            (0., 0.),
        ])]);
        assert_eq!(r.result, Err((0, RingRejection::SelfIntersection)));
    }

    #[test]
    fn collinear_points_are_zero_area_or_spikes() {
        let r = repair_polygon(&[ring(&[(0., 0.), (1., 0.), (2., 0.), (0., 0.)])]);
        assert!(r.result.is_err());
        let r = repair_polygon(&[ring(&[(0., 0.), (1., 0.), (0., 0.)])]);
        assert_eq!(r.result, Err((0, RingRejection::TooFewPoints)));
    }

    #[test]
    fn hole_touching_exterior_is_rejected() {
        let hole = ring(&[(0., 1.), (2., 1.), (2., 2.), (0., 1.)]);
        let r = repair_polygon(&[ring(SQUARE_CLOSED), hole]);
        assert_eq!(r.result, Err((0, RingRejection::SelfIntersection)));
    }

    #[test]
    fn hole_outside_or_nested_is_rejected() {
        let outside = ring(&[(5., 5.), (6., 5.), (6., 6.), (5., 5.)]);
        let r = repair_polygon(&[ring(SQUARE_CLOSED), outside]);
        assert_eq!(r.result, Err((1, RingRejection::HoleOutside)));
        let big = ring(&[(0.5, 0.5), (3.5, 0.5), (3.5, 3.5), (0.5, 3.5), (0.5, 0.5)]);
        let small = ring(&[(1., 1.), (2., 1.), (2., 2.), (1., 1.)]);
        let r = repair_polygon(&[ring(SQUARE_CLOSED), big, small]);
        // The small hole is the one nested inside another hole.
        assert_eq!(r.result, Err((2, RingRejection::HoleOutside)));
    }

    #[test]
    fn rtree_path_agrees_with_brute_force() {
        // A 200-gon star-ish ring, valid, then with one vertex pushed across the ring.
        let n = 200;
        let mut pts: Vec<(f64, f64)> = (0..n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                let r = if k % 2 == 0 { 10.0 } else { 7.0 };
                (r * t.cos(), r * t.sin())
            })
            .collect();
        pts.push(pts[0]);
        assert!(repair_polygon(&[ring(&pts)]).result.is_ok());
        pts[50] = (-20.0, 0.0);
        assert_eq!(
            repair_polygon(&[ring(&pts)]).result,
            Err((0, RingRejection::SelfIntersection))
        );
    }
}
