//! `vocc view`: the page written with `-o` and served with `--serve` (the same bytes), what it
//! holds (the store's bytes, the world boxes `vocc pvs` culls, each object's geometry), and its
//! refusals. What the page does in a browser is `make test-web`'s (js/test/web.mjs).

use crate::common;

use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Command, Stdio};

use common::repo;

fn vocc(args: &[&str]) -> std::process::Output {
    Command::new(common::vocc_bin())
        .args(args)
        .current_dir(repo(""))
        .output()
        .expect("vocc runs")
}

/// A tiny city of 3 x 3 buildings and its store (50 m cells).
fn tiny(dir: &std::path::Path) -> (String, String) {
    let mut features = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            let (x, y) = (1_842_000.0 + 60.0 * i as f64, 5_176_000.0 + 60.0 * j as f64);
            features.push(format!(
                r#"{{"type":"Feature","properties":{{"height":{}}},"geometry":{{"type":"Polygon","coordinates":[[[{x},{y}],[{},{y}],[{},{}],[{x},{}],[{x},{y}]]]}}}}"#,
                10 + 5 * i,
                x + 30.0,
                x + 30.0,
                y + 30.0,
                y + 30.0
            ));
        }
    }
    let scene = dir.join("tiny.geojson");
    std::fs::write(
        &scene,
        format!(
            r#"{{"type":"FeatureCollection","features":[{}]}}"#,
            features.join(",")
        ),
    )
    .unwrap();
    let store = dir.join("tiny.vocc");
    let (s, t) = (scene.to_str().unwrap(), store.to_str().unwrap());
    let out = vocc(&[
        "bake",
        s,
        "--height-attr",
        "height",
        "--cell-size",
        "50",
        "-o",
        t,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    (s.to_string(), t.to_string())
}

/// The text of the `<script>` element with `id`.
fn script<'a>(page: &'a str, id: &str) -> &'a str {
    let open = page.find(&format!("id=\"{id}\">")).expect("the element") + id.len() + 6;
    &page[open..open + page[open..].find("</script>").unwrap()]
}

fn unbase64(s: &str) -> Vec<u8> {
    let val = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        _ => 63,
    };
    let b: Vec<u8> = s
        .bytes()
        .filter(|&c| c != b'=' && !c.is_ascii_whitespace())
        .collect();
    let mut out = Vec::new();
    for c in b.chunks(4) {
        let n = c
            .iter()
            .enumerate()
            .fold(0u32, |n, (k, &x)| n | (val(x) as u32) << (18 - 6 * k));
        out.extend_from_slice(&n.to_be_bytes()[1..c.len()]);
    }
    out
}

#[test]
fn view_writes_one_page_holding_the_store_boxes_and_geometry() {
    let dir = common::temp_dir("cli-view");
    let (scene, store) = tiny(&dir);
    let page = dir.join("tiny.html");
    let out = vocc(&[
        "view",
        &store,
        &scene,
        "--height-attr",
        "height",
        "-o",
        page.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.starts_with("<!doctype html>"));
    // Offline: nothing is fetched.
    assert!(
        !html.contains("src=\"http") && !html.contains("import("),
        "the page loads something"
    );
    let meta: serde_json::Value = serde_json::from_str(script(&html, "vocc-meta")).unwrap();
    assert_eq!(meta["objects"], 9);
    let data = unbase64(script(&html, "vocc-data"));
    assert_eq!(data.len() as u64, meta["bytes"].as_u64().unwrap());
    let section = |name: &str| {
        let s = &meta["sections"][name];
        let (off, n) = (
            s[0].as_u64().unwrap() as usize,
            s[1].as_u64().unwrap() as usize,
        );
        let size = match s[2].as_str().unwrap() {
            "u8" => 1,
            "f64" => 8,
            _ => 4,
        };
        assert_eq!(off % 8, 0, "{name} is aligned");
        &data[off..off + n * size]
    };
    assert_eq!(section("store"), std::fs::read(&store).unwrap());
    // The world boxes, as vocc pvs culls them: building (1, 2) from (1842060, 5176120).
    let boxes: Vec<f64> = section("boxes")
        .chunks(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(boxes.len(), 9 * 6);
    assert_eq!(
        &boxes[5 * 6..6 * 6],
        &[1842060.0, 5176120.0, 0.0, 1842090.0, 5176150.0, 15.0]
    );
    // One footprint polygon of one ring of 4 points (the closing point dropped) per building.
    assert_eq!(meta["sections"]["fpRings"][1], 9);
    assert_eq!(meta["sections"]["fpXy"][1], 9 * 4 * 2);
    assert_eq!(meta["sections"]["faceObject"][1], 0);
    // The page's title names the store.
    assert!(html.contains("<title>vocc view: tiny.vocc</title>"));
}

#[test]
fn view_serves_the_same_page() {
    let dir = common::temp_dir("cli-view-serve");
    let (scene, store) = tiny(&dir);
    let page = dir.join("tiny.html");
    let out = vocc(&[
        "view",
        &store,
        &scene,
        "--height-attr",
        "height",
        "-o",
        page.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let mut child = Command::new(common::vocc_bin())
        .args([
            "view",
            &store,
            &scene,
            "--height-attr",
            "height",
            "--serve",
            "--addr",
            "127.0.0.1:0",
        ])
        .current_dir(repo(""))
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    err.read_line(&mut line).unwrap();
    let addr = line
        .split("http://")
        .nth(1)
        .and_then(|s| s.split('/').next())
        .unwrap_or_else(|| panic!("no address in {line:?}"))
        .to_string();
    let get = |request: &str| {
        let mut s = std::net::TcpStream::connect(&addr).unwrap();
        s.write_all(request.as_bytes()).unwrap();
        let mut got = Vec::new();
        s.read_to_end(&mut got).unwrap();
        String::from_utf8(got).unwrap()
    };
    let got = get("GET / HTTP/1.1\r\nHost: x\r\n\r\n");
    let refused = get("POST / HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n\r\n");
    child.kill().unwrap();
    child.wait().unwrap();
    let (head, body) = got.split_once("\r\n\r\n").unwrap();
    assert!(head.starts_with("HTTP/1.1 200 OK"), "{head}");
    assert!(head.contains("Content-Type: text/html"));
    assert_eq!(body, std::fs::read_to_string(&page).unwrap());
    assert!(refused.starts_with("HTTP/1.1 405"), "{refused}");
}

#[test]
fn view_refuses_a_bad_store_a_missing_output_choice_and_its_inputs_as_output() {
    let dir = common::temp_dir("cli-view-refusals");
    let (scene, store) = tiny(&dir);
    let out = vocc(&["view", &store, &scene, "--height-attr", "height"]);
    assert_eq!(out.status.code(), Some(2), "neither -o nor --serve");
    let bad = dir.join("bad.vocc");
    std::fs::write(&bad, b"not a store").unwrap();
    let page = dir.join("p.html");
    let out = vocc(&[
        "view",
        bad.to_str().unwrap(),
        &scene,
        "--height-attr",
        "height",
        "-o",
        page.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("truncated: 136 bytes needed, 11 given"));
    assert!(!page.exists());
    let out = vocc(&[
        "view",
        &store,
        &scene,
        "--height-attr",
        "height",
        "-o",
        &scene,
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(std::fs::read_to_string(&scene)
        .unwrap()
        .starts_with("{\"type\""));
}
