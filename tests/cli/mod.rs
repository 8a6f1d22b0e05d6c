//! The `vocc` binary as a user runs it.

use crate::common;

use std::process::Command;

use common::{repo, LYON};

mod basics;
mod friction;
mod issue13;
mod issue31;
mod issue33;
mod issue33_smaller;

fn vocc(args: &[&str]) -> std::process::Output {
    Command::new(common::vocc_bin())
        .args(args)
        .current_dir(repo(""))
        .output()
        .expect("vocc runs")
}

/// Runs `vocc bake` on a 3 x 3-cell region of Lyon with `extra` options, into `store`.
fn bake_lyon_region_with(extra: &[&str], store: &std::path::Path) -> std::process::Output {
    let mut args = vec![
        "bake",
        LYON,
        "--height-attr",
        "HAUTEUR",
        "--region",
        "1841900,5175950,1842100,5176150",
    ];
    args.extend_from_slice(extra);
    args.extend(["-o", store.to_str().unwrap()]);
    vocc(&args)
}

/// Bakes a 3 x 3-cell region of Lyon into `dir/lyon.vocc`.
fn bake_lyon_region(dir: &std::path::Path) -> std::path::PathBuf {
    let store = dir.join("lyon.vocc");
    let out = bake_lyon_region_with(&[], &store);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("baked 9 cells"), "{err}");
    assert!(err.contains("bytes per cell"), "{err}");
    assert!(
        err.contains("time by stage, summed over cells: maps ") && err.contains(", selection "),
        "{err}"
    );
    // Lyon's blocks lie among few blockers: the far field is sought per quarter, and the stage
    // line says how often.
    assert!(
        err.contains("(0 blocks whole, ") && err.contains(" of blocks split among few blockers)"),
        "{err}"
    );
    store
}

/// The bytes of a ```hex example:NAME block of docs/FORMAT.md.
fn doc_hex(name: &str) -> Vec<u8> {
    let doc = std::fs::read_to_string(repo("docs/FORMAT.md")).unwrap();
    let fence = format!("```hex example:{name}\n");
    let start = doc.find(&fence).unwrap() + fence.len();
    let end = start + doc[start..].find("```").unwrap();
    doc[start..end]
        .lines()
        .flat_map(|l| {
            let hex = l.split('#').next().unwrap().split_once(':').unwrap().1;
            hex.split_whitespace()
                .map(|t| u8::from_str_radix(t, 16).unwrap())
                .collect::<Vec<_>>()
        })
        .collect()
}

/// A GeoJSON of square buildings (world coordinates): `(x, y, side, height)` each, attribute
/// `height`.
fn boxes_geojson(b: &[(f64, f64, f64, f64)]) -> String {
    boxes_geojson_attr("height", b)
}

/// [`boxes_geojson`] with the height in attribute `attr`.
fn boxes_geojson_attr(attr: &str, b: &[(f64, f64, f64, f64)]) -> String {
    let feats: Vec<String> = b
        .iter()
        .map(|&(x, y, s, h)| {
            format!(
                r#"{{"type":"Feature","properties":{{"{attr}":{h}}},"geometry":{{"type":"Polygon","coordinates":[[[{x},{y}],[{},{y}],[{},{}],[{x},{}],[{x},{y}]]]}}}}"#,
                x + s,
                x + s,
                y + s,
                y + s
            )
        })
        .collect();
    format!(
        r#"{{"type":"FeatureCollection","features":[{}]}}"#,
        feats.join(",")
    )
}

/// A block of `n` x `n` buildings of 30 m, 40 m apart (10 m streets), 20 to 29 m tall, from
/// world (x0, y0).
fn block(x0: f64, y0: f64, n: usize) -> Vec<(f64, f64, f64, f64)> {
    (0..n * n)
        .map(|k| {
            let (i, j) = (k % n, k / n);
            let h = 20.0 + ((7 * i + 3 * j) % 10) as f64;
            (x0 + 40.0 * i as f64, y0 + 40.0 * j as f64, 30.0, h)
        })
        .collect()
}

/// Runs vocc under `ulimit -v 4000000` (4 GB of address space), as the issue asks.
fn vocc_limited(args: &[&str]) -> (std::process::Output, std::time::Duration) {
    let t = std::time::Instant::now();
    let out = Command::new("sh")
        .arg("-c")
        .arg(r#"ulimit -v 4000000 && exec "$0" "$@""#)
        .arg(common::vocc_bin())
        .args(args)
        .current_dir(repo(""))
        .output()
        .expect("sh runs");
    (out, t.elapsed())
}

/// Runs vocc and returns (exit code, stderr).
fn run(args: &[&str]) -> (Option<i32>, String) {
    let out = vocc(args);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A tiny city of 8 x 8 buildings at Lyon's coordinates, baked on 50 m cells (7 x 7) into
/// `dir/tiny.vocc` in about 0.2 s; it stores about 80 VOs.
fn tiny_scene_and_store(dir: &std::path::Path) -> (String, String) {
    let scene = dir.join("tiny.geojson");
    std::fs::write(&scene, boxes_geojson(&block(1_842_000.0, 5_176_000.0, 8))).unwrap();
    let store = dir.join("tiny.vocc");
    let (s, t) = (
        scene.to_str().unwrap().to_string(),
        store.to_str().unwrap().to_string(),
    );
    let (rc, err) = run(&[
        "bake",
        &s,
        "--height-attr",
        "height",
        "--cell-size",
        "50",
        "-o",
        &t,
    ]);
    assert_eq!(rc, Some(0), "{err}");
    (s, t)
}

/// The scene of issue 12's test: four features, the first without a height, the third "tall":
/// features 1 and 3 load.
fn row_geojson(extra: &str) -> String {
    let f = |i: usize, h: &str| {
        let x = 1_842_000 + 20 * i;
        format!(
            r#"{{"type":"Feature","properties":{{"h":{h}}},"geometry":{{"type":"Polygon","coordinates":[[[{x},5176000],[{},5176000],[{},5176010],[{x},5176010],[{x},5176000]]]}}}}"#,
            x + 10,
            x + 10
        )
    };
    format!(
        r#"{{"type":"FeatureCollection",{extra}"features":[{},{},{},{}]}}"#,
        f(0, "null"),
        f(1, "\"12.13 m\""),
        f(2, "\"tall\""),
        f(3, "9")
    )
}

/// A box file's rows: (id, box).
fn box_rows(path: &std::path::Path) -> Vec<(u32, Vec<f64>)> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            let mut t = l.split(' ');
            let id = t.next().unwrap().parse().unwrap();
            (id, t.map(|v| v.parse().unwrap()).collect())
        })
        .collect()
}
