//! Incremental rebake (issue 6): after a one-building edit of Lyon, baking only the cells whose
//! hash changed and reusing the old records for the rest gives a store byte-identical to a full
//! bake of the edited scene; and the CLI's `bake --reuse` does the same from files.
//!
//! Input: Lyon's footprints, edited as GeoJSON (a building deleted mid-file, so every later
//! index shifts, and one appended); a generated city with one building 1.5 m higher, for the CLI.
//! Output: the counts of rebaked cells, printed (the figures of the issue's note).
//! Invariants: reuse is exact (bytes equal); an edit rebakes some cells but not all; an unchanged
//! scene rebakes none.
//!
//! `make test` checks each property on a band of cells across the scene, west to east (the
//! middle row of cells, or the rows meeting a strip for the CLI), each bake a band's; the same
//! tests over every cell (several whole bakes of Lyon, minutes on 2 cores) are ignored here and run
//! by `make test-long` (`cargo test --test all incremental:: -- --ignored`).

use crate::common;

use std::process::Command;

use common::{lyon_options, repo, temp_dir, LYON};
use serde_json::Value;
use vocc::bake::incremental::hashes_path;
use vocc::bake::job::BakeJob;
use vocc::bake::params::{BakeParams, Effort};
use vocc::runtime::format::Store;
use vocc::runtime::grid::CellId;
use vocc::scene::{self, Scene};

fn load(json: &Value, name: &str) -> Scene {
    let path = temp_dir(&format!("incremental-{name}")).join("scene.geojson");
    std::fs::write(&path, serde_json::to_vec(json).unwrap()).unwrap();
    scene::load(&[path], &lyon_options()).unwrap()
}

/// The index of the feature whose first vertex is nearest the middle of the extract.
/// A feature in the west of the scene (the 50th from the west by its first vertex, so that
/// deleting it does not move the scene's extent): an edit there leaves the cells more than a
/// bake's reach (1 km at 100 m cells) to the east untouched.
fn western_feature(json: &Value) -> usize {
    let first_x = |f: &Value| -> f64 {
        let mut c = &f["geometry"]["coordinates"];
        while c[0].is_array() {
            c = &c[0];
        }
        c[0].as_f64().unwrap()
    };
    let feats = json["features"].as_array().unwrap();
    let mut order: Vec<usize> = (0..feats.len()).collect();
    order.sort_by(|&a, &b| first_x(&feats[a]).total_cmp(&first_x(&feats[b])));
    order[49.min(order.len() - 1)]
}

/// The bake the tests reuse from: the fast effort (the reuse logic is the same at every effort).
/// The fast effort, with the reach of a cell's bake cut short (weights within 600 m, the far
/// field 500 m past 200 m blocks): the default reaches kilometres, past the whole of Lyon, so
/// an edit there rebakes every cell; cut short, an edit rebakes a neighbourhood, and a reuse
/// that read too little would show.
fn params() -> BakeParams {
    let mut p = BakeParams::default().with_effort(Effort::Fast);
    p.weigh_m = 600.0;
    p.far.reach_m = 500.0;
    p.far.block_m = 200.0;
    p
}

fn shift(v: &mut Value, dx: f64) {
    match v {
        Value::Array(a) if a.first().is_some_and(Value::is_number) => {
            a[0] = Value::from(a[0].as_f64().unwrap() + dx);
        }
        Value::Array(a) => a.iter_mut().for_each(|x| shift(x, dx)),
        _ => {}
    }
}

/// Which cells the library bakes: every cell, or the middle row of the grid (west to east).
#[derive(Clone, Copy)]
enum Cells {
    All,
    MiddleRow,
}

/// The bake job of `scene` over `cells`.
fn job(scene: &Scene, cells: Cells) -> BakeJob<'_> {
    let job = BakeJob::new(scene, params()).unwrap();
    match cells {
        Cells::All => job,
        Cells::MiddleRow => {
            let g = job.plan().frame.grid;
            let row = (g.ny / 2) as CellId;
            let nx = g.nx as CellId;
            let ids: Vec<CellId> = (row * nx..(row + 1) * nx).collect();
            job.cells(&ids).unwrap()
        }
    }
}

