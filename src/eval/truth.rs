//! The ground-truth visible set (VS) of a view cell, by ray sampling.
//!
//! Input: a [`Caster`] over a scene, the scene, a cell rectangle and eye height range (local
//! frame), and [`TruthParams`] (eyes, samples per object, radius, seed).
//! Output: [`visible_set`], the ascending indices of the objects that are the first hit of some
//! ray from a sampled eye; [`convergence`], how that set grows with eyes and samples.
//! Invariants:
//! - never reads virtual occluders, blockers or any code of the occlusion pipeline: only the
//!   scene's original geometry through [`Caster`];
//! - a sample set, not a bound: every object reported is truly visible from the cell (up to rays
//!   that graze an edge), but a visible object may be missed if no ray finds it;
//! - deterministic: the same scene, cell, heights and params give the same set on any thread
//!   count; more eyes or samples (same seed) give a superset (eye `i` and sample `k` of an object
//!   do not depend on how many there are).

use glam::DVec2;
use rayon::prelude::*;

use super::raycast::Caster;
use crate::scene::Scene;

/// A ray reaches its target at `t = 1`; anything first hit this close to it counts as the target
/// (relative to the eye–target distance).
pub const REACH_TOLERANCE: f64 = 1e-7;
/// Rays are cast up to `t = 1 + TARGET_SLACK`, so the target itself is found despite rounding.
pub const TARGET_SLACK: f64 = 1e-9;
/// Draws per eye before giving up on finding a point outside every object.
pub const EYE_TRIES: usize = 8;

/// How densely to sample.
#[derive(Clone, Debug, PartialEq)]
pub struct TruthParams {
    /// Eye points per cell: spread over the cell rectangle by a randomly shifted R2
    /// low-discrepancy sequence (so any prefix covers the cell evenly), height uniform in the eye
    /// range. An eye inside an object is drawn again, uniformly, up to [`EYE_TRIES`] times.
    pub eyes: usize,
    /// Rays per eye and object, aimed at area-uniform points of the object's surface.
    pub samples_per_object: usize,
    /// Only objects whose bounding box lies within this xy distance of the cell are targeted;
    /// `None`: all. Objects outside may still be reported as blockers of a ray.
    pub radius: Option<f64>,
    pub seed: u64,
    /// Eye heights above the terrain, `(lo, hi)`: where the scene has a terrain under an eye's
    /// point, the eye stands at the terrain's height there plus a height uniform in this range
    /// (a camera on the ground); elsewhere, and when `None`, uniform in the cell's eye range.
    pub eye_above: Option<(f64, f64)>,
}

impl Default for TruthParams {
    fn default() -> Self {
        TruthParams {
            eyes: 16,
            samples_per_object: 4,
            radius: None,
            seed: 0x7275_7468,
            eye_above: None,
        }
    }
}

/// SplitMix64.
#[derive(Clone, Debug)]
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        mix(self.0)
    }

    /// Uniform in `[0, 1)`.
    fn f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// SplitMix64's finalizer.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// xy distance between an object's bounding box and the cell rectangle.
fn box_distance(lo: DVec2, hi: DVec2, cell: [f64; 4]) -> f64 {
    let dx = (cell[0] - hi.x).max(lo.x - cell[2]).max(0.0);
    let dy = (cell[1] - hi.y).max(lo.y - cell[3]).max(0.0);
    dx.hypot(dy)
}

/// The objects targeted from a cell.
fn targets(scene: &Scene, cell: [f64; 4], radius: Option<f64>) -> Vec<u32> {
    scene
        .objects
        .iter()
        .filter(|o| match radius {
            None => true,
            Some(r) => box_distance(o.bbox.min.truncate(), o.bbox.max.truncate(), cell) <= r,
        })
        .map(|o| o.index)
        .collect()
}

/// The first object each ray hits from one eye of the cell, over `samples` samples per target.
/// The eye stands at `first` (fractions of the cell's sides), or, if that is inside an object, at
/// a point drawn from `eye_seed`. Returns the sorted, deduplicated hits and the number of rays.
#[allow(clippy::too_many_arguments)]
fn eye_hits(
    caster: &Caster,
    cell: [f64; 4],
    eye_z: (f64, f64),
    targets: &[u32],
    samples: usize,
    eye_seed: u64,
    first: (f64, f64),
    eye_above: Option<(f64, f64)>,
) -> (Vec<u32>, u64) {
    let mut rng = Rng(eye_seed);
    let mut eye = None;
    for k in 0..EYE_TRIES {
        let (u, v) = if k == 0 {
            first
        } else {
            (rng.f64(), rng.f64())
        };
        let xy = DVec2::new(
            cell[0] + (cell[2] - cell[0]) * u,
            cell[1] + (cell[3] - cell[1]) * v,
        );
        let (s, ground) = (
            rng.f64(),
            eye_above.and_then(|e| Some((e, caster.ground_height(xy)?))),
        );
        let z = match ground {
            Some(((lo, hi), g)) => g + lo + (hi - lo) * s,
            None => eye_z.0 + (eye_z.1 - eye_z.0) * s,
        };
        let p = xy.extend(z);
        if caster.contains(p).is_none() {
            eye = Some(p);
            break;
        }
    }
    let Some(eye) = eye else {
        return (Vec::new(), 0);
    };
    let mut hits = Vec::new();
    let mut rays = 0u64;
    for &x in targets {
        let mut r = Rng(mix(eye_seed ^ mix(x as u64 ^ 0x6f62_6a65_6374)));
        let mut u = || r.f64();
        let mut seen = false;
        for _ in 0..samples {
            let Some(q) = caster.sample_surface(x, &mut u) else {
                break;
            };
            rays += 1;
            match caster.first_hit(eye, q - eye, 1.0 + TARGET_SLACK) {
                Some((o, t)) if t < 1.0 - REACH_TOLERANCE => {
                    if o != crate::scene::TERRAIN_OBJECT {
                        hits.push(o)
                    }
                }
                // Reached (or, by rounding, nothing at all met before the target point).
                _ => {
                    if !seen {
                        hits.push(x);
                        seen = true;
                    }
                }
            }
        }
    }
    hits.sort_unstable();
    hits.dedup();
    (hits, rays)
}

