//! `vocc bake`: scene files in, an occluder store out.
//!
//! Input: scene files, reader options and bake options. Output: the store file (written
//! atomically), a progress bar on stderr while cells bake, and a summary on stderr.
//! Invariant: the store's bytes depend only on the inputs and options, never on `--threads`.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::error::ErrorKind;
use clap::Args;

use vocc::bake::incremental::hashes_path;
use vocc::bake::job::{BakeJob, BakeSummary, JobError, ReuseRefusal};
use vocc::bake::params::{BakeParams, Effort, Generator, Reach, Slices};
use vocc::scene;

use crate::args::{
    parse_bytes_per_cell, parse_cell_size, parse_count, parse_count_u32, parse_effort, parse_eye,
    parse_far_block, parse_generator, parse_max_vos, parse_reach, parse_rect, parse_shard,
    parse_slices, FarBlock, ReadArgs, ShardSpec,
};
use crate::files::{check_output, parse, read_store, write_atomically};
use crate::progress::Progress;
use crate::report::plural;

#[derive(Args)]
#[command(after_help = "Examples:
  vocc bake data/lyon1/buildings_lyon1.geojson --height-attr HAUTEUR -o lyon.vocc
  vocc bake city.geojson --height-attr height --cell-size 50 --region 1841900,5175950,1842300,5176250 -o part.vocc
  vocc bake city-v2.geojson --height-attr height --reuse city-v1.vocc -o city-v2.vocc --json
  vocc bake city.geojson --height-attr height --walkable streets.geojson -o walkable.vocc
  vocc bake city.geojson --height-attr height --shard auto --shard-count 16 -o shard.vocc")]