/// (cells rebaked, cells baked) for `new` given the bake of `old` (the library job with the old
/// store's bytes and hashes), and checks the bytes equal a full bake of `new` (over the same cells).
fn rebake(
    old_out: &vocc::bake::job::BakeOutput,
    new: &Scene,
    cells: Cells,
    what: &str,
) -> (usize, usize) {
    let job = job(new, cells);
    assert_eq!(
        &job.plan().frame,
        Store::parse(&old_out.store).unwrap().frame(),
        "{what}: the edit moved the frame"
    );
    let inc = job
        .reuse(old_out.store.clone(), Some(old_out.hashes.clone()))
        .run(&|_| {})
        .unwrap();
    let full = self::job(new, cells).run(&|_| {}).unwrap();
    assert!(
        inc.store == full.store,
        "{what}: the incremental store differs from a full bake"
    );
    assert_eq!(inc.hashes, full.hashes, "{what}: hashes differ");
    let r = inc.summary.reuse.expect("a reuse decision");
    assert_eq!(r.refused, None, "{what}: reuse refused");
    assert_eq!(r.changed, inc.cells.len());
    assert_eq!(r.changed + r.reused, inc.summary.cells_selected);
    (r.changed, inc.summary.cells_selected)
}

#[test]
fn one_building_edits_of_lyon_rebake_a_neighbourhood_and_match_a_full_bake() {
    lyon_edits(Cells::MiddleRow, "row");
}

/// The same over every cell of Lyon (about 100 s on 2 cores): `make test-long`.
#[test]
#[ignore]
fn one_building_edits_of_lyon_rebake_a_neighbourhood_and_match_a_full_bake_on_every_cell() {
    lyon_edits(Cells::All, "all");
}

fn lyon_edits(cells: Cells, name: &str) {
    let json: Value =
        serde_json::from_slice(&std::fs::read(repo(LYON)).unwrap()).expect("Lyon is JSON");
    let old = load(&json, &format!("old-{name}"));
    let k = western_feature(&json);

    // An unchanged scene rebakes nothing: the job reuses every cell of its own bake.
    let first = job(&old, cells).run(&|_| {}).unwrap();
    let again = job(&old, cells)
        .reuse(first.store.clone(), Some(first.hashes.clone()))
        .run(&|_| {})
        .unwrap();
    assert_eq!(again.store, first.store);
    let r = again.summary.reuse.unwrap();
    assert_eq!(
        (r.refused, r.changed),
        (None, 0),
        "an unchanged scene rebakes nothing"
    );
    assert_eq!(again.summary.ms_per_cell_median, None, "no cell baked");

    // Deleting a feature mid-file shifts every later object index; appending one adds an index.
    let mut edited = json.clone();
    let f = edited["features"].as_array_mut().unwrap();
    let mut extra = f[k].clone();
    shift(&mut extra["geometry"]["coordinates"], 30.0);
    f.remove(k);
    f.push(extra);
    let (n_edited, total) = rebake(
        &first,
        &load(&edited, &format!("edited-{name}")),
        cells,
        "deleted and appended",
    );

    println!(
        "Lyon, 100 m cells ({name}): deleting one building and adding one 30 m away rebakes {n_edited} of {total} cells"
    );
    assert!(
        0 < n_edited && n_edited < total,
        "{n_edited} of {total} cells rebaked"
    );
}

fn vocc(args: &[&str]) -> std::process::Output {
    let out = Command::new(common::vocc_bin())
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "vocc {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

#[test]
fn bake_reuse_from_the_cli_matches_a_full_bake_and_refuses_stale_hashes() {
    cli_reuse(true);
}

/// The same over every cell of the generated city (about 2 minutes on 2 cores): `make test-long`.
#[test]
#[ignore]
fn bake_reuse_from_the_cli_matches_a_full_bake_and_refuses_stale_hashes_on_every_cell() {
    cli_reuse(false);
}

/// The world rectangle of a strip 100 m high across the middle of a GeoJSON scene, west to east,
/// as `--region` takes it.
fn middle_strip(json: &Value) -> String {
    fn walk(v: &Value, b: &mut [f64; 4]) {
        match v {
            Value::Array(a) if a.first().is_some_and(Value::is_number) => {
                let (x, y) = (a[0].as_f64().unwrap(), a[1].as_f64().unwrap());
                *b = [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)];
            }
            Value::Array(a) => a.iter().for_each(|x| walk(x, b)),
            _ => {}
        }
    }
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for f in json["features"].as_array().unwrap() {
        walk(&f["geometry"]["coordinates"], &mut b);
    }
    let y = (b[1] + b[3]) / 2.0;
    format!("{},{},{},{}", b[0], y - 50.0, b[2], y + 50.0)
}

