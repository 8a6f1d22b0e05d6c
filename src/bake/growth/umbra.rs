//! Aggregate umbrae: the growth from one seed and its 2D virtual occluders (paper 002,
//! section 3).
//!
//! Input: a convex cell (counter-clockwise), the slice's [`BlockerSet`], the blockers it may use
//! (sorted ids, none overlapping the cell), [`GrowParams`], the search distance `search_m`
//! (metres) and a seed. Output: the VOs placed behind the seed's chains ([`Vo`]), each a segment
//! with both endpoints on a 2^-10 m grid and hidden from the whole cell, and the growth trace for
//! pictures ([`SeedTrace`]). The dense set over all seeds, and the verifier's gate, are
//! [`super::dense`]'s.
//! Invariants: every VO lies in its chain's certified region, both snapped ends checked exactly
//! (below); the caches are keyed by blocker ids and coordinate bits and only looked up, so the
//! output does not depend on their order; chains hold only the blockers given as usable, found
//! along the active lines no farther than `search_m`.
//!
//! ## Growth
//! From each seed a chain `K = (B_1, .., B_m)` of blockers grows, ordered left to right as seen
//! from the cell. Both sides are active at once (the paper's Fig. 4). Per side it tracks the
//! *active supporting line* `P` (the outer common tangent of the cell and the end blocker: the
//! umbra boundary) and the *active separating line* `Q` (their crossing common tangent: the
//! penumbra boundary); the joins between chain members, drawn between their crossing-tangent
//! contacts, make up the separating polyline. Candidates are the blockers that the rays of `P`
//! and `Q` meet, found through the R-tree in short boxes along each ray, never by a scan.
//! A candidate `B` is tried at the end of the chain; with the paper's three cases:
//! 1. `B` meets `P` only: it reaches into the umbra; it joins when the chain's umbra grows.
//! 2. `B` meets `Q` only: it bends the separating polyline (Fig. 3, object 3).
//! 3. `B` meets both: it updates the umbra and both lines.
//!
//! In every case `B` joins when the chain's best VO grows; and it joins as a *bridge* when the
//! chain stays valid and `B` reaches past `P`, even if the umbra does not grow yet, so that a
//! later blocker (object 2 of Fig. 3) can join through it. Bridges in a row are limited.
//! Each accepted chain drops VOs behind itself into the dense set.
//!
//! ## Why every VO is hidden (the chain certificate)
//! For a chain with fixed vertex choices — `l_1` where the left outer tangent touches `B_1`,
//! `r_m` where the right one touches `B_m`, and for each join the two contacts `r_k`, `l_{k+1}`
//! of a crossing tangent of `B_k` and `B_{k+1}`, or a point of both (a shared vertex, or a vertex
//! of one inside the other) — plus a separating line
//! `L_k` between each `B_k` and the cell, the set of points `q` with
//! - `q` strictly on `B_k`'s side of `L_k`,
//! - `orient(q, l_k, r_k) = Ccw` (behind each chord),
//! - `orient(q, l_{k+1}, r_k) != Cw` and `orient(q, r_k, r_{k+1}) != Cw` (each join seen
//!   closed: `r_k` lies in the next arc),
//! - `orient(q, l_1, c) != Cw` and `orient(q, c, r_m) != Cw` for every cell vertex `c`
//!   (between the supporting lines),
//!
//! is an intersection of half-planes through input vertices, hence convex, and every point of it
//! is hidden: the chords' angular intervals overlap in a chain that covers the cell's angle, and
//! each chord's blocker lies between `q` and the cell (the argument of the verifier's Lemma 1,
//! docs/DESIGN.md section 4a with the missing conditions added: the measured unsound points of the
//! plain intersection lay beside or in front of a blocker, which the separating-line and chord
//! conditions exclude). A VO is a segment of a line behind the chain, clipped to that region in
//! floating point, shrunk, snapped inward to the grid, and kept only when both snapped endpoints
//! pass every condition exactly; by convexity the whole segment then lies in the region.
//! The exact verifier then checks every VO again, independently ([`super::dense`], or the bake).

// The growth's caches are keyed by blocker ids and coordinate bits, which need no protection
// against crafted collisions: rustc-hash's FxHasher (a multiply-rotate hash) instead of SipHash.
// Iteration order never reaches the output (maps are looked up, sets only tested).
use rustc_hash::{FxHashMap as HashMap, FxHashSet};
pub(super) type HashSet<K> = FxHashSet<K>;

