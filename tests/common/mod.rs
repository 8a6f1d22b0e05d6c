//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

use vocc::scene::{self, ReadOptions, Scene};

/// A path inside the repository.
pub fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

pub const LYON: &str = "data/lyon1/buildings_lyon1.geojson";

pub fn lyon_options() -> ReadOptions {
    ReadOptions {
        height_attr: Some("HAUTEUR".into()),
        ..ReadOptions::default()
    }
}

pub fn load_lyon() -> Scene {
    scene::load(&[repo(LYON)], &lyon_options()).expect("Lyon loads")
}

/// A fresh temporary directory under the target dir, unique per test name.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

use glam::DVec2;
use vocc::geom::predicates::{point_in_convex, segment_meets_convex, Containment};

/// Brute-force oracle, independent of the verifier: is `q` hidden from the convex `cell`? Casts
/// exact segments from `q` to `n` points just inside the cell's boundary and to points near each
/// vertex; `q` is visible if any of them misses every blocker. (If `q` sees any point of the
/// cell it sees a boundary point, so boundary sampling suffices up to its density.)
pub fn brute_hidden(cell: &[DVec2], blockers: &[Vec<DVec2>], q: DVec2, n: usize) -> bool {
    if point_in_convex(cell, q) != Containment::Outside {
        return false;
    }
    let centre = cell.iter().copied().sum::<DVec2>() / cell.len() as f64;
    let perimeter: f64 = (0..cell.len())
        .map(|i| cell[i].distance(cell[(i + 1) % cell.len()]))
        .sum();
    let mut targets: Vec<DVec2> = Vec::with_capacity(n + cell.len());
    for k in 0..n {
        let mut d = perimeter * (k as f64 + 0.5) / n as f64;
        for i in 0..cell.len() {
            let (a, b) = (cell[i], cell[(i + 1) % cell.len()]);
            let len = a.distance(b);
            if d <= len {
                targets.push(a + (b - a) * (d / len));
                break;
            }
            d -= len;
        }
    }
    targets.extend(cell.iter().copied());
    targets.iter().all(|&t| {
        // Pull the target a hair inside so it surely belongs to the cell.
        let c = centre + (t - centre) * (1.0 - 1e-9);
        debug_assert!(point_in_convex(cell, c) != Containment::Outside);
        blockers.iter().any(|b| segment_meets_convex(q, c, b))
    })
}

/// Points exactly on `[a, b]` at parameters k / 2^levels (exact for dyadic endpoints).
pub fn dyadic_points(a: DVec2, b: DVec2, levels: u32) -> Vec<DVec2> {
    let n = 1u32 << levels;
    (0..=n)
        .map(|k| {
            let t = k as f64 / n as f64;
            let p = a + (b - a) * t;
            assert_eq!(p, a * (1.0 - t) + b * t, "sample point is not exact");
            p
        })
        .collect()
}
