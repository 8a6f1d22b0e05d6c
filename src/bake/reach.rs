//! How far a cell's own search reaches when the user does not say (`vocc bake --reach auto`, the
//! default): from how far a sight line travels among the scene's buildings before it meets one.
//!
//! Input: a loaded [`Scene`] (its objects' boxes; the terrain is not counted). Output: the mean
//! free path of a horizontal sight line ([`mean_free_path`]) and the reach it gives
//! ([`auto_reach`]), which the caller passes to [`super::params::BakeParams::with_reach`].
//!
//! Why: a VO must be hidden from every point of its cell, so it stands where the buildings' fused
//! occlusion has closed over every sight line from the cell. Among buildings scattered with a
//! mean width `w` per `A / n` of ground, a sight line meets the next one after about `A / (n w)`
//! metres (the mean free path; by Cauchy's formula a convex footprint's mean width is its
//! perimeter over pi), and the ground hidden from a whole 100 m cell lies several free paths out.
//! In a compact city (Tokyo centre, Lyon: 32 to 38 m, from the boxes below) the default 900 m
//! reaches far past that; in a district of free-standing towers (a path of 300 m) it stops where
//! the hidden ground only begins, and a reach of 6 free paths culls half as much again (README,
//! "How far a cell reaches").
//!
//! Invariants: the reach is a function of the whole scene alone (every shard, region and
//! rebake of one scene gets the same), never below [`SEARCH_M`] (a dense city bakes exactly as
//! with `--reach 900`), at most [`AUTO_REACH_MAX_M`], and moves in steps of
//! [`AUTO_REACH_STEP_M`], so an edit of a few buildings does not move it. The estimate errs
//! short: an object's box perimeter is at least its footprint's hull perimeter, and walls two
//! buildings share count twice. Every reach is equally safe; this only chooses what is searched.

use super::params::SEARCH_M;
use crate::scene::Scene;

/// The reach in free paths ([`auto_reach`]).
pub const AUTO_REACH_FREE_PATHS: f64 = 6.0;
/// The longest reach [`auto_reach`] picks, metres: the bake's cost grows with the reach's square
/// where the scene is not sparse, and 1.8 km took the towers' district (module header) to within
/// a point of what 2.5 km culls.
pub const AUTO_REACH_MAX_M: f64 = 1800.0;
/// [`auto_reach`] rounds down to a multiple of this, metres.
pub const AUTO_REACH_STEP_M: f64 = 100.0;

/// The mean free path of a horizontal sight line among the scene's objects, metres: `pi A / P`,
/// with `A` the area of the objects' bounding rectangle and `P` the sum of the perimeters of
/// their boxes (objects of no height left out). `None` without two such objects or without area.
pub fn mean_free_path(scene: &Scene) -> Option<f64> {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let (mut perimeter, mut n) = (0.0, 0usize);
    for o in &scene.objects {
        let b = o.bbox;
        let (w, d) = (b.max.x - b.min.x, b.max.y - b.min.y);
        if !(b.max.z > b.min.z) || !w.is_finite() || !d.is_finite() {
            continue;
        }
        perimeter += 2.0 * (w + d);
        n += 1;
        lo = [lo[0].min(b.min.x), lo[1].min(b.min.y)];
        hi = [hi[0].max(b.max.x), hi[1].max(b.max.y)];
    }
    let area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
    (n >= 2 && area > 0.0 && perimeter > 0.0).then(|| std::f64::consts::PI * area / perimeter)
}

/// The reach of `vocc bake --reach auto`, metres: [`AUTO_REACH_FREE_PATHS`] mean free paths,
/// rounded down to [`AUTO_REACH_STEP_M`], within [`SEARCH_M`] and [`AUTO_REACH_MAX_M`]
/// ([`SEARCH_M`] when the path is undefined).
pub fn auto_reach(scene: &Scene) -> f64 {
    reach_of_free_path(mean_free_path(scene))
}

/// [`auto_reach`] from the free path.
pub fn reach_of_free_path(path: Option<f64>) -> f64 {
    match path {
        Some(p) if p.is_finite() => {
            let r = (AUTO_REACH_FREE_PATHS * p / AUTO_REACH_STEP_M).floor() * AUTO_REACH_STEP_M;
            r.clamp(SEARCH_M, AUTO_REACH_MAX_M)
        }
        _ => SEARCH_M,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dense_city_keeps_the_default_and_a_sparse_one_reaches_further_in_steps() {
        assert_eq!(reach_of_free_path(None), SEARCH_M);
        assert_eq!(reach_of_free_path(Some(f64::INFINITY)), SEARCH_M);
        assert_eq!(reach_of_free_path(Some(32.0)), SEARCH_M);
        assert_eq!(reach_of_free_path(Some(149.9)), SEARCH_M);
        assert_eq!(reach_of_free_path(Some(200.0)), 1200.0);
        assert_eq!(reach_of_free_path(Some(216.0)), 1200.0);
        assert_eq!(reach_of_free_path(Some(298.1)), 1700.0);
        assert_eq!(reach_of_free_path(Some(5000.0)), AUTO_REACH_MAX_M);
        let mut last = 0.0;
        for k in 0..2000 {
            let r = reach_of_free_path(Some(k as f64));
            assert!(r >= last && r % AUTO_REACH_STEP_M == 0.0, "{k}: {r}");
            last = r;
        }
    }
}