pub struct BakeArgs {
    /// Scene files: GeoJSON, GeoPackage, FlatGeobuf or Shapefile footprints, OpenStreetMap PBF,
    /// CityJSON (0.3 to 0.9, 1.0, 1.1, 2.0), CityJSONSeq, CityGML 2.0, or OBJ (README, "What goes
    /// in").
    #[arg(required = true)]
    pub scene: Vec<PathBuf>,
    #[command(flatten)]
    pub read: ReadArgs,
    /// Output store file.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Side of the square view cells, metres.
    #[arg(long, default_value_t = 100.0, value_name = "M", value_parser = parse_cell_size, allow_hyphen_values = true)]
    pub cell_size: f64,
    /// Eye heights above the ground, metres: LOW..HIGH.
    #[arg(long, default_value = "1.5..2.0", value_parser = parse_eye, value_name = "LOW..HIGH", allow_hyphen_values = true)]
    pub eye: (f64, f64),
    /// Slices per cell (heights at which VOs are sought): `auto` (up to 5; up to 8 where the blockers around the cell stand under 12 m above the eyes, low-rise) or 1 to 8.
    #[arg(long, default_value = "auto", value_parser = parse_slices)]
    pub slices: Slices,
    /// Most VOs per cell (1 to 10).
    #[arg(long, default_value_t = 10, value_parser = parse_max_vos)]
    pub max_vos: usize,
    /// The store's budget, bytes per cell on average with every byte counted (header, index,
    /// records), or `none`. Each cell keeps the VOs that fit its share (8 on a large grid, 7
    /// with per-cell ground and rise bytes or on a small grid), and what a group of 4 x 4 cells
    /// leaves goes to its cells' best further VOs, up to --max-vos (docs/FORMAT.md, "Sizes")
    #[arg(long, default_value = "52", value_parser = parse_bytes_per_cell, value_name = "B")]
    pub bytes_per_cell: f64,
    /// Worker threads (default: all cores). The output does not depend on it; more threads
    /// than cores only share them (a note says so).
    #[arg(long, value_parser = parse_count, value_name = "N")]
    pub threads: Option<usize>,
    /// Bake only the cells meeting this world rectangle X0,Y0,X1,Y1 (the others stay empty).
    #[arg(long, value_parser = parse_rect, allow_hyphen_values = true, value_name = "X0,Y0,X1,Y1")]
    pub region: Option<[f64; 4]>,
    /// Bake only shard I of N: the cells whose group of 4 x 4 cells (row-major) is I modulo N
    /// (`I/N`, 0-based; a group shares its bytes, so it is baked whole), or `auto`: the
    /// array index from Slurm (`SLURM_ARRAY_TASK_ID`, with `SLURM_ARRAY_TASK_COUNT`), a
    /// Kubernetes Indexed Job (`JOB_COMPLETION_INDEX`) or AWS Batch (`AWS_BATCH_JOB_ARRAY_INDEX`),
    /// the count from `--shard-count` when the engine does not give it. `vocc merge` joins the
    /// shards into the store a single bake writes, byte for byte.
    #[arg(long, value_name = "I/N|auto", value_parser = parse_shard)]
    pub shard: Option<ShardSpec>,
    /// The number of shards, for `--shard auto` under Kubernetes or AWS Batch.
    #[arg(long, value_name = "N", value_parser = parse_count_u32, requires = "shard")]
    pub shard_count: Option<u32>,
    /// Bake only the cells meeting the polygons of this GeoJSON (the walkable area, world
    /// coordinates); the others stay empty. (`--cells FILE`, its old spelling, still works.)
    #[arg(long, alias = "cells", value_name = "GEOJSON")]
    pub walkable: Option<PathBuf>,
    /// Incremental rebake: reuse the records of this older store (and its `.hashes` file, which
    /// every bake writes beside its store) for the cells whose neighbourhood did not change; bake
    /// the rest. The output is byte-identical to a full bake.
    #[arg(long, value_name = "OLD_STORE")]
    pub reuse: Option<PathBuf>,
    /// How hard the generator looks: `fast`, `default` or `tight`. All are equally safe; they
    /// trade bake time for culled share (docs/RESULTS.md, "Speed against culling").
    #[arg(long, default_value = "default", value_parser = parse_effort)]
    pub effort: Effort,
    /// How far past a cell's sides its own VOs are sought: `auto`, or metres (100 to 5000): the
    /// blockers that may support them, its hidden maps and its scan lines. `auto` takes 16 mean
    /// free paths of a sight line among the scene's buildings, 900 to 1800 m: 900 in a compact
    /// or low-rise city, further among free-standing towers or wide streets (the summary says
    /// which). A longer reach finds VOs farther out, which close the wedges the near VOs leave
    /// open along streets seen end-on: on a large city it culls much more for two to three
    /// times the bake time, on a compact district a little less (its maps grow coarser; README,
    /// "How far a cell reaches"). Every reach is equally safe.
    #[arg(long, default_value = "auto", value_parser = parse_reach, value_name = "auto|M")]
    pub reach: Reach,
    /// The far field's blocks: `auto` (400 m, each split into 200 m quarters where at most
    /// 40,000 blockers lie within the far field's 3 km of it), metres a side for every block
    /// (rounded to whole cells, at least one), or `off`. The far field seeks long VOs
    /// kilometres out once per block, certified hidden from the whole block, and offers them to
    /// its cells. Smaller blocks give each cell larger umbrae for more bake time (on Tokyo
    /// centre, every cell: 1-cell blocks 91.5% culled and median PVS/VS 4.37 against 91.3% and
    /// 4.50 for `auto`, for 1.7 times the time; README, "How far a cell reaches"); `off` leaves
    /// the far field out (a small scene, where the cells' own reach covers it all). Every size
    /// is equally safe.
    #[arg(long, default_value = "auto", value_parser = parse_far_block, value_name = "auto|M|off")]
    pub far_block: FarBlock,
    /// Which generator proposes the VOs: `long` (long hidden runs of lines, the default) or
    /// `growth` (aggregate umbrae grown from single buildings, the generator before 0.2; kept as a
    /// measured baseline).
    #[arg(long, default_value = "long", value_parser = parse_generator)]
    pub generator: Generator,
    /// Print the summary as JSON on stdout (cells baked, reused and skipped, VOs, ms per cell,
    /// quantization, timings, bytes, the reuse decision, the scene's skipped objects by reason).
    #[arg(long)]
    pub json: bool,
}

