//! The `vocc` binary as a user runs it.

mod common;

use std::process::Command;

use common::{repo, LYON};

fn vocc(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_vocc"))
        .args(args)
        .current_dir(repo(""))
        .output()
        .expect("vocc runs")
}

#[test]
fn info_json_on_lyon_reports_objects_and_pieces() {
    let out = vocc(&["info", LYON, "--height-attr", "HAUTEUR", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["objects"], 2576);
    assert_eq!(v["blocker_objects"], 2576);
    let pieces = v["convex_pieces"].as_u64().unwrap();
    assert!((2576..=4 * 12_000).contains(&pieces), "{pieces} pieces");
    assert_eq!(v["origin"][0], 1841000.0);
    assert_eq!(v["origin"][1], 5175000.0);
    assert!(v["timings"].as_array().unwrap().len() >= 3);
    assert!(v["heights"]["max"].as_f64().unwrap() > 40.0);
}

#[test]
fn info_text_lists_reasons() {
    let out = vocc(&[
        "info",
        LYON,
        "--height-attr",
        "HAUTEUR",
        "--base-attr",
        "Z_MIN_SOL",
    ]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("objects: 2571"), "{text}");
    assert!(text.contains("no value for the base attribute"), "{text}");
    assert!(text.contains("feature 13"), "{text}");
}

#[test]
fn broken_file_is_an_error_with_location_not_a_panic() {
    let out = vocc(&[
        "info",
        "tests/fixtures/broken/geojson_unknown_geometry_type.geojson",
        "--height-attr",
        "height",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("feature 1"), "{err}");
    assert!(err.contains("Polygn"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn gen_city_is_deterministic_and_loads() {
    let dir = common::temp_dir("cli_gen_city");
    let a = dir.join("a.geojson");
    let b = dir.join("b.geojson");
    for p in [&a, &b] {
        let out = vocc(&[
            "gen-city",
            "--buildings",
            "500",
            "--seed",
            "7",
            "-o",
            p.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    let out = vocc(&[
        "info",
        a.to_str().unwrap(),
        "--height-attr",
        "height",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["objects"], 500);
    assert_eq!(v["blocker_objects"], 500);
}

#[test]
fn render_debug_draws_a_lyon_cell_with_verified_vos() {
    let dir = common::temp_dir("cli_render");
    let svg = dir.join("cell.svg");
    let out = vocc(&[
        "render",
        "--debug",
        LYON,
        "--height-attr",
        "HAUTEUR",
        "--at",
        "1842000,5176050",
        "-o",
        svg.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg"));
    assert!(
        text.contains("verifier rejections: 0"),
        "the gate never fires"
    );
    let vos = text.matches(r#"stroke="black" stroke-width="2.5""#).count();
    assert!(vos > 10, "{vos} VOs drawn");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("0 rejected by the verifier"), "{err}");
}

#[test]
fn render_rejects_a_malformed_point() {
    let out = vocc(&[
        "render",
        "--debug",
        LYON,
        "--height-attr",
        "HAUTEUR",
        "--at",
        "12;34",
        "-o",
        "/dev/null",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("expected X,Y"));
}
