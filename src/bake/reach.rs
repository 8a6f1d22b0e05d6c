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
//! perimeter over pi). In a compact city (Tokyo centre, Lyon, the generated 10^6 city: 30 to 39
//! m, from the boxes below) the default 900 m holds many free paths and closes the wedges a
//! cell's near VOs leave; among free-standing towers (a path of 300 m) or in a city of wide
//! streets (110 m) it stops where the hidden ground only begins, and 1.7 to 1.8 km cull half as
//! much again (README, "How far a cell reaches"). In a low-rise scene (the median object under
//! [`AUTO_REACH_LOW_RISE_M`] tall) a VO hides little far off from every point of a cell, and a
//! longer reach only costs (Salt River's houses, 4 m, path 63 m; README), so it keeps 900 m.
//!
//! Invariants: the reach is a function of the whole scene alone (every shard, region and
//! rebake of one scene gets the same), never below [`SEARCH_M`] (a dense or low-rise city bakes
//! exactly as with `--reach 900`), at most [`AUTO_REACH_MAX_M`], and moves in steps of
//! [`AUTO_REACH_STEP_M`], so an edit of a few buildings seldom moves it. The estimate is coarse
//! and chooses only what is searched: an object's box perimeter is at least its footprint's
//! hull perimeter and walls two buildings share count twice (the path comes out short), while a
//! square at the built ground's edge counts whole unless the scene's rectangle clips it (long).
//! Every reach is equally safe.

use super::params::SEARCH_M;
use crate::scene::Scene;

/// The reach in free paths ([`auto_reach`]): chosen on two stand-ins for issue 31's held-out
/// scenes, so that both reach about 1.7 to 1.8 km (README, "How far a cell reaches"), while
/// every compact bundled scene stays under 900 m.
pub const AUTO_REACH_FREE_PATHS: f64 = 16.0;
/// The longest reach [`auto_reach`] picks, metres: the bake's cost grows with the reach's square
/// where the scene is not sparse (the wide-street stand-in: 1.7 times the cells' summed bake
/// time at 1.7 km), and 1.8 km took the towers' stand-in to within half a point of what 2.5 km
/// culls.
pub const AUTO_REACH_MAX_M: f64 = 1800.0;
/// [`auto_reach`] rounds down to a multiple of this, metres.
pub const AUTO_REACH_STEP_M: f64 = 100.0;
/// A scene whose median object (height from its box) is lower than this, metres, is low-rise
/// and keeps [`SEARCH_M`] (module header).
pub const AUTO_REACH_LOW_RISE_M: f64 = 8.0;

/// The side of the squares whose occupied ones make the ground the buildings stand on, metres
/// ([`mean_free_path`]).
pub const OCCUPIED_SQUARE_M: f64 = 250.0;

