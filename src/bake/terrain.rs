//! Cells on the terrain: each cell's ground range, the frame's ground levels and the eye range
//! that covers a camera standing anywhere on a cell's ground.
//!
//! Input: a scene with a terrain ([`crate::scene::Terrain`]), the grid and the eye heights
//! `[eye_lo, eye_hi]` above the ground. Output: [`GroundTable`]: per cell, its ground level `L`
//! (the least terrain height over the cell, rounded down to a level) and whether its eyes fit
//! the frame; the frame's `ground_z0`, `ground_step` and the rise `R` added to `eye_hi`.
//!
//! ## The eye range (ARCHITECTURE.md, "Eyes on the terrain")
//! A camera stands at `T(p) + e`, `e` in `[eye_lo, eye_hi]`, over a point `p` of the cell where
//! the terrain is (and, where the terrain has a hole, between the least and greatest heights of
//! the triangles that meet the cell). With `gmin <= T(p) <= gmax` over the cell
//! ([`crate::scene::Terrain::range`], bounds over the triangles meeting the cell) and
//! `g = ground_z0 + L * step <= gmin`, every camera lies in `[g + eye_lo, g + rise + eye_hi]`
//! whenever `rise >= gmax - g`. The store keeps one rise for all cells, in the frame:
//! `eye_hi(frame) = eye_hi + R`. A cell whose own rise `gmax - g` exceeds `R` (a steep cell)
//! gets no VO (it culls nothing), so the stored eye range `[g + eye_lo, g + eye_hi(frame)]` of
//! every cell with VOs holds every camera of that cell. Rules 2 and 3 take that range as
//! `[e0, e1]` and the VO's bottom as `g`, unchanged: their proofs hold for any eye range
//! containing the cameras.
//! Invariants: a function of the scene's terrain, the grid and the eye heights alone (so of
//! what the frame records); cells with no terrain triangle get no VO.

use glam::DVec2;

use crate::runtime::grid::GridDescriptor;
use crate::scene::Scene;

/// The share of cells whose rise the frame's rise covers: the others (the steepest) get no VO.
pub const RISE_QUANTILE: f64 = 0.9;
/// Least step between ground levels, metres.
pub const GROUND_STEP_M: f64 = 0.25;

/// The ground of every cell of a grid on a terrain.
#[derive(Clone, Debug, PartialEq)]
pub struct GroundTable {
    pub ground_z0: f64,
    pub ground_step: f64,
    /// Added to the eyes' top height above the ground in the frame, metres.
    pub rise: f64,
    /// Per cell: its ground level, and whether a camera anywhere on its ground stands within
    /// the frame's eye range (else the cell stores no VO).
    pub levels: Vec<u8>,
    pub fits: Vec<bool>,
    /// Per cell, the least and greatest terrain height (NaN where no triangle meets the cell).
    pub range: Vec<(f64, f64)>,
}

fn pow2_at_least(x: f64) -> f64 {
    let mut q = 1.0f64 / 1024.0;
    while q < x {
        q *= 2.0;
    }
    q
}

impl GroundTable {
    /// The table of `grid` (local frame) on the scene's terrain; `None` without a terrain.
    pub fn new(scene: &Scene, grid: &GridDescriptor) -> Option<GroundTable> {
        let t = scene.terrain.as_ref()?;
        let n = grid.cell_count() as usize;
        let range: Vec<(f64, f64)> = (0..n as u32)
            .map(|id| {
                let r = grid.cell_rect(id).unwrap_or([0.0; 4]);
                t.range(DVec2::new(r[0], r[1]), DVec2::new(r[2], r[3]))
                    .unwrap_or((f64::NAN, f64::NAN))
            })
            .collect();
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for &(a, _) in &range {
            if a.is_finite() {
                lo = lo.min(a);
                hi = hi.max(a);
            }
        }
        if !(lo <= hi) {
            return Some(GroundTable {
                ground_z0: 0.0,
                ground_step: 0.0,
                rise: 0.0,
                levels: vec![0; n],
                fits: vec![false; n],
                range,
            });
        }
        let z0 = lo.floor();
        let step = pow2_at_least(((hi - z0) / 255.0).max(GROUND_STEP_M));
        let level = |g: f64| ((g - z0) / step).floor().clamp(0.0, 255.0) as u8;
        let levels: Vec<u8> = range
            .iter()
            .map(|&(a, _)| if a.is_finite() { level(a) } else { 0 })
            .collect();
        let rises: Vec<f64> = range
            .iter()
            .zip(&levels)
            .map(|(&(_, b), &l)| b - (z0 + l as f64 * step))
            .collect();
        let mut sorted: Vec<f64> = rises.iter().copied().filter(|r| r.is_finite()).collect();
        sorted.sort_by(f64::total_cmp);
        let quantile = std::env::var("VOCC_RISE_Q")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(RISE_QUANTILE);
        let q = sorted[((sorted.len() - 1) as f64 * quantile).round() as usize];
        if std::env::var_os("VOCC_DEBUG_RISE").is_some() {
            let pick = |p: f64| sorted[((sorted.len() - 1) as f64 * p).round() as usize];
            eprintln!(
                "rises: p10 {:.2} p25 {:.2} p50 {:.2} p75 {:.2} p90 {:.2} max {:.2}",
                pick(0.1),
                pick(0.25),
                pick(0.5),
                pick(0.75),
                pick(0.9),
                pick(1.0)
            );
        }
        // On the step grid, so that the frame's eye height reads back exactly.
        let rise = (q / GROUND_STEP_M).ceil() * GROUND_STEP_M;
        let fits = rises.iter().map(|&r| r.is_finite() && r <= rise).collect();
        Some(GroundTable {
            ground_z0: z0,
            ground_step: step,
            rise,
            levels,
            fits,
            range,
        })
    }
}
