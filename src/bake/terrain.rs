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
//! ([`crate::scene::Terrain::range`], bounds over the triangles meeting the cell),
//! `g = ground_z0 + L * step <= gmin` and `rise = R * step >= gmax - g`, every camera lies in
//! `[g + eye_lo, g + R * step + eye_hi]`: the cell's stored eye range (format 2.1 stores `R`
//! beside `L`). Rules 2 and 3 take that range as `[e0, e1]`, and the VO's bottom as `g` (or
//! `ground_z0` for a deep VO), unchanged: their proofs hold for any eye range containing the
//! cameras. A cell whose top eye would pass level 255, or that no terrain triangle meets, gets
//! no VO.
//! Invariants: a function of the scene's terrain and the grid alone; `L + R <= 255`.

use glam::DVec2;

use crate::runtime::grid::GridDescriptor;
use crate::scene::Scene;

/// Least step between ground levels, metres.
pub const GROUND_STEP_M: f64 = 0.25;

/// The ground of every cell of a grid on a terrain.
#[derive(Clone, Debug, PartialEq)]
pub struct GroundTable {
    pub ground_z0: f64,
    pub ground_step: f64,
    /// Per cell: its ground level, its rise (ground steps from its level to its highest
    /// ground), and whether it may store VOs (else it stores none).
    pub levels: Vec<u8>,
    pub rises: Vec<u8>,
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
                levels: vec![0; n],
                rises: vec![0; n],
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
        // Rounded up to whole steps; a top eye past level 255 is not stored.
        let rises: Vec<f64> = range
            .iter()
            .zip(&levels)
            .map(|(&(_, b), &l)| ((b - (z0 + l as f64 * step)) / step).ceil().max(0.0))
            .collect();
        let fits: Vec<bool> = rises
            .iter()
            .zip(&levels)
            .map(|(&r, &l)| r.is_finite() && l as f64 + r <= 255.0)
            .collect();
        let rises = rises
            .iter()
            .zip(&fits)
            .map(|(&r, &ok)| if ok { r as u8 } else { 0 })
            .collect();
        Some(GroundTable {
            ground_z0: z0,
            ground_step: step,
            levels,
            rises,
            fits,
            range,
        })
    }
}
