//! `vocc bake`: scene files in, an occluder store out.
//!
//! Input: scene files, reader options and bake options. Output: the store file (written
//! atomically), a progress bar on stderr while cells bake, and a summary on stderr.
//! Invariant: the store's bytes depend only on the inputs and options, never on `--threads`.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;

use vocc::bake::incremental::{hashes_path, CellHashes};
use vocc::bake::pipeline::{self, BakeParams, Plan, Slices};
use vocc::runtime::crc::crc32;
use vocc::runtime::format::{encode_frame, encode_store, CellRecord};
use vocc::scene;

use crate::args::{parse_range, parse_rect, parse_slices, ReadArgs};
use crate::files::write_atomically;

#[derive(Args)]
pub struct BakeArgs {
    /// Scene files: GeoJSON footprints, CityJSON (0.8, 1.x, 2.0) or OBJ.
    #[arg(required = true)]
    pub scene: Vec<PathBuf>,
    #[command(flatten)]
    pub read: ReadArgs,
    /// Output store file.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Side of the square view cells, metres.
    #[arg(long, default_value_t = 100.0, value_name = "M")]
    pub cell_size: f64,
    /// Eye heights above the ground, metres: LOW..HIGH.
    #[arg(long, default_value = "1.5..2.0", value_parser = parse_range, value_name = "LOW..HIGH")]
    pub eye: (f64, f64),
    /// Slices per cell: `auto` (up to 5) or 1 to 5.
    #[arg(long, default_value = "auto", value_parser = parse_slices)]
    pub slices: Slices,
    /// Most VOs per cell (1 to 10).
    #[arg(long, default_value_t = 10)]
    pub max_vos: usize,
    /// Worker threads (default: all cores). The output does not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Bake only the cells meeting this world rectangle X0,Y0,X1,Y1 (the others stay empty).
    #[arg(long, value_parser = parse_rect, allow_hyphen_values = true, value_name = "X0,Y0,X1,Y1")]
    pub region: Option<[f64; 4]>,
    /// Bake only shard I of N: the cells whose id is I modulo N (`I/N`, 0-based), or `auto`: the
    /// array index from Slurm (`SLURM_ARRAY_TASK_ID`, with `SLURM_ARRAY_TASK_COUNT`), a
    /// Kubernetes Indexed Job (`JOB_COMPLETION_INDEX`) or AWS Batch (`AWS_BATCH_JOB_ARRAY_INDEX`),
    /// the count from `--shard-count` when the engine does not give it. `vocc merge` joins the
    /// shards into the store a single bake writes, byte for byte.
    #[arg(long, value_name = "I/N|auto")]
    pub shard: Option<String>,
    /// The number of shards, for `--shard auto` under Kubernetes or AWS Batch.
    #[arg(long, value_name = "N")]
    pub shard_count: Option<u32>,
    /// Bake only the cells meeting the polygons of this GeoJSON (the walkable area, world
    /// coordinates); the others stay empty.
    #[arg(long, value_name = "GEOJSON")]
    pub cells: Option<PathBuf>,
    /// Incremental rebake: reuse the records of this older store (and its `.hashes` file, which
    /// every bake writes beside its store) for the cells whose neighbourhood did not change; bake
    /// the rest. The output is byte-identical to a full bake.
    #[arg(long, value_name = "OLD_STORE")]
    pub reuse: Option<PathBuf>,
    /// Also propose VOs running through blocks of touching buildings, from this many blockers
    /// per cell (largest area-angle first); 0: none. On Lyon, 64 culls about half again as many
    /// objects for about four times the bake time (docs/RESULTS.md).
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub spines: usize,
    /// Also propose VOs from the long hidden runs of lines around each cell, across blocks and
    /// hidden streets. On Lyon it culls four to six times as many objects, for roughly ten times
    /// the bake time (docs/RESULTS.md).
    #[arg(long)]
    pub scan: bool,
}