/// `strip`: every bake covers the cells meeting `middle_strip` only.
fn cli_reuse(strip: bool) {
    let d = temp_dir(if strip {
        "incremental-cli"
    } else {
        "incremental-cli-all"
    });
    let p = |n: &str| d.join(n).to_str().unwrap().to_string();
    vocc(&[
        "gen-city",
        "--buildings",
        "2500",
        "--seed",
        "3",
        "-o",
        &p("a.geojson"),
    ]);
    // The edit: a building in the west 1.5 m higher.
    let mut json: Value = serde_json::from_slice(&std::fs::read(p("a.geojson")).unwrap()).unwrap();
    let k = western_feature(&json);
    let h = json["features"][k]["properties"]["height"]
        .as_f64()
        .unwrap();
    json["features"][k]["properties"]["height"] = Value::from(h + 1.5);
    std::fs::write(p("b.geojson"), serde_json::to_vec(&json).unwrap()).unwrap();
    let region = middle_strip(&json);
    let region: Vec<&str> = if strip {
        vec!["--region", &region]
    } else {
        vec![]
    };
    let bake = |scene: &str, out: &str, reuse: Option<&str>| {
        let mut args = vec![
            "bake",
            scene,
            "--height-attr",
            "height",
            "--effort",
            "fast",
            "-o",
            out,
        ];
        args.extend(&region);
        if let Some(r) = reuse {
            args.extend(["--reuse", r]);
        }
        String::from_utf8_lossy(&vocc(&args).stderr).to_string()
    };
    bake(&p("a.geojson"), &p("a.vocc"), None);
    assert!(
        hashes_path(&d.join("a.vocc")).exists(),
        "bake writes hashes"
    );
    bake(&p("b.geojson"), &p("full.vocc"), None);
    let log = bake(&p("b.geojson"), &p("inc.vocc"), Some(&p("a.vocc")));
    let full = std::fs::read(p("full.vocc")).unwrap();
    assert_eq!(std::fs::read(p("inc.vocc")).unwrap(), full, "{log}");
    let line = log
        .lines()
        .find(|l| l.starts_with("incremental:"))
        .unwrap_or_else(|| panic!("no incremental line in {log}"));
    let changed: usize = line.split_whitespace().nth(1).unwrap().parse().unwrap();
    let of: usize = line.split_whitespace().nth(3).unwrap().parse().unwrap();
    // The default bake reads kilometres around a cell: the generated town's every cell.
    assert!(0 < changed && changed <= of, "{line}");
    assert_eq!(
        std::fs::read(hashes_path(&d.join("inc.vocc"))).unwrap(),
        std::fs::read(hashes_path(&d.join("full.vocc"))).unwrap(),
        "the incremental bake's hashes are a full bake's"
    );
    Store::parse(&full).unwrap();

    // Hashes beside another store than their own are not trusted: every cell is baked.
    let (scene_b, x) = (p("b.geojson"), p("x.vocc"));
    let mut args = vec![
        "bake",
        &scene_b,
        "--height-attr",
        "height",
        "--cell-size",
        "90",
        "--effort",
        "fast",
        "-o",
        &x,
    ];
    args.extend(&region);
    vocc(&args);
    assert_ne!(
        std::fs::read(p("x.vocc")).unwrap(),
        std::fs::read(p("a.vocc")).unwrap()
    );
    std::fs::copy(
        hashes_path(&d.join("x.vocc")),
        hashes_path(&d.join("a.vocc")),
    )
    .unwrap();
    let log = bake(&p("b.geojson"), &p("inc2.vocc"), Some(&p("a.vocc")));
    assert!(log.contains("belongs to another store"), "{log}");
    assert_eq!(std::fs::read(p("inc2.vocc")).unwrap(), full);
}
