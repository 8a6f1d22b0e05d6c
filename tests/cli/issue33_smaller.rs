//! Issue 33, defect 8 (the smaller ones): render's legend and labels, inspect on a blob, the
//! walkable area's message, the renamed --cells, plurals, rounded timings, threads, bake --json's words.

#[allow(unused_imports)]
use super::*;

/// Issue 33, defect 8: `inspect` on a blob said "truncated store". A blob, its frame and a
/// `.hashes` file are each named as what they are.
#[test]
fn inspect_on_a_blob_says_it_is_a_blob_not_a_truncated_store() {
    let dir = common::temp_dir("cli-inspect-blob");
    let (_, store) = tiny_scene_and_store(&dir);
    let blob = dir.join("c.blob");
    let b = blob.to_str().unwrap();
    let (rc, err) = run(&["export", &store, "--cell", "24", "--blob", b]);
    assert_eq!(rc, Some(0), "{err}");
    for (file, what) in [
        (b.to_string(), "it is a per-cell blob"),
        (format!("{b}.frame"), "it is a store's frame"),
        (
            format!("{store}.hashes"),
            "it is the content hashes of a bake",
        ),
    ] {
        let (rc, err) = run(&["inspect", &file]);
        assert_eq!(rc, Some(1), "{err}");
        assert!(err.contains(what) && !err.contains("truncated"), "{err}");
    }
}

