//! One test per broken file in `tests/fixtures/broken/` (GeoJSON and format detection): each
//! gives a typed error naming the file and the place, and nothing panics.

mod common;

use common::repo;
use vocc::scene::{self, LoadError, LoadErrorKind, Location, ReadOptions};

fn load_broken(name: &str) -> LoadError {
    let path = repo(&format!("tests/fixtures/broken/{name}"));
    let opts = ReadOptions {
        height_attr: Some("height".into()),
        ..ReadOptions::default()
    };
    let err =
        scene::load(std::slice::from_ref(&path), &opts).expect_err("broken input must not load");
    assert_eq!(err.path, path, "the error names the file");
    assert!(
        err.to_string().contains(name),
        "message names the file: {err}"
    );
    err
}

#[test]
fn empty_file() {
    let e = load_broken("geojson_empty.geojson");
    assert_eq!(e.kind, LoadErrorKind::Empty);
    assert_eq!(e.location, Location::File);
}

#[test]
fn truncated_json_names_its_line() {
    let e = load_broken("geojson_truncated.geojson");
    assert!(matches!(e.kind, LoadErrorKind::MalformedJson(_)), "{e}");
    assert!(matches!(e.location, Location::Line { line: 5, .. }), "{e}");
}

#[test]
fn unknown_geometry_type_names_the_feature() {
    let e = load_broken("geojson_unknown_geometry_type.geojson");
    assert_eq!(e.kind, LoadErrorKind::UnknownGeometryType("Polygn".into()));
    assert_eq!(e.location, Location::Feature(1));
}

#[test]
fn height_attribute_missing_from_every_feature() {
    let e = load_broken("geojson_height_missing_everywhere.geojson");
    let LoadErrorKind::MissingAttribute { attr, hint } = &e.kind else {
        panic!("{e}")
    };
    assert_eq!(attr, "height");
    assert!(
        hint.contains("HAUTEUR"),
        "the hint lists what is there: {hint}"
    );
}

#[test]
fn height_that_is_not_a_number() {
    let e = load_broken("geojson_height_not_a_number.geojson");
    assert!(matches!(&e.kind, LoadErrorKind::BadAttribute { attr, .. } if attr == "height"));
    assert_eq!(e.location, Location::Feature(1));
}

#[test]
fn coordinate_of_1e300_is_out_of_range() {
    let e = load_broken("geojson_coordinate_1e300.geojson");
    assert!(matches!(e.kind, LoadErrorKind::OutOfRange { value, .. } if value == 1e300));
    assert_eq!(e.location, Location::Feature(1));
}

#[test]
fn coordinate_beyond_f64_is_malformed_json_with_line() {
    let e = load_broken("geojson_coordinate_overflow.geojson");
    assert!(matches!(e.kind, LoadErrorKind::MalformedJson(_)), "{e}");
    assert!(matches!(e.location, Location::Line { line: 3, .. }), "{e}");
}

#[test]
fn position_that_is_not_numbers() {
    let e = load_broken("geojson_position_not_numbers.geojson");
    let LoadErrorKind::Malformed {
        format: "GeoJSON",
        message,
    } = &e.kind
    else {
        panic!("{e}")
    };
    assert!(message.starts_with("feature 0:"), "{e}");
    assert!(matches!(e.location, Location::Line { line: 2, .. }), "{e}");
}

#[test]
fn json_that_is_not_geojson_nor_cityjson() {
    let e = load_broken("geojson_not_a_feature_collection.geojson");
    assert!(
        matches!(e.kind, LoadErrorKind::Malformed { format: "JSON", .. }),
        "{e}"
    );
}

#[test]
fn feature_collection_without_features() {
    let e = load_broken("geojson_no_features.geojson");
    assert_eq!(e.kind, LoadErrorKind::NoObjects);
}

#[test]
fn unknown_extension() {
    let e = load_broken("scene_unknown_extension.csv");
    assert_eq!(e.kind, LoadErrorKind::UnknownFormat);
}

#[test]
fn no_height_option_for_geojson() {
    let path = repo(common::LYON);
    let e = scene::load(&[path], &ReadOptions::default()).unwrap_err();
    // Issue 13: this said `attribute "(none given)" is missing`.
    assert_eq!(e.kind, LoadErrorKind::NoHeightOption, "{e}");
    assert!(e.to_string().contains("--height-attr"), "{e}");
    assert!(!e.to_string().contains("(none given)"), "{e}");
}

#[test]
fn every_broken_fixture_has_a_test() {
    // Keeps this folder and the tests above in step: a new fixture needs a test.
    let tested = [
        "geojson_empty.geojson",
        "geojson_truncated.geojson",
        "geojson_unknown_geometry_type.geojson",
        "geojson_height_missing_everywhere.geojson",
        "geojson_height_not_a_number.geojson",
        "geojson_coordinate_1e300.geojson",
        "geojson_coordinate_overflow.geojson",
        "geojson_position_not_numbers.geojson",
        "geojson_not_a_feature_collection.geojson",
        "geojson_no_features.geojson",
        "scene_unknown_extension.csv",
    ];
    let mut missing = Vec::new();
    for e in std::fs::read_dir(repo("tests/fixtures/broken")).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().to_string();
        let is_mesh = name.starts_with("obj_") || name.starts_with("cityjson_");
        if !is_mesh && !tested.contains(&name.as_str()) {
            missing.push(name);
        }
    }
    assert!(missing.is_empty(), "fixtures without a test: {missing:?}");
}
