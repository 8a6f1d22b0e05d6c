//! The bake on Lyon (100 m cells, default options): ms per cell (median and p95) and the
//! whole-scene time at 1 and 2 threads, with the speed-up and the store's size.
//! `make bench` runs it (`cargo bench -p vocc-bench --bench bake`); it prints a table.
//!
//! The bake is the library job (`bake::job::BakeJob`, what `vocc bake` runs); the whole-bake time
//! includes its content hashes and encoding. Per-cell times are wall-clock times of `Plan::bake_cell`, measured while the pool runs at the
//! given thread count (so at 2 threads they include the contention of two busy cores). A
//! distribution's p95 is the figure asked for, which criterion's summary does not give; the
//! µs-scale culler is measured with criterion (`benches/culler.rs`).

use std::path::PathBuf;
use std::time::Instant;

use vocc::bake::job::BakeJob;
use vocc::bake::params::BakeParams;
use vocc::scene::{self, ReadOptions};

fn pct(v: &[f64], p: f64) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v.get(((v.len().max(1) - 1) as f64 * p).round() as usize)
        .copied()
        .unwrap_or(f64::NAN)
}

fn main() {
    let root = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/.."));
    let s = scene::load(
        &[root.join("data/lyon1/buildings_lyon1.geojson")],
        &ReadOptions {
            height_attr: Some("HAUTEUR".into()),
            ..ReadOptions::default()
        },
    )
    .expect("Lyon loads");
    let cells = BakeJob::new(&s, BakeParams::default())
        .unwrap()
        .selected()
        .unwrap();
    println!(
        "Lyon, {} cells of 100 m, {} blockers, {} objects",
        cells.len(),
        s.blockers.len(),
        s.objects.len()
    );
    println!("| threads | ms/cell median | ms/cell p95 | whole bake s | speed-up | VOs/cell | bytes/cell |");
    println!("|---|---|---|---|---|---|---|");
    let mut base = None;
    let mut first: Option<Vec<u8>> = None;
    for threads in [1, 2] {
        let job = BakeJob::new(&s, BakeParams::default())
            .unwrap()
            .threads(threads);
        let t = Instant::now();
        let out = job.run(&|_| {}).unwrap();
        let secs = t.elapsed().as_secs_f64();
        let ms: Vec<f64> = out.cells.iter().map(|c| c.stats.ms).collect();
        let cells_in_grid = out.summary.grid.cells as f64;
        let vos = out.summary.vos;
        let bytes = out.store;
        let b = *base.get_or_insert(secs);
        println!(
            "| {threads} | {:.1} | {:.1} | {secs:.2} | {:.2}x | {:.2} | {:.1} |",
            pct(&ms, 0.5),
            pct(&ms, 0.95),
            b / secs,
            vos as f64 / cells_in_grid,
            bytes.len() as f64 / cells_in_grid
        );
        match &first {
            None => first = Some(bytes),
            Some(f) => assert!(f == &bytes, "the store depends on the thread count"),
        }
    }
}
