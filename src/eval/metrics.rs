//! Metrics: each sampled cell's PVS (from the store, as the runtime builds it) against its
//! ground-truth visible set (from [`super::truth`], which never reads VOs).
//!
//! Input: a scene, a store's bytes for that scene, the ray caster and sampling parameters.
//! Output: per cell, |VS|, |PVS| (objects and triangles), the false culls (objects of the VS
//! missing from the PVS: must be none), the PVS build time, and the same PVS sizes with only the
//! first k stored VOs (k = 1..10, the paper's Table 1); and a summary over cells.
//! Invariants: the PVS comes from [`crate::runtime::culler::pvs`] on the decoded bytes, exactly
//! what an engine computes; the VS comes from rays against the original geometry; the two share
//! only the scene.

use std::time::Instant;

use crate::runtime::culler::{pvs, BoxTree};
use crate::runtime::format::{CellRecord, Store};
use crate::runtime::frame::MAX_VOS_PER_CELL;
use crate::runtime::CellId;
use crate::scene::Scene;

use super::raycast::Caster;
use super::truth::{visible_set, TruthParams};

/// One evaluated cell.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct CellEval {
    pub cell: CellId,
    pub vos: usize,
    pub vs: usize,
    pub pvs: usize,
    pub vs_triangles: u64,
    pub pvs_triangles: u64,
    /// Objects of the VS that the PVS misses (ascending). Must be empty.
    pub false_culls: Vec<u32>,
    /// PVS build time, µs (one run, after a warm-up run).
    pub pvs_us: f64,
    /// |PVS| with only the first k stored VOs, k = 0..=10 (k = 0: every object); empty when not
    /// measured.
    pub pvs_by_vos: Vec<usize>,
    /// Objects of the PVS outside the VS (kept, yet hidden), by the distance from the cell's
    /// centre to the centre of their box, in the bands of [`EXCESS_BANDS_M`] (within the first,
    /// then between each two, then beyond the last): where the culling falls short. Empty when
    /// not measured.
    pub excess_by_distance: Vec<usize>,
}

/// The distance bands of [`CellEval::excess_by_distance`], metres: near VOs serve the first
/// (a cell's own search reaches 900 m by default), the far field the others.
pub const EXCESS_BANDS_M: [f64; 3] = [300.0, 1000.0, 3000.0];

/// The names of the bands of [`EXCESS_BANDS_M`], for reports: "within 300 m", "at 300 m to
/// 1 km", "at 1 to 3 km", "beyond 3 km".
pub fn excess_band_names() -> Vec<String> {
    let km = |m: f64| m >= 1000.0;
    let name = |m: f64| {
        if km(m) {
            format!("{} km", m / 1000.0)
        } else {
            format!("{m} m")
        }
    };
    let b = EXCESS_BANDS_M;
    let mut names = vec![format!("within {}", name(b[0]))];
    for w in b.windows(2) {
        let lo = if km(w[0]) && km(w[1]) {
            format!("{}", w[0] / 1000.0)
        } else {
            name(w[0])
        };
        names.push(format!("at {lo} to {}", name(w[1])));
    }
    names.push(format!("beyond {}", name(b[b.len() - 1])));
    names
}

/// The objects of `pvs` outside `vs` (both ascending) by the distance of their box centre from
/// `centre` ([`CellEval::excess_by_distance`]).
pub fn excess_by_distance(scene: &Scene, centre: [f64; 2], vs: &[u32], pvs: &[u32]) -> Vec<usize> {
    let mut bands = vec![0; EXCESS_BANDS_M.len() + 1];
    for &i in pvs {
        if vs.binary_search(&i).is_ok() {
            continue;
        }
        let Some(o) = scene.objects.get(i as usize) else {
            continue;
        };
        let c = 0.5 * (o.bbox.min + o.bbox.max);
        let d = (c.x - centre[0]).hypot(c.y - centre[1]);
        bands[EXCESS_BANDS_M.iter().take_while(|&&b| d > b).count()] += 1;
    }
    bands
}

impl CellEval {
    /// |PVS| / |VS| in objects (1 when both are empty).
    pub fn ratio(&self) -> f64 {
        ratio(self.pvs as f64, self.vs as f64)
    }

