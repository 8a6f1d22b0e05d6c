//! The `vocc` binary as a user runs it.

use crate::common;

use std::process::Command;

use common::{repo, LYON};

fn vocc(args: &[&str]) -> std::process::Output {
    Command::new(common::vocc_bin())
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
        "--generator",
        "growth",
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
fn render_debug_draws_the_long_generators_trace_of_a_lyon_cell() {
    let dir = common::temp_dir("cli_render_long");
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
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg"));
    let count = |class: &str| text.matches(&format!(r#"class="{class}""#)).count();
    assert_eq!(count("cell"), 1);
    assert!(count("hidden") > 0 && count("blocker") > 0);
    assert!(count("proposal") >= count("picked") && count("certified") > 0);
    assert!((1..=10).contains(&count("picked")), "{}", count("picked"));
    // The counts on stderr are the picture's.
    let said = format!(
        "{} proposals, {} certified pieces, {} VOs stored, {} picked",
        count("proposal"),
        count("certified"),
        count("stored"),
        count("picked")
    );
    assert!(err.contains(&said), "{err} against {said}");
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

/// Bakes a 3 x 3-cell region of Lyon into `dir/lyon.vocc`.
fn bake_lyon_region(dir: &std::path::Path) -> std::path::PathBuf {
    let store = dir.join("lyon.vocc");
    let out = vocc(&[
        "bake",
        LYON,
        "--height-attr",
        "HAUTEUR",
        "--region",
        "1841900,5175950,1842100,5176150",
        "-o",
        store.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("baked 9 cells"), "{err}");
    assert!(err.contains("bytes per cell"), "{err}");
    store
}

#[test]
fn bake_then_inspect_pvs_and_export() {
    let dir = common::temp_dir("cli-bake");
    let store = bake_lyon_region(&dir);
    let s = store.to_str().unwrap();
    // No temporary file is left beside the store: only it and its content hashes.
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["lyon.vocc", "lyon.vocc.hashes"]);

    let out = vocc(&["inspect", s, "--json"]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v["max_vos_per_cell"].as_u64().unwrap() <= 10);
    assert!(v["vos"].as_u64().unwrap() >= 9, "{v}");
    assert_eq!(v["cells"], 228);
    assert_eq!(v["bytes"], std::fs::metadata(&store).unwrap().len());
    // Format 2.0, with the scene it was baked from (FORMAT.md 5.2).
    assert_eq!(v["version"], "2.0");
    assert_eq!(v["objects"], 2576);
    let fingerprint = v["scene"].as_str().unwrap();
    assert_eq!(fingerprint.len(), 16);
    assert_ne!(u64::from_str_radix(fingerprint, 16).unwrap(), 0);
    // Lyon's GeoJSON names its CRS (EPSG:3946), and the store records it.
    assert_eq!(v["crs"], "EPSG:3946");
    assert_eq!(v["vo_top_levels_above_eye_m"].as_array().unwrap().len(), 32);
    let text = String::from_utf8_lossy(&vocc(&["inspect", s]).stdout).into_owned();
    assert!(text.contains(": vocc store 2.0, "), "{text}");
    assert!(
        text.contains(&format!(
            "scene: baked for 2576 objects; fingerprint {fingerprint}; CRS \"EPSG:3946\""
        )),
        "{text}"
    );

    // The cell of the README's picture.
    let out = vocc(&[
        "pvs",
        s,
        LYON,
        "--height-attr",
        "HAUTEUR",
        "--at",
        "1842000,5176050",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let p: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let id = p["cell"].as_u64().unwrap();
    assert_eq!(p["objects"], 2576);
    let pvs: Vec<u64> = p["pvs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect();
    assert!(pvs.windows(2).all(|w| w[0] < w[1]), "ascending, no repeats");
    assert!(pvs.len() < 2576, "the VOs cull something");
    assert!(pvs.len() > 100);

    let cell = id.to_string();
    let out = vocc(&["export", s, "--cell", &cell, "--json"]);
    assert!(out.status.success());
    let e: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let vos = e["vos"].as_array().unwrap();
    assert!(!vos.is_empty() && vos.len() <= 10);
    // World coordinates: near the cell, far from the local origin.
    assert!(vos[0]["a"][0].as_f64().unwrap() > 1_840_000.0);

    let obj = dir.join("cell.obj");
    let out = vocc(&["export", s, "--cell", &cell, "--obj", obj.to_str().unwrap()]);
    assert!(out.status.success());
    let text = std::fs::read_to_string(&obj).unwrap();
    assert_eq!(
        text.lines().filter(|l| l.starts_with("v ")).count(),
        4 * vos.len()
    );
    assert_eq!(
        text.lines().filter(|l| l.starts_with("f ")).count(),
        vos.len()
    );

    let blob = dir.join("cell.blob");
    let out = vocc(&[
        "export",
        s,
        "--cell",
        &cell,
        "--blob",
        blob.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let frame =
        vocc::runtime::decode_frame(&std::fs::read(dir.join("cell.blob.frame")).unwrap()).unwrap();
    let blob = std::fs::read(&blob).unwrap();
    assert_eq!(blob[4], 2, "export --blob writes 2.0");
    assert_eq!(blob.len(), 14 + 6 * vos.len());
    let (bid, rec) = vocc::runtime::decode_blob(&frame, &blob).unwrap();
    assert_eq!(bid as u64, id);
    assert_eq!(rec.vos().len(), vos.len());
    // Each VO's stored fields and bytes, as the JSON gives them.
    for (q, v) in rec.vos().iter().zip(vos) {
        let f = &v["fields"];
        assert_eq!(
            [
                &f["a"]["e"],
                &f["a"]["x"],
                &f["a"]["y"],
                &f["b"]["e"],
                &f["b"]["x"],
                &f["b"]["y"]
            ]
            .map(|x| x.as_u64().unwrap()),
            [
                q.a.e as u64,
                q.a.x as u64,
                q.a.y as u64,
                q.b.e as u64,
                q.b.x as u64,
                q.b.y as u64
            ]
        );
        assert_eq!(f["level"], q.level);
        let hex: String = q.to_bytes().iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(v["bytes"], hex);
    }
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

/// `inspect` reads both versions: the version, the scene section (none in 1.0), and per VO its
/// stored fields, exponents included, and its bytes as the file holds them.
#[test]
fn inspect_reads_both_versions_with_the_scene_and_each_vos_fields() {
    let dir = common::temp_dir("cli-inspect-versions");
    let (new, old) = (dir.join("doc2.vocc"), dir.join("doc1.vocc"));
    std::fs::write(&new, doc_hex("store")).unwrap();
    std::fs::write(&old, doc_hex("store-1.0")).unwrap();
    let (n, o) = (new.to_str().unwrap(), old.to_str().unwrap());
    let t = String::from_utf8_lossy(&vocc(&["inspect", n]).stdout).into_owned();
    assert!(t.contains(": vocc store 2.0, 184 bytes, 3 cells"), "{t}");
    assert!(
        t.contains(
            "scene: baked for 2576 objects; fingerprint 9e3779b97f4a7c15; CRS \"EPSG:2154\""
        ),
        "{t}"
    );
    let t = String::from_utf8_lossy(&vocc(&["inspect", o]).stdout).into_owned();
    assert!(t.contains(": vocc store 1.0, 154 bytes, 3 cells"), "{t}");
    assert!(
        t.contains("scene: object count not recorded; fingerprint not recorded; CRS unknown"),
        "{t}"
    );
    let j: serde_json::Value =
        serde_json::from_slice(&vocc(&["inspect", o, "--json"]).stdout).unwrap();
    assert_eq!(
        (&j["version"], &j["objects"], &j["scene"], &j["crs"]),
        (
            &serde_json::json!("1.0"),
            &serde_json::json!(0),
            &serde_json::json!("0000000000000000"),
            &serde_json::json!("")
        )
    );
    assert_eq!(j["vo_top_levels_above_eye_m"].as_array().unwrap().len(), 16);
    // Cell 0 of the 2.0 example: the far VO's exponents 3, the mixed one's 0 and 2.
    let t = String::from_utf8_lossy(&vocc(&["inspect", n, "--cell", "0"]).stdout).into_owned();
    assert!(t.contains("cell 0: "), "{t}");
    assert!(
        t.contains("  VO 1: (842802.000, 6518650.000) - (843402.000, 6518650.000), 600.0 m long, 162.00..506.94 m, level 20; a (e 3, x 194, y 406), b (e 3, x 344, y 406), bytes 136679582d53"),
        "{t}"
    );
    assert!(
        t.contains("level 16; a (e 0, x 376, y 346), b (e 2, x 286, y 456), bytes c0ab551e9143"),
        "{t}"
    );
    let j: serde_json::Value =
        serde_json::from_slice(&vocc(&["inspect", n, "--cell", "0", "--json"]).stdout).unwrap();
    let v = &j["vos"][2];
    assert_eq!(
        v["fields"]["b"],
        serde_json::json!({"e": 2, "x": 286, "y": 456})
    );
    assert_eq!(
        (&v["a"], &v["b"]),
        (
            &serde_json::json!([843110.0, 6518095.0]),
            &serde_json::json!([843110.0, 6518450.0])
        )
    );
    // The 1.0 VO's bytes are its 5 stored bytes.
    let j: serde_json::Value =
        serde_json::from_slice(&vocc(&["inspect", o, "--cell", "0", "--json"]).stdout).unwrap();
    assert_eq!(j["vos"][0]["bytes"], "c4f042c55b");
    assert_eq!(
        j["vos"][0]["fields"]["a"],
        serde_json::json!({"e": 0, "x": 196, "y": 376})
    );
    // The same wall in both versions.
    let j2: serde_json::Value =
        serde_json::from_slice(&vocc(&["inspect", n, "--cell", "0", "--json"]).stdout).unwrap();
    for k in ["a", "b", "bottom", "top", "level"] {
        assert_eq!(j["vos"][0][k], j2["vos"][0][k], "{k}");
    }
    // export --blob of a 1.0 store writes a 2.0 blob of the same record.
    let blob = dir.join("c0.blob");
    let out = vocc(&["export", o, "--cell", "0", "--blob", blob.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let b = std::fs::read(&blob).unwrap();
    assert_eq!((b[4], b.len()), (2, 14 + 1 + 12));
}

#[test]
fn bake_refuses_bad_options_and_pvs_bad_stores() {
    let dir = common::temp_dir("cli-bake-bad");
    let store = dir.join("x.vocc");
    let s = store.to_str().unwrap();
    for (args, want) in [
        (vec!["--cell-size", "0"], "cell size"),
        (vec!["--max-vos", "11"], "--max-vos"),
        (vec!["--eye", "2..1"], "eye heights"),
        (vec!["--slices", "6"], "--slices"),
    ] {
        let mut a = vec!["bake", LYON, "--height-attr", "HAUTEUR", "-o", s];
        a.extend(args);
        let out = vocc(&a);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(want), "{err}");
        assert!(!store.exists(), "no output after a refused bake");
    }
    // Not a store.
    let out = vocc(&["inspect", LYON]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("not a valid vocc store"), "{err}");
}

#[test]
fn bake_only_the_cells_of_a_walkable_area() {
    let dir = common::temp_dir("cli-walkable");
    let store = dir.join("w.vocc");
    let out = vocc(&[
        "bake",
        LYON,
        "--height-attr",
        "HAUTEUR",
        "--walkable",
        "tests/fixtures/scenes/lyon_walkable_street.geojson",
        "-o",
        store.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    // A 200 m x 40 m street strip meets three 100 m cells of one row.
    assert!(err.contains("baked 3 cells"), "{err}");
    let v: serde_json::Value =
        serde_json::from_slice(&vocc(&["inspect", store.to_str().unwrap(), "--json"]).stdout)
            .unwrap();
    let empty = v["cells_by_vo_count"][0].as_u64().unwrap();
    assert!(empty >= 225, "{v}");

    // A walkable area must be polygons.
    let bad = dir.join("bad.geojson");
    std::fs::write(
        &bad,
        r#"{"type":"FeatureCollection","features":[{"type":"Feature","geometry":{"type":"Point","coordinates":[1,2]}}]}"#,
    )
    .unwrap();
    let out = vocc(&[
        "bake",
        LYON,
        "--height-attr",
        "HAUTEUR",
        "--walkable",
        bad.to_str().unwrap(),
        "-o",
        store.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("feature 0") && err.contains("Point"), "{err}");
}

#[test]
fn four_shards_in_four_processes_merge_into_the_single_bake() {
    let dir = common::temp_dir("cli-shards");
    let city = dir.join("city.geojson");
    let p = |f: &std::path::Path| f.to_str().unwrap().to_string();
    assert!(vocc(&[
        "gen-city",
        "--buildings",
        "600",
        "--seed",
        "3",
        "-o",
        &p(&city)
    ])
    .status
    .success());
    let common_args = |out: &std::path::Path| {
        vec![
            "bake".to_string(),
            p(&city),
            "--height-attr".into(),
            "height".into(),
            "--cell-size".into(),
            "50".into(),
            "-o".into(),
            p(out),
            // Shards merge into the single bake at any effort: the fast one, for time.
            "--effort".into(),
            "fast".into(),
        ]
    };
    let single = dir.join("single.vocc");
    assert!(vocc(
        &common_args(&single)
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>()
    )
    .status
    .success());
    // Four processes at once, one thread each.
    let shards: Vec<std::path::PathBuf> = (0..4).map(|i| dir.join(format!("s{i}.vocc"))).collect();
    let children: Vec<std::process::Child> = shards
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let mut a = common_args(s);
            a.extend([
                "--threads".into(),
                "1".into(),
                "--shard".into(),
                format!("{i}/4"),
            ]);
            Command::new(common::vocc_bin())
                .args(&a)
                .current_dir(repo(""))
                .stderr(std::process::Stdio::null())
                .spawn()
                .unwrap()
        })
        .collect();
    for mut c in children {
        assert!(c.wait().unwrap().success());
    }
    let merged = dir.join("merged.vocc");
    let mut a = vec!["merge".to_string()];
    a.extend(shards.iter().map(|s| p(s)));
    a.extend(["-o".into(), p(&merged)]);
    let out = vocc(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (m, s) = (
        std::fs::read(&merged).unwrap(),
        std::fs::read(&single).unwrap(),
    );
    assert!(s.len() > 136, "the single bake stored something");
    assert_eq!(m, s, "merged shards differ from the single bake");
    // The shards' content hashes merge into the single bake's, so `--reuse` works on the merge.
    let hashes = |f: &std::path::Path| std::fs::read(vocc::bake::incremental::hashes_path(f));
    assert_eq!(
        hashes(&merged).expect("merge writes hashes"),
        hashes(&single).unwrap(),
        "merged hashes differ from the single bake's"
    );
    // A shard of another bake (other cell size) is refused.
    let other = dir.join("other.vocc");
    let mut a = common_args(&other);
    a[5] = "100".into();
    assert!(vocc(&a.iter().map(String::as_str).collect::<Vec<_>>())
        .status
        .success());
    let out = vocc(&[
        "merge",
        &p(&shards[0]),
        &p(&other),
        "-o",
        &p(&dir.join("bad.vocc")),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("another frame"));
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

/// Issue 13, defect 2: grids that cannot fit aborted with a backtrace (rc 134) after asking for
/// 13-36 GB. Each way in is refused before allocating, in under a second, with exit status 1, no
/// backtrace, and a message naming the cause.
#[test]
fn grids_that_cannot_fit_are_refused_naming_the_cause_not_aborted_with_a_backtrace() {
    let dir = common::temp_dir("cli-grid-too-large");
    let write = |name: &str, b: &[(f64, f64, f64, f64)]| {
        let p = dir.join(name);
        std::fs::write(&p, boxes_geojson(b)).unwrap();
        p.to_str().unwrap().to_string()
    };
    let out = dir.join("x.vocc");
    let o = out.to_str().unwrap();
    // Two scenes in different coordinate systems: Lambert-93 (Lyon) and RD New (Den Haag).
    let lyon = write("lyon_l93.geojson", &block(1_842_000.0, 5_176_000.0, 3));
    let haag = write("denhaag_rd.geojson", &block(78_500.0, 457_900.0, 3));
    // One building 10^6 m away from the rest.
    let mut b = block(1_842_000.0, 5_176_000.0, 3);
    b.push((2_842_000.0, 6_176_000.0, 20.0, 25.0));
    let outlier = write("outlier.geojson", &b);
    // A scene too wide for its cell size: two buildings 300 km apart, 1 m cells.
    let wide = write(
        "wide.geojson",
        &[(0.0, 0.0, 20.0, 25.0), (300_000.0, 300_000.0, 20.0, 25.0)],
    );
    for (args, want) in [
        (
            vec![lyon.as_str(), haag.as_str()],
            vec![
                "lyon_l93.geojson",
                "denhaag_rd.geojson",
                "do not meet",
                "coordinate system",
            ],
        ),
        (
            vec![outlier.as_str()],
            vec![
                "object #9",
                "feature 9",
                "from the other objects",
                "fix or remove it",
            ],
        ),
        (
            vec![wide.as_str(), "--cell-size", "1"],
            vec!["the scene spans 300 km x 300 km", "use cells of"],
        ),
    ] {
        let mut a = vec!["bake"];
        a.extend(&args);
        a.extend(["--height-attr", "height", "-o", o]);
        let (res, took) = vocc_limited(&a);
        let err = String::from_utf8_lossy(&res.stderr);
        assert_eq!(res.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            !err.contains("panicked")
                && !err.contains("backtrace")
                && !err.contains("memory allocation"),
            "{err}"
        );
        assert!(err.contains("the grid would have"), "{err}");
        for w in want {
            assert!(err.contains(w), "{args:?}: no {w:?} in {err}");
        }
        assert!(took.as_secs_f64() < 1.0, "{args:?}: refused after {took:?}");
        assert!(!out.exists(), "no output after a refused bake");
    }
}

/// Issue 13, defect 2 (third way in): `--cell-size 0.1` on 150 buildings ran for nearly two
/// minutes, then aborted. Cells under 1 m are refused as a usage error (VO endpoints lie on a
/// grid of 2 m at the default search distance, so they could only multiply the work).
#[test]
fn cell_size_0_1_on_150_buildings_is_refused_at_once_not_run_for_minutes() {
    let dir = common::temp_dir("cli-cell-size-0-1");
    let city = dir.join("city150.geojson");
    let c = city.to_str().unwrap();
    assert!(vocc(&["gen-city", "--buildings", "150", "-o", c])
        .status
        .success());
    let o = dir.join("x.vocc");
    let (res, took) = vocc_limited(&[
        "bake",
        c,
        "--height-attr",
        "height",
        "--cell-size",
        "0.1",
        "-o",
        o.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&res.stderr);
    assert_eq!(res.status.code(), Some(2), "{err}");
    assert!(err.contains("cell size of 1 to 100000 metres"), "{err}");
    assert!(took.as_secs_f64() < 1.0, "refused after {took:?}");
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

/// Issue 13, defect 1: `vocc bake victim.geojson --height-attr HAUTEUR -o victim.geojson`
/// exited 0 and turned the GeoJSON into a 1.9 KB store; `render ... SCENE -o SCENE`,
/// `export S.vocc --obj S.vocc` and `export S.vocc --blob S.vocc` did the same. Every output
/// that is an input is refused, compared as a file (another spelling, a hard link), and the
/// input is left as it was.
#[test]
fn output_equal_to_an_input_is_refused_and_the_input_is_not_destroyed() {
    let dir = common::temp_dir("cli-output-is-input");
    let victim = dir.join("victim.geojson");
    let text = boxes_geojson_attr("HAUTEUR", &block(1_842_000.0, 5_176_000.0, 8));
    std::fs::write(&victim, &text).unwrap();
    let v = victim.to_str().unwrap();
    let (_, store) = tiny_scene_and_store(&dir);
    let store_bytes = std::fs::read(&store).unwrap();
    let other_spelling = format!("{}/./victim.geojson", dir.display());
    let link = dir.join("link.geojson");
    std::fs::hard_link(&victim, &link).unwrap();
    let l = link.to_str().unwrap();
    let cases: Vec<Vec<&str>> = vec![
        vec!["bake", v, "--height-attr", "HAUTEUR", "-o", v],
        vec!["bake", v, "--height-attr", "HAUTEUR", "-o", &other_spelling],
        vec!["bake", v, "--height-attr", "HAUTEUR", "-o", l],
        vec![
            "render",
            &store,
            v,
            "--height-attr",
            "HAUTEUR",
            "--cell",
            "0",
            "-o",
            v,
        ],
        vec!["export", &store, "--cell", "0", "--obj", &store],
        vec!["export", &store, "--cell", "0", "--blob", &store],
        vec![
            "render",
            "--debug",
            v,
            "--height-attr",
            "HAUTEUR",
            "--at",
            "1842010,5176010",
            "-o",
            v,
        ],
    ];
    for args in cases {
        let (rc, err) = run(&args);
        assert_eq!(rc, Some(1), "{args:?}: {err}");
        assert!(err.contains("is also an input"), "{args:?}: {err}");
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), text, "{args:?}");
        assert_eq!(std::fs::read(&store).unwrap(), store_bytes, "{args:?}");
    }
    // `--reuse OLD -o OLD` would replace the old store the bake reads: refused too.
    let (rc, err) = run(&[
        "bake",
        v,
        "--height-attr",
        "HAUTEUR",
        "--cell-size",
        "50",
        "--reuse",
        &store,
        "-o",
        &store,
    ]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(err.contains("is also an input"), "{err}");
}

/// Issue 13, defect 5: a bake into a missing directory ran 26 s before failing. The output is
/// checked before any work: here before the `--reuse` store (missing too) is even looked at.
#[test]
fn bake_into_a_missing_directory_fails_before_any_work() {
    let dir = common::temp_dir("cli-missing-dir");
    let (scene, _) = tiny_scene_and_store(&dir);
    let out = dir.join("no/such/dir/city.vocc");
    let (rc, err) = run(&[
        "bake",
        &scene,
        "--height-attr",
        "height",
        "--reuse",
        dir.join("missing.vocc").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(
        err.contains("does not exist") && err.contains("no/such/dir"),
        "{err}"
    );
    assert!(
        !err.contains("missing.vocc"),
        "the output was not checked first: {err}"
    );
    // The same for every command that writes.
    for args in [
        vec![
            "gen-city",
            "--buildings",
            "10",
            "-o",
            "/no/such/dir/c.geojson",
        ],
        vec![
            "export",
            dir.join("tiny.vocc").to_str().unwrap(),
            "--cell",
            "0",
            "--obj",
            "/no/such/dir/c.obj",
        ],
    ]
    .iter()
    .map(|a| a.iter().map(|s| s.to_string()).collect::<Vec<_>>())
    {
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let (rc, err) = run(&a);
        assert_eq!(rc, Some(1), "{a:?}: {err}");
        assert!(
            err.contains("the folder /no/such/dir does not exist"),
            "{a:?}: {err}"
        );
    }
}

/// Issue 13, defect 3: `gen-city --buildings 99999999999` asked for 4 TB and aborted. It is
/// refused at once with the bound.
#[test]
fn gen_city_99999999999_buildings_is_refused_with_its_bound_not_aborted() {
    let (rc, err) = run(&[
        "gen-city",
        "--buildings",
        "99999999999",
        "-o",
        "/tmp/never.geojson",
    ]);
    assert_eq!(rc, Some(2), "{err}");
    assert!(err.contains("from 1 to 10000000"), "{err}");
    assert!(
        !err.contains("memory allocation") && !err.contains("panicked"),
        "{err}"
    );
    assert!(!std::path::Path::new("/tmp/never.geojson").exists());
}

/// Issue 13, defect 6: `render --radius 0` and negative values wrote SVGs with `inf`
/// coordinates or empty ones, and `--storey-height -3` gave a store with 0 VOs. Every numeric
/// option is checked by one rule: a usage error (exit 2) naming the option.
#[test]
fn render_radius_0_negative_values_and_storey_height_minus_3_are_refused() {
    let dir = common::temp_dir("cli-bad-numbers");
    let (scene, store) = tiny_scene_and_store(&dir);
    let svg = dir.join("x.svg");
    let o = svg.to_str().unwrap();
    let render = |v: &str| {
        run(&[
            "render",
            &store,
            &scene,
            "--height-attr",
            "height",
            "--cell",
            "0",
            "--radius",
            v,
            "-o",
            o,
        ])
    };
    for v in ["0", "-100", "inf", "NaN"] {
        let (rc, err) = render(v);
        assert_eq!(rc, Some(2), "--radius {v}: {err}");
        assert!(err.contains("--radius"), "{err}");
        assert!(!svg.exists(), "--radius {v} wrote a picture");
    }
    let out = dir.join("s.vocc");
    for (flag, v) in [
        ("--storey-height", "-3"),
        ("--storey-height", "0"),
        ("--cell-size", "-50"),
        ("--threads", "0"),
        ("--eye", "-1..2"),
        ("--shard-count", "0"),
    ] {
        let (rc, err) = run(&[
            "bake",
            &scene,
            "--height-attr",
            "height",
            flag,
            v,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_eq!(rc, Some(2), "{flag} {v}: {err}");
        assert!(err.contains(flag), "{flag} {v}: {err}");
        assert!(!out.exists());
    }
    for (flag, v) in [("--eyes", "0"), ("--samples", "0"), ("--cells", "0")] {
        let (rc, err) = run(&["eval", &store, &scene, "--height-attr", "height", flag, v]);
        assert_eq!(rc, Some(2), "{flag} {v}: {err}");
    }
}

/// Issue 13, defect 4: `merge sh0.vocc` (1 of 3) and `merge sh0.vocc sh0.vocc sh1.vocc`
/// exited 0 and the result looked complete. Each shard's hashes record its index and count;
/// a missing or repeated shard is refused, naming it.
#[test]
fn merge_of_an_incomplete_or_repeated_set_of_shards_is_refused() {
    let dir = common::temp_dir("cli-merge-incomplete");
    let (scene, whole) = tiny_scene_and_store(&dir);
    let sh: Vec<String> = (0..3)
        .map(|i| {
            let p = dir
                .join(format!("sh{i}.vocc"))
                .to_str()
                .unwrap()
                .to_string();
            let shard = format!("{i}/3");
            let (rc, err) = run(&[
                "bake",
                &scene,
                "--height-attr",
                "height",
                "--cell-size",
                "50",
                "--shard",
                &shard,
                "-o",
                &p,
            ]);
            assert_eq!(rc, Some(0), "{err}");
            p
        })
        .collect();
    let m = dir.join("m.vocc");
    let mo = m.to_str().unwrap();
    let (rc, err) = run(&["merge", &sh[0], "-o", mo]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(err.contains("2 of 3 shards are missing: 1/3, 2/3"), "{err}");
    let (rc, err) = run(&["merge", &sh[0], &sh[0], &sh[1], "-o", mo]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(err.contains("shard 0/3 is given twice"), "{err}");
    assert!(!m.exists(), "no output after a refused merge");
    // A whole bake is not a shard; a shard without its hashes cannot be placed.
    let (rc, err) = run(&["merge", &sh[0], &sh[1], &whole, "-o", mo]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(err.contains("is not a shard"), "{err}");
    // A shard that records another scene (here: another object count) is refused.
    let mut other = std::fs::read(&sh[1]).unwrap();
    other[136] ^= 1;
    other[132..136].fill(0);
    let crc = vocc::runtime::crc::crc32(&other);
    other[132..136].copy_from_slice(&crc.to_le_bytes());
    let ox = dir.join("other.vocc");
    std::fs::write(&ox, &other).unwrap();
    let (rc, err) = run(&["merge", &sh[0], ox.to_str().unwrap(), &sh[2], "-o", mo]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(
        err.contains("records another scene than") && err.contains("objects 65 and 64"),
        "{err}"
    );
    assert!(!m.exists(), "no output after a refused merge");
    // The complete set merges into the whole bake, byte for byte, scene section included.
    let (rc, err) = run(&["merge", &sh[2], &sh[0], &sh[1], "-o", mo]);
    assert_eq!(rc, Some(0), "{err}");
    assert_eq!(std::fs::read(&m).unwrap(), std::fs::read(&whole).unwrap());
    std::fs::remove_file(format!("{}.hashes", sh[1])).unwrap();
    let (rc, err) = run(&["merge", &sh[0], &sh[1], &sh[2], "-o", mo]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(
        err.contains("cannot tell which shard") && err.contains("sh1.vocc.hashes"),
        "{err}"
    );
}

/// Issue 13, defect 10: a reuse bake with 0 cells rebaked printed "313.00 VOs per baked cell"
/// (every VO of the store over max(baked, 1) = 1 cell). Counts are per selected cell, and a bake
/// that baked nothing says so.
#[test]
fn a_reuse_bake_with_0_cells_rebaked_does_not_print_vos_per_baked_cell_over_one_cell() {
    let dir = common::temp_dir("cli-reuse-zero");
    let (scene, store) = tiny_scene_and_store(&dir);
    let again = dir.join("again.vocc");
    let (rc, err) = run(&[
        "bake",
        &scene,
        "--height-attr",
        "height",
        "--cell-size",
        "50",
        "--reuse",
        &store,
        "-o",
        again.to_str().unwrap(),
    ]);
    assert_eq!(rc, Some(0), "{err}");
    assert!(err.contains("incremental: 0 of"), "{err}");
    assert!(err.contains("no cell baked"), "{err}");
    assert!(!err.contains("per baked cell,"), "{err}");
    let v: serde_json::Value =
        serde_json::from_slice(&vocc(&["inspect", &store, "--json"]).stdout).unwrap();
    assert!(
        v["vos"].as_u64().unwrap() > 10,
        "the tiny city stores VOs: {v}"
    );
    let want = format!(
        "VOs: {} in {} cells ({:.2} per cell",
        v["vos"],
        v["cells"],
        v["vos"].as_f64().unwrap() / v["cells"].as_f64().unwrap()
    );
    assert!(err.contains(&want), "{want:?} not in {err}");
}

/// Issue 13, defect 8: `vocc inspect S --json | head -1` printed "error: Broken pipe" and exited
/// 1. A closed output pipe ends the run quietly with status 0, as Unix tools do.
#[test]
fn inspect_json_into_a_closed_pipe_exits_quietly_not_with_error_broken_pipe() {
    let dir = common::temp_dir("cli-broken-pipe");
    let (_, store) = tiny_scene_and_store(&dir);
    // The reader (`true`) is gone before vocc writes: every write meets a closed pipe.
    let out = Command::new("sh")
        .arg("-c")
        .arg(r#"{ sleep 0.3; "$0" inspect "$1" --json; echo "rc=$?" >&2; } | true"#)
        .arg(common::vocc_bin())
        .arg(&store)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("rc=0"), "{err}");
    assert!(!err.contains("error"), "{err}");
}

/// Issue 13, defect 9: `eval --report DIR` promised plots and wrote only eval.md. It writes the
/// two plots eval.md shows. And (friction) `eval` names cells by id, shows its progress in a log,
/// and a false cull's exit status (3) is not a usage error's (2).
#[test]
fn eval_report_dir_writes_the_plots_it_promises_and_cells_are_named_by_id() {
    let dir = common::temp_dir("cli-eval-report");
    let (scene, store) = tiny_scene_and_store(&dir);
    let rep = dir.join("report");
    let out = Command::new(common::vocc_bin())
        .args([
            "eval",
            &store,
            &scene,
            "--height-attr",
            "height",
            "--cell",
            "10,3,24",
            "--json",
            "--report",
            rep.to_str().unwrap(),
        ])
        .env("VOCC_PROGRESS_SECONDS", "0")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let ids: Vec<u64> = v["cells"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["cell"].as_u64().unwrap())
        .collect();
    assert_eq!(ids, [3, 10, 24]);
    let md = std::fs::read_to_string(rep.join("eval.md")).unwrap();
    for plot in ["vos.svg", "map.svg"] {
        assert!(
            md.contains(&format!("]({plot})")),
            "eval.md does not show {plot}"
        );
        let svg = std::fs::read_to_string(rep.join(plot)).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("</svg>"), "{plot}");
    }
    // Progress in a log: count, rate and time left, not a spinner.
    assert!(err.contains("ground truth: 3 cells"), "{err}");
    assert!(err.contains("cells/s") && err.contains("left"), "{err}");
    assert!(err.contains("ground truth: 3/3 cells done"), "{err}");
    let (rc, err) = run(&[
        "eval",
        &store,
        &scene,
        "--height-attr",
        "height",
        "--cell",
        "49",
    ]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(
        err.contains("cell 49 is outside the grid (cells 0..49)"),
        "{err}"
    );
    let help = String::from_utf8_lossy(&vocc(&["--help"]).stdout).into_owned();
    assert!(help.contains("3  vocc eval: a false cull"), "{help}");
}

/// Issue 13 (friction): `inspect --json` did nothing with `--cell`, and there was no per-cell
/// listing (finding a store's busiest cells took thousands of calls). `--cell` prints text or
/// JSON; `--cells` lists every cell, as a table or JSON, sorted and cut, with each cell's culled
/// share when the scene is given.
#[test]
fn inspect_cell_json_differs_from_text_and_cells_lists_every_cell() {
    let dir = common::temp_dir("cli-inspect-cells");
    let (scene, store) = tiny_scene_and_store(&dir);
    let text = vocc(&["inspect", &store, "--cell", "24"]);
    let json = vocc(&["inspect", &store, "--cell", "24", "--json"]);
    assert!(text.status.success() && json.status.success());
    let t = String::from_utf8_lossy(&text.stdout);
    assert!(t.starts_with("cell 24: x "), "{t}");
    let j: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    assert_eq!(j["cell"], 24);
    let n_vos = j["vos"].as_array().unwrap().len();
    assert_eq!(t.matches("  VO ").count(), n_vos, "{t}");
    // Each VO line gives its stored fields, exponents included.
    assert_eq!(t.matches("; a (e ").count(), n_vos, "{t}");

    let all: serde_json::Value =
        serde_json::from_slice(&vocc(&["inspect", &store, "--cells", "--json"]).stdout).unwrap();
    let cells = all["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 49);
    let total: u64 = cells.iter().map(|c| c["vos"].as_u64().unwrap()).sum();
    let summary: serde_json::Value =
        serde_json::from_slice(&vocc(&["inspect", &store, "--json"]).stdout).unwrap();
    assert_eq!(total, summary["vos"].as_u64().unwrap());
    // Bytes per cell: index byte + 6 per VO (+ a ground byte on uneven ground, not here).
    assert!(cells
        .iter()
        .all(|c| c["bytes"].as_u64().unwrap() == 1 + 6 * c["vos"].as_u64().unwrap()));
    let top: serde_json::Value = serde_json::from_slice(
        &vocc(&[
            "inspect",
            &store,
            &scene,
            "--height-attr",
            "height",
            "--cells",
            "--sort",
            "culled",
            "--top",
            "3",
            "--json",
        ])
        .stdout,
    )
    .unwrap();
    let top = top["cells"].as_array().unwrap();
    assert_eq!(top.len(), 3);
    let c: Vec<f64> = top.iter().map(|c| c["culled"].as_f64().unwrap()).collect();
    assert!(c[0] > 0.0 && c.windows(2).all(|w| w[0] >= w[1]), "{c:?}");
    let table = vocc(&["inspect", &store, "--cells", "--sort", "vos", "--top", "5"]);
    let t = String::from_utf8_lossy(&table.stdout);
    assert_eq!(t.lines().count(), 6, "{t}");
    assert!(t.lines().next().unwrap().contains("VOs"), "{t}");
}

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
/// fell off the canvas, and there was no scale bar. Here a 300 m view of a 50 m cell whose VOs
/// reach its edge (their labels stood at y = 0 and x = 882 of 900).
#[test]
fn render_legend_names_its_window_vo_labels_stay_on_the_canvas_and_a_scale_bar() {
    let dir = common::temp_dir("cli-render-legend");
    let (scene, store) = tiny_scene_and_store(&dir);
    // The cell with the most VOs.
    let top: serde_json::Value = serde_json::from_slice(
        &vocc(&[
            "inspect",
            &store,
            "--list-cells",
            "--sort",
            "vos",
            "--top",
            "1",
            "--json",
        ])
        .stdout,
    )
    .unwrap();
    let cell = top["cells"][0]["cell"].to_string();
    assert!(top["cells"][0]["vos"].as_u64().unwrap() >= 3, "{top}");
    let svg = dir.join("cell.svg");
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
    let (w, h) = (attr(&text, "width"), attr(&text, "height"));
    let mut labels = 0;
    for t in text.split("<text").skip(1) {
        let (x, y) = (attr(t, "x"), attr(t, "y"));
        assert!(
            (0.0..=w).contains(&x) && (0.0..=h).contains(&y),
            "off the canvas: <text{t}"
        );
        let body = t.split('>').nth(1).unwrap().split('<').next().unwrap();
        labels += usize::from(body.parse::<u32>().is_ok());
    }
    assert!(labels > 0, "{text}");
    assert!(
        text.contains("in this view (300 m square): visible "),
        "{text}"
    );
    assert!(text.contains("whole scene: PVS "), "{text}");
    assert!(text.contains(">50 m</text>"), "a scale bar: {text}");
}

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
