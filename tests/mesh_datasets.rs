//! Real-data tests of the mesh readers and solid extraction.
//!
//! Input: the repo copies of the Den Haag (CityJSON 0.8 and OBJ), Delft (CityJSON 2.0 and OBJ)
//! and Gelderseplein (OBJ) datasets under `data/`. Output: assertions on object counts, other
//! types, and how many objects gave blockers (solid prisms, walls) or none and why (figures
//! measured on these files).
//! Invariant: every blocker is a convex piece (strictly convex and counter-clockwise, or a
//! 2-vertex wall), has top above base, and lies within its object's bounding box.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use vocc::geom::predicates::is_convex_piece;
use vocc::scene::{load, ReadOptions, Scene};

fn data(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("data")
        .join(rel)
}

struct Summary {
    objects: usize,
    with_blockers: usize,
    /// Objects with a solid prism, and with a wall.
    with_prisms: usize,
    with_walls: usize,
    without: BTreeMap<String, usize>,
    pieces: usize,
    walls: usize,
}

fn load_one(rel: &str) -> (Scene, Summary) {
    let t = Instant::now();
    let scene = load(&[data(rel)], &ReadOptions::default()).unwrap();
    let secs = t.elapsed().as_secs_f64();
    let mut has = vec![false; scene.objects.len()];
    let mut prism = vec![false; scene.objects.len()];
    let mut wall = vec![false; scene.objects.len()];
    for b in &scene.blockers {
        has[b.object as usize] = true;
        if b.polygon.len() == 2 {
            wall[b.object as usize] = true;
        } else {
            prism[b.object as usize] = true;
        }
        assert!(is_convex_piece(&b.polygon), "{b:?}");
        assert!(b.top > b.base);
        let bb = scene.objects[b.object as usize].bbox;
        for p in &b.polygon {
            assert!(p.x >= bb.min.x && p.x <= bb.max.x && p.y >= bb.min.y && p.y <= bb.max.y);
        }
        // A blocker joined with the solid ground under it (scene/terrain.rs) reaches down to
        // the terrain's floor; every other lies in its object.
        let floor = scene.terrain.as_ref().map(|t| t.floor);
        assert!((b.base >= bb.min.z || Some(b.base) == floor) && b.top <= bb.max.z);
    }
    let mut without = BTreeMap::new();
    for (_, why) in &scene.report.no_blocker {
        *without.entry(why.label()).or_default() += 1;
    }
    let count = |v: &[bool]| v.iter().filter(|&&h| h).count();
    let s = Summary {
        objects: scene.objects.len(),
        with_blockers: count(&has),
        with_prisms: count(&prism),
        with_walls: count(&wall),
        without,
        pieces: scene.blockers.len(),
        walls: scene
            .blockers
            .iter()
            .filter(|b| b.polygon.len() == 2)
            .count(),
    };
    eprintln!(
        "{rel}: {} objects, {} with blockers ({} prisms, {} walls), without: {:?}, {} pieces ({} walls), skipped {}, other types {:?}, load {secs:.3} s",
        s.objects,
        s.with_blockers,
        s.with_prisms,
        s.with_walls,
        s.without,
        s.pieces,
        s.walls,
        scene.report.skipped.len(),
        scene.report.files[0].other_types
    );
    (scene, s)
}

fn counts(s: &Summary) -> (usize, usize, usize, usize, usize) {
    let get = |k: &str| s.without.get(k).copied().unwrap_or(0);
    (
        s.objects,
        s.with_blockers,
        get("open mesh"),
        get("no provable interior"),
        s.without.values().sum::<usize>() - get("open mesh") - get("no provable interior"),
    )
}

#[test]
fn denhaag_obj() {
    let (scene, s) = load_one("denhaag/DenHaag_01_buildings.obj");
    assert_eq!(scene.report.files[0].format, "OBJ");
    // (objects, with blockers, open, closed but unproven, other reasons), as measured: every
    // object gives walls now; 1,918 also give solid prisms (2 are open, 70 closed but unproven).
    assert_eq!(counts(&s), (1990, 1990, 0, 0, 0));
    assert_eq!((s.with_prisms, s.with_walls, s.walls), (1918, 1990, 10236));
    // Every object either gives blockers or says why not.
    assert_eq!(
        s.with_blockers + s.without.values().sum::<usize>(),
        s.objects
    );
    assert!(s.pieces >= s.with_blockers);
}

