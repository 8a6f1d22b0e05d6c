//! The `vocc` command line: a thin layer over the library.
//!
//! Input: command-line arguments. Output: reports on stdout, files where asked, errors on stderr
//! with a non-zero exit status. Invariant: no geometry here; every decision is the library's.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};

use vocc::scene::{self, summary, ReadOptions};

mod bake;
mod eval;
mod store;

#[derive(Parser)]
#[command(name = "vocc", version, about = "Virtual occluders for city models")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Bake a scene into an occluder store: at most 10 virtual occluders per view cell.
    Bake(bake::BakeArgs),
    /// Describe a store: grid, frame, VOs per cell, bytes; or one cell's VOs (world coordinates).
    Inspect {
        /// Store file.
        store: PathBuf,
        /// Show this cell's VOs.
        #[arg(long, value_name = "ID")]
        cell: Option<u32>,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Build the potentially visible set of one cell from a store and the scene's objects.
    Pvs {
        /// Store file.
        store: PathBuf,
        /// Scene files (the occludees: each object's bounding box).
        #[arg(required = true)]
        scene: Vec<PathBuf>,
        #[command(flatten)]
        read: ReadArgs,
        /// The cell, by id.
        #[arg(long, value_name = "ID", conflicts_with = "at")]
        cell: Option<u32>,
        /// The cell holding this world position X,Y.
        #[arg(long, value_name = "X,Y", value_parser = parse_xy, allow_hyphen_values = true)]
        at: Option<(f64, f64)>,
        /// Print {"cell": ID, "objects": N, "pvs": [object indices in input order]}.
        #[arg(long)]
        json: bool,
    },
    /// Export one cell's VOs: as JSON (world coordinates), as OBJ quads, or as a per-cell blob.
    Export {
        /// Store file.
        store: PathBuf,
        /// The cell.
        #[arg(long, value_name = "ID")]
        cell: u32,
        /// Print the VOs as JSON on stdout.
        #[arg(long, conflicts_with_all = ["obj", "blob"])]
        json: bool,
        /// Write the VO quads as an OBJ file.
        #[arg(long, value_name = "FILE", conflicts_with = "blob")]
        obj: Option<PathBuf>,
        /// Write the cell's self-contained blob (and FILE.frame, the frame it decodes with).
        #[arg(long, value_name = "FILE")]
        blob: Option<PathBuf>,
    },
    /// Load scene files and report objects, blockers, convex pieces, repairs and timings.
    Info {
        /// Scene files: GeoJSON footprints, CityJSON (0.8, 1.x, 2.0) or OBJ.
        #[arg(required = true)]
        scene: Vec<PathBuf>,
        #[command(flatten)]
        read: ReadArgs,
        /// Print the full report as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Draw one cell as an SVG: `vocc render STORE SCENE... --cell ID -o cell.svg` draws the
    /// cell, its VOs and the buildings, coloured visible, culled thanks to fusion, or culled by
    /// single buildings alone (like the paper's Fig. 8). With --debug: `vocc render --debug
    /// SCENE... --at X,Y` draws the 2D growth of one slice (blockers, seeds, supporting and
    /// separating lines, the dense VOs).
    Render {
        /// Draw the growth of one slice instead.
        #[arg(long)]
        debug: bool,
        /// STORE then scene files; with --debug, scene files only.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// The cell, by id (store mode).
        #[arg(long, value_name = "ID")]
        cell: Option<u32>,
        /// A point of the cell, in world coordinates: X,Y.
        #[arg(long, value_name = "X,Y", value_parser = parse_xy, allow_hyphen_values = true)]
        at: Option<(f64, f64)>,
        /// --debug: side of the square cells, metres (grid anchored at the scene's minimum
        /// corner).
        #[arg(long, default_value_t = 100.0, value_name = "M")]
        cell_size: f64,
        /// --debug: slice height in world metres (default: half the median building height).
        #[arg(long, value_name = "Z")]
        slice: Option<f64>,
        /// Store mode: metres shown around the cell's centre.
        #[arg(long, default_value_t = 500.0, value_name = "M")]
        radius: f64,
        #[command(flatten)]
        read: ReadArgs,
        /// Output SVG file.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Join the shards of one bake (`vocc bake --shard I/N`) into the store a single bake writes.
    Merge {
        /// Shard store files.
        #[arg(required = true)]
        shards: Vec<PathBuf>,
        /// Output store file.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Evaluate a store against the ground truth: false culls (must be 0), PVS/VS, occlusion,
    /// occlusion against the number of VOs, culler time. Exit status 2 on any false cull.
    Eval(eval::EvalArgs),
    /// Regenerate docs/RESULTS.md and its plots from the bundled data (what `make eval` runs).
    Results(eval::ResultsArgs),
    /// Write a deterministic procedural city (GeoJSON footprints, attribute `height`).
    GenCity {
        /// Number of buildings.
        #[arg(long)]
        buildings: usize,
        /// Random seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Output GeoJSON file.
        #[arg(short, long)]
        output: PathBuf,
    },
}

/// Options of the scene readers.
#[derive(Args)]
struct ReadArgs {
    /// GeoJSON: attribute with the building height above its base, metres.
    #[arg(long, value_name = "NAME")]
    height_attr: Option<String>,
    /// GeoJSON: attribute with the base elevation, metres (default: base at 0).
    #[arg(long, value_name = "NAME")]
    base_attr: Option<String>,
    /// GeoJSON: attribute with the number of storeys, used when the height is missing.
    #[arg(long, value_name = "NAME")]
    levels_attr: Option<String>,
    /// Metres per storey for --levels-attr.
    #[arg(long, default_value_t = 3.0, value_name = "M")]
    storey_height: f64,
    /// CityJSON: level of detail to read (default: the highest each object has).
    #[arg(long)]
    lod: Option<String>,
}

impl ReadArgs {
    fn options(&self) -> ReadOptions {
        ReadOptions {
            height_attr: self.height_attr.clone(),
            base_attr: self.base_attr.clone(),
            levels_attr: self.levels_attr.clone(),
            storey_height: self.storey_height,
            lod: self.lod.clone(),
        }
    }
}

/// Parses a finite number (the one number rule of every option).
pub(crate) fn parse_num(t: &str) -> Result<f64, String> {
    t.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("{t:?} is not a finite number"))
}

/// Parses "X,Y".
fn parse_xy(s: &str) -> Result<(f64, f64), String> {
    let (x, y) = s
        .split_once(',')
        .ok_or_else(|| format!("expected X,Y, got {s:?}"))?;
    Ok((parse_num(x)?, parse_num(y)?))
}

fn main() {
    if let Err(e) = run(Cli::parse()) {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Bake(a) => bake::run(a),
        Command::Inspect { store, cell, json } => store::inspect(store, cell, json),
        Command::Pvs {
            store,
            scene,
            read,
            cell,
            at,
            json,
        } => store::pvs(store, scene, &read, cell, at, json),
        Command::Export {
            store,
            cell,
            json,
            obj,
            blob,
        } => {
            let to = match (json, obj, blob) {
                (_, Some(f), None) => store::ExportTo::Obj(f),
                (_, None, Some(f)) => store::ExportTo::Blob(f),
                (true, None, None) => store::ExportTo::Json,
                _ => anyhow::bail!("give one of --json, --obj FILE, --blob FILE"),
            };
            store::export(store, cell, to)
        }
        Command::Info { scene, read, json } => {
            let s = scene::load(&scene, &read.options())?;
            let sum = summary::summarize(&s);
            let mut out = std::io::stdout().lock();
            if json {
                serde_json::to_writer_pretty(&mut out, &sum)?;
                writeln!(out)?;
            } else {
                print_summary(&mut out, &sum)?;
            }
            Ok(())
        }
        Command::Render {
            debug,
            files,
            cell,
            at,
            cell_size,
            slice,
            radius,
            read,
            output,
        } => {
            if !debug {
                return store::render(files, &read, cell, at, radius, &output);
            }
            let at = at.context("--debug needs --at X,Y")?;
            let scene = files;
            anyhow::ensure!(
                cell_size.is_finite() && cell_size > 0.0,
                "--cell-size must be a positive number of metres"
            );
            let s = scene::load(&scene, &read.options())?;
            let local = glam::DVec2::new(at.0 - s.origin.x, at.1 - s.origin.y);
            let z = match slice {
                Some(z) => z - s.origin.z,
                None => vocc::bake::mid_slice(&s),
            };
            let set = vocc::bake::slice_blockers(&s, z);
            let cell = vocc::bake::grid_cell(&s, local, cell_size);
            let t = Instant::now();
            let out = vocc::bake::umbra::grow_cell(&cell, &set, &Default::default());
            let ms = t.elapsed().as_secs_f64() * 1e3;
            let svg = vocc::bake::svg::render(&cell, &set, &out, 0.1 * cell_size);
            write_atomically(&output, |w| w.write_all(svg.as_bytes()))?;
            eprintln!(
                "cell at ({:.1}, {:.1}) world, slice z = {:.1} m: {} blockers in the slice, {} seeds, {} dense VOs, {} rejected by the verifier, {ms:.1} ms; wrote {}",
                cell[0].x + s.origin.x,
                cell[0].y + s.origin.y,
                z + s.origin.z,
                set.len(),
                out.traces.len(),
                out.vos.len(),
                out.rejected(),
                output.display()
            );
            Ok(())
        }
        Command::Eval(a) => eval::eval(a),
        Command::Merge { shards, output } => store::merge(shards, &output),
        Command::Results(a) => eval::results(a),
        Command::GenCity {
            buildings,
            seed,
            output,
        } => {
            let t = Instant::now();
            let city = scene::gencity::generate(&scene::gencity::CityParams { buildings, seed });
            write_atomically(&output, |w| scene::gencity::write_geojson(w, &city))?;
            eprintln!(
                "wrote {} buildings to {} in {:.2} s",
                city.len(),
                output.display(),
                t.elapsed().as_secs_f64()
            );
            Ok(())
        }
    }
}

/// Writes through a temporary file in the same folder (`.NAME.tmp`), then renames, so an
/// interrupted run never leaves a complete-looking output: the output path holds either its old
/// content or the new one in full. Every failure names the output and the temporary file and
/// removes the temporary file; a full disk (ENOSPC) says so. A run killed by a signal while the
/// temporary file is open leaves it behind (it is overwritten by the next run and is never a
/// valid store before the write completes).
fn write_atomically(
    path: &std::path::Path,
    write: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> Result<()> {
    let name = path
        .file_name()
        .with_context(|| format!("{} is not a file path", path.display()))?;
    let tmp = path.with_file_name(format!(".{}.tmp", name.to_string_lossy()));
    let fail = |step: &str, e: std::io::Error| {
        let full = if e.kind() == std::io::ErrorKind::StorageFull {
            ": the disk is full"
        } else {
            ""
        };
        anyhow::Error::new(e).context(format!(
            "cannot write {} ({step} {}){full}",
            path.display(),
            tmp.display()
        ))
    };
    let result = (|| -> Result<()> {
        let f = std::fs::File::create(&tmp).map_err(|e| fail("creating", e))?;
        let mut w = std::io::BufWriter::new(f);
        write(&mut w).map_err(|e| fail("writing", e))?;
        let f = w
            .into_inner()
            .map_err(|e| fail("writing", e.into_error()))?;
        f.sync_all().map_err(|e| fail("syncing", e))?;
        std::fs::rename(&tmp, path).map_err(|e| fail("renaming", e))?;
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

fn print_summary(out: &mut impl Write, s: &summary::Summary) -> std::io::Result<()> {
    const LIST: usize = 10;
    for f in &s.files {
        write!(
            out,
            "file {} ({}): {} objects, {} skipped",
            f.path, f.format, f.objects, f.skipped
        )?;
        if !f.other_types.is_empty() {
            let o: Vec<String> = f
                .other_types
                .iter()
                .map(|(k, v)| format!("{k} {v}"))
                .collect();
            write!(out, "; other city objects not read: {}", o.join(", "))?;
        }
        writeln!(out)?;
    }
    writeln!(
        out,
        "objects: {} ({} footprints, {} meshes, {} triangles)",
        s.objects, s.footprint_objects, s.mesh_objects, s.triangles
    )?;
    writeln!(
        out,
        "blockers: {} objects gave blockers, {} gave none",
        s.blocker_objects, s.no_blocker_objects
    )?;
    writeln!(
        out,
        "convex pieces: {} ({:.2} per blocker object)",
        s.convex_pieces,
        s.convex_pieces as f64 / s.blocker_objects.max(1) as f64
    )?;
    let st = |x: &summary::Stats| {
        format!(
            "min {:.1}, median {:.1}, mean {:.1}, p90 {:.1}, max {:.1}",
            x.min, x.p50, x.mean, x.p90, x.max
        )
    };
    writeln!(out, "object heights (m): {}", st(&s.heights))?;
    writeln!(out, "blocker heights (m): {}", st(&s.blocker_heights))?;
    writeln!(
        out,
        "origin (world): {:.3}, {:.3}, {:.3}",
        s.origin[0], s.origin[1], s.origin[2]
    )?;
    writeln!(
        out,
        "extent (local): x {:.2}..{:.2}, y {:.2}..{:.2}, z {:.2}..{:.2} ({:.0} x {:.0} x {:.1} m)",
        s.extent_min[0],
        s.extent_max[0],
        s.extent_min[1],
        s.extent_max[1],
        s.extent_min[2],
        s.extent_max[2],
        s.extent_max[0] - s.extent_min[0],
        s.extent_max[1] - s.extent_min[1],
        s.extent_max[2] - s.extent_min[2]
    )?;
    let section = |out: &mut dyn Write,
                   title: &str,
                   counts: &std::collections::BTreeMap<String, usize>,
                   entries: &[summary::Entry]|
     -> std::io::Result<()> {
        if entries.is_empty() {
            return writeln!(out, "{title}: none");
        }
        writeln!(out, "{title}: {}", entries.len())?;
        for (k, v) in counts {
            writeln!(out, "  {v:>6}  {k}")?;
        }
        for e in entries.iter().take(LIST) {
            let obj = e.object.map(|i| format!("#{i} ")).unwrap_or_default();
            writeln!(
                out,
                "    {obj}{:?} ({}, {}): {}",
                e.name, e.file, e.location, e.reason
            )?;
        }
        if entries.len() > LIST {
            writeln!(
                out,
                "    ... {} more (--json lists all)",
                entries.len() - LIST
            )?;
        }
        Ok(())
    };
    section(out, "skipped objects", &s.skipped_by_reason, &s.skipped)?;
    // Repairs move no point; counts are enough here, and --json lists each one.
    writeln!(
        out,
        "repaired rings: {} in {} objects (--json lists each)",
        s.repaired.len(),
        s.repaired_objects
    )?;
    for (k, v) in &s.repaired_rings_by_kind {
        writeln!(out, "  {v:>6}  {k}")?;
    }
    section(
        out,
        "geometry that gave no blocker",
        &s.no_blocker_by_reason,
        &s.no_blocker,
    )?;
    let t: Vec<String> = s
        .timings
        .iter()
        .map(|(k, v)| format!("{k} {:.3} s", v))
        .collect();
    writeln!(out, "timings: {}", t.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{Error, ErrorKind};

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("vocc-write-atomically-{name}"));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// A writer that fails with ENOSPC halfway, as on a full disk: an error that names the
    /// output and says the disk is full, no temporary file, and the old output unchanged.
    #[test]
    fn a_full_disk_is_an_error_and_leaves_the_old_output() {
        let d = dir("full");
        let out = d.join("city.vocc");
        std::fs::write(&out, b"old store").unwrap();
        let e = write_atomically(&out, |w| {
            w.write_all(&[7; 100_000])?;
            Err(Error::from(ErrorKind::StorageFull))
        })
        .unwrap_err();
        let msg = format!("{e:#}");
        assert!(msg.contains("the disk is full"), "{msg}");
        assert!(msg.contains(&out.display().to_string()), "{msg}");
        assert!(msg.contains(".city.vocc.tmp"), "{msg}");
        assert_eq!(std::fs::read(&out).unwrap(), b"old store");
        assert!(!d.join(".city.vocc.tmp").exists(), "temporary file left");
        // Without an old output, nothing is left at all.
        let fresh = d.join("new.vocc");
        assert!(write_atomically(&fresh, |_| Err(Error::from(ErrorKind::StorageFull))).is_err());
        let left: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(left, ["city.vocc"], "only the old output remains");
    }

    #[test]
    fn other_write_errors_name_the_output_but_not_a_full_disk() {
        let d = dir("other");
        let out = d.join("x.svg");
        let e = write_atomically(&out, |_| Err(Error::other("boom"))).unwrap_err();
        let msg = format!("{e:#}");
        assert!(
            msg.contains(&out.display().to_string()) && msg.contains("boom"),
            "{msg}"
        );
        assert!(!msg.contains("disk is full"), "{msg}");
        assert!(!out.exists() && !d.join(".x.svg.tmp").exists());
        // A missing folder fails at creation, naming it.
        let e = write_atomically(&d.join("no/such/dir/x.svg"), |_| Ok(())).unwrap_err();
        assert!(format!("{e:#}").contains("creating"), "{e:#}");
    }

    #[test]
    fn a_successful_write_replaces_the_output_and_leaves_no_temporary_file() {
        let d = dir("ok");
        let out = d.join("a.txt");
        std::fs::write(&out, b"old").unwrap();
        write_atomically(&out, |w| w.write_all(b"new")).unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"new");
        assert!(!d.join(".a.txt.tmp").exists());
    }
}