use glam::DVec2;

use super::GrowParams;
use crate::bake::cell::VO_GRID_M;
use crate::bake::{bounds, BlockerSet};
use crate::geom::predicates::{
    common_tangents, orient, point_in_convex, segment_meets_convex, set_side, CommonTangents,
    Containment, Orientation, SetSide,
};

/// Inward shrink of a clipped VO before snapping, metres.
pub const VO_SHRINK_M: f64 = 0.005;
/// Length of the boxes that query the R-tree along an active line, metres.
pub const QUERY_STEP_M: f64 = 25.0;

/// A 2D virtual occluder.
#[derive(Clone, Debug, PartialEq)]
pub struct Vo {
    pub a: DVec2,
    pub b: DVec2,
    /// The chain behind which it was placed (blocker ids, left to right).
    pub chain: Vec<u32>,
}

impl Vo {
    pub fn length(&self) -> f64 {
        self.a.distance(self.b)
    }
}

/// How a blocker joined a chain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Case {
    /// The seed itself.
    Seed,
    /// Case 1: met the supporting line.
    Umbra,
    /// Case 2: met only the separating line (a bridge).
    Separating,
    /// Case 3: met both.
    Both,
}

/// One accepted chain state, for pictures.
#[derive(Clone, Debug)]
pub struct Step {
    pub chain: Vec<u32>,
    pub case: Case,
    /// Supporting lines, from the cell contact to the blocker contact.
    pub support_left: (DVec2, DVec2),
    pub support_right: (DVec2, DVec2),
    /// Separating polylines: cell contact, then end-blocker contact, then the join contacts.
    pub separating_left: Vec<DVec2>,
    pub separating_right: Vec<DVec2>,
}

/// The growth from one seed.
#[derive(Clone, Debug)]
pub struct SeedTrace {
    pub seed: u32,
    pub steps: Vec<Step>,
}

/// `orient(u, v, q)` must be `Ccw` (strict) or not `Cw`.
#[derive(Clone, Copy, Debug)]
struct HalfPlane {
    u: DVec2,
    v: DVec2,
    strict: bool,
}

impl HalfPlane {
    fn holds(&self, q: DVec2) -> bool {
        match orient(self.u, self.v, q) {
            Orientation::Ccw => true,
            Orientation::Collinear => !self.strict,
            Orientation::Cw => false,
        }
    }
}

/// A chain's certified region: the half-planes whose intersection it is.
struct Region {
    planes: Vec<HalfPlane>,
}

/// Per-cell growth state: the cell, blockers and cached tangents.
pub(super) struct Grower<'a> {
    pub(super) cell: &'a [DVec2],
    centre: DVec2,
    pub(super) set: &'a BlockerSet,
    pub(super) params: &'a GrowParams,
    /// How far the active lines are followed from the cell, metres.
    search_m: f64,
    pub(super) usable: HashSet<u32>,
    cell_tangents: HashMap<u32, CommonTangents>,
    pair_tangents: HashMap<(u32, u32), CommonTangents>,
    common: HashMap<(u32, u32), Vec<DVec2>>,
    /// Blockers met by a ray, before the `usable` filter, keyed by the ray's end points' bits.
    rays: HashMap<[u64; 4], Vec<u32>>,
    /// Candidate separating lines per blocker ([`Grower::separator_candidates`]).
    separators: HashMap<u32, Vec<HalfPlane>>,
}

