//! The vocc binary as a user runs it: info, render --debug, bake then inspect, pvs and export,
//! both store versions, refusals, walkable areas, shards.

#[allow(unused_imports)]
use super::*;

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

    // --all-cells: one JSON line a cell, in cell order, each the line --cell gives.
    let out = vocc(&[
        "pvs",
        s,
        LYON,
        "--height-attr",
        "HAUTEUR",
        "--all-cells",
        "--json",
    ]);
    assert!(out.status.success());
    let lines: Vec<serde_json::Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 228);
    for (i, l) in lines.iter().enumerate() {
        assert_eq!(l["cell"], i as u64);
    }
    assert_eq!(lines[id as usize], p);
    let out = vocc(&["pvs", s, LYON, "--height-attr", "HAUTEUR", "--all-cells"]);
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert_eq!(text.lines().count(), 228, "{text}");
    assert!(text.contains(&format!("cell {id}: {} of 2576 objects", pvs.len())));
    // --all-cells with --cell is a usage error.
    let out = vocc(&["pvs", s, LYON, "--all-cells", "--cell", "0"]);
    assert_eq!(out.status.code(), Some(2));

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
        (vec!["--slices", "9"], "--slices"),
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