/// Which shard this process bakes: `(index, count)`. A missing `--shard-count` is a usage
/// error (exit status 2); an environment that gives no usable index, a run failure.
pub fn shard(
    spec: ShardSpec,
    count: Option<u32>,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<(u32, u32)> {
    let num = |what: &str, v: &str| -> Result<u32> {
        v.trim()
            .parse::<u32>()
            .with_context(|| format!("{what} must be a whole number, got {v:?}"))
    };
    let (i, n) = if let ShardSpec::Fixed(i, n) = spec {
        (i, n)
    } else {
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
            _ => {
                return Err(crate::args::usage(
                    "bake",
                    ErrorKind::MissingRequiredArgument,
                    format!(
                        "--shard auto with {var}: give the number of shards with --shard-count N"
                    ),
                ))
            }
        };
        (i, n)
    };
    anyhow::ensure!(
        n >= 1 && i < n,
        "shard index {i} is not below the shard count {n}"
    );
    Ok((i, n))
}

pub fn run(a: BakeArgs) -> Result<()> {
    let t0 = Instant::now();
    // Before any work: the outputs can be written and are none of the inputs.
    let mut inputs: Vec<PathBuf> = a.scene.clone();
    inputs.extend(a.walkable.iter().cloned());
    if let Some(r) = &a.reuse {
        inputs.extend([r.clone(), hashes_path(r)]);
    }
    let inputs: Vec<&std::path::Path> = inputs.iter().map(PathBuf::as_path).collect();
    check_output(&a.output, &inputs)?;
    check_output(&hashes_path(&a.output), &inputs)?;
    let shard = match a.shard {
        Some(spec) => Some(shard(spec, a.shard_count, &|k| std::env::var(k).ok())?),
        None => None,
    };
    if let (Some(n), Ok(cores)) = (a.threads, std::thread::available_parallelism()) {
        if n > cores.get() {
            eprintln!(
                "note: --threads {n} on {}: the extra threads only share them (no faster; the store is the same)",
                crate::report::plural(cores.get(), "core", "cores")
            );
        }
    }
    let s = scene::load(&a.scene, &a.read.options())?;
    for n in &s.report.notes {
        eprintln!("note: {n}");
    }
    let load_s = t0.elapsed().as_secs_f64();
    // A large scene takes seconds to load and to plan before the first cell: say where it is.
    eprintln!(
        "loaded {} in {load_s:.1} s; preparing the bake (blockers, frame, content hashes)",
        plural(s.objects.len(), "object", "objects")
    );
    let region = a.region.map(|[x0, y0, x1, y1]| {
        [
            x0 - s.origin.x,
            y0 - s.origin.y,
            x1 - s.origin.x,
            y1 - s.origin.y,
        ]
    });
    let walkable = match &a.walkable {
        Some(p) => Some(scene::walkable::read(p, s.origin)?),
        None => None,
    };
    let params = BakeParams {
        walkable,
        cell_size: a.cell_size,
        eye: a.eye,
        slices: a.slices,
        max_vos: a.max_vos,
        bytes_per_cell: a.bytes_per_cell,
        generator: a.generator,
        region,
        ..BakeParams::default()
            .with_effort(a.effort)
            .with_reach_for(a.reach, &s)
    };
    let params = match a.far_block {
        FarBlock::Metres(m) => params.with_far_block(m),
        FarBlock::Auto => params,
    };
    let reach_m = params.search_m;
    if a.reach == Reach::Auto && reach_m > vocc::bake::params::SEARCH_M {
        eprintln!(
            "reach: {reach_m:.0} m past each cell's sides (auto: a sight line runs {:.0} m between this scene's buildings on average; --reach sets it)",
            vocc::bake::reach::mean_free_path(&s).unwrap_or(f64::NAN)
        );
    }
    let mut job = BakeJob::new(&s, params)?;
    if let Some((i, n)) = shard {
        job = job.shard(i, n)?;
        eprintln!(
            "shard {i}/{n}: {}",
            crate::report::plural(job.selected()?.len(), "cell", "cells")
        );
    }
    if let Some(n) = a.threads {
        job = job.threads(n);
    }
    if let Some(old) = &a.reuse {
        let bytes = read_store(old)?;
        parse(old, &bytes)?;
        let hp = hashes_path(old);
        let hashes = match std::fs::read(&hp) {
            Ok(b) => Some(b),
            Err(e) => {
                eprintln!("incremental: cannot read {} ({e})", hp.display());
                None
            }
        };
        job = job.reuse(bytes, hashes);
    }
    let progress = Progress::new("baking", ("cell", "cells"), 0);
    let out = job
        .run(&|p: vocc::bake::job::Progress| {
            if p.done == 0 {
                progress.start(p.total as u64);
            } else {
                progress.inc();
            }
        })
        .map_err(|e| match (&e, &a.reuse) {
            (JobError::OldHashes(_), Some(old)) => {
                anyhow::Error::new(e).context(format!("{} is damaged", hashes_path(old).display()))
            }
            _ => e.into(),
        })?;
    progress.finish();
    let sum = &out.summary;
    if let (Some(r), Some(old)) = (&sum.reuse, &a.reuse) {
        match r.refused {
            Some(ReuseRefusal::OtherStore) => eprintln!(
                "incremental: {} belongs to another store; baking every cell",
                hashes_path(old).display()
            ),
            Some(why) => eprintln!("incremental: {why}; baking every cell"),
            None => {}
        }
        eprintln!(
            "incremental: {} of {} changed since {}, {} reused",
            r.changed,
            plural(sum.cells_selected, "cell", "cells"),
            old.display(),
            r.reused
        );
    }

    // The old hashes go first, the new ones last: a run stopped in between leaves a store
    // without hashes (the next `--reuse` bakes every cell), never a store with stale hashes.
    let hashes_file = hashes_path(&a.output);
    match std::fs::remove_file(&hashes_file) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(e).with_context(|| format!("cannot remove {}", hashes_file.display()))
        }
        _ => {}
    }
    write_atomically(&a.output, |w| w.write_all(&out.store))?;
    write_atomically(&hashes_file, |w| w.write_all(&out.hashes))?;
    if a.json {
        let mut v = summary_json(sum)?;
        v["load_s"] = load_s.into();
        v["reach_m"] = reach_m.into();
        crate::report::round_timings(&mut v);
        v["store"] = a.output.display().to_string().into();
        v["hashes"] = hashes_file.display().to_string().into();
        let mut out = std::io::stdout().lock();
        serde_json::to_writer_pretty(&mut out, &v)?;
        writeln!(out)?;
    } else {
        print_summary(sum, load_s, &a.output);
    }
    Ok(())
}

