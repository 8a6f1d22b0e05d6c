//! Issue 13's friction and issue 12: listings, errors not silent no-ops, help, JSON summaries,
//! captions, messages, input feature numbers, the pictures of meshes and skipped objects.

#[allow(unused_imports)]
use super::*;

/// Issue 13 (friction): silent no-ops. `--region` outside the grid baked 0 cells and exited 0;
/// `pvs` with a scene in another coordinate system than the store reported 100% visible. Both
/// are errors now, naming the grid.
#[test]
fn region_outside_the_grid_and_pvs_with_a_scene_elsewhere_are_errors_not_silent_no_ops() {
    let dir = common::temp_dir("cli-silent-no-ops");
    let (scene, store) = tiny_scene_and_store(&dir);
    let (rc, err) = run(&[
        "bake",
        &scene,
        "--height-attr",
        "height",
        "--region",
        "0,0,100,100",
        "-o",
        dir.join("r.vocc").to_str().unwrap(),
    ]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(
        err.contains("meets no cell of the grid, which covers x 1842000.0..1842400.0"),
        "{err}"
    );
    let elsewhere = dir.join("rd.geojson");
    std::fs::write(&elsewhere, boxes_geojson(&block(78_500.0, 457_900.0, 3))).unwrap();
    let (rc, err) = run(&[
        "pvs",
        &store,
        elsewhere.to_str().unwrap(),
        "--height-attr",
        "height",
        "--cell",
        "0",
    ]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(
        err.contains(
            "the scene is not the one the store was baked from: 9 objects where 64 were baked"
        ),
        "{err}"
    );
    // Told to go on, the grid still refuses it.
    let (rc, err) = run(&[
        "pvs",
        &store,
        elsewhere.to_str().unwrap(),
        "--height-attr",
        "height",
        "--cell",
        "0",
        "--allow-other-scene",
    ]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(
        err.contains("no object of the scene meets the grid"),
        "{err}"
    );
}

/// Issue 13 (friction): `vocc help --help` failed; bake, eval and render had no examples.
#[test]
fn help_help_works_and_bake_eval_render_show_examples() {
    let out = vocc(&["help", "--help"]);
    assert_eq!(out.status.code(), Some(0));
    let out = vocc(&["help", "bake"]);
    assert_eq!(out.status.code(), Some(0));
    for cmd in ["bake", "eval", "render"] {
        let h = String::from_utf8_lossy(&vocc(&[cmd, "--help"]).stdout).into_owned();
        assert!(
            h.contains("Examples:") && h.contains(&format!("vocc {cmd} ")),
            "{cmd}: {h}"
        );
    }
    // Every command's one-line summary fits a line.
    let h = String::from_utf8_lossy(&vocc(&["--help"]).stdout).into_owned();
    for l in h.lines().filter(|l| l.starts_with("  ")) {
        assert!(l.chars().count() <= 100, "too long: {l}");
    }
}

/// Issue 13 (friction): `bake --json`, a machine-readable summary, with the scene's skipped
/// objects; and a bake logged to a file shows progress lines, not nothing.
#[test]
fn bake_json_summary_carries_cells_vos_timings_bytes_and_skipped_objects() {
    let dir = common::temp_dir("cli-bake-json");
    let scene = dir.join("city.geojson");
    let mut text = boxes_geojson(&block(1_842_000.0, 5_176_000.0, 8));
    // One feature without a height: skipped, with its reason.
    text = text.replacen(r#""properties":{"height":20}"#, r#""properties":{}"#, 1);
    std::fs::write(&scene, text).unwrap();
    let store = dir.join("c.vocc");
    let out = Command::new(common::vocc_bin())
        .args([
            "bake",
            scene.to_str().unwrap(),
            "--height-attr",
            "height",
            "--cell-size",
            "50",
            "--json",
            "-o",
            store.to_str().unwrap(),
        ])
        .env("VOCC_PROGRESS_SECONDS", "0")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["cells_baked"], 49);
    assert_eq!(v["store_bytes"], std::fs::metadata(&store).unwrap().len());
    assert!(v["vos"].as_u64().unwrap() > 10, "{v}");
    assert!(v["timings"]["bake_s"].as_f64().unwrap() > 0.0);
    // Where the bake spent its time, by the long generator's stage: every stage named, none
    // negative, together no more than the threads' time over the bake.
    let stages = v["stages_s"].as_object().expect("stages_s");
    let names: Vec<&str> = stages.keys().map(|k| k.as_str()).collect();
    assert_eq!(
        names,
        ["far_field", "maps", "proposals", "selection", "weights"],
        "{v}"
    );
    let sum: f64 = stages.values().map(|s| s.as_f64().unwrap()).sum();
    assert!(stages.values().all(|s| s.as_f64().unwrap() >= 0.0), "{v}");
    let budget = v["timings"]["bake_s"].as_f64().unwrap() * v["threads"].as_f64().unwrap();
    assert!(
        sum > 0.0 && sum <= budget * 1.01 + 1e-3,
        "{sum} s of stages in {budget} s: {v}"
    );
    // The far field: this small scene's one block of 8 x 8 cells lies among few blockers, so
    // it is sought per quarter (4 x 4 cells).
    let far = &v["far_searches"];
    assert_eq!(far[0], 0, "{v}");
    assert!((1..=4).contains(&far[1].as_u64().unwrap()), "{v}");
    assert_eq!(v["scene"]["skipped"], 1, "{v}");
    assert_eq!(
        v["scene"]["skipped_by_reason"]["no height attribute and no storey count"], 1,
        "{v}"
    );
    // stderr is not a terminal here: progress comes as lines.
    assert!(
        err.contains("baking: 49 cells") && err.contains("cells/s"),
        "{err}"
    );
}

/// Issue 13, defect 7: the render caption overflowed the picture's right edge in every render
/// (one line of about 150 characters in a 900 px picture). Every caption line fits: at 13 px
/// sans-serif a character is at most about 0.6 em wide on average.
#[test]
fn render_caption_fits_within_the_pictures_right_edge() {
    let dir = common::temp_dir("cli-render-caption");
    let (scene, store) = tiny_scene_and_store(&dir);
    let svg = dir.join("cell.svg");
    let (rc, err) = run(&[
        "render",
        &store,
        &scene,
        "--height-attr",
        "height",
        "--cell",
        "24",
        "-o",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(rc, Some(0), "{err}");
    let text = std::fs::read_to_string(&svg).unwrap();
    let width: f64 = text
        .split("width=\"")
        .nth(1)
        .and_then(|t| t.split('"').next())
        .unwrap()
        .parse()
        .unwrap();
    let mut captions = 0;
    for t in text.split("<text ").skip(1) {
        let x: f64 = t
            .split("x=\"")
            .nth(1)
            .and_then(|v| v.split('"').next())
            .unwrap()
            .parse()
            .unwrap();
        let body = t.split('>').nth(1).unwrap().split('<').next().unwrap();
        if body.len() < 20 {
            continue; // a VO's number
        }
        captions += 1;
        let right = x + 0.6 * 13.0 * body.chars().count() as f64;
        assert!(
            right <= width,
            "caption reaches {right:.0} px of {width}: {body}"
        );
    }
    assert!(captions >= 2, "{text}");
}

/// Issue 13, defect 11: a one-triangle OBJ was reported as "closed mesh, but no column could be
/// proven solid". Its three edges are each used once: it is an open mesh.
#[test]
fn a_one_triangle_obj_is_an_open_mesh_not_a_closed_one() {
    let dir = common::temp_dir("cli-one-triangle");
    let obj = dir.join("triangle.obj");
    std::fs::write(&obj, "o tri\nv 0 0 0\nv 10 0 0\nv 0 10 0\nf 1 2 3\n").unwrap();
    let out = vocc(&["info", obj.to_str().unwrap(), "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let reasons = v["no_blocker"].as_array().unwrap();
    assert_eq!(reasons.len(), 1, "{v}");
    let why = reasons[0]["reason"].as_str().unwrap();
    assert!(why.starts_with("open mesh (3 edges"), "{why}");
    assert!(!why.contains("closed mesh"), "{why}");
}

/// Issue 13 (friction), misleading messages: a 1e9 m height was blamed as a coordinate; a
/// 1e300 coordinate printed 301 digits; a missing `--height-attr` said
/// `attribute "(none given)" is missing`.
#[test]
fn messages_blame_the_height_print_1e300_short_and_ask_for_height_attr() {
    let dir = common::temp_dir("cli-messages");
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let tall = write(
        "tall.geojson",
        r#"{"type":"FeatureCollection","features":[{"type":"Feature","properties":{"height":1e9},"geometry":{"type":"Polygon","coordinates":[[[0,0],[10,0],[10,10],[0,10],[0,0]]]}}]}"#,
    );
    let far = write(
        "far.geojson",
        r#"{"type":"FeatureCollection","features":[{"type":"Feature","properties":{"height":10},"geometry":{"type":"Polygon","coordinates":[[[1e300,0],[10,0],[10,10],[0,10],[1e300,0]]]}}]}"#,
    );
    let (rc, err) = run(&["info", &tall, "--height-attr", "height"]);
    assert_eq!(rc, Some(1));
    // Issue 33, defect 7: a height beyond 1,000 m is a bad height; here the only one.
    assert!(
        err.contains("feature 0: \"height\" is 1e9 m, beyond the 1000 m a height may have"),
        "{err}"
    );
    assert!(!err.contains("coordinate"), "{err}");
    let (rc, err) = run(&["info", &far, "--height-attr", "height"]);
    assert_eq!(rc, Some(1));
    assert!(
        err.contains("coordinate x = 1e300 m is out of range"),
        "{err}"
    );
    assert!(err.len() < 300, "{} bytes: {err}", err.len());
    let (rc, err) = run(&["info", &far]);
    assert_eq!(rc, Some(1));
    assert!(
        err.contains("need a height: give --height-attr NAME"),
        "{err}"
    );
    assert!(!err.contains("(none given)"), "{err}");
}

/// Issue 13 (friction): `--lod 9` said "the scene has no objects"; it names the LoDs there are.
#[test]
fn lod_9_lists_the_lods_that_exist_not_the_scene_has_no_objects() {
    let dir = common::temp_dir("cli-lod-9");
    let city = dir.join("city.json");
    std::fs::write(
        &city,
        r#"{"type":"CityJSON","version":"1.1","transform":{"scale":[1,1,1],"translate":[0,0,0]},
        "vertices":[[0,0,0],[10,0,0],[10,10,0],[0,10,0]],
        "CityObjects":{"b1":{"type":"Building","geometry":[
          {"type":"MultiSurface","lod":"1","boundaries":[[[0,1,2,3]]]},
          {"type":"MultiSurface","lod":"2.2","boundaries":[[[0,1,2,3]]]}]}}}"#,
    )
    .unwrap();
    let (rc, err) = run(&["info", city.to_str().unwrap(), "--lod", "9"]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(
        err.contains("no object has geometry at LoD 9; the files hold LoD 1, 2.2"),
        "{err}"
    );
}

/// Issue 12: objects skipped for their height vanished without a word in `bake`, and `pvs`
/// numbered the loaded objects, not the input features.
#[test]
fn bake_counts_skipped_features_and_pvs_keeps_input_feature_numbers() {
    let dir = common::temp_dir("cli-feature-numbers");
    let scene = dir.join("row.geojson");
    let f = |i: usize, h: &str| {
        let x = 20 * i;
        format!(
            r#"{{"type":"Feature","properties":{{"h":{h}}},"geometry":{{"type":"Polygon","coordinates":[[[{x},0],[{},0],[{},10],[{x},10],[{x},0]]]}}}}"#,
            x + 10,
            x + 10
        )
    };
    let text = format!(
        r#"{{"type":"FeatureCollection","features":[{},{},{},{}]}}"#,
        f(0, "null"),
        f(1, "\"12.13 m\""),
        f(2, "\"tall\""),
        f(3, "9")
    );
    std::fs::write(&scene, text).unwrap();
    let store = dir.join("row.vocc");
    let s = scene.to_str().unwrap();
    let out = vocc(&[
        "bake",
        s,
        "--height-attr",
        "h",
        "-o",
        store.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("scene: 2 objects; 2 skipped (1 height attribute \"h\" not a number, 1 no height attribute and no storey count; vocc info lists each)"),
        "{err}"
    );
    let out = vocc(&[
        "pvs",
        store.to_str().unwrap(),
        s,
        "--height-attr",
        "h",
        "--cell",
        "0",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["pvs"], serde_json::json!([1, 3]), "{v}");
    // info names them by the same numbers.
    let out = vocc(&["info", s, "--height-attr", "h"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains(r##"#2 "feature 2""##), "{text}");
    assert!(
        text.contains(r#"height attribute "h" is "tall", not a number"#),
        "{text}"
    );
    // Under --on-bad-height error the load stops at feature 2.
    let out = vocc(&["info", s, "--height-attr", "h", "--on-bad-height", "error"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(r#"feature 2: attribute "h" has value "tall", which is not a number"#),
        "{err}"
    );
}

/// Issue 12, pictures: `render` drew mesh objects as their bounding boxes and left skipped
/// objects out. A mesh of walls alone (an open L, no roof) is drawn by its walls' lines, and the
/// GeoJSON features skipped for their height are drawn dashed.
#[test]
fn render_draws_mesh_walls_and_skipped_objects() {
    let dir = common::temp_dir("cli-render-walls");
    let geo = dir.join("row.geojson");
    let f = |i: usize, h: &str| {
        let x = 20 * i;
        format!(
            r#"{{"type":"Feature","properties":{{"h":{h}}},"geometry":{{"type":"Polygon","coordinates":[[[{x},0],[{},0],[{},10],[{x},10],[{x},0]]]}}}}"#,
            x + 10,
            x + 10
        )
    };
    std::fs::write(
        &geo,
        format!(
            r#"{{"type":"FeatureCollection","features":[{},{},{}]}}"#,
            f(0, "null"),
            f(1, "8"),
            f(2, "\"tall\"")
        ),
    )
    .unwrap();
    // Two walls of an L from (0,30) to (30,30) to (30,60), 6 m high.
    let obj = dir.join("l.obj");
    std::fs::write(
        &obj,
        "o l\nv 0 30 0\nv 30 30 0\nv 30 30 6\nv 0 30 6\nv 30 60 0\nv 30 60 6\nf 1 2 3 4\nf 2 5 6 3\n",
    )
    .unwrap();
    let store = dir.join("s.vocc");
    let (g, o, st) = (
        geo.to_str().unwrap(),
        obj.to_str().unwrap(),
        store.to_str().unwrap(),
    );
    let out = vocc(&["bake", g, o, "--height-attr", "h", "-o", st]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let svg = dir.join("c.svg");
    let out = vocc(&[
        "render",
        st,
        g,
        o,
        "--height-attr",
        "h",
        "--cell",
        "0",
        "-o",
        svg.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    assert_eq!(
        text.matches("stroke-dasharray").count(),
        2,
        "two skipped features"
    );
    assert!(text.contains("2 skipped objects (dashed)"), "{text}");
    // The L's walls: one open polyline per wall face (no closing Z), drawn as strokes; and no
    // filled box for it.
    let walls: Vec<&str> = text
        .split("<path d=\"")
        .skip(1)
        .map(|p| p.split("/>").next().unwrap())
        .filter(|p| p.contains("stroke-width=\"2\""))
        .collect();
    assert_eq!(walls.len(), 1, "{text}");
    assert_eq!(walls[0].split('"').next().unwrap().matches('M').count(), 2);
    assert!(!walls[0].split('"').next().unwrap().contains('Z'));
}

/// Issue 33, defect 1: `info` reports the CRS of every input and of the scene, and the notes of
/// the load (many buildings without a height, flags no input uses); `bake` prints the notes.
#[test]
fn info_reports_each_files_crs_the_scenes_and_the_notes() {
    let pbf = common::repo("data/helsinki/Helsinki.osm.pbf");
    let pbf = pbf.to_str().unwrap();
    let out = vocc(&["info", pbf, "--lod", "2"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("(OpenStreetMap PBF, CRS EPSG:4326 (from the file)): 154 objects"),
        "{text}"
    );
    assert!(
        text.contains("CRS: EPSG:32635 (projected on load from EPSG:4326)"),
        "{text}"
    );
    assert!(
        text.contains("292 of 500 OpenStreetMap PBF features skipped for want of a height")
            && text.contains("--default-height M"),
        "{text}"
    );
    assert!(text.contains("note: --lod applies to CityJSON"), "{text}");
    let out = vocc(&["info", pbf, "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["crs_epsg"], 32635);
    assert_eq!(v["files"][0]["crs"], "EPSG:4326 (from the file)");
}
