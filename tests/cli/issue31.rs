//! Issue 31 (whole cities), item 6: every report says how far the bake is from its own ceiling
//! over the whole scene. `vocc eval --ceiling` adds the 2.5D ceiling of 10 ideal VOs
//! (`eval::bound::ceiling_sliced` with `CeilingParams::scene()`) for the evaluated cells, in the
//! text and the JSON report; without the flag the report has none.

use super::*;

#[test]
fn eval_ceiling_reports_the_whole_scene_ceiling_of_the_evaluated_cells() {
    let dir = common::temp_dir("cli-eval-ceiling");
    let (scene, store) = tiny_scene_and_store(&dir);
    let args = |extra: &[&'static str]| {
        let mut a = vec![
            "eval".to_string(),
            store.clone(),
            scene.clone(),
            "--height-attr".into(),
            "height".into(),
            "--cell".into(),
            "10,24".into(),
        ];
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    let json = |extra: &[&'static str]| -> serde_json::Value {
        let a = args(extra);
        let out = vocc(&a.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let plain = json(&["--json"]);
    assert!(plain.get("ceiling").is_none(), "{plain}");
    let v = json(&["--json", "--ceiling"]);
    let c = &v["ceiling"];
    assert_eq!(c["cells"], 2, "{c}");
    assert_eq!(c["objects"], v["summary"]["objects"], "{c}");
    let share = c["occluded_share"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&share), "{c}");
    // The store's own figures are the same with or without the ceiling.
    assert_eq!(v["summary"]["mean_pvs"], plain["summary"]["mean_pvs"]);
    let a = args(&["--ceiling"]);
    let out = vocc(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("ceiling over the whole scene (10 ideal VOs in 2.5D, an estimate): "),
        "{text}"
    );
}

/// Issue 31, a cell's reach: `vocc bake --reach 900` is the default bake byte for byte, a
/// longer reach bakes another store on the same frame, and a reach out of range is a usage
/// error naming the range, with no store written.
#[test]
fn bake_reach_900_is_the_default_and_out_of_range_is_refused() {
    let dir = common::temp_dir("cli-bake-reach");
    let default = bake_lyon_region(&dir);
    let bake = |reach: &str, name: &str| {
        let store = dir.join(name);
        (bake_lyon_region_with(&["--reach", reach], &store), store)
    };
    let (out, same) = bake("900", "same.vocc");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read(&same).unwrap(),
        std::fs::read(&default).unwrap()
    );
    let (out, far) = bake("1800", "far.vocc");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (a, b) = (
        std::fs::read(&far).unwrap(),
        std::fs::read(&default).unwrap(),
    );
    assert_ne!(a, b, "a 1.8 km reach bakes the same store as 900 m");
    // The same frame (grid, origin, eyes, quantization: the far field's 3.4 km still sets
    // the quantum), other VOs.
    let (fa, fb) = (
        vocc::runtime::format::Store::parse(&a).unwrap(),
        vocc::runtime::format::Store::parse(&b).unwrap(),
    );
    assert_eq!(fa.frame(), fb.frame());
    assert_refused(
        "--reach",
        &bake,
        ["50", "6000", "far"],
        "expected `auto` or metres from 100 to 5000",
    );
}

/// Issue 31, the held-out scenes: `--reach auto` (the default) reaches 16 mean free paths of a
/// sight line, in steps of 100 m. Among 15 x 15 towers of 30 m on a 60 m grid the path is
/// `pi A / P` = pi 870^2 / (225 * 120) = 88.06 m, so the default bake reaches 1400 m: it says
/// so, writes it in its JSON, and its store is `--reach 1400`'s byte for byte, not `--reach
/// 900`'s. `vocc info` reports the path and the reach.
#[test]
fn bake_reach_auto_reaches_sixteen_free_paths_among_towers() {
    let dir = common::temp_dir("cli-bake-reach-auto");
    let towers: Vec<(f64, f64, f64, f64)> = (0..225)
        .map(|k| {
            let (i, j) = ((k % 15) as f64, (k / 15) as f64);
            let h = 60.0 + 37.0 * ((k * 7) % 11) as f64;
            (1_842_000.0 + 60.0 * i, 5_176_000.0 + 60.0 * j, 30.0, h)
        })
        .collect();
    let scene = dir.join("towers.geojson");
    std::fs::write(&scene, boxes_geojson(&towers)).unwrap();
    let scene = scene.to_str().unwrap().to_string();
    let bake = |extra: &[&str], name: &str| {
        let store = dir.join(name).to_str().unwrap().to_string();
        let mut a = vec![
            "bake",
            &scene,
            "--height-attr",
            "height",
            "--region",
            "1842400,5176400,1842450,5176450",
            "--json",
            "-o",
            &store,
        ];
        a.extend_from_slice(extra);
        let out = vocc(&a);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        (out, std::fs::read(&store).unwrap())
    };
    let (out, auto) = bake(&[], "auto.vocc");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["reach_m"], 1400.0, "{v}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("reach: 1400 m past each cell's sides (auto: a sight line runs 88 m"),
        "{err}"
    );
    assert_eq!(bake(&["--reach", "1400"], "r1400.vocc").1, auto);
    assert_ne!(bake(&["--reach", "900"], "r900.vocc").1, auto);
    let out = vocc(&["info", &scene, "--height-attr", "height", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let expected = std::f64::consts::PI * 870.0 * 870.0 / (225.0 * 120.0);
    assert!(
        (v["free_path_m"].as_f64().unwrap() - expected).abs() < 1e-6,
        "{v}"
    );
    assert_eq!(v["auto_reach_m"], 1400.0, "{v}");
}

/// Each of `values` given to `option` through `bake` (the value and a store name, to the
/// process's output and the store's path) is a usage error whose message holds `expected`,
/// with no store written.
fn assert_refused(
    option: &str,
    bake: &dyn Fn(&str, &str) -> (std::process::Output, std::path::PathBuf),
    values: [&str; 3],
    expected: &str,
) {
    for (value, name) in values
        .into_iter()
        .zip(["low.vocc", "high.vocc", "nan.vocc"])
    {
        let (out, store) = bake(value, name);
        assert_eq!(out.status.code(), Some(2), "{option} {value}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(expected), "{err}");
        assert!(
            !store.exists(),
            "{option} {value} wrote {}",
            store.display()
        );
    }
}

/// Issue 31, the far field's blocks: `vocc bake --far-block auto` is the default bake byte for
/// byte, and so is `--far-block 200` on Lyon, whose 400 m blocks all split into 200 m quarters
/// (fewer than 40,000 blockers around each); 400 m blocks unsplit, 1-cell blocks and `off` bake
/// other stores; a size out of range is a usage error naming the range, with no store written.
#[test]
fn bake_far_block_auto_is_the_default_and_out_of_range_is_refused() {
    let dir = common::temp_dir("cli-bake-far-block");
    let default = std::fs::read(bake_lyon_region(&dir)).unwrap();
    let bake = |block: &str, name: &str| {
        let store = dir.join(name);
        (
            bake_lyon_region_with(&["--far-block", block], &store),
            store,
        )
    };
    for (block, name, same) in [
        ("auto", "auto.vocc", true),
        ("200", "quarters.vocc", true),
        ("400", "whole.vocc", false),
        ("100", "cells.vocc", false),
        ("off", "off.vocc", false),
    ] {
        let (out, store) = bake(block, name);
        assert!(
            out.status.success(),
            "--far-block {block}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let bytes = std::fs::read(&store).unwrap();
        assert_eq!(bytes == default, same, "--far-block {block}");
        assert!(vocc::runtime::format::Store::parse(&bytes).is_ok());
    }
    assert_refused(
        "--far-block",
        &bake,
        ["0.5", "20000", "near"],
        "expected `auto`, `off`, or metres from 1 to 10000",
    );
}
