//! The readers of issue 33 on real data, and its defects kept as regression tests with their
//! literal inputs (`defect1_...`, `defect7_...`, `defect8_...`).
//!
//! - Lyon written as GeoPackage, FlatGeobuf and Shapefile (`tools/lyon_formats.sh`) loads the
//!   same scene as the GeoJSON and bakes the same store bytes; written in longitude/latitude it
//!   is detected, projected on load, and culls the same share;
//! - Helsinki's OpenStreetMap extract reads heights from its tags and evaluates with no false
//!   cull; the hand-made `tiny.osm.pbf` checks each tag rule;
//! - the CityGML sample (`tools/denhaag_to_citygml.py`) gives the blockers of the CityJSON it
//!   came from, and bakes and evaluates; Delft as CityJSONSeq reads as Delft's CityJSON.

use crate::common;

use std::path::PathBuf;

use common::{load_lyon, lyon_options, repo};
use vocc::eval::metrics::{cell_vs, eval_cell, object_boxes, sample_cells, vo_rays};
use vocc::eval::raycast::Caster;
use vocc::eval::report::bake;
use vocc::eval::truth::TruthParams;
use vocc::runtime::culler::{pvs, BoxTree};
use vocc::runtime::format::Store;
use vocc::runtime::CellId;
use vocc::scene::{
    self, CrsSource, LoadErrorKind, Location, OnBadHeight, ReadOptions, Scene, Shape, SkipReason,
};

/// The cells of the grid's middle row (an empty bake gives the grid).
fn middle_row(s: &Scene) -> Vec<CellId> {
    let empty = bake(s, Default::default(), Some(&[])).expect("the bake runs");
    let g = Store::parse(&empty.bytes).unwrap().frame().grid;
    let row = (g.ny / 2) as CellId;
    (row * g.nx as CellId..(row + 1) * g.nx as CellId).collect()
}

/// The share of objects the stored VOs cull, over `ids`.
fn culled_share(s: &Scene, bytes: &[u8], ids: &[CellId]) -> f64 {
    let store = Store::parse(bytes).unwrap();
    let tree = BoxTree::new(&object_boxes(s));
    let mut out = Vec::new();
    let mut culled = 0usize;
    for &id in ids {
        out.clear();
        pvs(store.frame(), id, &store.cell(id).unwrap(), &tree, &mut out);
        culled += s.objects.len() - out.len();
    }
    culled as f64 / (ids.len() * s.objects.len()) as f64
}

/// Objects (shapes) and blockers of two scenes are the same.
fn same_geometry(a: &Scene, b: &Scene, what: &str) {
    assert_eq!(a.origin, b.origin, "{what}: origin");
    assert_eq!(a.objects.len(), b.objects.len(), "{what}: objects");
    for (x, y) in a.objects.iter().zip(&b.objects) {
        assert_eq!(x.shape, y.shape, "{what}: object {} ({})", x.index, x.name);
        assert_eq!(x.bbox, y.bbox, "{what}: object {}", x.index);
    }
    assert_eq!(a.blockers, b.blockers, "{what}: blockers");
}

#[test]
fn lyon_as_geopackage_flatgeobuf_and_shapefile_bakes_the_same_store() {
    let original = load_lyon();
    let ids = middle_row(&original);
    let want = bake(&original, Default::default(), Some(&ids))
        .expect("the bake runs")
        .bytes;
    assert_eq!(original.crs().map(|c| c.name.as_str()), Some("EPSG:3946"));
    for (ext, crs) in [
        ("gpkg", "EPSG:3946"),
        ("fgb", "EPSG:3946"),
        ("shp", "RGF_1993_CC46"),
    ] {
        let path = repo(&format!("data/lyon1/buildings_lyon1.{ext}"));
        let s = scene::load(&[path], &lyon_options()).unwrap();
        assert_eq!(s.crs().map(|c| c.name.as_str()), Some(crs), "{ext}");
        same_geometry(&original, &s, ext);
        let got = bake(&s, Default::default(), Some(&ids))
            .expect("the bake runs")
            .bytes;
        if crs == "EPSG:3946" {
            assert!(got == want, "{ext}: the store differs from the GeoJSON's");
            continue;
        }
        // The store records the CRS name its scene states (the Shapefile's .prj names it
        // otherwise): everything else is the same.
        let (g, w) = (Store::parse(&got).unwrap(), Store::parse(&want).unwrap());
        assert_eq!((g.crs(), w.crs()), (crs, "EPSG:3946"), "{ext}");
        assert_eq!(g.frame(), w.frame(), "{ext}");
        assert_eq!((g.objects(), g.scene()), (w.objects(), w.scene()), "{ext}");
        assert_eq!(g.cell_count(), w.cell_count(), "{ext}");
        for id in 0..w.cell_count() {
            assert_eq!(g.cell(id), w.cell(id), "{ext}: cell {id}");
        }
    }
}

