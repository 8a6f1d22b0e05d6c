//! Issue 33, defects 1 to 6: CRS notes, one numbering (vocc boxes), the scene check, exit
//! status 2 for usage errors, one rule for output folders.

#[allow(unused_imports)]
use super::*;

/// Issue 33, defect 2 (three numberings): `vocc pvs` gave input feature numbers while the C
/// example's box file (`examples/boxes.rs`) gave positions among the loaded objects, with
/// nothing to map one to the other. `vocc boxes` writes each box beside its input feature
/// number, and names the scene; the C example prints those numbers (examples/c/test.sh).
#[test]
fn three_numberings_vocc_boxes_writes_input_feature_numbers_beside_the_boxes() {
    let dir = common::temp_dir("cli-boxes-ids");
    let scene = dir.join("row.geojson");
    std::fs::write(&scene, row_geojson("")).unwrap();
    let s = scene.to_str().unwrap();
    let out = dir.join("row.boxes");
    let (rc, err) = run(&[
        "boxes",
        s,
        "--height-attr",
        "h",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(rc, Some(0), "{err}");
    assert!(err.contains("wrote 2 boxes to"), "{err}");
    let rows = box_rows(&out);
    assert_eq!(rows.iter().map(|r| r.0).collect::<Vec<_>>(), [1, 3]);
    assert_eq!(
        rows[1].1,
        [1_842_060.0, 5_176_000.0, 0.0, 1_842_070.0, 5_176_010.0, 9.0]
    );
    let text = std::fs::read_to_string(&out).unwrap();
    let info: serde_json::Value =
        serde_json::from_slice(&vocc(&["info", s, "--height-attr", "h", "--json"]).stdout).unwrap();
    assert_eq!(info["objects"], 2);
    assert!(
        text.lines().nth(1).unwrap().starts_with("# scene ")
            && text.lines().nth(1).unwrap().contains(" objects 2 crs \"\""),
        "{text}"
    );
    // The example is gone; `vocc boxes` is documented where it was.
    assert!(!common::repo("examples/boxes.rs").exists());
    let doc = std::fs::read_to_string(common::repo("docs/EMBEDDING.md")).unwrap();
    assert!(doc.contains("vocc boxes ") && !doc.contains("--example boxes"));
}

/// Issue 33, defect 3: the C box writer read only --height-attr and --base-attr. `vocc boxes`
/// takes every reader flag: here --default-height gives features 0 and 2 a height, and
/// --on-bad-height error stops at "tall".
#[test]
fn vocc_boxes_takes_every_reader_flag_default_height_on_bad_height() {
    let dir = common::temp_dir("cli-boxes-flags");
    let scene = dir.join("row.geojson");
    std::fs::write(&scene, row_geojson("")).unwrap();
    let s = scene.to_str().unwrap();
    let out = dir.join("row.boxes");
    let o = out.to_str().unwrap();
    let (rc, err) = run(&[
        "boxes",
        s,
        "--height-attr",
        "h",
        "--default-height",
        "5",
        "-o",
        o,
    ]);
    assert_eq!(rc, Some(0), "{err}");
    let rows = box_rows(&out);
    assert_eq!(rows.iter().map(|r| r.0).collect::<Vec<_>>(), [0, 1, 2, 3]);
    assert_eq!(
        rows.iter().map(|r| r.1[5]).collect::<Vec<_>>(),
        [5.0, 12.13, 5.0, 9.0]
    );
    let (rc, err) = run(&[
        "boxes",
        s,
        "--height-attr",
        "h",
        "--on-bad-height",
        "error",
        "-o",
        o,
    ]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(err.contains("feature 2") && err.contains("tall"), "{err}");
    // Written whole or not at all: the failed run left the earlier file.
    assert_eq!(box_rows(&out).len(), 4);
}

/// Issue 33, defect 4: `pvs` and `eval` with other reader flags or another version of the file
/// answered silently (`eval` then reported false culls with no hint). The store's scene section
/// is checked: another scene is refused naming what differs and the likely cause; a 1.0 store
/// gets a note that the check could not be made; `--allow-other-scene` goes on with a warning.
#[test]
fn pvs_and_eval_with_other_reader_flags_or_another_version_of_the_file_say_what_differs() {
    let dir = common::temp_dir("cli-other-scene");
    let (scene, store) = tiny_scene_and_store(&dir);
    // Other reader flags: --base-attr height lifts every box; the same count, other boxes.
    let (rc, err) = run(&[
        "pvs",
        &store,
        &scene,
        "--height-attr",
        "height",
        "--base-attr",
        "height",
        "--cell",
        "24",
    ]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(
        err.contains("the scene is not the one the store was baked from: fingerprint ")
            && err.contains("likely other reader flags that change heights or bases")
            && err.contains("--allow-other-scene"),
        "{err}"
    );
    // Another version of the file: one building fewer.
    let v2 = dir.join("tiny-v2.geojson");
    let mut b = block(1_842_000.0, 5_176_000.0, 8);
    b.pop();
    std::fs::write(&v2, boxes_geojson(&b)).unwrap();
    let v2 = v2.to_str().unwrap();
    for args in [
        vec!["pvs", &store, v2, "--height-attr", "height", "--cell", "24"],
        vec![
            "eval",
            &store,
            v2,
            "--height-attr",
            "height",
            "--cell",
            "24",
            "--eyes",
            "4",
        ],
    ] {
        let (rc, err) = run(&args);
        assert_eq!(rc, Some(1), "{args:?}: {err}");
        assert!(
            err.contains("63 objects where 64 were baked")
                && err.contains("likely another file, or another version of it"),
            "{args:?}: {err}"
        );
        assert!(!err.contains("false cull"), "{err}");
    }
    // Told to go on, eval runs and says why its answer may not hold.
    let (rc, err) = run(&[
        "eval",
        &store,
        v2,
        "--height-attr",
        "height",
        "--cell",
        "24",
        "--eyes",
        "4",
        "--samples",
        "1",
        "--allow-other-scene",
    ]);
    assert!(matches!(rc, Some(0 | 3)), "{err}");
    assert!(
        err.contains("warning: ") && err.contains("not guaranteed"),
        "{err}"
    );
    // Another CRS: the scene states EPSG:3946 and is put into EPSG:2154.
    let crs_scene = dir.join("tiny-3946.geojson");
    let text = boxes_geojson(&block(1_842_000.0, 5_176_000.0, 4)).replacen(
        r#""type":"FeatureCollection","#,
        r#""type":"FeatureCollection","crs":{"type":"name","properties":{"name":"urn:ogc:def:crs:EPSG::3946"}},"#,
        1,
    );
    std::fs::write(&crs_scene, text).unwrap();
    let c = crs_scene.to_str().unwrap();
    let crs_store = dir.join("tiny-3946.vocc");
    let cs = crs_store.to_str().unwrap();
    let (rc, err) = run(&[
        "bake",
        c,
        "--height-attr",
        "height",
        "--cell-size",
        "50",
        "-o",
        cs,
    ]);
    assert_eq!(rc, Some(0), "{err}");
    let (rc, err) = run(&[
        "pvs",
        cs,
        c,
        "--height-attr",
        "height",
        "--crs",
        "EPSG:2154",
        "--cell",
        "0",
    ]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(
        err.contains("CRS EPSG:2154 where EPSG:3946 was baked")
            && err.contains("likely another CRS"),
        "{err}"
    );
    // A 1.0 store records no scene: the check could not be made, and the note says so.
    let old = dir.join("doc-1.0.vocc");
    std::fs::write(&old, doc_hex("store-1.0")).unwrap();
    let (_, err) = run(&[
        "pvs",
        old.to_str().unwrap(),
        &scene,
        "--height-attr",
        "height",
        "--cell",
        "0",
    ]);
    assert!(
        err.contains("note: ")
            && err.contains("(store 1.0) records no scene, so whether these files and reader flags are the ones baked could not be checked"),
        "{err}"
    );
}

/// Issue 33, defect 5: usage errors exited 1 like failed runs. Each literal case of the issue
/// exits 2 with the command's usage, before anything is read (the store here does not exist).
#[test]
fn usage_errors_exit_2_missing_cell_or_at_export_format_render_scene_shard_2_of_2_sort_culled() {
    let cases: Vec<Vec<&str>> = vec![
        vec!["pvs", "missing.vocc", LYON, "--height-attr", "HAUTEUR"],
        vec!["export", "missing.vocc", "--cell", "3"],
        vec!["render", "missing.vocc", "--cell", "3", "-o", "/tmp/x.svg"],
        vec!["render", "missing.vocc", LYON, "-o", "/tmp/x.svg"],
        vec!["render", "--debug", LYON, "-o", "/tmp/x.svg"],
        vec![
            "bake",
            LYON,
            "--height-attr",
            "HAUTEUR",
            "--shard",
            "2/2",
            "-o",
            "/tmp/s.vocc",
        ],
        vec!["bake", LYON, "--shard-count", "4", "-o", "/tmp/s.vocc"],
        vec![
            "inspect",
            "missing.vocc",
            "--list-cells",
            "--sort",
            "culled",
        ],
        vec!["inspect", "missing.vocc", LYON, "--cell", "3"],
        vec!["help", "nosuch"],
    ];
    for args in cases {
        let (rc, err) = run(&args);
        assert_eq!(rc, Some(2), "{args:?}: {err}");
        assert!(err.contains("try '--help'"), "{args:?}: {err}");
        assert!(!err.contains("missing.vocc"), "{args:?} read a file: {err}");
    }
    // Under a job array, --shard auto without its count is a usage error too; without any
    // array engine's variable it is the environment that does not fit (1).
    let out = Command::new(common::vocc_bin())
        .args(["bake", LYON, "--shard", "auto", "-o", "/tmp/s.vocc"])
        .env("JOB_COMPLETION_INDEX", "1")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{out:?}");
}

/// Issue 33, defect 6: `bake` and `export` refused a missing folder while `eval --report`
/// created it (and `render -o` and `gen-city -o` were said to). One rule: vocc creates the
/// output it is asked for (a file, or the report folder itself), never the folders above it.
/// And the report is written all or nothing (the full disk case: `files.rs`,
/// `eval_report_on_a_full_disk_leaves_no_half_report`).
#[test]
fn one_rule_for_output_folders_render_eval_report_gen_city_refuse_a_missing_folder() {
    let dir = common::temp_dir("cli-output-folders");
    let (scene, store) = tiny_scene_and_store(&dir);
    let missing = dir.join("no/such");
    let m = |name: &str| missing.join(name).to_str().unwrap().to_string();
    let cases: Vec<Vec<String>> = vec![
        vec![
            "render".into(),
            store.clone(),
            scene.clone(),
            "--height-attr".into(),
            "height".into(),
            "--cell".into(),
            "24".into(),
            "-o".into(),
            m("x.svg"),
        ],
        vec![
            "gen-city".into(),
            "--buildings".into(),
            "10".into(),
            "-o".into(),
            m("c.geojson"),
        ],
        vec![
            "boxes".into(),
            scene.clone(),
            "--height-attr".into(),
            "height".into(),
            "-o".into(),
            m("b.boxes"),
        ],
        // Checked before the store (missing too) is read.
        vec![
            "eval".into(),
            "missing.vocc".into(),
            scene.clone(),
            "--height-attr".into(),
            "height".into(),
            "--report".into(),
            m("report"),
        ],
    ];
    for args in cases {
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let (rc, err) = run(&a);
        assert_eq!(rc, Some(1), "{a:?}: {err}");
        assert!(
            err.contains(&format!("the folder {} does not exist", missing.display())),
            "{a:?}: {err}"
        );
    }
    assert!(!dir.join("no").exists(), "a folder was created");
    // The report folder itself is created, then replaced whole; no temporary folder is left.
    let rep = dir.join("report");
    for _ in 0..2 {
        let (rc, err) = run(&[
            "eval",
            &store,
            &scene,
            "--height-attr",
            "height",
            "--cell",
            "24",
            "--eyes",
            "4",
            "--samples",
            "1",
            "--report",
            rep.to_str().unwrap(),
        ]);
        assert_eq!(rc, Some(0), "{err}");
        let mut names: Vec<String> = std::fs::read_dir(&rep)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["eval.md", "map.svg", "vos.svg"]);
    }
    let mut left: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    left.sort();
    assert!(left.is_empty(), "{left:?}");
    let readme = std::fs::read_to_string(common::repo("README.md")).unwrap();
    assert!(
        readme.contains("never the folders above it"),
        "README states the rule"
    );
}

/// Issue 33, defect 8: `render`'s legend counted only its window without saying so, VO labels
/// fell off the canvas, and there was no scale bar. Here 300 m views of 50 m cells whose VOs
/// reach the view's edge (their labels stood at y = 0 and x = 882 of 900): the cells with the
/// most VOs, in that order, until one has a VO in its view to label (a corner cell's VOs may
/// all lie beyond it); every view's text is checked.
#[test]
fn render_legend_names_its_window_vo_labels_stay_on_the_canvas_and_a_scale_bar() {
    let dir = common::temp_dir("cli-render-legend");
    let (scene, store) = tiny_scene_and_store(&dir);
    let top: serde_json::Value = serde_json::from_slice(
        &vocc(&[
            "inspect",
            &store,
            "--list-cells",
            "--sort",
            "vos",
            "--top",
            "8",
            "--json",
        ])
        .stdout,
    )
    .unwrap();
    let cells = top["cells"].as_array().unwrap();
    assert!(cells[0]["vos"].as_u64().unwrap() >= 3, "{top}");
    let svg = dir.join("cell.svg");
    let attr = |t: &str, name: &str| -> f64 {
        t.split(&format!(" {name}=\""))
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    let mut labelled = false;
    for c in cells.iter().filter(|c| c["vos"].as_u64().unwrap() >= 3) {
        let cell = c["cell"].to_string();
        let (rc, err) = run(&[
            "render",
            &store,
            &scene,
            "--height-attr",
            "height",
            "--cell",
            &cell,
            "--radius",
            "150",
            "-o",
            svg.to_str().unwrap(),
        ]);
        assert_eq!(rc, Some(0), "{err}");
        let text = std::fs::read_to_string(&svg).unwrap();
        let (w, h) = (attr(&text, "width"), attr(&text, "height"));
        let mut labels = 0;
        for t in text.split("<text").skip(1) {
            let (x, y) = (attr(t, "x"), attr(t, "y"));
            assert!(
                (0.0..=w).contains(&x) && (0.0..=h).contains(&y),
                "cell {cell}, off the canvas: <text{t}"
            );
            let body = t.split('>').nth(1).unwrap().split('<').next().unwrap();
            labels += usize::from(body.parse::<u32>().is_ok());
        }
        assert!(
            text.contains("in this view (300 m square): visible "),
            "{text}"
        );
        assert!(text.contains("whole scene: PVS "), "{text}");
        assert!(text.contains(">50 m</text>"), "a scale bar: {text}");
        if labels > 0 {
            labelled = true;
            break;
        }
    }
    assert!(labelled, "no view labels a VO: {top}");
}