impl<'a> Grower<'a> {
    fn poly(&self, id: u32) -> &'a [DVec2] {
        &self.set.polys[id as usize]
    }

    fn cell_t(&mut self, id: u32) -> CommonTangents {
        let (cell, p) = (self.cell, self.poly(id));
        *self
            .cell_tangents
            .entry(id)
            .or_insert_with(|| common_tangents(cell, p))
    }

    fn pair_t(&mut self, a: u32, b: u32) -> CommonTangents {
        let (p, q) = (self.poly(a), self.poly(b));
        *self
            .pair_tangents
            .entry((a, b))
            .or_insert_with(|| common_tangents(p, q))
    }

    /// Vertices of either blocker that lie in both (closed), cached per pair.
    fn common_points(&mut self, a: u32, b: u32) -> &[DVec2] {
        let (p, q) = (self.poly(a), self.poly(b));
        self.common.entry((a, b)).or_insert_with(|| {
            let ((pl, ph), (ql, qh)) = (bounds(p), bounds(q));
            if pl.x > qh.x || ql.x > ph.x || pl.y > qh.y || ql.y > ph.y {
                return Vec::new();
            }
            p.iter()
                .chain(q.iter())
                .copied()
                .filter(|&v| {
                    point_in_convex(p, v) != Containment::Outside
                        && point_in_convex(q, v) != Containment::Outside
                })
                .collect()
        })
    }

    /// The chain's certified region as seen from the reference point `q` (module header).
    fn region(&mut self, chain: &[u32], q: DVec2) -> Option<Region> {
        use Orientation::*;
        let m = chain.len();
        let (first, last) = (chain[0], chain[m - 1]);
        let t1 = self.cell_t(first).outer_left?;
        let tm = self.cell_t(last).outer_right?;
        let mut ls = vec![DVec2::ZERO; m];
        let mut rs = vec![DVec2::ZERO; m];
        ls[0] = self.poly(first)[t1.j];
        rs[m - 1] = self.poly(last)[tm.j];
        for k in 0..m - 1 {
            let t = self.pair_t(chain[k], chain[k + 1]);
            let (pk, pn) = (self.poly(chain[k]), self.poly(chain[k + 1]));
            // Blockers that share a point `v` — a common vertex, or a vertex of one lying in the
            // other (overlapping blockers) — look joined through it from everywhere: with
            // contacts `r_k = l_{k+1} = v` the join condition holds trivially, and both chords
            // still lie in their blockers (convexity). It is the best join when the chords stay
            // valid.
            let common = self.common_points(chain[k], chain[k + 1]);
            // Among the shared points, the one furthest from `q`: on the face of the chain
            // nearest the cell, where the end contacts (outer tangents from the cell) lie too.
            // A float choice only. In a straight row it keeps every chord on the front face;
            // mixing faces cuts diagonal chords across the pieces and pinches the region.
            let lk = ls[k];
            let mut best: Option<(f64, DVec2, DVec2)> = common
                .iter()
                .filter(|&&v| orient(q, lk, v) == Ccw)
                .max_by(|&&a, &&b| a.distance_squared(q).total_cmp(&b.distance_squared(q)))
                .map(|&v| (f64::INFINITY, v, v));
            for c in [t.cross_left, t.cross_right].into_iter().flatten() {
                let (r, l) = (pk[c.i], pn[c.j]);
                if orient(q, l, r) == Cw {
                    continue;
                }
                // Prefer the join line that `q` is furthest behind (a float choice only).
                let d = (r - l).perp_dot(q - l) / (r - l).length().max(1e-300);
                if best.is_none_or(|b| d.abs() > b.0) {
                    best = Some((d.abs(), r, l));
                }
            }
            let (_, r, l) = best?;
            rs[k] = r;
            ls[k + 1] = l;
        }
        let mut planes = Vec::with_capacity(6 * m + 3 * self.cell.len());
        for k in 0..m {
            if orient(q, ls[k], rs[k]) != Ccw {
                return None;
            }
            planes.push(HalfPlane {
                u: ls[k],
                v: rs[k],
                strict: true,
            });
            if k + 1 < m {
                // The chord's end lies in the next arc.
                planes.push(HalfPlane {
                    u: ls[k + 1],
                    v: rs[k],
                    strict: false,
                });
                planes.push(HalfPlane {
                    u: rs[k],
                    v: rs[k + 1],
                    strict: false,
                });
            }
            planes.push(self.separating(chain[k], q)?);
        }
        for &c in self.cell {
            planes.push(HalfPlane {
                u: ls[0],
                v: c,
                strict: false,
            });
            planes.push(HalfPlane {
                u: c,
                v: rs[m - 1],
                strict: false,
            });
        }
        if !planes.iter().all(|h| h.holds(q)) {
            return None;
        }
        Some(Region { planes })
    }

    /// A separating line between blocker `id` and the cell, with `q` strictly on the blocker's
    /// side, as a strict half-plane.
    fn separating(&mut self, id: u32, q: DVec2) -> Option<HalfPlane> {
        if !self.separators.contains_key(&id) {
            let c = self.separator_candidates(id);
            self.separators.insert(id, c);
        }
        self.separators[&id].iter().copied().find(|h| h.holds(q))
    }

    /// The candidate separating lines of blocker `id` and the cell, in preference order: cell
    /// edges and blocker edges with the other wholly on their right, then the crossing tangents.
    fn separator_candidates(&mut self, id: u32) -> Vec<HalfPlane> {
        let (cell, b) = (self.cell, self.poly(id));
        let mut cands: Vec<HalfPlane> = Vec::new();
        for i in 0..cell.len() {
            let (u, v) = (cell[i], cell[(i + 1) % cell.len()]);
            if set_side(u, v, b) == SetSide::Right {
                cands.push(HalfPlane {
                    u: v,
                    v: u,
                    strict: true,
                });
            }
        }
        for i in 0..b.len() {
            let (u, v) = (b[i], b[(i + 1) % b.len()]);
            if set_side(u, v, cell) == SetSide::Right {
                cands.push(HalfPlane { u, v, strict: true });
            }
        }
        let t = self.cell_t(id);
        if let Some(c) = t.cross_left {
            cands.push(HalfPlane {
                u: b[c.j],
                v: cell[c.i],
                strict: true,
            });
        }
        if let Some(c) = t.cross_right {
            cands.push(HalfPlane {
                u: cell[c.i],
                v: b[c.j],
                strict: true,
            });
        }
        cands
    }

    /// VOs behind the chain, at several distances and in two orientations (facing the cell
    /// centre, and along the chain's front); each certified by the chain's region as seen from
    /// one of a few reference points on its line. The longest per line is kept.
    fn place(&mut self, chain: &[u32]) -> Vec<Vo> {
        let mut out = Vec::new();
        let Some((l1, rm)) = self.ends(chain) else {
            return out;
        };
        let mid = (l1 + rm) * 0.5;
        let w = l1.distance(rm).max(1.0);
        let view = (mid - self.centre).normalize_or_zero();
        let front = (rm - l1).normalize_or_zero();
        let mut dirs = Vec::new();
        if view != DVec2::ZERO {
            dirs.push(view.perp());
        }
        if front != DVec2::ZERO && (view == DVec2::ZERO || front.dot(view.perp()).abs() < 0.999) {
            dirs.push(front);
        }
        for dir in dirs {
            let mut n = dir.perp();
            if n.dot(mid - self.centre) < 0.0 {
                n = -n;
            }
            let depth = chain
                .iter()
                .flat_map(|&id| self.poly(id).iter())
                .map(|&v| (v - mid).dot(n))
                .fold(0.0f64, f64::max);
            for off in [1.0, 0.5 * w, 2.0 * w] {
                let o = mid + n * (depth + off);
                let mut best: Option<Vo> = None;
                for shift in [0.0, -0.25, 0.25] {
                    let q = o + dir * (shift * w);
                    let Some(region) = self.region(chain, q) else {
                        continue;
                    };
                    if let Some((a, b)) = clip_snap(&region.planes, q, dir) {
                        let len = a.distance(b);
                        if len >= self.params.min_vo_m
                            && best.as_ref().is_none_or(|v| len > v.length())
                        {
                            best = Some(Vo {
                                a,
                                b,
                                chain: chain.to_vec(),
                            });
                        }
                    }
                }
                out.extend(best);
            }
        }
        out
    }

    /// The chain's end contacts (outer tangents), without building the region.
    fn ends(&mut self, chain: &[u32]) -> Option<(DVec2, DVec2)> {
        let (first, last) = (chain[0], chain[chain.len() - 1]);
        let t1 = self.cell_t(first).outer_left?;
        let tm = self.cell_t(last).outer_right?;
        Some((self.poly(first)[t1.j], self.poly(last)[tm.j]))
    }

    /// Angular size of the best VO, as seen from the cell centre (length over distance).
    fn score(&self, vos: &[Vo]) -> f64 {
        vos.iter()
            .map(|v| v.length() / ((v.a + v.b) * 0.5).distance(self.centre).max(1.0))
            .fold(0.0, f64::max)
    }

    /// Blockers met by the ray from `a` through `b`, up to the search distance from the cell.
    fn along(&mut self, a: DVec2, b: DVec2) -> Vec<u32> {
        let key = [a.x.to_bits(), a.y.to_bits(), b.x.to_bits(), b.y.to_bits()];
        if !self.rays.contains_key(&key) {
            let met = self.along_all(a, b);
            self.rays.insert(key, met);
        }
        self.rays[&key]
            .iter()
            .copied()
            .filter(|id| self.usable.contains(id))
            .collect()
    }

    /// [`Self::along`] over every blocker of the set, usable or not (cached across slices).
    fn along_all(&self, a: DVec2, b: DVec2) -> Vec<u32> {
        let d = (b - a).normalize_or_zero();
        if d == DVec2::ZERO {
            return Vec::new();
        }
        let end = a + d * self.search_m;
        let steps = (self.search_m / QUERY_STEP_M).ceil() as usize;
        let mut out: Vec<u32> = Vec::new();
        for s in 0..steps {
            let p = a + d * (s as f64 * QUERY_STEP_M);
            let q = a + d * (((s + 1) as f64 * QUERY_STEP_M).min(self.search_m));
            self.set.each_in_box(p.min(q), p.max(q), |id| {
                if !out.contains(&id) && segment_meets_convex(a, end, self.poly(id)) {
                    out.push(id);
                }
            });
        }
        out
    }

    /// The lines of one side of a chain: (supporting line, separating line), each from its cell
    /// contact to its end-blocker contact.
    fn side_lines(
        &mut self,
        chain: &[u32],
        left: bool,
    ) -> Option<((DVec2, DVec2), (DVec2, DVec2))> {
        let end = if left {
            chain[0]
        } else {
            chain[chain.len() - 1]
        };
        let t = self.cell_t(end);
        let (sup, sep) = if left {
            (t.outer_left?, t.cross_left?)
        } else {
            (t.outer_right?, t.cross_right?)
        };
        let p = self.poly(end);
        Some(((self.cell[sup.i], p[sup.j]), (self.cell[sep.i], p[sep.j])))
    }

    fn step_trace(&mut self, chain: &[u32], case: Case) -> Option<Step> {
        let (sl, ql) = self.side_lines(chain, true)?;
        let (sr, qr) = self.side_lines(chain, false)?;
        // Joins: the crossing-tangent contacts between neighbours, on the separating polyline.
        let mut joins = Vec::new();
        for k in 0..chain.len().saturating_sub(1) {
            let t = self.pair_t(chain[k], chain[k + 1]);
            if let Some(c) = t.cross_left.or(t.cross_right) {
                joins.push((self.poly(chain[k])[c.i], self.poly(chain[k + 1])[c.j]));
            }
        }
        let mut separating_left = vec![ql.0, ql.1];
        let mut separating_right = vec![qr.0, qr.1];
        for &(r, l) in &joins {
            separating_left.push(r);
            separating_left.push(l);
        }
        for &(r, l) in joins.iter().rev() {
            separating_right.push(l);
            separating_right.push(r);
        }
        Some(Step {
            chain: chain.to_vec(),
            case,
            support_left: sl,
            support_right: sr,
            separating_left,
            separating_right,
        })
    }

    /// Grows one seed; returns its dense VOs and trace.
    pub(super) fn grow(&mut self, seed: u32) -> (Vec<Vo>, SeedTrace) {
        let mut chain = vec![seed];
        let mut vos = self.place(&chain);
        let mut best = self.score(&vos);
        let mut trace = SeedTrace {
            seed,
            steps: self.step_trace(&chain, Case::Seed).into_iter().collect(),
        };
        let mut bridges = [0usize; 2];
        let mut tried: HashSet<(bool, u32, u32)> = HashSet::default();
        while chain.len() < self.params.max_chain {
            let mut accepted = false;
            for (si, left) in [(0usize, true), (1usize, false)] {
                let Some((sup, sep)) = self.side_lines(&chain, left) else {
                    continue;
                };
                let on_p = self.along(sup.0, sup.1);
                let on_q = self.along(sep.0, sep.1);
                let end = if left {
                    chain[0]
                } else {
                    chain[chain.len() - 1]
                };
                let contact = sup.1;
                let mut cands: Vec<(f64, u32, Case)> = on_p
                    .iter()
                    .chain(on_q.iter())
                    .filter(|id| !chain.contains(id))
                    .map(|&id| {
                        let case = match (on_p.contains(&id), on_q.contains(&id)) {
                            (true, true) => Case::Both,
                            (true, false) => Case::Umbra,
                            _ => Case::Separating,
                        };
                        let d = self
                            .poly(id)
                            .iter()
                            .map(|v| v.distance_squared(contact))
                            .fold(f64::INFINITY, f64::min);
                        (d, id, case)
                    })
                    .collect();
                cands.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                cands.dedup_by_key(|c| c.1);
                let single = self.params.single_object;
                for &(_, id, case) in cands
                    .iter()
                    .filter(|c| !single || self.set.same_object(c.1, seed))
                    .take(self.params.tries)
                {
                    if !tried.insert((left, end, id)) {
                        continue;
                    }
                    let mut next = chain.clone();
                    if left {
                        next.insert(0, id);
                    } else {
                        next.push(id);
                    }
                    let placed = self.place(&next);
                    let s = self.score(&placed);
                    let reaches_past = self.poly(id).iter().any(|&v| {
                        let o = orient(sup.0, sup.1, v);
                        if left {
                            o == Orientation::Ccw
                        } else {
                            o == Orientation::Cw
                        }
                    });
                    let grows = s > best * (1.0 + 1e-9) && s > 0.0;
                    // A bridge moves this side's active lines outward so that a blocker further
                    // out can join through it (Fig. 3, object 3), even before the umbra grows.
                    let bridge = reaches_past
                        && bridges[si] < self.params.max_bridges
                        && self.region_exists(&next);
                    if grows || bridge {
                        bridges[si] = if grows { 0 } else { bridges[si] + 1 };
                        best = best.max(s);
                        vos.extend(placed);
                        chain = next;
                        if let Some(step) = self.step_trace(&chain, case) {
                            trace.steps.push(step);
                        }
                        accepted = true;
                        break;
                    }
                }
            }
            if !accepted {
                break;
            }
        }
        (vos, trace)
    }

    /// True when the chain's region is non-empty somewhere behind it.
    fn region_exists(&mut self, chain: &[u32]) -> bool {
        let Some((l1, rm)) = self.ends(chain) else {
            return false;
        };
        let mid = (l1 + rm) * 0.5;
        let w = l1.distance(rm).max(1.0);
        let n = {
            let d = (mid - self.centre).normalize_or_zero();
            if d == DVec2::ZERO {
                return false;
            }
            d
        };
        [0.5, 1.0, 2.0, 4.0]
            .iter()
            .any(|&f| self.region(chain, mid + n * (w * f)).is_some())
    }
}