#[test]
fn lyon_in_longitude_latitude_is_projected_and_culls_the_same_share() {
    let original = load_lyon();
    let path = repo("data/lyon1/buildings_lyon1_lonlat.geojson");
    // No CRS stated (RFC 7946): detected, projected to UTM 31N.
    let s = scene::load(std::slice::from_ref(&path), &lyon_options()).unwrap();
    let c = s.crs().unwrap();
    assert_eq!(c.name, "EPSG:32631");
    assert_eq!(c.source, CrsSource::Projected);
    assert_eq!(c.projected_from, ["EPSG:4326"]);
    let file = s.report.files[0].crs.as_ref().unwrap();
    assert_eq!(file.source, CrsSource::Detected);
    let (e, o) = (s.extent(), original.extent());
    for k in 0..2 {
        let (a, b) = (e.max[k] - e.min[k], o.max[k] - o.min[k]);
        assert!((a / b - 1.0).abs() < 0.01, "axis {k}: {a} m against {b} m");
    }
    // Asked for Lyon's own CRS, the footprints come back within the 7 decimals' centimetre.
    let back = scene::load(
        &[path],
        &ReadOptions {
            crs: Some("EPSG:3946".into()),
            ..lyon_options()
        },
    )
    .unwrap();
    assert_eq!(back.crs().unwrap().name, "EPSG:3946");
    assert_eq!(back.origin, original.origin);
    assert_eq!(back.objects.len(), original.objects.len());
    for (a, b) in back.objects.iter().zip(&original.objects) {
        let d = (a.bbox.min - b.bbox.min)
            .abs()
            .max((a.bbox.max - b.bbox.max).abs());
        assert!(d.max_element() < 0.02, "object {}: {d}", a.index);
    }
    let ids = middle_row(&original);
    let want = culled_share(
        &original,
        &bake(&original, Default::default(), Some(&ids))
            .expect("the bake runs")
            .bytes,
        &ids,
    );
    let got = culled_share(
        &back,
        &bake(&back, Default::default(), Some(&ids))
            .expect("the bake runs")
            .bytes,
        &ids,
    );
    assert!(want > 0.2, "the row culls {want}");
    assert!(
        (got - want).abs() < 0.02,
        "longitude/latitude culls {got}, the original {want}"
    );
}

#[test]
fn tiny_osm_pbf_reads_each_tag_rule() {
    let s = scene::load(
        &[repo("tests/fixtures/scenes/tiny.osm.pbf")],
        &ReadOptions::default(),
    )
    .unwrap();
    let fp = |name: &str| {
        let o = s.objects.iter().find(|o| o.name == name).unwrap();
        let Shape::Footprint(f) = &o.shape else {
            panic!()
        };
        f.clone()
    };
    let f = fp("way 100");
    assert_eq!((f.base, f.top), (0.0, 12.0), "height");
    let f = fp("way 101");
    assert_eq!(
        (f.base, f.top),
        (3.0, 15.0),
        "storeys and building:min_level"
    );
    let f = fp("relation 200");
    assert_eq!((f.base, f.top), (0.0, 25.0), "\"30 m\" less roof:height");
    assert_eq!(f.polygons.len(), 1);
    assert_eq!(
        f.polygons[0].len(),
        2,
        "the outer ring from two ways, and the hole"
    );
    let reasons: Vec<(String, String)> = s
        .report
        .skipped
        .iter()
        .map(|(_, k)| (k.name.clone(), k.reason.label()))
        .collect();
    assert_eq!(
        reasons,
        [
            ("way 102".into(), "geometry not all in the file".into()),
            (
                "way 104".into(),
                "no height attribute and no storey count".into()
            ),
            (
                "way 105".into(),
                "height attribute \"height\" out of range".into()
            ),
        ]
    );
    assert_eq!(s.crs().unwrap().name, "EPSG:32635");
    // Each footprint of 22 m or so in metres.
    let b = s.objects[0].bbox;
    assert!((b.max.x - b.min.x - 22.0).abs() < 2.0, "{b:?}");
}