/// The seed of eye `i` of a cell: depends on the params' seed, the cell and heights, and `i`.
fn eye_seed(seed: u64, cell: [f64; 4], eye_z: (f64, f64), i: usize) -> u64 {
    let mut h = mix(seed ^ 0x7665_7965);
    for v in [cell[0], cell[1], cell[2], cell[3], eye_z.0, eye_z.1] {
        h = mix(h ^ v.to_bits());
    }
    mix(h ^ (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15))
}

/// Point `i` of the R2 low-discrepancy sequence (Roberts' generalized golden ratio) in the unit
/// square, shifted by `shift` (mod 1): any prefix of it covers the square evenly.
fn r2(shift: (f64, f64), i: usize) -> (f64, f64) {
    const G: f64 = 1.324_717_957_244_746;
    let (a1, a2) = (1.0 / G, 1.0 / (G * G));
    let k = i as f64 + 1.0;
    ((shift.0 + a1 * k).fract(), (shift.1 + a2 * k).fract())
}

/// [`visible_set`] with the number of rays cast.
pub fn visible_set_counted(
    caster: &Caster,
    scene: &Scene,
    cell: [f64; 4],
    eye_z: (f64, f64),
    p: &TruthParams,
) -> (Vec<u32>, u64) {
    let targets = targets(scene, cell, p.radius);
    let mut sr = Rng(eye_seed(p.seed, cell, eye_z, usize::MAX));
    let shift = (sr.f64(), sr.f64());
    let per_eye: Vec<(Vec<u32>, u64)> = (0..p.eyes)
        .into_par_iter()
        .map(|i| {
            eye_hits(
                caster,
                cell,
                eye_z,
                &targets,
                p.samples_per_object,
                eye_seed(p.seed, cell, eye_z, i),
                r2(shift, i),
                p.eye_above,
            )
        })
        .collect();
    let mut all: Vec<u32> = per_eye
        .iter()
        .flat_map(|(h, _)| h.iter().copied())
        .collect();
    all.sort_unstable();
    all.dedup();
    (all, per_eye.iter().map(|(_, r)| r).sum())
}

/// The visible set of a cell: ascending indices of the objects hit first by some ray from some
/// eye. `cell` is `[x0, y0, x1, y1]` and `eye_z` `(lo, hi)`, local frame. Eyes that land inside
/// an object are drawn again (up to [`EYE_TRIES`] times, then that eye is dropped). A ray whose
/// first hit is within [`REACH_TOLERANCE`] of its target point, or that meets nothing (rounding
/// at a grazing target), counts as reaching the target.
pub fn visible_set(
    caster: &Caster,
    scene: &Scene,
    cell: [f64; 4],
    eye_z: (f64, f64),
    p: &TruthParams,
) -> Vec<u32> {
    visible_set_counted(caster, scene, cell, eye_z, p).0
}

/// One point of a convergence study.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ConvergencePoint {
    pub eyes: usize,
    pub samples_per_object: usize,
    pub rays: u64,
    pub vs: usize,
}

/// |VS| for every combination of `eyes` and `samples` (the rest of the params from `base`), in
/// the order eyes-major. With one seed, the sets are nested: more eyes or samples never lose an
/// object.
pub fn convergence(
    caster: &Caster,
    scene: &Scene,
    cell: [f64; 4],
    eye_z: (f64, f64),
    base: &TruthParams,
    eyes: &[usize],
    samples: &[usize],
) -> Vec<ConvergencePoint> {
    let mut out = Vec::new();
    for &e in eyes {
        for &s in samples {
            let p = TruthParams {
                eyes: e,
                samples_per_object: s,
                ..base.clone()
            };
            let (vs, rays) = visible_set_counted(caster, scene, cell, eye_z, &p);
            out.push(ConvergencePoint {
                eyes: e,
                samples_per_object: s,
                rays,
                vs: vs.len(),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rng_is_uniform_enough() {
        let mut r = Rng(1);
        let n = 10_000;
        let mean = (0..n).map(|_| r.f64()).sum::<f64>() / n as f64;
        assert!((mean - 0.5).abs() < 0.02, "{mean}");
    }

    #[test]
    fn box_distance_is_zero_when_overlapping() {
        let c = [0.0, 0.0, 10.0, 10.0];
        assert_eq!(
            box_distance(DVec2::new(5.0, 5.0), DVec2::new(20.0, 6.0), c),
            0.0
        );
        assert_eq!(
            box_distance(DVec2::new(13.0, 14.0), DVec2::new(20.0, 20.0), c),
            5.0
        );
    }
}