/// The mean free path of a horizontal sight line among the scene's objects, metres: `pi A / P`,
/// with `P` the sum of the perimeters of their boxes (objects of no height left out) and `A` the
/// ground they stand on: the squares of [`OCCUPIED_SQUARE_M`] (on a grid from the boxes' lowest
/// corner, clipped to their bounding rectangle) that hold an object's box centre. So a stray
/// object kilometres off, a river or a park adds at most a square, not the bounding rectangle's
/// whole emptiness (which would lengthen the path and so the reach). `None` without two such
/// objects or without area.
pub fn mean_free_path(scene: &Scene) -> Option<f64> {
    let boxes: Vec<_> = scene
        .objects
        .iter()
        .map(|o| o.bbox)
        .filter(|b| {
            b.max.z > b.min.z && (b.max.x - b.min.x).is_finite() && (b.max.y - b.min.y).is_finite()
        })
        .collect();
    if boxes.len() < 2 {
        return None;
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let mut perimeter = 0.0;
    for b in &boxes {
        perimeter += 2.0 * ((b.max.x - b.min.x) + (b.max.y - b.min.y));
        lo = [lo[0].min(b.min.x), lo[1].min(b.min.y)];
        hi = [hi[0].max(b.max.x), hi[1].max(b.max.y)];
    }
    let s = OCCUPIED_SQUARE_M;
    let mut squares: Vec<(i64, i64)> = boxes
        .iter()
        .map(|b| {
            let c = [0.5 * (b.min.x + b.max.x), 0.5 * (b.min.y + b.max.y)];
            (((c[0] - lo[0]) / s) as i64, ((c[1] - lo[1]) / s) as i64)
        })
        .collect();
    squares.sort_unstable();
    squares.dedup();
    let area: f64 = squares
        .iter()
        .map(|&(i, j)| {
            let side = |k: i64, a: usize| (hi[a] - lo[a] - k as f64 * s).clamp(0.0, s);
            side(i, 0) * side(j, 1)
        })
        .sum();
    (area > 0.0 && perimeter > 0.0).then(|| std::f64::consts::PI * area / perimeter)
}

/// The median height of the scene's objects (box top minus box bottom; objects of no height
/// left out), metres; `None` without objects.
pub fn median_height(scene: &Scene) -> Option<f64> {
    let mut h: Vec<f64> = scene
        .objects
        .iter()
        .map(|o| o.bbox.max.z - o.bbox.min.z)
        .filter(|h| *h > 0.0)
        .collect();
    if h.is_empty() {
        return None;
    }
    h.sort_by(f64::total_cmp);
    Some(h[h.len() / 2])
}

/// The reach of `vocc bake --reach auto`, metres: [`SEARCH_M`] in a low-rise scene (median
/// object under [`AUTO_REACH_LOW_RISE_M`]), else [`AUTO_REACH_FREE_PATHS`] mean free paths,
/// rounded down to [`AUTO_REACH_STEP_M`], within [`SEARCH_M`] and [`AUTO_REACH_MAX_M`]
/// ([`SEARCH_M`] when the path is undefined).
pub fn auto_reach(scene: &Scene) -> f64 {
    reach_of(mean_free_path(scene), median_height(scene))
}

/// [`auto_reach`] from the free path and the median height.
pub fn reach_of(path: Option<f64>, median_height: Option<f64>) -> f64 {
    if !median_height.is_some_and(|h| h >= AUTO_REACH_LOW_RISE_M) {
        return SEARCH_M;
    }
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

    /// A scene of 30 m squares, 40 m tall, with lower-left corners at `corners` (metres).
    fn squares(corners: &[(f64, f64)]) -> Scene {
        let b: Vec<([f64; 4], f64)> = corners
            .iter()
            .map(|&(x, y)| ([x, y, x + 30.0, y + 30.0], 40.0))
            .collect();
        crate::scene::boxes_scene(&b)
    }

    /// 15 x 15 squares 60 m apart: they span 870 m, every 250 m square of it holds one, so the
    /// path is pi 870^2 / (225 * 120) = 88.06 m. One more square 5 km off adds one occupied
    /// square (30 m by 30, clipped to the new bounding rectangle) and its perimeter, not the
    /// 5 km of empty ground between (that would make the path 84 km); the district's 4 x 4
    /// squares are now whole (the rectangle no longer clips them at 870 m): 116 m.
    #[test]
    fn the_free_path_counts_the_occupied_ground_not_a_stray_objects_emptiness() {
        let mut c: Vec<(f64, f64)> = (0..225)
            .map(|k| (60.0 * (k % 15) as f64, 60.0 * (k / 15) as f64))
            .collect();
        let pi = std::f64::consts::PI;
        let p = mean_free_path(&squares(&c)).unwrap();
        assert!((p - pi * 870.0 * 870.0 / 27_000.0).abs() < 1e-9, "{p}");
        assert_eq!(auto_reach(&squares(&c)), 1400.0);
        c.push((5000.0, 5000.0));
        let p = mean_free_path(&squares(&c)).unwrap();
        let expected = pi * (16.0 * 250.0 * 250.0 + 30.0 * 30.0) / (226.0 * 120.0);
        assert!((p - expected).abs() < 1e-9, "{p} against {expected}");
        assert_eq!(auto_reach(&squares(&c)), AUTO_REACH_MAX_M);
        assert_eq!(mean_free_path(&squares(&c[..1])), None);
    }

    #[test]
    fn a_dense_or_low_city_keeps_the_default_and_a_sparse_one_reaches_further_in_steps() {
        let tall = Some(AUTO_REACH_LOW_RISE_M);
        assert_eq!(reach_of(None, tall), SEARCH_M);
        assert_eq!(reach_of(Some(f64::INFINITY), tall), SEARCH_M);
        // Tokyo centre, Lyon, the generated 10^6 city.
        for p in [31.6, 29.5, 39.2, 56.2] {
            assert_eq!(reach_of(Some(p), tall), SEARCH_M, "{p}");
        }
        // The wide-street stand-in, the towers' (README).
        assert_eq!(reach_of(Some(111.0), Some(12.0)), 1700.0);
        assert_eq!(reach_of(Some(298.1), Some(101.1)), AUTO_REACH_MAX_M);
        assert_eq!(reach_of(Some(88.06), tall), 1400.0);
        // Salt River's houses: low-rise, whatever the path.
        assert_eq!(reach_of(Some(62.8), Some(4.1)), SEARCH_M);
        assert_eq!(reach_of(Some(62.8), None), SEARCH_M);
        let mut last = 0.0;
        for k in 0..2000 {
            let r = reach_of(Some(k as f64), tall);
            assert!(r >= last && r % AUTO_REACH_STEP_M == 0.0, "{k}: {r}");
            assert!((SEARCH_M..=AUTO_REACH_MAX_M).contains(&r), "{k}: {r}");
            last = r;
        }
    }
}