#[test]
fn helsinki_pbf_reads_heights_from_its_tags_and_evaluates_with_no_false_culls() {
    let path = repo("data/helsinki/Helsinki.osm.pbf");
    let s = scene::load(std::slice::from_ref(&path), &ReadOptions::default()).unwrap();
    assert_eq!(s.report.files[0].format, "OpenStreetMap PBF");
    assert_eq!(s.objects.len(), 154);
    let from_storeys = s.report.height_fallbacks.len();
    assert_eq!(from_storeys, 138, "building:levels");
    assert_eq!(s.crs().unwrap().name, "EPSG:32635");
    let e = s.extent();
    assert!(e.max.x - e.min.x > 900.0 && e.max.x - e.min.x < 1100.0);
    assert!(e.max.y - e.min.y > 1500.0 && e.max.y - e.min.y < 1800.0);
    // Bake a seeded sample of cells and check them against the ray-sampled ground truth.
    let empty = bake(&s, Default::default(), Some(&[])).expect("the bake runs");
    let ids = sample_cells(&Store::parse(&empty.bytes).unwrap(), Some(10), 3);
    let baked = bake(&s, Default::default(), Some(&ids)).expect("the bake runs");
    let store = Store::parse(&baked.bytes).unwrap();
    let caster = Caster::new(&s);
    let tree = BoxTree::new(&object_boxes(&s));
    let truth = TruthParams {
        eyes: 8,
        samples_per_object: 1,
        radius: None,
        seed: 3,
        eye_above: None,
    };
    for &id in &ids {
        let r = vo_rays(&caster, &store, id, 8, 8, 3);
        assert_eq!(r.reached, 0, "cell {id}: rays reached a VO");
        let vs = cell_vs(&s, &store, &caster, id, &truth);
        let ev = eval_cell(&s, &store, &tree, id, &vs);
        assert!(ev.false_culls.is_empty(), "cell {id}: {:?}", ev.false_culls);
    }
}

#[test]
fn citygml_sample_gives_the_blockers_of_its_cityjson_and_bakes() {
    let gml = scene::load(
        &[repo("data/denhaag/DenHaag_01_lod2.gml")],
        &ReadOptions::default(),
    )
    .unwrap();
    assert_eq!(gml.report.files[0].format, "CityGML");
    assert_eq!(gml.crs().unwrap().name, "EPSG:28992");
    assert_eq!(gml.objects.len(), 234);
    let json = scene::load(
        &[repo("data/denhaag/DenHaag_01.json")],
        // Without its TINRelief, whose joins lower the bases of blockers standing on it (the
        // CityGML sample holds no terrain).
        &ReadOptions {
            no_terrain: true,
            ..ReadOptions::default()
        },
    )
    .unwrap();
    // Per object, by id: the same blockers in world coordinates.
    let world = |s: &Scene, name: &str| {
        let o = s.objects.iter().find(|o| o.name == name).unwrap();
        let mut b: Vec<String> = s
            .blockers
            .iter()
            .filter(|b| b.object == o.index)
            .map(|b| {
                let pts: Vec<String> = b
                    .polygon
                    .iter()
                    .map(|p| format!("{:?},{:?}", p.x + s.origin.x, p.y + s.origin.y))
                    .collect();
                format!(
                    "{} {:?} {:?}",
                    pts.join(" "),
                    b.base + s.origin.z,
                    b.top + s.origin.z
                )
            })
            .collect();
        b.sort();
        b
    };
    let mut walls = 0;
    for o in &gml.objects {
        let a = world(&gml, &o.name);
        assert_eq!(a, world(&json, &o.name), "{}", o.name);
        walls += a.len();
    }
    assert!(walls > 2000, "{walls} blockers");
    let empty = bake(&gml, Default::default(), Some(&[])).expect("the bake runs");
    let ids = sample_cells(&Store::parse(&empty.bytes).unwrap(), Some(6), 5);
    let baked = bake(&gml, Default::default(), Some(&ids)).expect("the bake runs");
    let store = Store::parse(&baked.bytes).unwrap();
    let caster = Caster::new(&gml);
    for &id in &ids {
        assert_eq!(
            vo_rays(&caster, &store, id, 8, 8, 5).reached,
            0,
            "cell {id}"
        );
    }
}