/// The bake's summary as JSON, in `vocc info`'s words for the scene: `convex_pieces` (all
/// blockers, convex pieces and walls), `blocker_objects` and `no_blocker_objects` (objects that
/// gave blockers, and none).
pub fn summary_json(sum: &BakeSummary) -> Result<serde_json::Value> {
    let mut v = serde_json::to_value(sum)?;
    if let Some(sc) = v.get_mut("scene").and_then(|s| s.as_object_mut()) {
        let objects = sc.get("objects").and_then(|x| x.as_u64()).unwrap_or(0);
        if let Some(b) = sc.remove("blockers") {
            sc.insert("convex_pieces".into(), b);
        }
        if let Some(n) = sc.remove("no_blocker") {
            let none = n.as_u64().unwrap_or(0);
            sc.insert(
                "blocker_objects".into(),
                objects.saturating_sub(none).into(),
            );
            sc.insert("no_blocker_objects".into(), n);
        }
    }
    Ok(v)
}

/// The bake's summary, three lines on stderr.
fn print_summary(sum: &BakeSummary, load_s: f64, output: &std::path::Path) {
    let g = &sum.grid;
    eprintln!(
        "grid {} x {} of {} m; baked {} ({} skipped: inside a building) in {:.1} s on {} (scene loaded in {:.1} s)",
        g.nx,
        plural(g.ny as usize, "cell", "cells"),
        g.cell_size,
        plural(sum.cells_baked, "cell", "cells"),
        sum.cells_skipped,
        sum.timings.bake_s,
        plural(sum.threads, "thread", "threads"),
        load_s
    );
    let q = &sum.quantization;
    let ms = match (sum.ms_per_cell_median, sum.ms_per_cell_p95) {
        (Some(m), Some(p)) => format!("per baked cell {m:.1} ms median, {p:.1} ms p95"),
        _ => "no cell baked".to_string(),
    };
    eprintln!(
        "VOs: {} in {} ({:.2} per cell, at most {}); {ms}; quantization: {} tried, {} shrunk, {} dropped, {} exact checks",
        sum.vos, plural(sum.cells_selected, "cell", "cells"), sum.vos_per_cell, sum.max_vos, q.tried, q.shrunk, q.dropped, q.checks
    );
    if !sum.stages_s.is_empty() {
        // In the generator's order, not the map's.
        let parts: Vec<String> = vocc::bake::plan::STAGES
            .iter()
            .filter_map(|k| {
                let s = sum.stages_s.get(*k)?;
                let [whole, quarters] = sum.far_searches;
                Some(if *k == "far_field" && whole + quarters > 0 {
                    format!(
                        "far field {s:.1} s ({} whole, {} of blocks split among few blockers)",
                        plural(whole, "block", "blocks"),
                        plural(quarters, "quarter", "quarters")
                    )
                } else {
                    format!("{} {s:.1} s", k.replace('_', " "))
                })
            })
            .collect();
        eprintln!("time by stage, summed over cells: {}", parts.join(", "));
    }
    if let Some([median, most]) = sum.ground_rise_m {
        eprintln!(
            "terrain: the ground rises {median:.2} m across the median cell, {most:.2} m at most; a cell's eyes span its rise and the eye range, and the more they span the less it culls (smaller cells on a slope: README, \"Low-rise ground on a slope\")"
        );
    }
    eprintln!(
        "wrote {} to {} ({:.1} bytes per cell over {})",
        plural(sum.store_bytes, "byte", "bytes"),
        output.display(),
        sum.bytes_per_cell,
        plural(g.cells as usize, "cell", "cells")
    );
    let sc = &sum.scene;
    if sc.skipped > 0 {
        let why: Vec<String> = sc
            .skipped_by_reason
            .iter()
            .map(|(k, v)| format!("{v} {k}"))
            .collect();
        eprintln!(
            "scene: {}; {} skipped ({}; vocc info lists each)",
            plural(sc.objects, "object", "objects"),
            sc.skipped,
            why.join(", ")
        );
    }
}