#[test]
fn denhaag_cityjson_0_8() {
    let (scene, s) = load_one("denhaag/DenHaag_01.json");
    let f = &scene.report.files[0];
    assert_eq!(f.format, "CityJSON");
    // Its TINRelief is read as the terrain (scene/terrain.rs).
    assert_eq!(f.other_types.get("TINRelief (read as terrain)"), Some(&1));
    assert_eq!(
        scene.terrain.as_ref().map(|t| t.triangles.len()),
        Some(5595)
    );
    // 844 buildings + 1,653 parts; 507 buildings carry their geometry in their parts.
    assert_eq!(
        f.other_types.get("Building (geometry in parts)"),
        Some(&507)
    );
    assert_eq!(s.objects, 844 + 1653 - 507);
    assert!(scene.report.skipped.is_empty());
    // Every object gives walls; 1,913 also give solid prisms. The triangulated OBJ of the same
    // data gives the same 10,236 walls: the triangles of a wall face join again.
    assert_eq!(counts(&s), (1990, 1990, 0, 0, 0));
    assert_eq!((s.with_prisms, s.with_walls, s.walls), (1913, 1990, 10236));
}

#[test]
fn delft_cityjson_2_0() {
    let (scene, s) = load_one("delft/delft.json");
    let f = &scene.report.files[0];
    let want: BTreeMap<String, usize> = [
        ("Bridge", 3),
        ("GenericCityObject", 54),
        ("LandUse", 81),
        ("PlantCover", 126),
        ("Road", 143),
        ("WaterBody", 3),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect();
    assert_eq!(f.other_types, want);
    // The LoD1 solids of 3dfier have no floor surface: every odd edge lies at the lowest
    // vertex, so the floor cap closes them (solid.rs, step 1) and every building gives blockers.
    assert_eq!(counts(&s), (160, 160, 0, 0, 0));
    assert_eq!((s.with_prisms, s.with_walls, s.walls), (160, 160, 1601));
}

#[test]
fn delft_obj() {
    let (_, s) = load_one("delft/delft_buildings.obj");
    assert_eq!(counts(&s), (160, 160, 0, 0, 0));
}

#[test]
fn gelderseplein_obj_groups_are_objects() {
    let (scene, s) = load_one("gelderseplein/gelderseplein.obj");
    // 24 buildings, each a footprint group and overlapping 3D groups: every group is an object.
    assert_eq!(s.objects, 105);
    // The 24 flat footprint groups lie wholly in one plane: open meshes with no vertical face.
    // Every 3D group of every building gives walls; 77 also give solid prisms (4 LoD groups
    // are open above their base).
    assert_eq!(counts(&s), (105, 81, 24, 0, 0));
    assert_eq!((s.with_prisms, s.with_walls, s.walls), (77, 81, 2631));
    for o in &scene.objects {
        let flat = o.bbox.max.z == o.bbox.min.z;
        let walls = scene
            .blockers
            .iter()
            .filter(|b| b.object == o.index && b.polygon.len() == 2)
            .count();
        assert_eq!(walls == 0, flat, "{} {:?}: {walls} walls", o.name, o.bbox);
    }
    // Objects keep file order and their group line.
    let lines: Vec<usize> = scene
        .objects
        .iter()
        .map(|o| match o.location {
            vocc::scene::Location::Line { line, .. } => line,
            ref other => panic!("{other:?}"),
        })
        .collect();
    assert!(lines.windows(2).all(|w| w[0] < w[1]));
    assert_eq!(lines[0], 10904);
}

// ---- CityJSON versions and types (fixtures in tests/fixtures/cityjson/) ----

fn fixture(name: &str, types: &[&str]) -> Result<Scene, vocc::scene::LoadError> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/cityjson")
        .join(name);
    load(
        &[p],
        &ReadOptions {
            types: types.iter().map(|t| t.to_string()).collect(),
            ..ReadOptions::default()
        },
    )
}