    /// |PVS| / |VS| in triangles.
    pub fn ratio_triangles(&self) -> f64 {
        ratio(self.pvs_triangles as f64, self.vs_triangles as f64)
    }
}

fn ratio(a: f64, b: f64) -> f64 {
    if b > 0.0 {
        a / b
    } else if a > 0.0 {
        f64::INFINITY
    } else {
        1.0
    }
}

/// The object boxes of a scene, local frame, by object index.
pub fn object_boxes(scene: &Scene) -> Vec<[f64; 6]> {
    scene
        .objects
        .iter()
        .map(|o| {
            let (a, b) = (o.bbox.min, o.bbox.max);
            [a.x, a.y, a.z, b.x, b.y, b.z]
        })
        .collect()
}

/// Cells to evaluate: every non-skipped cell of the grid, or a seeded sample of `n` of them
/// (ascending).
pub fn sample_cells(store: &Store, n: Option<usize>, seed: u64) -> Vec<CellId> {
    let mut all: Vec<CellId> = (0..store.cell_count())
        .filter(|&id| !matches!(store.cell(id), Ok(CellRecord::Skipped) | Err(_)))
        .collect();
    if let Some(n) = n {
        // Partial Fisher–Yates with splitmix64: deterministic for a seed.
        let mut state = seed ^ 0x9e37_79b9_7f4a_7c15;
        let mut next = || {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        };
        let k = n.min(all.len());
        for i in 0..k {
            let j = i + (next() % (all.len() - i) as u64) as usize;
            all.swap(i, j);
        }
        all.truncate(k);
        all.sort_unstable();
    }
    all
}

/// A record with only its first `k` VOs.
fn truncated(rec: &CellRecord, k: usize) -> CellRecord {
    match rec {
        CellRecord::Skipped => CellRecord::Skipped,
        CellRecord::Vos { ground, rise, vos } => CellRecord::new(*ground, &vos[..k.min(vos.len())])
            .map_or(CellRecord::EMPTY, |r| r.with_rise(*rise)),
    }
}

/// The ground-truth visible set of a store's cell (its rectangle and eye heights).
pub fn cell_vs(
    scene: &Scene,
    store: &Store,
    caster: &Caster,
    id: CellId,
    truth: &TruthParams,
) -> Vec<u32> {
    let f = store.frame();
    let rec = store.cell(id).unwrap_or(CellRecord::EMPTY);
    let rect = f.grid.cell_rect(id).unwrap_or([0.0; 4]);
    let view = f.cell_view(id, rec.stand());
    let (e0, e1) = view.map(|v| (v.e0, v.e1)).unwrap_or((0.0, 0.0));
    // On a terrain, eyes stand on it at the frame's eye heights over the whole cell.
    let truth = TruthParams {
        eye_above: Some((f.eye_lo, f.eye_hi)),
        ..truth.clone()
    };
    visible_set(caster, scene, rect, (e0, e1), &truth)
}

/// Evaluates one cell against its visible set `vs` (ascending).
pub fn eval_cell(scene: &Scene, store: &Store, tree: &BoxTree, id: CellId, vs: &[u32]) -> CellEval {
    let f = store.frame();
    let rec = store.cell(id).unwrap_or(CellRecord::EMPTY);
    let mut out = Vec::new();
    pvs(f, id, &rec, tree, &mut out);
    let t = Instant::now();
    pvs(f, id, &rec, tree, &mut out);
    let pvs_us = t.elapsed().as_secs_f64() * 1e6;
    let mut by = Vec::with_capacity(MAX_VOS_PER_CELL + 1);
    let mut tmp = Vec::new();
    for k in 0..=MAX_VOS_PER_CELL {
        pvs(f, id, &truncated(&rec, k), tree, &mut tmp);
        by.push(tmp.len());
    }
    let excess = f
        .cell_centre(id)
        .map(|c| excess_by_distance(scene, c, vs, &out))
        .unwrap_or_default();
    CellEval {
        pvs_us,
        pvs_by_vos: by,
        excess_by_distance: excess,
        ..compare(scene, id, rec.vos().len(), vs, &out)
    }
}

