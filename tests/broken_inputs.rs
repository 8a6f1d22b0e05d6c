//! One test per broken file in `tests/fixtures/broken/` (GeoJSON, OpenStreetMap PBF, GeoPackage,
//! FlatGeobuf, Shapefile, CityGML, CityJSONSeq and format detection): each gives a typed error
//! naming the file and the place, and nothing panics.

use crate::common;

use common::repo;
use vocc::scene::{self, LoadError, LoadErrorKind, Location, OnBadHeight, ReadOptions};

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
fn height_that_is_not_a_number_fails_under_on_bad_height_error() {
    let path = repo("tests/fixtures/broken/geojson_height_not_a_number.geojson");
    let opts = ReadOptions {
        height_attr: Some("height".into()),
        on_bad_height: OnBadHeight::Error,
        ..ReadOptions::default()
    };
    let e = scene::load(std::slice::from_ref(&path), &opts).expect_err("must not load");
    assert!(matches!(&e.kind, LoadErrorKind::BadAttribute { attr, .. } if attr == "height"));
    assert_eq!(e.location, Location::Feature(1));
    assert!(
        e.to_string()
            .contains(r#"feature 1: attribute "height" has value "tall""#),
        "{e}"
    );
    // By default the feature is skipped, with its reason, and the other one loads.
    let s = scene::load(
        &[path],
        &ReadOptions {
            on_bad_height: OnBadHeight::Skip,
            ..opts
        },
    )
    .unwrap();
    assert_eq!(s.objects.len(), 1);
    assert_eq!(
        s.report.skipped[0].1.reason.to_string(),
        r#"height attribute "height" is "tall", not a number"#
    );
}

/// `tests/fixtures/scenes/messy_heights.geojson`: one feature per case (its `what` property).
fn messy(opts: ReadOptions) -> Result<scene::Scene, LoadError> {
    let path = repo("tests/fixtures/scenes/messy_heights.geojson");
    scene::load(
        &[path],
        &ReadOptions {
            height_attr: Some("height".into()),
            levels_attr: Some("levels".into()),
            ..opts
        },
    )
}

#[test]
fn messy_heights_parse_where_their_meaning_is_clear() {
    let s = messy(ReadOptions::default()).unwrap();
    let height = |f: u32| {
        let o = s.objects.iter().find(|o| o.feature == f)?;
        match &o.shape {
            scene::Shape::Footprint(fp) => Some(fp.top - fp.base),
            _ => None,
        }
    };
    assert_eq!(height(0), Some(10.0), "a number");
    assert_eq!(height(1), Some(12.13), "\"12.13 m\"");
    assert_eq!(height(2), Some(12.5), "\"12,5\"");
    assert!((height(3).unwrap() - 12.192).abs() < 1e-9, "\"40 ft\"");
    assert_eq!(height(4), Some(9.0), "bad height: 3 storeys of 3 m");
    assert_eq!(height(6), Some(12.0), "no height: \"4\" storeys");
    assert_eq!(
        height(9),
        Some(9.0),
        "the height, the bad storey count unread"
    );
    // Skipped, each with its reason, by input feature number.
    let skipped: Vec<(u32, String)> = s
        .report
        .skipped
        .iter()
        .map(|(_, k)| (k.feature, k.reason.to_string()))
        .collect();
    assert_eq!(
        skipped,
        vec![
            (
                5,
                r#"height attribute "height" is "tall", not a number"#.to_string()
            ),
            (7, "no height attribute and no storey count".to_string()),
            (
                8,
                r#"height attribute "height" is "1,234", not a number"#.to_string()
            ),
        ]
    );
    // The fallbacks are reported too.
    let fallbacks: Vec<(u32, String)> = s
        .report
        .height_fallbacks
        .iter()
        .map(|(i, f)| (s.objects[*i as usize].feature, f.to_string()))
        .collect();
    assert_eq!(
        fallbacks,
        vec![
            (
                4,
                r#"height from the storey count; "height" is "tall", not a number"#.to_string()
            ),
            (6, "height from the storey count".to_string()),
        ]
    );
}

#[test]
fn messy_heights_fall_back_to_the_default_height_or_stop_at_the_first_bad_value() {
    let s = messy(ReadOptions {
        default_height: Some(6.0),
        ..ReadOptions::default()
    })
    .unwrap();
    assert_eq!(s.objects.len(), 10);
    assert!(s.report.skipped.is_empty());
    let defaults: Vec<u32> = s
        .report
        .height_fallbacks
        .iter()
        .filter(|(_, f)| f.source == scene::HeightSource::Default)
        .map(|(i, _)| s.objects[*i as usize].feature)
        .collect();
    assert_eq!(defaults, vec![5, 7, 8]);
    let e = messy(ReadOptions {
        on_bad_height: OnBadHeight::Error,
        ..ReadOptions::default()
    })
    .unwrap_err();
    assert_eq!(e.location, Location::Feature(4));
    assert_eq!(
        e.kind,
        LoadErrorKind::BadAttribute {
            attr: "height".into(),
            value: "\"tall\"".into()
        }
    );
}

#[test]
fn a_default_height_alone_reads_geojson_without_height_attributes() {
    let path = repo("tests/fixtures/scenes/messy_heights.geojson");
    let s = scene::load(
        &[path],
        &ReadOptions {
            default_height: Some(4.0),
            ..ReadOptions::default()
        },
    )
    .unwrap();
    assert_eq!(s.objects.len(), 10);
    assert_eq!(s.report.height_fallbacks.len(), 10);
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

/// A broken fixture of the new readers under `opts` (heights from `height`, else as given).
fn load_broken_with(name: &str, opts: ReadOptions) -> LoadError {
    let path = repo(&format!("tests/fixtures/broken/{name}"));
    let err =
        scene::load(std::slice::from_ref(&path), &opts).expect_err("broken input must not load");
    assert_eq!(err.path, path, "the error names the file");
    assert!(
        err.to_string().contains(name),
        "message names the file: {err}"
    );
    err
}

fn malformed_of(e: &LoadError) -> (&'static str, &str) {
    match &e.kind {
        LoadErrorKind::Malformed { format, message } => (format, message.as_str()),
        _ => panic!("not a Malformed error: {e}"),
    }
}

#[test]
fn osm_pbf_truncated_or_not_pbf() {
    for name in ["osm_truncated.osm.pbf", "osm_not_pbf.osm.pbf"] {
        let e = load_broken(name);
        assert_eq!(malformed_of(&e).0, "OpenStreetMap PBF", "{e}");
        assert_eq!(e.location, Location::File);
    }
}

#[test]
fn gpkg_not_sqlite_no_feature_table_bad_geometry_blob() {
    let e = load_broken("gpkg_not_sqlite.gpkg");
    assert!(malformed_of(&e).1.contains("not a SQLite database"), "{e}");
    let e = load_broken("gpkg_no_feature_table.gpkg");
    assert!(malformed_of(&e).1.contains("gpkg_geometry_columns"), "{e}");
    let e = load_broken("gpkg_bad_geometry.gpkg");
    assert_eq!(
        e.location,
        Location::Element("table \"buildings\", fid 1".into()),
        "{e}"
    );
    assert!(malformed_of(&e).1.contains("magic"), "{e}");
}

#[test]
fn fgb_truncated_or_without_magic() {
    let e = load_broken("fgb_truncated.fgb");
    let (format, message) = malformed_of(&e);
    assert_eq!(format, "FlatGeobuf");
    assert!(message.contains("does not fit"), "{e}");
    assert!(matches!(e.location, Location::Feature(_)), "{e}");
    let e = load_broken("fgb_no_magic.fgb");
    assert!(malformed_of(&e).1.contains("magic"), "{e}");
}

#[test]
fn shp_without_its_dbf_or_truncated() {
    // Heights are asked for by attribute, and the attributes are in the .dbf that is missing.
    let e = load_broken("shp_no_dbf.shp");
    let LoadErrorKind::MissingCompanion { path, .. } = &e.kind else {
        panic!("{e}")
    };
    assert!(path.ends_with("shp_no_dbf.dbf"), "{e}");
    // With a default height the shapes read without attributes.
    let path = repo("tests/fixtures/broken/shp_no_dbf.shp");
    let s = scene::load(
        &[path],
        &ReadOptions {
            default_height: Some(7.0),
            ..ReadOptions::default()
        },
    )
    .unwrap();
    assert_eq!(s.objects.len(), 1);
    let e = load_broken_with(
        "shp_truncated.shp",
        ReadOptions {
            default_height: Some(7.0),
            ..ReadOptions::default()
        },
    );
    assert_eq!(malformed_of(&e).0, "Shapefile", "{e}");
}

#[test]
fn citygml_bad_coordinate_truncated_not_citygml() {
    let e = load_broken("citygml_bad_coordinate.gml");
    assert!(malformed_of(&e).1.contains("\"nine\""), "{e}");
    assert!(matches!(e.location, Location::Line { line: 7, .. }), "{e}");
    let e = load_broken("citygml_truncated.gml");
    assert!(malformed_of(&e).1.contains("truncated"), "{e}");
    assert!(matches!(e.location, Location::Line { line: 7, .. }), "{e}");
    let e = load_broken("citygml_not_citygml.xml");
    assert!(malformed_of(&e).1.contains("CityModel"), "{e}");
}

#[test]
fn cityjsonseq_bad_line_and_vertex_out_of_range_name_the_line() {
    let e = load_broken("cityjsonseq_bad_line.city.jsonl");
    assert!(matches!(e.kind, LoadErrorKind::MalformedJson(_)), "{e}");
    assert!(matches!(e.location, Location::Line { line: 3, .. }), "{e}");
    let e = load_broken("cityjsonseq_vertex_out_of_range.city.jsonl");
    assert_eq!(
        e.location,
        Location::InLine {
            line: 3,
            inner: Box::new(Location::CityObject("b".into()))
        },
        "{e}"
    );
    assert!(e.to_string().contains("line 3, city object \"b\""), "{e}");
}

#[test]
fn unsupported_format_names_a_converter() {
    let e = load_broken("scene_unsupported.kml");
    let LoadErrorKind::UnsupportedFormat { format, hint } = &e.kind else {
        panic!("{e}")
    };
    assert_eq!(format, "KML");
    assert!(hint.starts_with("ogr2ogr -f GeoJSON"), "{hint}");
}

/// Findings of the fuzz targets (docs/FUZZING.md), kept with their literal bytes: osmpbf panicked
/// on a relation member of an unknown type, rusqlite on a column name that is not UTF-8, and the
/// shapefile crate reserved 6.9 GB for what a 393-byte file stated (now refused at its records'
/// headers, each checked against the bytes it holds).
#[test]
fn fuzz_findings_of_the_new_readers_are_errors() {
    let e = load_broken("osm_fuzz_unknown_member_type.osm.pbf");
    assert_eq!(malformed_of(&e).0, "OpenStreetMap PBF", "{e}");
    let path = repo("tests/fixtures/broken/gpkg_fuzz_non_utf8_column.gpkg");
    match scene::load(std::slice::from_ref(&path), &vocc::fuzzing::scene_options()) {
        Ok(s) => assert!(!s.objects.is_empty()),
        Err(e) => assert!(
            e.to_string().contains("gpkg_fuzz_non_utf8_column.gpkg"),
            "{e}"
        ),
    }
    let e = load_broken_with(
        "shp_fuzz_huge_counts.shp",
        ReadOptions {
            default_height: Some(10.0),
            ..ReadOptions::default()
        },
    );
    let (format, message) = malformed_of(&e);
    assert_eq!(format, "Shapefile");
    assert!(message.contains("record"), "{e}");
    assert!(matches!(e.location, Location::Feature(_)), "{e}");
    // A record holding more bytes than its shape uses shifted the crate's reading of the next
    // record's header (it asked for 16 GB): each record is now read from its own bytes.
    let path = repo("tests/fixtures/broken/shp_fuzz_record_slack.shp");
    let r = scene::load(
        &[path],
        &ReadOptions {
            default_height: Some(10.0),
            ..ReadOptions::default()
        },
    );
    if let Err(e) = r {
        assert!(e.to_string().contains("shp_fuzz_record_slack.shp"), "{e}");
    }
    // A part starting at a negative point: the crate sized it at 28 GB.
    let e = load_broken_with(
        "shp_fuzz_part_start.shp",
        ReadOptions {
            default_height: Some(10.0),
            ..ReadOptions::default()
        },
    );
    assert!(malformed_of(&e).1.starts_with("part "), "{e}");
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
        "osm_truncated.osm.pbf",
        "osm_not_pbf.osm.pbf",
        "gpkg_not_sqlite.gpkg",
        "gpkg_no_feature_table.gpkg",
        "gpkg_bad_geometry.gpkg",
        "fgb_truncated.fgb",
        "fgb_no_magic.fgb",
        "shp_no_dbf.shp",
        "shp_no_dbf.shx",
        "shp_truncated.shp",
        "citygml_bad_coordinate.gml",
        "citygml_truncated.gml",
        "citygml_not_citygml.xml",
        "cityjsonseq_bad_line.city.jsonl",
        "cityjsonseq_vertex_out_of_range.city.jsonl",
        "scene_unsupported.kml",
        "geojson_height_1e300.geojson",
        "osm_fuzz_unknown_member_type.osm.pbf",
        "gpkg_fuzz_non_utf8_column.gpkg",
        "shp_fuzz_huge_counts.shp",
        "shp_fuzz_record_slack.shp",
        "shp_fuzz_part_start.shp",
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