#[test]
fn delft_as_cityjsonseq_reads_as_its_cityjson() {
    let seq = scene::load(
        &[repo("data/delft/delft.city.jsonl")],
        &ReadOptions::default(),
    )
    .unwrap();
    let json = scene::load(&[repo("data/delft/delft.json")], &ReadOptions::default()).unwrap();
    assert_eq!(seq.report.files[0].format, "CityJSONSeq");
    same_geometry(&json, &seq, "CityJSONSeq");
    assert_eq!(seq.crs().unwrap().name, "EPSG:7415");
}

/// A literal two-building GeoJSON of Lyon in longitude/latitude, with an optional `crs` member.
fn lonlat(crs: &str) -> String {
    format!(
        r#"{{"type": "FeatureCollection", {crs} "features": [
{{"type": "Feature", "properties": {{"h": 20}}, "geometry": {{"type": "Polygon", "coordinates": [[[4.8330, 45.7640], [4.8334, 45.7640], [4.8334, 45.7643], [4.8330, 45.7643], [4.8330, 45.7640]]]}}}},
{{"type": "Feature", "properties": {{"h": 25}}, "geometry": {{"type": "Polygon", "coordinates": [[[4.8340, 45.7640], [4.8344, 45.7640], [4.8344, 45.7643], [4.8340, 45.7643], [4.8340, 45.7640]]]}}}}
]}}"#
    )
}

fn load_text(files: &[(&str, &str)], opts: &ReadOptions) -> Result<Scene, scene::LoadError> {
    let owned: Vec<(PathBuf, &[u8])> = files
        .iter()
        .map(|(n, t)| (PathBuf::from(n), t.as_bytes()))
        .collect();
    scene::load_bytes(&owned, opts)
}

fn h() -> ReadOptions {
    ReadOptions {
        height_attr: Some("h".into()),
        ..ReadOptions::default()
    }
}

/// Issue 33, defect 1: a GeoJSON in longitude/latitude baked into "0 x 0 x 70 m", 1 cell, 0 VOs,
/// with no warning; its `crs` member was ignored.
#[test]
fn defect1_lonlat_geojson_bakes_silently_into_a_useless_store() {
    for crs in [
        "",
        r#""crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:OGC:1.3:CRS84"}},"#,
        r#""crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::4326"}},"#,
    ] {
        let s = load_text(&[("a.geojson", &lonlat(crs))], &h()).unwrap();
        let c = s.crs().unwrap();
        assert_eq!(c.name, "EPSG:32631", "{crs}");
        let e = s.extent();
        // 0.0014 degrees of longitude at 45.76 N: about 109 m.
        assert!(
            (e.max.x - e.min.x - 109.0).abs() < 3.0,
            "{crs}: {} m",
            e.max.x - e.min.x
        );
        let file = s.report.files[0].crs.as_ref().unwrap();
        let want = if crs.is_empty() {
            CrsSource::Detected
        } else {
            CrsSource::File
        };
        assert_eq!(file.source, want);
    }
    // A stated projected CRS is kept: Lyon's own.
    let stated =
        r#""crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::3946"}},"#;
    let text = lonlat(stated)
        .replace("4.83", "184")
        .replace("45.76", "51760");
    let s = load_text(&[("b.geojson", &text)], &h()).unwrap();
    assert_eq!(s.crs().unwrap().name, "EPSG:3946");
    assert_eq!(s.crs().unwrap().source, CrsSource::File);
}