/// Clips the line `o + t dir` to the half-planes in floating point, shrinks, snaps the ends
/// inward to [`VO_GRID_M`] and returns them only when both pass every half-plane exactly.
fn clip_snap(planes: &[HalfPlane], o: DVec2, dir: DVec2) -> Option<(DVec2, DVec2)> {
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for h in planes {
        let e = h.v - h.u;
        let alpha = e.perp_dot(o - h.u);
        let beta = e.perp_dot(dir);
        if beta > 0.0 {
            t0 = t0.max(-alpha / beta);
        } else if beta < 0.0 {
            t1 = t1.min(-alpha / beta);
        } else if alpha < 0.0 {
            return None;
        }
    }
    if !(t0.is_finite() && t1.is_finite() && t0 < t1) {
        return None;
    }
    let snap = |p: DVec2| (p / VO_GRID_M).round() * VO_GRID_M;
    let mut shrink = VO_SHRINK_M + 1e-12 * o.abs().max_element();
    for _ in 0..8 {
        if t1 - t0 <= 2.0 * shrink {
            return None;
        }
        let a = snap(o + dir * (t0 + shrink));
        let b = snap(o + dir * (t1 - shrink));
        if a != b && planes.iter().all(|h| h.holds(a) && h.holds(b)) {
            return Some((a, b));
        }
        shrink *= 2.0;
    }
    None
}

/// The growth state of `cell` over the blockers `near` (sorted ids), its active lines followed
/// `search_m` metres.
pub(super) fn grower<'a>(
    cell: &'a [DVec2],
    set: &'a BlockerSet,
    params: &'a GrowParams,
    search_m: f64,
    near: &[u32],
) -> Grower<'a> {
    Grower {
        cell,
        centre: cell.iter().copied().sum::<DVec2>() / cell.len() as f64,
        set,
        params,
        search_m,
        usable: near.iter().copied().collect(),
        cell_tangents: HashMap::default(),
        pair_tangents: HashMap::default(),
        common: HashMap::default(),
        rays: HashMap::default(),
        separators: HashMap::default(),
    }
}