/// Issue 33, defect 8: the message for a Point in the walkable area swallowed its explanation
/// inside the quoted type name (`unknown geometry type "Point (a walkable area ...)"`).
#[test]
fn a_point_in_the_walkable_area_keeps_its_explanation() {
    let dir = common::temp_dir("cli-walkable-point");
    let (scene, _) = tiny_scene_and_store(&dir);
    let pt = dir.join("pt.geojson");
    std::fs::write(
        &pt,
        r#"{"type":"FeatureCollection","features":[{"type":"Feature","properties":{},"geometry":{"type":"Point","coordinates":[1842000,5176050]}}]}"#,
    )
    .unwrap();
    let (rc, err) = run(&[
        "bake",
        &scene,
        "--height-attr",
        "height",
        "--walkable",
        pt.to_str().unwrap(),
        "-o",
        dir.join("w.vocc").to_str().unwrap(),
    ]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(
        err.contains(r#"feature 0: geometry type "Point" has no area: a walkable area is made of Polygon and MultiPolygon geometries"#),
        "{err}"
    );
    assert!(!err.contains(r#""Point ("#), "{err}");
}

/// Issue 33, defect 8: `--cells` meant a file in `bake`, a count in `eval` and a switch in
/// `inspect`. The names say what they are (`--walkable FILE`, `--sample N`, `--list-cells`); the
/// old spelling still works in each, with a deprecation note.
#[test]
fn cells_is_now_walkable_sample_and_list_cells_and_the_old_spelling_gets_a_note() {
    let dir = common::temp_dir("cli-cells-names");
    let (scene, store) = tiny_scene_and_store(&dir);
    let area = dir.join("area.geojson");
    std::fs::write(
        &area,
        r#"{"type":"Polygon","coordinates":[[[1842010,5176010],[1842040,5176010],[1842040,5176040],[1842010,5176040],[1842010,5176010]]]}"#,
    )
    .unwrap();
    let a = area.to_str().unwrap();
    let w = dir.join("w.vocc");
    let w = w.to_str().unwrap();
    let eval = |flag: &str| {
        run(&[
            "eval",
            &store,
            &scene,
            "--height-attr",
            "height",
            flag,
            "1",
            "--eyes",
            "4",
            "--samples",
            "1",
        ])
    };
    type Run = (Option<i32>, String);
    let spellings: Vec<(Run, Run, &str)> = vec![
        (
            run(&[
                "bake",
                &scene,
                "--height-attr",
                "height",
                "--cell-size",
                "50",
                "--walkable",
                a,
                "-o",
                w,
            ]),
            run(&[
                "bake",
                &scene,
                "--height-attr",
                "height",
                "--cell-size",
                "50",
                "--cells",
                a,
                "-o",
                w,
            ]),
            "use --walkable FILE",
        ),
        (eval("--sample"), eval("--cells"), "use --sample N"),
        (
            run(&["inspect", &store, "--list-cells"]),
            run(&["inspect", &store, "--cells"]),
            "use --list-cells",
        ),
    ];
    for ((rc_new, err_new), (rc_old, err_old), note) in spellings {
        assert_eq!(rc_new, Some(0), "{err_new}");
        assert_eq!(rc_old, Some(0), "{err_old}");
        assert!(!err_new.contains("deprecated"), "{err_new}");
        assert!(
            err_old.contains("is deprecated") && err_old.contains(note),
            "{err_old}"
        );
    }
}

/// Issue 33, defect 8: "1 cells", "1 threads". A one-cell bake on one thread says "1 cell" and
/// "1 thread".
#[test]
fn one_cell_on_one_thread_is_singular_not_1_cells_1_threads() {
    let dir = common::temp_dir("cli-plurals");
    let (scene, store) = tiny_scene_and_store(&dir);
    let (rc, err) = run(&[
        "bake",
        &scene,
        "--height-attr",
        "height",
        "--cell-size",
        "50",
        "--threads",
        "1",
        "--region",
        "1842010,5176010,1842020,5176020",
        "-o",
        dir.join("one.vocc").to_str().unwrap(),
    ]);
    assert_eq!(rc, Some(0), "{err}");
    assert!(
        err.contains("baked 1 cell (")
            && err.contains(" on 1 thread (")
            && err.contains("baking: 1 cell\n"),
        "{err}"
    );
    assert!(
        !err.contains("1 cells") && !err.contains("1 threads"),
        "{err}"
    );
    // eval of one cell.
    let out = vocc(&[
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
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.starts_with("1 cell, 64 objects: 0 false culls;"),
        "{text}"
    );
}

/// Issue 33, defect 8: `pvs_us: 15.780000000000001` in `eval --json`. Timings are printed
/// rounded (0.01 µs or ms, 0.001 s), in `eval --json` and `bake --json`.
#[test]
fn pvs_us_15_780000000000001_is_printed_rounded() {
    let dir = common::temp_dir("cli-rounding");
    let (scene, store) = tiny_scene_and_store(&dir);
    let out = vocc(&[
        "eval",
        &store,
        &scene,
        "--height-attr",
        "height",
        "--sample",
        "3",
        "--eyes",
        "4",
        "--samples",
        "1",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out2 = vocc(&[
        "bake",
        &scene,
        "--height-attr",
        "height",
        "--cell-size",
        "50",
        "--json",
        "-o",
        dir.join("b.vocc").to_str().unwrap(),
    ]);
    assert!(out2.status.success());
    for text in [&out.stdout, &out2.stdout] {
        let text = String::from_utf8_lossy(text);
        let mut timings = 0;
        for l in text
            .lines()
            .filter(|l| l.contains("_us\"") || l.contains("_s\"") || l.contains("\"ms_"))
        {
            let v = l.rsplit(": ").next().unwrap().trim_end_matches(',');
            if let Some((_, frac)) = v.split_once('.') {
                assert!(frac.len() <= 3, "not rounded: {l}");
            }
            timings += 1;
        }
        assert!(timings >= 3, "{text}");
    }
}

/// Issue 33, defect 8: `--threads 64` on 2 cores passed without a word.
#[test]
fn threads_64_on_2_cores_says_so() {
    let dir = common::temp_dir("cli-threads-note");
    let (scene, _) = tiny_scene_and_store(&dir);
    let (rc, err) = run(&[
        "bake",
        &scene,
        "--height-attr",
        "height",
        "--cell-size",
        "50",
        "--threads",
        "64",
        "--region",
        "1842010,5176010,1842020,5176020",
        "-o",
        dir.join("t.vocc").to_str().unwrap(),
    ]);
    assert_eq!(rc, Some(0), "{err}");
    let cores = std::thread::available_parallelism().unwrap().get();
    if cores < 64 {
        assert!(
            err.contains(&format!("note: --threads 64 on {cores} core"))
                && err.contains("only share them"),
            "{err}"
        );
    }
}

/// Issue 33, defect 8: bake --json called convex pieces `blockers` while `info` counts objects
/// that gave blockers. One vocabulary: info's.
#[test]
fn bake_json_counts_convex_pieces_and_blocker_objects_as_info_does() {
    let dir = common::temp_dir("cli-bake-vocabulary");
    let (scene, _) = tiny_scene_and_store(&dir);
    let bake = vocc(&[
        "bake",
        &scene,
        "--height-attr",
        "height",
        "--cell-size",
        "50",
        "--json",
        "-o",
        dir.join("v.vocc").to_str().unwrap(),
    ]);
    let info = vocc(&["info", &scene, "--height-attr", "height", "--json"]);
    let b: serde_json::Value = serde_json::from_slice(&bake.stdout).unwrap();
    let i: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
    let sc = &b["scene"];
    assert!(
        sc.get("blockers").is_none() && sc.get("no_blocker").is_none(),
        "{sc}"
    );
    for k in [
        "objects",
        "convex_pieces",
        "blocker_objects",
        "no_blocker_objects",
    ] {
        assert_eq!(sc[k], i[k], "{k}: {sc} against info");
    }
}
