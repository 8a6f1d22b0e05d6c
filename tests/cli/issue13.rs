//! Issue 13's defects and friction, each a regression test with its literal input: grids that
//! cannot fit, outputs that are inputs, missing folders, numbers refused, merges, reuse, pipes, reports.

#[allow(unused_imports)]
use super::*;

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
