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
//! perimeter over pi). In a compact city (Tokyo centre, Lyon, the generated 10^6 city: 32 to 39
//! m, from the boxes below) the default 900 m holds many free paths and closes the wedges a
//! cell's near VOs leave; among free-standing towers (a path of 300 m) or in a city of wide
//! streets (110 m) it stops where the hidden ground only begins, and 1.7 to 1.8 km cull half as
//! much again (README, "How far a cell reaches"). In a low-rise scene (the median object under
//! [`AUTO_REACH_LOW_RISE_M`] tall) a VO hides little far off from every point of a cell, and a
//! longer reach only costs (Salt River's houses, 4 m, path 129 m; README), so it keeps 900 m.
//!
//! Invariants: the reach is a function of the whole scene alone (every shard, region and
//! rebake of one scene gets the same), never below [`SEARCH_M`] (a dense or low-rise city bakes
//! exactly as with `--reach 900`), at most [`AUTO_REACH_MAX_M`], and moves in steps of
//! [`AUTO_REACH_STEP_M`], so an edit of a few buildings seldom moves it. The estimate errs
//! short: an object's box perimeter is at least its footprint's hull perimeter, and walls two
//! buildings share count twice. Every reach is equally safe; this only chooses what is searched.

use super::params::SEARCH_M;
use crate::scene::Scene;

/// The reach in free paths ([`auto_reach`]): chosen on two stand-ins for issue 31's held-out
/// scenes, so that both reach about 1.7 to 1.8 km (README, "How far a cell reaches"), while
/// every compact bundled scene stays under 900 m.
pub const AUTO_REACH_FREE_PATHS: f64 = 16.0;
/// The longest reach [`auto_reach`] picks, metres: the bake's cost grows with the reach's square
/// where the scene is not sparse (the wide-street stand-in: 2.2 times the bake at 1.8 km), and
/// 1.8 km took the towers' stand-in to within half a point of what 2.5 km culls.
pub const AUTO_REACH_MAX_M: f64 = 1800.0;
/// [`auto_reach`] rounds down to a multiple of this, metres.
pub const AUTO_REACH_STEP_M: f64 = 100.0;
/// A scene whose median object (height from its box) is lower than this, metres, is low-rise
/// and keeps [`SEARCH_M`] (module header).
pub const AUTO_REACH_LOW_RISE_M: f64 = 8.0;

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

    #[test]
    fn a_dense_or_low_city_keeps_the_default_and_a_sparse_one_reaches_further_in_steps() {
        let tall = Some(AUTO_REACH_LOW_RISE_M);
        assert_eq!(reach_of(None, tall), SEARCH_M);
        assert_eq!(reach_of(Some(f64::INFINITY), tall), SEARCH_M);
        // Tokyo centre, Lyon, the generated 10^6 city.
        for p in [32.0, 38.4, 39.2, 56.2] {
            assert_eq!(reach_of(Some(p), tall), SEARCH_M, "{p}");
        }
        // The wide-street stand-in, the towers' (README).
        assert_eq!(reach_of(Some(111.0), Some(12.0)), 1700.0);
        assert_eq!(reach_of(Some(298.1), Some(101.1)), AUTO_REACH_MAX_M);
        assert_eq!(reach_of(Some(88.06), tall), 1400.0);
        // Salt River's houses: low-rise, whatever the path.
        assert_eq!(reach_of(Some(129.0), Some(4.1)), SEARCH_M);
        assert_eq!(reach_of(Some(129.0), None), SEARCH_M);
        let mut last = 0.0;
        for k in 0..2000 {
            let r = reach_of(Some(k as f64), tall);
            assert!(r >= last && r % AUTO_REACH_STEP_M == 0.0, "{k}: {r}");
            assert!((SEARCH_M..=AUTO_REACH_MAX_M).contains(&r), "{k}: {r}");
            last = r;
        }
    }
}
