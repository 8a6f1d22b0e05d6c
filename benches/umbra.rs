//! The 2D core on Lyon: per-cell dense-set size, VO length, growth time (median and p95) and
//! the verifier's rejection count, for 50, 100 and 200 m cells with one slice at mid height.
//! `make bench` runs it (`cargo bench -p vocc-bench --bench umbra`); it prints a table.
//!
//! Slice: the blockers cut by the plane at half the median building height
//! (`vocc::bake::mid_slice`).

use std::path::PathBuf;
use std::time::Instant;

use glam::DVec2;
use vocc::bake::growth::dense::grow_cell;
use vocc::bake::growth::GrowParams;
use vocc::bake::params::SEARCH_M;
use vocc::scene::{self, ReadOptions};

fn pct(v: &mut [f64], p: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

fn main() {
    // `cargo bench` passes --bench; a filter argument selects cell sizes ("50", "100", "200").
    let filter: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .join("data/lyon1/buildings_lyon1.geojson");
    let opts = ReadOptions {
        height_attr: Some("HAUTEUR".into()),
        ..ReadOptions::default()
    };
    let scene = scene::load(&[path], &opts).expect("Lyon loads");
    let slice = vocc::bake::mid_slice(&scene);
    let set = vocc::bake::slice_blockers(&scene, slice);
    let ext = scene.extent();
    println!(
        "Lyon: {} blockers at the slice z = {slice:.1} m (of {} pieces); extent {:.0} x {:.0} m",
        set.len(),
        scene.blockers.len(),
        ext.max.x - ext.min.x,
        ext.max.y - ext.min.y
    );
    println!(
        "| cell | cells | dense VOs/cell (median, p95, max) | VO length m (median, p95, max) | ms/cell (median, p95) | rejected |"
    );
    println!("|---|---|---|---|---|---|");
    for size in [50.0, 100.0, 200.0] {
        if !filter.is_empty() && !filter.iter().any(|f| f == &format!("{size}")) {
            continue;
        }
        let params = GrowParams::default();
        let (nx, ny) = (
            ((ext.max.x - ext.min.x) / size).ceil() as usize,
            ((ext.max.y - ext.min.y) / size).ceil() as usize,
        );
        let (mut counts, mut lens, mut times) = (Vec::new(), Vec::new(), Vec::new());
        let mut rejected = 0;
        for j in 0..ny {
            for i in 0..nx {
                let x0 = ext.min.x + i as f64 * size;
                let y0 = ext.min.y + j as f64 * size;
                let cell = [
                    DVec2::new(x0, y0),
                    DVec2::new(x0 + size, y0),
                    DVec2::new(x0 + size, y0 + size),
                    DVec2::new(x0, y0 + size),
                ];
                let t = Instant::now();
                let out = grow_cell(&cell, &set, &params, SEARCH_M);
                times.push(t.elapsed().as_secs_f64() * 1e3);
                counts.push(out.vos.len() as f64);
                lens.extend(out.vos.iter().map(|v| v.length()));
                rejected += out.rejected();
            }
        }
        let n = counts.len();
        println!(
            "| {size:.0} m | {n} | {:.0}, {:.0}, {:.0} | {:.1}, {:.1}, {:.1} | {:.2}, {:.2} | {rejected} |",
            pct(&mut counts, 0.5),
            pct(&mut counts, 0.95),
            pct(&mut counts, 1.0),
            pct(&mut lens, 0.5),
            pct(&mut lens, 0.95),
            pct(&mut lens, 1.0),
            pct(&mut times, 0.5),
            pct(&mut times, 0.95),
        );
    }
}