/// Issue 33, defect 1: inputs in two CRSs are projected into one, or refused naming both CRSs
/// and files (not by the grid-size check).
#[test]
fn defect1_inputs_in_two_crs_are_projected_or_refused_by_name() {
    // Longitude/latitude beside Lyon's EPSG:3946: projected into EPSG:3946.
    let lyon = std::fs::read_to_string(repo(common::LYON)).unwrap();
    let s = load_text(
        &[("lyon.geojson", &lyon), ("ll.geojson", &lonlat(""))],
        &ReadOptions {
            height_attr: Some("HAUTEUR".into()),
            levels_attr: Some("h".into()),
            storey_height: 1.0,
            ..ReadOptions::default()
        },
    )
    .unwrap();
    let c = s.crs().unwrap();
    assert_eq!(c.name, "EPSG:3946");
    assert_eq!(c.projected_from, ["EPSG:4326"]);
    assert!(
        c.to_string().contains("projected on load from EPSG:4326"),
        "{c}"
    );
    // Beside a file that states no CRS (an OBJ, metres of unknown origin): refused by name.
    let obj = "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let e = load_text(&[("ll.geojson", &lonlat("")), ("m.obj", obj)], &h()).unwrap_err();
    let LoadErrorKind::MixedCrs(c) = &e.kind else {
        panic!("{e}")
    };
    let (a_file, a_crs, b_file, b_crs) = (&c.a_file, &c.a_crs, &c.b_file, &c.b_crs);
    assert_eq!(a_file, &PathBuf::from("ll.geojson"));
    assert!(a_crs.contains("EPSG:4326"), "{a_crs}");
    assert_eq!(b_file, &PathBuf::from("m.obj"));
    assert_eq!(b_crs, "no CRS stated");
    // A CRS known only by name beside an EPSG one: refused, naming both.
    let named = r#""crs": {"type": "name", "properties": {"name": "My local grid"}},"#;
    let text = lonlat(named)
        .replace("4.83", "184")
        .replace("45.76", "51760");
    let e = load_text(&[("lyon.geojson", &lyon), ("local.geojson", &text)], &{
        ReadOptions {
            height_attr: Some("HAUTEUR".into()),
            levels_attr: Some("h".into()),
            ..ReadOptions::default()
        }
    })
    .unwrap_err();
    assert!(matches!(e.kind, LoadErrorKind::MixedCrs(_)), "{e}");
    let m = e.to_string();
    assert!(
        m.contains("EPSG:3946") && m.contains("My local grid") && m.contains("local.geojson"),
        "{m}"
    );
}

/// Issue 33, defect 7: "317 of Helsinki's 486 features are skipped without a hint that
/// --default-height exists".
#[test]
fn defect7_many_features_without_height_name_default_height() {
    let s = scene::load(
        &[repo("data/helsinki/Helsinki.osm.pbf")],
        &ReadOptions::default(),
    )
    .unwrap();
    let note = s
        .report
        .notes
        .iter()
        .find(|n| n.contains("--default-height"))
        .expect("a note naming --default-height");
    assert!(note.contains("292 of 500"), "{note}");
    let s = scene::load(
        &[repo("data/helsinki/Helsinki.osm.pbf")],
        &ReadOptions {
            default_height: Some(9.0),
            ..ReadOptions::default()
        },
    )
    .unwrap();
    assert_eq!(s.objects.len(), 154 + 292);
    assert!(s.report.notes.is_empty(), "{:?}", s.report.notes);
}