#[cfg(test)]
mod tests {
    use super::shard;
    use crate::args::{parse_shard, ShardSpec};

    #[test]
    fn shard_from_arguments_and_array_engines() {
        let none = |_: &str| None;
        let spec = |s: &str| parse_shard(s).unwrap();
        assert_eq!(shard(spec("2/4"), None, &none).unwrap(), (2, 4));
        assert!(parse_shard("4/4").is_err());
        assert!(parse_shard("x/4").is_err());
        assert_eq!(spec("auto"), ShardSpec::Auto);
        assert!(shard(spec("auto"), None, &none).is_err());
        let slurm = |k: &str| match k {
            "SLURM_ARRAY_TASK_ID" => Some("3".to_string()),
            "SLURM_ARRAY_TASK_COUNT" => Some("8".to_string()),
            _ => None,
        };
        assert_eq!(shard(spec("auto"), None, &slurm).unwrap(), (3, 8));
        let k8s = |k: &str| (k == "JOB_COMPLETION_INDEX").then(|| "5".to_string());
        assert!(
            shard(spec("auto"), None, &k8s).is_err(),
            "Kubernetes needs the count"
        );
        assert_eq!(shard(spec("auto"), Some(6), &k8s).unwrap(), (5, 6));
        let aws = |k: &str| (k == "AWS_BATCH_JOB_ARRAY_INDEX").then(|| "0".to_string());
        assert_eq!(shard(spec("auto"), Some(2), &aws).unwrap(), (0, 2));
    }
}