/// A cell's PVS (ascending) against its VS: sizes, triangles, false culls (no timing, no VO
/// sweep).
pub fn compare(scene: &Scene, id: CellId, vos: usize, vs: &[u32], pvs: &[u32]) -> CellEval {
    let tris = |ids: &[u32]| -> u64 {
        ids.iter()
            .map(|&i| scene.objects.get(i as usize).map_or(0, |o| o.cost))
            .sum()
    };
    CellEval {
        cell: id,
        vos,
        vs: vs.len(),
        pvs: pvs.len(),
        vs_triangles: tris(vs),
        pvs_triangles: tris(pvs),
        false_culls: vs
            .iter()
            .copied()
            .filter(|i| pvs.binary_search(i).is_err())
            .collect(),
        ..CellEval::default()
    }
}

/// The PVS of cell `view` from VO geometries (no quantization), by rule 3 box by box: for the
/// quantization sweep.
pub fn pvs_from_geoms(
    view: &crate::runtime::CellView,
    geoms: &[crate::runtime::VoGeom],
    boxes: &[[f64; 6]],
) -> Vec<u32> {
    use crate::runtime::occlusion::{Cover, PreparedVo};
    let prepared: Vec<PreparedVo> = geoms.iter().map(|g| PreparedVo::new(view, g)).collect();
    (0..boxes.len() as u32)
        .filter(|&i| {
            !prepared
                .iter()
                .any(|p| p.cover(view, &boxes[i as usize]) == Cover::Hidden)
        })
        .collect()
}

/// The 3D check of a cell's stored VOs (docs/DESIGN.md section 6.2): rays from sampled eye points of
/// the cell to sampled points of every stored VO quad must hit the original geometry before they
/// reach the VO. This checks rule 2 (and rule 1) end to end, with the ray caster of the ground
/// truth, on the VOs as the runtime decodes them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct VoRays {
    /// Rays cast.
    pub rays: u64,
    /// Rays that reached a VO without meeting any geometry: each one a counterexample.
    pub reached: u64,
}

/// Casts `eyes` x `points` rays per stored VO of cell `id` (seeded; eyes inside an object are
/// skipped, as the ground truth skips them).
pub fn vo_rays(
    caster: &Caster,
    store: &Store,
    id: CellId,
    eyes: usize,
    points: usize,
    seed: u64,
) -> VoRays {
    use glam::DVec3;
    let f = store.frame();
    let rec = store.cell(id).unwrap_or(CellRecord::EMPTY);
    let (Some(r), Some(view)) = (f.grid.cell_rect(id), f.cell_view(id, rec.stand())) else {
        return VoRays::default();
    };
    // On a terrain, eyes stand on it at the frame's eye heights (a camera on the ground).
    let eye_above = Some((f.eye_lo, f.eye_hi));
    let mut state = seed ^ (id as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    let mut u = move || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut out = VoRays::default();
    for q in rec.vos() {
        let Some(g) = f.dequantize(id, rec.stand(), q) else {
            continue;
        };
        for _ in 0..eyes {
            let (x, y, s) = (r[0] + u() * (r[2] - r[0]), r[1] + u() * (r[3] - r[1]), u());
            // On the terrain where there is one (a camera on the ground), as the ground truth.
            let ground =
                eye_above.and_then(|e| Some((e, caster.ground_height(glam::DVec2::new(x, y))?)));
            let z = match ground {
                Some(((lo, hi), g)) => g + lo + s * (hi - lo),
                None => view.e0 + s * (view.e1 - view.e0),
            };
            let eye = DVec3::new(x, y, z);
            if caster.contains(eye).is_some() {
                continue;
            }
            for _ in 0..points {
                let t = u();
                let p = DVec3::new(
                    g.a[0] + t * (g.b[0] - g.a[0]),
                    g.a[1] + t * (g.b[1] - g.a[1]),
                    g.g + u() * (g.h - g.g),
                );
                out.rays += 1;
                // Hit strictly before the VO (a hit within 1e-9 of it does not count).
                if caster.first_hit(eye, p - eye, 1.0 - 1e-9).is_none() {
                    out.reached += 1;
                }
            }
        }
    }
    out
}

/// [`vo_rays`] over many cells, in parallel, summed.
pub fn vo_rays_all(
    caster: &Caster,
    store: &Store,
    ids: &[CellId],
    eyes: usize,
    points: usize,
    seed: u64,
) -> VoRays {
    use rayon::prelude::*;
    ids.par_iter()
        .map(|&id| vo_rays(caster, store, id, eyes, points, seed))
        .reduce(VoRays::default, |a, b| VoRays {
            rays: a.rays + b.rays,
            reached: a.reached + b.reached,
        })
}

/// A summary over cells.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Summary {
    pub cells: usize,
    pub objects: usize,
    pub false_culls: usize,
    pub median_ratio: f64,
    pub median_ratio_triangles: f64,
    pub mean_vs: f64,
    pub mean_pvs: f64,
    /// Mean share of the scene's objects culled.
    pub occluded_share: f64,
    /// Mean share of the scene's triangles culled.
    pub occluded_share_triangles: f64,
    pub median_pvs_us: f64,
    pub p95_pvs_us: f64,
    /// Mean occluded share with the first k VOs, k = 0..=10.
    pub occluded_by_vos: Vec<f64>,
    pub mean_vos: f64,
    /// Mean of [`CellEval::excess_by_distance`] over the cells that measured it, band by band
    /// (empty when none did).
    pub mean_excess_by_distance: Vec<f64>,
}