/// Which shard this process bakes: `(index, count)`.
pub fn shard(
    spec: &str,
    count: Option<u32>,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<(u32, u32)> {
    let num = |what: &str, v: &str| -> Result<u32> {
        v.trim()
            .parse::<u32>()
            .with_context(|| format!("{what} must be a whole number, got {v:?}"))
    };
    let (i, n) = if spec == "auto" {
        let from = [
            "SLURM_ARRAY_TASK_ID",
            "JOB_COMPLETION_INDEX",
            "AWS_BATCH_JOB_ARRAY_INDEX",
        ]
        .iter()
        .find_map(|k| env(k).map(|v| (*k, v)));
        let (var, v) = from.context(
            "--shard auto: none of SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX, AWS_BATCH_JOB_ARRAY_INDEX is set",
        )?;
        let i = num(var, &v)?;
        let n = match (count, env("SLURM_ARRAY_TASK_COUNT")) {
            (Some(n), _) => n,
            (None, Some(c)) if var == "SLURM_ARRAY_TASK_ID" => num("SLURM_ARRAY_TASK_COUNT", &c)?,
            _ => anyhow::bail!(
                "--shard auto with {var}: give the number of shards with --shard-count N"
            ),
        };
        (i, n)
    } else {
        let (i, n) = spec
            .split_once('/')
            .with_context(|| format!("--shard expects I/N or auto, got {spec:?}"))?;
        (num("the shard index", i)?, num("the shard count", n)?)
    };
    anyhow::ensure!(
        n >= 1 && i < n,
        "shard index {i} is not below the shard count {n}"
    );
    Ok((i, n))
}

/// The hashes and bytes of the older store `old` when its cells may be reused under `plan`;
/// `None` (every cell is baked, and the reason is printed) when its hashes are missing, belong
/// to another store, or its frame differs.
fn reusable(
    old: &std::path::Path,
    plan: &Plan,
    hashes: &CellHashes,
) -> Result<Option<(CellHashes, Vec<u8>)>> {
    let bytes = crate::files::read_store(old)?;
    let store = crate::files::parse(old, &bytes)?;
    let hp = hashes_path(old);
    let old_hashes = match std::fs::read(&hp) {
        Ok(b) => CellHashes::decode(&b).with_context(|| format!("{} is damaged", hp.display()))?,
        Err(e) => {
            eprintln!(
                "incremental: cannot read {} ({e}); baking every cell",
                hp.display()
            );
            return Ok(None);
        }
    };
    let why = if old_hashes.store_crc != crc32(&bytes) {
        Some(format!("{} belongs to another store", hp.display()))
    } else if encode_frame(store.frame()) != encode_frame(&plan.frame) {
        Some("the grid, origin, eyes, ground range or quantization changed".to_string())
    } else if old_hashes.global != hashes.global {
        Some("the options or the vocc version changed".to_string())
    } else {
        None
    };
    if let Some(why) = why {
        eprintln!("incremental: {why}; baking every cell");
        return Ok(None);
    }
    Ok(Some((old_hashes, bytes)))
}

pub fn run(a: BakeArgs) -> Result<()> {
    let t0 = Instant::now();
    let shard = match &a.shard {
        Some(spec) => Some(shard(spec, a.shard_count, &|k| std::env::var(k).ok())?),
        None => None,
    };
    let s = scene::load(&a.scene, &a.read.options())?;
    let load_s = t0.elapsed().as_secs_f64();
    let region = a.region.map(|[x0, y0, x1, y1]| {
        [
            x0 - s.origin.x,
            y0 - s.origin.y,
            x1 - s.origin.x,
            y1 - s.origin.y,
        ]
    });
    let walkable = match &a.cells {
        Some(p) => Some(scene::walkable::read(p, s.origin)?),
        None => None,
    };
    let params = BakeParams {
        walkable,
        cell_size: a.cell_size,
        eye: a.eye,
        slices: a.slices,
        max_vos: a.max_vos,
        spines: a.spines,
        scan: a.scan,
        region,
        ..BakeParams::default()
    };
    let plan = Plan::new(&s, params)?;
    let mut cells = plan.cells();
    if let Some((i, n)) = shard {
        cells.retain(|id| id % n == i);
        eprintln!("shard {i}/{n}: {} cells", cells.len());
    }
    let hashes = CellHashes::new(&plan, &cells);
    let reused_from = match &a.reuse {
        Some(old) => reusable(old, &plan, &hashes)?,
        None => None,
    };
    let (to_bake, reused): (Vec<u32>, Vec<(u32, CellRecord)>) = match &reused_from {
        Some((old_hashes, old_bytes)) => {
            let old_store = vocc::runtime::format::Store::parse(old_bytes)?;
            let bake = hashes.changed(old_hashes, &cells);
            let mut reused = Vec::with_capacity(cells.len() - bake.len());
            for &id in &cells {
                if bake.binary_search(&id).is_err() {
                    reused.push((id, old_store.cell(id)?));
                }
            }
            (bake, reused)
        }
        None => (cells.clone(), Vec::new()),
    };
    if let Some(old) = &a.reuse {
        eprintln!(
            "incremental: {} of {} cells changed since {}, {} reused",
            to_bake.len(),
            cells.len(),
            old.display(),
            reused.len()
        );
    }
    let cells = to_bake;
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(n) = a.threads {
        anyhow::ensure!(n >= 1, "--threads must be at least 1");
        pool = pool.num_threads(n);
    }
    let pool = pool.build().context("cannot start the worker threads")?;
    let bar = indicatif::ProgressBar::new(cells.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "baking {bar:40} {pos}/{len} cells, {elapsed} elapsed, about {eta} left",
        )
        .expect("a valid template"),
    );
    let t1 = Instant::now();
    let baked = pool.install(|| {
        pipeline::bake_cells(&plan, &cells, &|_| {
            bar.inc(1);
        })
    });
    bar.finish_and_clear();
    let bake_s = t1.elapsed().as_secs_f64();
    let mut records = pipeline::records(&plan.frame, &baked);
    for (id, rec) in reused {
        records[id as usize] = rec;
    }
    let bytes = encode_store(&plan.frame, &records)?;
    // The old hashes go first, the new ones last: a run stopped in between leaves a store
    // without hashes (the next `--reuse` bakes every cell), never a store with stale hashes.
    let hashes_file = hashes_path(&a.output);
    match std::fs::remove_file(&hashes_file) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(e).with_context(|| format!("cannot remove {}", hashes_file.display()))
        }
        _ => {}
    }
    write_atomically(&a.output, |w| std::io::Write::write_all(w, &bytes))?;
    let hashes = CellHashes {
        store_crc: crc32(&bytes),
        ..hashes
    };
    write_atomically(&hashes_file, |w| {
        std::io::Write::write_all(w, &hashes.encode())
    })?;

    let n = baked.len().max(1);
    let vos: usize = records.iter().map(|r| r.vos().len()).sum();
    let most = records.iter().map(|r| r.vos().len()).max().unwrap_or(0);
    let skipped = records
        .iter()
        .filter(|r| matches!(r, CellRecord::Skipped))
        .count();
    let mut ms: Vec<f64> = baked.iter().map(|c| c.stats.ms).collect();
    ms.sort_by(f64::total_cmp);
    let pct = |p: f64| {
        ms.get(((ms.len() as f64 - 1.0) * p) as usize)
            .copied()
            .unwrap_or(0.0)
    };
    let (tried, shrunk, dropped, checks) = baked.iter().fold((0, 0, 0, 0), |(t, s, d, k), c| {
        (
            t + c.stats.tried,
            s + c.stats.shrunk,
            d + c.stats.dropped,
            k + c.stats.checks,
        )
    });
    let g = &plan.frame.grid;
    eprintln!(
        "grid {} x {} cells of {} m; baked {} cells ({} skipped: inside a building) in {:.1} s on {} threads (scene loaded in {:.1} s)",
        g.nx,
        g.ny,
        g.cell_size,
        baked.len(),
        skipped,
        bake_s,
        pool.current_num_threads(),
        load_s
    );
    eprintln!(
        "VOs: {vos} ({:.2} per baked cell, at most {most}); per cell {:.1} ms median, {:.1} ms p95; quantization: {tried} tried, {shrunk} shrunk, {dropped} dropped, {checks} exact checks",
        vos as f64 / n as f64,
        pct(0.5),
        pct(0.95)
    );
    eprintln!(
        "wrote {} bytes to {} ({:.1} bytes per cell over {} cells)",
        bytes.len(),
        a.output.display(),
        bytes.len() as f64 / records.len().max(1) as f64,
        records.len()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::shard;

    #[test]
    fn shard_from_arguments_and_array_engines() {
        let none = |_: &str| None;
        assert_eq!(shard("2/4", None, &none).unwrap(), (2, 4));
        assert!(shard("4/4", None, &none).is_err());
        assert!(shard("x/4", None, &none).is_err());
        assert!(shard("auto", None, &none).is_err());
        let slurm = |k: &str| match k {
            "SLURM_ARRAY_TASK_ID" => Some("3".to_string()),
            "SLURM_ARRAY_TASK_COUNT" => Some("8".to_string()),
            _ => None,
        };
        assert_eq!(shard("auto", None, &slurm).unwrap(), (3, 8));
        let k8s = |k: &str| (k == "JOB_COMPLETION_INDEX").then(|| "5".to_string());
        assert!(
            shard("auto", None, &k8s).is_err(),
            "Kubernetes needs the count"
        );
        assert_eq!(shard("auto", Some(6), &k8s).unwrap(), (5, 6));
        let aws = |k: &str| (k == "AWS_BATCH_JOB_ARRAY_INDEX").then(|| "0".to_string());
        assert_eq!(shard("auto", Some(2), &aws).unwrap(), (0, 2));
    }
}
