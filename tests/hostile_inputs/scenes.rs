//! Hostile scene files: NaN, infinite and huge values, empty geometries, deep nesting, huge
//! polygons and many holes; each a located error or a quick load, never a panic.

#[allow(unused_imports)]
use super::*;

#[test]
fn geojson_nan_infinite_and_huge_values_are_located_errors() {
    let ok = feature(r#"{"height":5}"#, &polygon(SQUARE));
    let with =
        |props: &str, coords: &str| collection(&[ok.clone(), feature(props, &polygon(coords))]);
    // JSON has no NaN literal: the strings "NaN" and "inf" are not coordinates.
    for bad in ["NaN", "inf", "-Infinity"] {
        let coords = format!(r#"[[["{bad}",0],[10,0],[10,10],[0,0]]]"#);
        let e = fails("a.geojson", &with(r#"{"height":5}"#, &coords));
        assert!(
            matches!(&e.kind, LoadErrorKind::Malformed { format: "GeoJSON", message }
                if message.starts_with("feature 1:") && message.contains(bad)),
            "{bad}: {e}"
        );
        assert!(matches!(e.location, Location::Line { line: 1, .. }), "{e}");
    }
    // As attribute strings they are not numbers (scene::attr): the feature is skipped with its
    // reason, or, under --on-bad-height error, the load fails there.
    for (props, what) in [
        (r#"{"height":"NaN"}"#, "height"),
        (r#"{"height":"inf"}"#, "height"),
        (r#"{"height":"-1e999"}"#, "height"),
        (r#"{"height":null,"levels":"NaN"}"#, "levels"),
    ] {
        let text = with(props, SQUARE);
        let s = load_one("a.geojson", &text).unwrap();
        assert_eq!(s.objects.len(), 1, "{what}");
        assert!(
            matches!(&s.report.skipped[0].1.reason, vocc::scene::SkipReason::BadHeight { attr, .. } if attr == what),
            "{what}: {:?}",
            s.report.skipped
        );
        let strict = ReadOptions {
            on_bad_height: vocc::scene::OnBadHeight::Error,
            ..opts()
        };
        let e = load_bytes(&[(PathBuf::from("a.geojson"), text.as_bytes())], &strict).unwrap_err();
        assert!(
            matches!(&e.kind, LoadErrorKind::BadAttribute { attr, .. } if attr == what),
            "{what}: {e}"
        );
        assert_eq!(e.location, Location::Feature(1), "{e}");
    }
    // 1e300 as a height, or as storeys: a bad height (issue 33, defect 7), skipped with its
    // reason, or under --on-bad-height error a located error; never an abort of the load.
    for (props, what) in [
        (r#"{"height":1e300}"#, "height"),
        (r#"{"height":null,"levels":"1e300"}"#, "levels"),
    ] {
        let text = with(props, SQUARE);
        let s = load_one("a.geojson", &text).unwrap();
        assert!(
            matches!(&s.report.skipped[0].1.reason, vocc::scene::SkipReason::BadHeight { attr, value }
                if attr == what && value.contains("1e300")),
            "{what}: {:?}",
            s.report.skipped
        );
        let strict = ReadOptions {
            on_bad_height: vocc::scene::OnBadHeight::Error,
            ..opts()
        };
        let e = load_bytes(&[(PathBuf::from("a.geojson"), text.as_bytes())], &strict).unwrap_err();
        assert!(
            matches!(&e.kind, LoadErrorKind::AbsurdHeight { attr, .. } if attr == what),
            "{what}: {e}"
        );
        assert_eq!(e.location, Location::Feature(1), "{e}");
    }
    // A coordinate of 1e300 written with a huge exponent; the largest finite f64 too.
    for (props, coords) in [
        (
            r#"{"height":5}"#,
            "[[[0,0],[10000000000000000000000e280,0],[10,10],[0,0]]]",
        ),
        (
            r#"{"height":5}"#,
            "[[[0,0],[1.7976931348623157e308,0],[10,10],[0,0]]]",
        ),
    ] {
        let e = fails("a.geojson", &with(props, coords));
        assert!(
            matches!(e.kind, LoadErrorKind::OutOfRange { .. }),
            "{props} {coords}: {e}"
        );
        assert_eq!(e.location, Location::Feature(1), "{e}");
    }
    // A literal beyond f64 is refused by the JSON parser, with its line.
    let e = fails("a.geojson", &with(r#"{"height":1e400}"#, SQUARE));
    assert!(matches!(e.kind, LoadErrorKind::MalformedJson(_)), "{e}");
    assert!(matches!(e.location, Location::Line { line: 1, .. }), "{e}");
}

#[test]
fn cityjson_transform_that_overflows_is_a_vertex_error() {
    let doc = |scale: &str, vertex: &str| {
        format!(
            r#"{{"type":"CityJSON","version":"1.1","transform":{{"scale":{scale},"translate":[0,0,0]}},
            "vertices":[[0,0,0],[1,0,0],[1,1,0],{vertex}],
            "CityObjects":{{"b":{{"type":"Building","geometry":[{{"type":"MultiSurface","lod":1,"boundaries":[[[0,1,2,3]]]}}]}}}}}}"#
        )
    };
    // scale 1e8 (allowed) times a vertex of 1e301 is infinite: NonFinite at that vertex.
    let e = fails("c.json", &doc("[1e8,1e8,1]", "[1e301,0,0]"));
    assert!(matches!(e.kind, LoadErrorKind::NonFinite(_)), "{e}");
    assert_eq!(e.location, Location::Vertex(3));
    // scale 1e8 times 1e10 is finite but beyond 1e9 m.
    let e = fails("c.json", &doc("[1e8,1e8,1]", "[0,10000000000,0]"));
    assert!(matches!(e.kind, LoadErrorKind::OutOfRange { .. }), "{e}");
    assert_eq!(e.location, Location::Vertex(3));
    // A scale of 1e300 is refused where it stands.
    let e = fails("c.json", &doc("[1e300,1,1]", "[0,1,0]"));
    assert!(
        matches!(e.kind, LoadErrorKind::OutOfRange { value, .. } if value == 1e300),
        "{e}"
    );
    assert_eq!(e.location, Location::File);
    // The same document with a sane transform loads.
    let s = load_one("c.json", &doc("[0.5,0.5,1]", "[0,1,0]")).unwrap();
    assert_eq!(s.objects.len(), 1);
}

#[test]
fn obj_nan_infinite_and_huge_vertices_fail_at_their_line() {
    for (v, nonfinite) in [
        ("v nan nan nan", true),
        ("v inf 0 0", true),
        ("v 0 -inf 0", true),
        ("v 1 2 3 0", true), // w = 0 divides to infinity
        ("v 1e300 0 0", false),
        ("v 0 0 -2e9", false),
    ] {
        let text = format!("v 0 0 0\nv 1 0 0\n{v}\nv 0 1 0\nf 1 2 4\nf 1 2 3\n");
        let e = fails("m.obj", &text);
        assert_eq!(
            e.location,
            Location::Line {
                line: 3,
                column: None
            },
            "{v}: {e}"
        );
        if nonfinite {
            assert!(matches!(e.kind, LoadErrorKind::NonFinite(_)), "{v}: {e}");
        } else {
            assert!(
                matches!(e.kind, LoadErrorKind::OutOfRange { .. }),
                "{v}: {e}"
            );
        }
    }
}

#[test]
fn empty_geometries_are_skipped_or_refused_never_a_panic() {
    let ok = feature(r#"{"height":5}"#, &polygon(SQUARE));
    let empties = [
        polygon("[]"),
        polygon("[[]]"),
        polygon("[[],[]]"),
        r#"{"type":"MultiPolygon","coordinates":[]}"#.to_string(),
        r#"{"type":"MultiPolygon","coordinates":[[]]}"#.to_string(),
        r#"{"type":"MultiPolygon","coordinates":[[[]]]}"#.to_string(),
        "null".to_string(),
    ];
    let mut features = vec![ok];
    features.extend(empties.iter().map(|g| feature(r#"{"height":5}"#, g)));
    let s = load_one("e.geojson", &collection(&features)).unwrap();
    assert_eq!(s.objects.len(), 1, "only the square is an object");
    assert_eq!(s.report.skipped.len(), empties.len());
    assert!(s
        .report
        .skipped
        .iter()
        .all(|(_, k)| k.reason == vocc::scene::SkipReason::EmptyGeometry));

    // Rings of one or two points: an occludee, but no blocker.
    let s = load_one(
        "e.geojson",
        &collection(&[
            feature(r#"{"height":5}"#, &polygon("[[[0,0]]]")),
            feature(r#"{"height":5}"#, &polygon("[[[0,0],[5,5]]]")),
        ]),
    )
    .unwrap();
    assert_eq!(s.objects.len(), 2);
    assert!(s.blockers.is_empty());
    assert_eq!(s.report.no_blocker.len(), 2);

    // Nothing but empty geometry: no objects, with heights present (not a missing attribute).
    let only_empty: Vec<String> = empties
        .iter()
        .map(|g| feature(r#"{"height":5}"#, g))
        .collect();
    let e = fails("e.geojson", &collection(&only_empty));
    assert_eq!(e.kind, LoadErrorKind::NoObjects, "{e}");
    let e = fails("e.geojson", &collection(&[]));
    assert_eq!(e.kind, LoadErrorKind::NoObjects, "{e}");

    // CityJSON: a building whose boundaries are empty is skipped; with nothing else, no objects.
    let cj = |geometry: &str| {
        format!(
            r#"{{"type":"CityJSON","version":"2.0","vertices":[],"CityObjects":{{"b":{{"type":"Building","geometry":{geometry}}}}}}}"#
        )
    };
    for g in [
        r#"[{"type":"Solid","lod":1,"boundaries":[]}]"#,
        r#"[{"type":"Solid","lod":1,"boundaries":[[]]}]"#,
        r#"[{"type":"MultiSurface","lod":1,"boundaries":[[[]]]}]"#,
        r#"[{"type":"MultiSolid","lod":1,"boundaries":[]}]"#,
        "[]",
    ] {
        let e = fails("c.json", &cj(g));
        assert_eq!(e.kind, LoadErrorKind::NoObjects, "{g}: {e}");
    }

    // OBJ: vertices and groups but not one face.
    for text in [
        "v 0 0 0\nv 1 0 0\nv 0 1 0\no a\ng b\n",
        "o a\n",
        "# nothing\n",
    ] {
        let e = fails("m.obj", text);
        assert_eq!(
            e.kind,
            LoadErrorKind::MalformedObj("no faces".into()),
            "{e}"
        );
    }
}

#[test]
fn json_nested_past_any_depth_is_an_error_not_a_stack_overflow() {
    let deep = |n: usize| format!("{}{}", "[".repeat(n), "]".repeat(n));
    let coords = deep(100_000);
    let text = collection(&[feature(r#"{"height":5}"#, &polygon(&coords))]);
    let e = fails("d.geojson", &text);
    assert!(
        matches!(e.kind, LoadErrorKind::MalformedJson(ref m) if m.contains("recursion")),
        "{e}"
    );
    let e = fails("d.json", &deep(100_000));
    assert!(matches!(e.kind, LoadErrorKind::MalformedJson(_)), "{e}");
    let e = walkable::read_bytes(
        Path::new("w.geojson"),
        polygon(&coords).as_bytes(),
        glam::DVec3::ZERO,
    )
    .unwrap_err();
    assert!(matches!(e.kind, LoadErrorKind::MalformedJson(_)), "{e}");
}

#[test]
fn polygons_of_100_000_vertices_load_or_are_refused_quickly() {
    gear(100_000);
    star(100_000);
}

/// 10^6 vertices: about 28 MB of GeoJSON each. Run with `cargo test --release --test all
/// hostile_inputs:: -- --ignored`; figures in docs/FUZZING.md.
#[test]
#[ignore]
fn polygons_of_1_000_000_vertices_load_or_are_refused_quickly() {
    gear(1_000_000);
    star(1_000_000);
}

/// 2,500 square holes in a square: each hole is checked against the exterior and every other
/// hole (by one ray per hole through the edges' R-tree, not a scan of every ring); then a hole
/// nested in another and a hole outside are refused.
#[test]
fn a_polygon_with_thousands_of_holes() {
    let sq = |x: f64, y: f64, s: f64, ccw: bool| {
        let mut p = [[x, y], [x + s, y], [x + s, y + s], [x, y + s], [x, y]];
        if !ccw {
            p.reverse();
        }
        let p: Vec<String> = p
            .iter()
            .map(|c| format!("[{},{}]", c[0] + 1_842_000.0, c[1] + 5_176_000.0))
            .collect();
        format!("[{}]", p.join(","))
    };
    let mut rings = vec![sq(0.0, 0.0, 1000.0, true)];
    for i in 0..50 {
        for j in 0..50 {
            rings.push(sq(
                5.0 + 20.0 * i as f64,
                5.0 + 20.0 * j as f64,
                10.0,
                false,
            ));
        }
    }
    let (s, _) = load_timed("2,500 holes", &footprint_file(&rings));
    assert!(s.report.no_blocker.is_empty(), "{:?}", s.report.no_blocker);
    let pieces: f64 = s
        .blockers
        .iter()
        .map(|b| vocc::scene::decompose::signed_area(&b.polygon))
        .sum();
    let area = 1000.0 * 1000.0 - 2500.0 * 100.0;
    assert!((pieces - area).abs() < 1e-6 * area, "{pieces} vs {area}");
    for (extra, what) in [
        (sq(6.0, 6.0, 2.0, false), "nested"),
        (sq(2000.0, 0.0, 5.0, false), "outside"),
    ] {
        let mut bad = rings.clone();
        bad.push(extra);
        let (s, _) = load_timed(what, &footprint_file(&bad));
        assert_eq!(
            s.report.no_blocker,
            [(
                0,
                vocc::scene::NoBlocker::InvalidRing {
                    polygon: 0,
                    ring: 2501,
                    why: vocc::scene::RingRejection::HoleOutside
                }
            )],
            "{what}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// A bake killed midway, and a full disk