#[test]
fn cityjson_versions_from_0_3_to_2_0_load_and_others_are_refused() {
    // 0.3, the oldest read: no transform, an integer LoD, semantics as a list.
    let s = fixture("building_v0_3.json", &[]).unwrap();
    assert_eq!(s.objects.len(), 1);
    assert!(s.blockers.iter().any(|b| b.polygon.len() == 2));
    assert!(s.blockers.iter().any(|b| b.polygon.len() > 2));
    for (name, v) in [("building_v0_2.json", "0.2"), ("building_v2_1.json", "2.1")] {
        let e = fixture(name, &[]).unwrap_err();
        assert_eq!(
            e.kind,
            vocc::scene::LoadErrorKind::UnsupportedVersion(v.into())
        );
        assert!(
            e.to_string().ends_with(&format!(
                "unsupported CityJSON version \"{v}\" (this reader knows 0.3 to 0.9, 1.0, 1.1, 2.0)"
            )),
            "{e}"
        );
    }
    // 1.0, 1.1 and 2.0 are the bundled Delft (2.0) and the fixtures below (1.1, 2.0).
}

#[test]
fn cityjson_without_buildings_says_which_types_it_holds() {
    // Like the specification's simplegeom files: a cube, a block with a hole through it, two
    // cubes as one composite solid, each a +GenericCityObject.
    for (name, walls) in [
        ("generic_cube_v1_1.json", 4),
        ("generic_torus_v1_1.json", 8),
        ("composite_solid_v1_1.json", 5),
    ] {
        let e = fixture(name, &[]).unwrap_err();
        assert!(
            e.to_string().ends_with(
                "no city object of the types read (Building, BuildingPart); the files hold \
                 +GenericCityObject 1; read them with --types +GenericCityObject"
            ),
            "{e}"
        );
        let s = fixture(name, &["+GenericCityObject"]).unwrap();
        assert_eq!(s.objects.len(), 1, "{name}");
        let w = s.blockers.iter().filter(|b| b.polygon.len() == 2).count();
        assert_eq!(w, walls, "{name}");
        assert!(
            s.blockers.iter().any(|b| b.polygon.len() > 2),
            "{name}: no prism"
        );
    }
}

#[test]
fn cityjson_types_add_bridges_constructions_and_extension_types() {
    let all = [
        "Bridge",
        "OtherConstruction",
        "GenericCityObject",
        "+GenericCityObject",
    ];
    let s = fixture("mixed_types_v2_0.json", &[]).unwrap();
    assert_eq!(s.objects.len(), 1);
    let other = &s.report.files[0].other_types;
    for t in all {
        assert_eq!(other.get(t), Some(&1), "{t}");
    }
    let s = fixture("mixed_types_v2_0.json", &all).unwrap();
    let names: Vec<&str> = s.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["b1", "bridge", "shed", "kiosk", "tower"]);
    // Feature numbers follow the file's city objects, whatever is read.
    let features: Vec<u32> = s.objects.iter().map(|o| o.feature).collect();
    assert_eq!(features, [0, 1, 2, 3, 4]);
    let s = fixture("mixed_types_v2_0.json", &["+GenericCityObject"]).unwrap();
    let features: Vec<u32> = s.objects.iter().map(|o| o.feature).collect();
    assert_eq!(features, [0, 4]);
    assert_eq!(s.report.files[0].other_types.get("Road"), Some(&1));
}

#[test]
fn the_results_table_of_blocker_shares_is_measured() {
    // The table docs/RESULTS.md carries (vocc results), on two of the datasets.
    let md = vocc::eval::report::blocker_share_section(&[
        ("Gelderseplein", data("gelderseplein/gelderseplein.obj")),
        ("Delft", data("delft/delft_buildings.obj")),
    ])
    .unwrap();
    eprintln!("{md}");
    // Regression: the text and the table head were indented by 9 spaces (a string literal
    // without line continuations), which Markdown shows as a code block, not a table.
    assert!(
        md.lines().all(|l| !l.starts_with(' ')),
        "an indented line turns into a code block: {md}"
    );
    assert!(md.contains("\n\n| dataset | objects |"), "{md}");
    assert!(
        md.contains("| 105 | 77 (73.3%) | 81 (77.1%) | 2631 |"),
        "{md}"
    );
    assert!(
        md.contains("| 160 | 160 (100.0%) | 160 (100.0%) | 1601 |"),
        "{md}"
    );
}
