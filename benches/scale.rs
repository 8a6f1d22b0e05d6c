//! The bake at scale (issue 6): generated cities of 10^4 and 10^5 buildings (and 10^6 when asked)
//! baked end to end on 100 m cells with every core: generate, write GeoJSON, load, bake, encode.
//!
//! The bake is the library job (`bake::job::BakeJob`, what `vocc bake` runs); the hashes it computes
//! for incremental rebakes are timed apart (its own timing), and its CPU time includes them.
//! Input: `VOCC_SCALE` (comma-separated building counts; default `10000,100000`), `VOCC_SEED`
//! (default 1). `cargo bench -p vocc-bench --bench scale`; `make scale` runs 10^4 to 10^6.
//! Output: one table row per size: cells, stage times, core-ms per cell (wall x threads), CPU ms
//! per cell (what the process used: robust when other work shares the machine), peak memory,
//! store size;
//! the rows are also appended as JSON lines to `target/scale.jsonl`.
//! Each size runs in a child process of this bench (the same executable, `VOCC_SCALE_CHILD` set),
//! so its peak resident memory (`VmHWM` of /proc/self/status) is its own.

use std::io::Write;
use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

use vocc::bake::job::BakeJob;
use vocc::bake::params::BakeParams;
use vocc::scene::gencity::{generate, write_geojson, CityParams};
use vocc::scene::{self, ReadOptions};

/// Peak resident memory of this process, MiB (Linux; NaN elsewhere).
fn peak_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// CPU seconds (user + system) used by this process so far (Linux; NaN elsewhere). Unlike wall
/// time it hardly depends on what else the machine runs.
fn cpu_s() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            // Fields after the command name's closing parenthesis; utime and stime are the
            // 14th and 15th fields of the line, in clock ticks (100 per second on Linux).
            let rest = &s[s.rfind(')')? + 2..];
            let f: Vec<&str> = rest.split_whitespace().collect();
            let t = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
            Some(t / 100.0)
        })
        .unwrap_or(f64::NAN)
}

fn child(buildings: usize, seed: u64) {
    let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/..")).join("target/tmp/scale");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("city_{buildings}.geojson"));
    let t = Instant::now();
    let city = generate(&CityParams { buildings, seed });
    write_geojson(
        std::io::BufWriter::new(std::fs::File::create(&path).unwrap()),
        &city,
    )
    .unwrap();
    drop(city);
    let gen_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let s = scene::load(
        std::slice::from_ref(&path),
        &ReadOptions {
            height_attr: Some("height".into()),
            ..ReadOptions::default()
        },
    )
    .expect("the generated city loads");
    let load_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let cpu0 = cpu_s();
    let out = BakeJob::new(&s, BakeParams::default())
        .unwrap()
        .run(&|_| {})
        .unwrap();
    let bake_cpu_s = cpu_s() - cpu0;
    // What `vocc bake` adds to the cells: the content hashes for a later incremental rebake.
    let hash_s = out.summary.timings.hashes_s;
    let bake_s = t.elapsed().as_secs_f64() - hash_s;
    let hashes = out.hashes;
    let bytes = out.store;
    let baked = out.cells;
    let cells = baked.len();
    let _ = std::fs::remove_file(&path);
    let threads = rayon::current_num_threads();
    let mut ms: Vec<f64> = baked.iter().map(|c| c.stats.ms).collect();
    ms.sort_by(f64::total_cmp);
    let vos: usize = baked.iter().map(|c| c.record.vos().len()).sum();
    println!(
        "{{\"buildings\":{buildings},\"blockers\":{},\"cells\":{},\"threads\":{threads},\"gen_s\":{gen_s:.2},\"load_s\":{load_s:.2},\"bake_s\":{bake_s:.2},\"hash_s\":{hash_s:.2},\"hash_bytes\":{},\"core_ms_per_cell\":{:.2},\"cpu_ms_per_cell\":{:.2},\"median_ms\":{:.2},\"vos\":{vos},\"bytes\":{},\"peak_mib\":{:.0}}}",
        s.blockers.len(),
        cells,
        hashes.len(),
        bake_s * 1e3 * threads as f64 / cells.max(1) as f64,
        bake_cpu_s * 1e3 / cells.max(1) as f64,
        ms.get(ms.len() / 2).copied().unwrap_or(0.0),
        bytes.len(),
        peak_mib()
    );
}

fn main() {
    let seed: u64 = std::env::var("VOCC_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    if let Ok(n) = std::env::var("VOCC_SCALE_CHILD") {
        child(n.parse().expect("a building count"), seed);
        return;
    }
    let sizes: Vec<usize> = std::env::var("VOCC_SCALE")
        .unwrap_or_else(|_| "10000,100000".into())
        .split(',')
        .map(|s| {
            s.trim()
                .parse()
                .expect("VOCC_SCALE: comma-separated counts")
        })
        .collect();
    let log = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/..")).join("target/scale.jsonl");
    println!("generated city, 100 m cells, seed {seed}; each size in its own process");
    println!(
        "{:>10} {:>9} {:>8} {:>7} {:>7} {:>9} {:>7} {:>13} {:>12} {:>10} {:>6} {:>9} {:>9}",
        "buildings",
        "blockers",
        "cells",
        "gen s",
        "load s",
        "bake s",
        "hash s",
        "core-ms/cell",
        "CPU ms/cell",
        "median ms",
        "VOs",
        "bytes",
        "peak MiB"
    );
    for n in sizes {
        let out = Command::new(std::env::current_exe().unwrap())
            .env("VOCC_SCALE_CHILD", n.to_string())
            .output()
            .expect("the bench can run itself");
        assert!(
            out.status.success(),
            "size {n} failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let line = String::from_utf8_lossy(&out.stdout)
            .lines()
            .find(|l| l.starts_with('{'))
            .expect("the child prints its row")
            .to_string();
        let v: serde_json::Value = serde_json::from_str(&line).unwrap();
        println!(
            "{:>10} {:>9} {:>8} {:>7} {:>7} {:>9} {:>7} {:>13} {:>12} {:>10} {:>6} {:>9} {:>9}",
            v["buildings"].to_string(),
            v["blockers"].to_string(),
            v["cells"].to_string(),
            v["gen_s"].to_string(),
            v["load_s"].to_string(),
            v["bake_s"].to_string(),
            v["hash_s"].to_string(),
            v["core_ms_per_cell"].to_string(),
            v["cpu_ms_per_cell"].to_string(),
            v["median_ms"].to_string(),
            v["vos"].to_string(),
            v["bytes"].to_string(),
            v["peak_mib"].to_string()
        );
        let mut f = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&log)
            .unwrap();
        writeln!(f, "{line}").unwrap();
    }
}