/// Issue 33, defect 7: "`1e300` aborts the load even under `--on-bad-height skip`, while 1e6 m
/// is accepted without a word".
#[test]
fn defect7_height_1e300_is_a_bad_height_not_an_abort_and_1e6_is_not_accepted() {
    let path = repo("tests/fixtures/broken/geojson_height_1e300.geojson");
    let opts = ReadOptions {
        height_attr: Some("height".into()),
        ..ReadOptions::default()
    };
    let s = scene::load(std::slice::from_ref(&path), &opts).unwrap();
    assert_eq!(s.objects.len(), 1);
    let reasons: Vec<(u32, String)> = s
        .report
        .skipped
        .iter()
        .map(|(_, k)| (k.feature, k.reason.to_string()))
        .collect();
    assert_eq!(
        reasons,
        [
            (
                1,
                "height attribute \"height\" is 1e300 m, beyond the 1000 m a height may have"
                    .to_string()
            ),
            (
                2,
                "height attribute \"height\" is 1e6 m, beyond the 1000 m a height may have"
                    .to_string()
            ),
        ]
    );
    let e = scene::load(
        &[path],
        &ReadOptions {
            on_bad_height: OnBadHeight::Error,
            ..opts
        },
    )
    .unwrap_err();
    assert_eq!(e.location, Location::Feature(1));
    assert!(matches!(e.kind, LoadErrorKind::AbsurdHeight { value, .. } if value == 1e300));
    assert!(
        e.to_string()
            .contains("feature 1: attribute \"height\" has value 1e300 m"),
        "{e}"
    );
}

/// Issue 33, defect 7: "OpenStreetMap's `min_height` and `building:min_level` are not read".
#[test]
fn defect7_min_height_and_building_min_level_are_read() {
    let text = r#"{"type": "FeatureCollection", "features": [
{"type": "Feature", "properties": {"height": 20, "min_height": 8}, "geometry": {"type": "Polygon", "coordinates": [[[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]]}},
{"type": "Feature", "properties": {"height": 20, "building:min_level": "2"}, "geometry": {"type": "Polygon", "coordinates": [[[20, 0], [30, 0], [30, 10], [20, 10], [20, 0]]]}},
{"type": "Feature", "properties": {"height": 20, "min_height": "low"}, "geometry": {"type": "Polygon", "coordinates": [[[40, 0], [50, 0], [50, 10], [40, 10], [40, 0]]]}}
]}"#;
    let s = load_text(
        &[("parts.geojson", text)],
        &ReadOptions {
            height_attr: Some("height".into()),
            ..ReadOptions::default()
        },
    )
    .unwrap();
    let spans: Vec<(f64, f64)> = s
        .objects
        .iter()
        .map(|o| match &o.shape {
            Shape::Footprint(f) => (f.base, f.top),
            _ => panic!(),
        })
        .collect();
    assert_eq!(spans, [(8.0, 20.0), (6.0, 20.0)]);
    // A bottom that is not a number is not taken for the ground: the part is skipped.
    assert!(matches!(
        &s.report.skipped[0].1.reason,
        SkipReason::BadBase { attr, .. } if attr == "min_height"
    ));
}

/// Issue 33, defect 8: "the same file given twice doubles the scene silently".
#[test]
fn defect8_the_same_file_given_twice_is_refused() {
    let a = repo(common::LYON);
    let b = repo("data/lyon1/../lyon1/buildings_lyon1.geojson");
    let e = scene::load(&[a.clone(), b.clone()], &lyon_options()).unwrap_err();
    assert_eq!(e.kind, LoadErrorKind::DuplicateFile { first: a });
    assert_eq!(e.path, b);
    assert!(e.to_string().contains("given again"), "{e}");
}

/// Issue 33, defect 8: "flags of another reader are ignored silently (`--lod` on GeoJSON)".
#[test]
fn defect8_flags_of_another_reader_are_noted() {
    let s = scene::load(
        &[repo(common::LYON)],
        &ReadOptions {
            lod: Some("2".into()),
            ..lyon_options()
        },
    )
    .unwrap();
    assert!(
        s.report
            .notes
            .iter()
            .any(|n| n.starts_with("--lod applies to CityJSON")
                && n.contains("buildings_lyon1.geojson")),
        "{:?}",
        s.report.notes
    );
    let s = scene::load(
        &[repo("data/delft/delft.json")],
        &ReadOptions {
            height_attr: Some("height".into()),
            ..ReadOptions::default()
        },
    )
    .unwrap();
    assert!(
        s.report
            .notes
            .iter()
            .any(|n| n.starts_with("--height-attr applies to") && n.contains("delft.json")),
        "{:?}",
        s.report.notes
    );
}
