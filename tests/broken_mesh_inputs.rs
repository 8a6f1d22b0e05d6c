//! Broken mesh inputs: each fixture under `tests/fixtures/broken/` fails the load with the exact
//! error kind and place.
//!
//! Input: small hand-written OBJ and CityJSON files, each with one defect. Output: assertions on
//! `LoadErrorKind` and `Location`. Invariant: a broken file fails the whole load, never panics.

use std::path::PathBuf;

use vocc::scene::{load, LoadError, LoadErrorKind, Location, ReadOptions};

fn fail(name: &str) -> LoadError {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/broken")
        .join(name);
    let e = load(std::slice::from_ref(&p), &ReadOptions::default()).unwrap_err();
    assert_eq!(e.path, p);
    e
}

fn line(line: usize) -> Location {
    Location::Line { line, column: None }
}

#[test]
fn obj_nan_vertex() {
    let e = fail("obj_nan_vertex.obj");
    assert_eq!(e.location, line(4));
    assert!(matches!(e.kind, LoadErrorKind::NonFinite(_)), "{e}");
}

#[test]
fn obj_bad_face_index() {
    let e = fail("obj_bad_face_index.obj");
    assert_eq!(e.location, line(6));
    assert!(matches!(e.kind, LoadErrorKind::MalformedObj(_)), "{e}");
}

#[test]
fn obj_garbage() {
    let e = fail("obj_garbage.obj");
    assert_eq!(e.location, line(4));
    assert!(matches!(e.kind, LoadErrorKind::MalformedObj(_)), "{e}");
}

#[test]
fn obj_no_faces() {
    let e = fail("obj_no_faces.obj");
    assert_eq!(e.location, Location::File);
    assert_eq!(e.kind, LoadErrorKind::MalformedObj("no faces".into()));
}

#[test]
fn cityjson_unknown_geometry() {
    let e = fail("cityjson_unknown_geometry.json");
    assert_eq!(e.location, Location::CityObject("bad".into()));
    assert_eq!(
        e.kind,
        LoadErrorKind::UnknownGeometryType("Polyhedron".into())
    );
}

#[test]
fn cityjson_vertex_index_out_of_range() {
    let e = fail("cityjson_vertex_index_out_of_range.json");
    assert_eq!(e.location, Location::CityObject("b1".into()));
    assert!(
        matches!(
            e.kind,
            LoadErrorKind::Malformed {
                format: "CityJSON",
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn cityjson_bad_version() {
    let e = fail("cityjson_bad_version.json");
    assert_eq!(e.location, Location::File);
    assert_eq!(e.kind, LoadErrorKind::UnsupportedVersion("3.1".into()));
}

#[test]
fn cityjson_vertex_out_of_range_after_transform() {
    // 2,000,000 x 1000 m = 2e9 m, beyond MAX_COORD_M.
    let e = fail("cityjson_nonfinite_vertex.json");
    assert_eq!(e.location, Location::Vertex(3));
    assert!(matches!(e.kind, LoadErrorKind::OutOfRange { .. }), "{e}");
}

#[test]
fn cityjson_overflowing_literal_is_rejected_by_the_json_parser() {
    // serde_json refuses 1e400, so the error is the caller's MalformedJson with the line.
    let e = fail("cityjson_overflow_literal.json");
    assert!(matches!(e.kind, LoadErrorKind::MalformedJson(_)), "{e}");
    assert!(matches!(e.location, Location::Line { line: 3, .. }), "{e}");
}