pub fn percentile(v: &[f64], p: f64) -> f64 {
    let mut v: Vec<f64> = v.iter().copied().filter(|x| !x.is_nan()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

pub fn summarize(scene: &Scene, cells: &[CellEval]) -> Summary {
    let n = cells.len().max(1) as f64;
    let objects = scene.objects.len();
    let total_tris: u64 = scene.objects.iter().map(|o| o.cost).sum();
    let mean = |f: &dyn Fn(&CellEval) -> f64| cells.iter().map(f).sum::<f64>() / n;
    Summary {
        cells: cells.len(),
        objects,
        false_culls: cells.iter().map(|c| c.false_culls.len()).sum(),
        median_ratio: percentile(&cells.iter().map(|c| c.ratio()).collect::<Vec<_>>(), 0.5),
        median_ratio_triangles: percentile(
            &cells
                .iter()
                .map(|c| c.ratio_triangles())
                .collect::<Vec<_>>(),
            0.5,
        ),
        mean_vs: mean(&|c| c.vs as f64),
        mean_pvs: mean(&|c| c.pvs as f64),
        occluded_share: mean(&|c| 1.0 - c.pvs as f64 / objects.max(1) as f64),
        occluded_share_triangles: mean(&|c| {
            1.0 - c.pvs_triangles as f64 / total_tris.max(1) as f64
        }),
        median_pvs_us: percentile(&cells.iter().map(|c| c.pvs_us).collect::<Vec<_>>(), 0.5),
        p95_pvs_us: percentile(&cells.iter().map(|c| c.pvs_us).collect::<Vec<_>>(), 0.95),
        occluded_by_vos: (0..=MAX_VOS_PER_CELL)
            .map(|k| {
                mean(&|c| {
                    let p = c.pvs_by_vos.get(k).copied().unwrap_or(c.pvs);
                    1.0 - p as f64 / objects.max(1) as f64
                })
            })
            .collect(),
        mean_vos: mean(&|c| c.vos as f64),
        mean_excess_by_distance: {
            let measured: Vec<&CellEval> = cells
                .iter()
                .filter(|c| c.excess_by_distance.len() == EXCESS_BANDS_M.len() + 1)
                .collect();
            if measured.is_empty() {
                Vec::new()
            } else {
                (0..=EXCESS_BANDS_M.len())
                    .map(|k| {
                        measured
                            .iter()
                            .map(|c| c.excess_by_distance[k] as f64)
                            .sum::<f64>()
                            / measured.len() as f64
                    })
                    .collect()
            }
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn excess_band_names_read_as_the_report_prints_them() {
        assert_eq!(
            excess_band_names(),
            [
                "within 300 m",
                "at 300 m to 1 km",
                "at 1 to 3 km",
                "beyond 3 km"
            ]
        );
    }
}
