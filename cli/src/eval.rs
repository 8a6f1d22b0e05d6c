//! `vocc eval` (a store against the ground truth) and `vocc results` (the suite behind
//! `docs/RESULTS.md`, run by `make eval`).
//!
//! Input: a store and its scene; or dataset paths. Output: a report on stdout (text or JSON),
//! Markdown and SVG files where asked (`eval.md`, `vos.svg`, `map.svg`). Exit status 3 (not 2, which is a usage error) when any false cull is found, so scripts and CI
//! can rely on it, or when a ray from an eye reaches a stored VO unblocked.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;

use rayon::prelude::*;

use vocc::eval::bound::CeilingParams;
use vocc::eval::metrics::{
    cell_vs, object_boxes, percentile, sample_cells, summarize, vo_rays_all,
};
use vocc::eval::plot::{cell_map, chart, Series};
use vocc::eval::raycast::Caster;
use vocc::eval::report::{
    blocker_share_section, dataset_section, eval_cells, eval_markdown, machine,
    sliced_ceiling_cells, Dataset, SuiteParams,
};
use vocc::eval::truth::TruthParams;
use vocc::runtime::culler::BoxTree;
use vocc::scene::ReadOptions;

use crate::args::{parse_count, ReadArgs, SceneCheckArgs};
use crate::files::{
    check_output, check_report_dir, parse, read_store, write_atomically, write_report,
};
use crate::progress::Progress;
use crate::report::{plural, round_timings};
use crate::store::load_checked;

/// Ground-truth sampling options.
#[derive(Args, Clone)]
pub struct TruthArgs {
    /// Eye points per cell (spread over the cell, heights within the eye range).
    #[arg(long, default_value_t = 64, value_parser = parse_count)]
    pub eyes: usize,
    /// Rays aimed at each object from each eye point, at points of its surface.
    #[arg(long, default_value_t = 4, value_parser = parse_count)]
    pub samples: usize,
    /// Random seed (cells and rays).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

impl TruthArgs {
    fn params(&self) -> TruthParams {
        TruthParams {
            eyes: self.eyes,
            samples_per_object: self.samples,
            radius: None,
            seed: self.seed,
            eye_above: None,
        }
    }
}

#[derive(Args)]
#[command(after_help = "Examples:
  vocc eval city.vocc city.geojson --height-attr height --sample 20
  vocc eval city.vocc city.geojson --height-attr height --cell 57,58,120 --json
  vocc eval city.vocc city.geojson --height-attr height --sample 100 --report eval")]
pub struct EvalArgs {
    /// Store file.
    pub store: PathBuf,
    /// The scene files the store was baked from (same files, same order, same reader flags:
    /// checked against the store's scene, as `vocc pvs` does).
    #[arg(required = true)]
    pub scene: Vec<PathBuf>,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub check: SceneCheckArgs,
    /// Evaluate a seeded sample of N cells (default: every cell). (`--cells N`, its old
    /// spelling, still works.)
    #[arg(long, alias = "cells", value_name = "N", value_parser = parse_count, conflicts_with = "cell")]
    pub sample: Option<usize>,
    /// Evaluate these cells, by id (comma-separated).
    #[arg(long, value_name = "ID,...", value_delimiter = ',')]
    pub cell: Vec<u32>,
    #[command(flatten)]
    pub truth: TruthArgs,
    /// Print JSON (summary and per-cell figures).
    #[arg(long)]
    pub json: bool,
    /// Also estimate each evaluated cell's ceiling over the whole scene: what 10 ideal VOs in
    /// 2.5D could cull (long runs hidden in 2D from 16 points of the cell's boundary, on lines out
    /// to the scene's edge, VO tops up to its tallest blocker; `eval::bound::ceiling_sliced`),
    /// at the heights the store declares. An estimate, not conservative; it tells how far the
    /// bake is from what its representation could reach. Seconds per cell: about 10 s a cell on
    /// 2 cores on Tokyo centre (13,699 buildings), so sample a large city (`--sample`).
    #[arg(long)]
    pub ceiling: bool,
    /// Write a Markdown report and its plots into this folder: eval.md, vos.svg (objects culled
    /// against the number of VOs) and map.svg (PVS/VS per cell). The folder is created (the
    /// folder holding it must exist), and written all or nothing.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
}

/// The report's files, in a `--report` folder.
const REPORT_FILES: [&str; 3] = ["eval.md", "vos.svg", "map.svg"];

/// `vocc eval`; returns the exit status: 0, or 3 on a false cull or a ray reaching a VO.
pub fn eval(a: EvalArgs) -> Result<i32> {
    let mut inputs: Vec<&Path> = vec![&a.store];
    inputs.extend(a.scene.iter().map(PathBuf::as_path));
    if let Some(dir) = &a.report {
        check_report_dir(dir, &REPORT_FILES, &inputs)?;
    }
    let bytes = read_store(&a.store)?;
    let store = parse(&a.store, &bytes)?;
    let s = load_checked(&store, &a.store, &a.scene, &a.read, &a.check)?;
    anyhow::ensure!(
        store.frame().origin == s.origin.to_array(),
        "the store's origin {:?} is not the scene's {:?}: give the files the store was baked from",
        store.frame().origin,
        s.origin.to_array()
    );
    let truth = a.truth.params();
    let ids = if a.cell.is_empty() {
        sample_cells(&store, a.sample, a.truth.seed)
    } else {
        let mut ids = a.cell.clone();
        ids.sort_unstable();
        ids.dedup();
        if let Some(&id) = ids.iter().find(|&&id| id >= store.cell_count()) {
            anyhow::bail!(
                "cell {id} is outside the grid (cells 0..{})",
                store.cell_count()
            );
        }
        ids
    };
    let caster = Caster::new(&s);
    let tree = BoxTree::new(&object_boxes(&s));
    let progress = Progress::new("ground truth", ("cell", "cells"), ids.len() as u64);
    progress.start(ids.len() as u64);
    let vs: Vec<Vec<u32>> = ids
        .par_iter()
        .map(|&id| {
            let v = cell_vs(&s, &store, &caster, id, &truth);
            progress.inc();
            v
        })
        .collect();
    progress.finish();
    // The 3D check of the stored VOs: 16 eye points x 16 points per VO.
    let rays = vo_rays_all(&caster, &store, &ids, 16, 16, a.truth.seed);
    let cells = eval_cells(&s, &store, &tree, &ids, &vs);
    let sum = summarize(&s, &cells);
    let ceiling = a.ceiling.then(|| {
        let progress = Progress::new("ceiling", ("cell", "cells"), ids.len() as u64);
        progress.start(ids.len() as u64);
        let c: Vec<_> = ids
            .par_iter()
            .zip(&vs)
            .flat_map_iter(|(&id, vs)| {
                let c = sliced_ceiling_cells(
                    &s,
                    &store,
                    &[id],
                    std::slice::from_ref(vs),
                    &CeilingParams::scene(),
                );
                progress.inc();
                c
            })
            .collect();
        progress.finish();
        summarize(&s, &c)
    });
    let mut out = std::io::stdout().lock();
    if a.json {
        let mut v = serde_json::json!({"summary": sum, "vo_rays": rays, "cells": cells, "machine": machine()});
        if let Some(c) = &ceiling {
            v["ceiling"] = serde_json::json!(c);
        }
        round_timings(&mut v);
        serde_json::to_writer_pretty(&mut out, &v)?;
        writeln!(out)?;
    } else {
        writeln!(
            out,
            "{}, {}: {}; PVS/VS median {:.2} (objects), {:.2} (triangles); {:.1}% of objects culled on average; culler {:.0} µs median",
            plural(sum.cells, "cell", "cells"),
            plural(sum.objects, "object", "objects"),
            plural(sum.false_culls, "false cull", "false culls"),
            sum.median_ratio,
            sum.median_ratio_triangles,
            100.0 * sum.occluded_share,
            sum.median_pvs_us
        )?;
        let by: Vec<String> = sum
            .occluded_by_vos
            .iter()
            .enumerate()
            .map(|(k, o)| format!("{k}: {:.1}%", 100.0 * o))
            .collect();
        writeln!(
            out,
            "objects culled with the first k VOs: {}",
            by.join(", ")
        )?;
        if !sum.mean_excess_by_distance.is_empty() {
            let bands: Vec<String> = sum
                .mean_excess_by_distance
                .iter()
                .zip(vocc::eval::metrics::excess_band_names())
                .map(|(n, name)| format!("{n:.0} {name}"))
                .collect();
            writeln!(
                out,
                "PVS beyond the VS (objects kept yet hidden), mean a cell by distance from it: {}",
                bands.join(", ")
            )?;
        }
        writeln!(
            out,
            "3D check of the stored VOs: {} rays from eye points to VO points, {} reached a VO unblocked",
            rays.rays, rays.reached
        )?;
        if let Some(c) = &ceiling {
            writeln!(
                out,
                "ceiling over the whole scene (10 ideal VOs in 2.5D, an estimate): {:.1}% of objects culled on average, PVS/VS median {:.2}; the store reaches {:.0}% of the culled share",
                100.0 * c.occluded_share,
                c.median_ratio,
                100.0 * sum.occluded_share / c.occluded_share.max(1e-12)
            )?;
        }
    }
    if let Some(dir) = &a.report {
        let cmd = std::env::args().collect::<Vec<_>>().join(" ");
        let mut md = eval_markdown(
            &format!("vocc eval: {}", a.store.display()),
            &sum,
            &cells,
            &truth,
            &cmd,
        );
        md.push_str("\n![objects culled against the number of VOs](vos.svg)\n\n![PVS/VS per cell](map.svg)\n");
        let vo_plot = chart(
            "objects culled against VOs per cell",
            "VOs per cell (first k stored)",
            "objects culled, % (mean over cells)",
            &[Series {
                label: "store".into(),
                points: sum
                    .occluded_by_vos
                    .iter()
                    .enumerate()
                    .map(|(k, o)| (k as f64, 100.0 * o))
                    .collect(),
                line: true,
            }],
        );
        let ratio_of = |id: u32| {
            ids.binary_search(&id)
                .ok()
                .map(|k| cells[k].ratio())
                .filter(|r| r.is_finite())
        };
        let ratios: Vec<f64> = cells
            .iter()
            .map(|c| c.ratio())
            .filter(|r| r.is_finite())
            .collect();
        let g = store.frame().grid;
        let map = cell_map(
            "PVS/VS per cell (evaluated cells)",
            g.nx,
            g.ny,
            &ratio_of,
            1.0,
            percentile(&ratios, 0.95).max(1.5),
            "PVS/VS",
        );
        write_report(
            dir,
            &[
                (REPORT_FILES[0], md.as_bytes()),
                (REPORT_FILES[1], vo_plot.as_bytes()),
                (REPORT_FILES[2], map.as_bytes()),
            ],
        )?;
        eprintln!(
            "wrote the report {} ({})",
            dir.display(),
            REPORT_FILES.join(", ")
        );
    }
    if sum.false_culls > 0 || rays.reached > 0 {
        eprintln!(
            "error: {} (visible objects the PVS misses), {} reached a VO unblocked",
            plural(sum.false_culls, "false cull", "false culls"),
            plural(rays.reached as usize, "ray", "rays")
        );
        return Ok(3);
    }
    Ok(0)
}

#[derive(Args)]
pub struct ResultsArgs {
    /// The Markdown file to write; plots go into `img/` beside it.
    #[arg(short, long, default_value = "docs/RESULTS.md")]
    pub output: PathBuf,
    /// Cells sampled for the sweeps.
    #[arg(long, default_value_t = 40, value_parser = parse_count)]
    pub sample: usize,
    /// Regenerate only this dataset's section (its `##` heading, e.g. "Tokyo centre") and its
    /// plots, and keep the rest of the existing output file as it is: for a dataset added to the
    /// suite, or one that a change alone concerns. The file must exist; a section not in it is
    /// added at its end.
    #[arg(long, value_name = "NAME")]
    pub only: Option<String>,
    #[command(flatten)]
    pub truth: TruthArgs,
}

pub fn results(a: ResultsArgs) -> Result<()> {
    let img = a
        .output
        .parent()
        .map(|p| p.join("img"))
        .unwrap_or_else(|| PathBuf::from("img"));
    let datasets = [
        Dataset {
            name: "Lyon".into(),
            files: vec![PathBuf::from("data/lyon1/buildings_lyon1.geojson")],
            read: ReadOptions {
                height_attr: Some("HAUTEUR".into()),
                ..ReadOptions::default()
            },
            flags: "--height-attr HAUTEUR".into(),
            size_sample: None,
        },
        Dataset {
            name: "Den Haag".into(),
            files: vec![PathBuf::from("data/denhaag/DenHaag_01.json")],
            read: ReadOptions::default(),
            flags: String::new(),
            size_sample: None,
        },
        // Terrain (issue 32): Den Haag without its TIN, and Salt River (Cape Town) on its slope
        // without terrain and on the 25 m DEM.
        Dataset {
            name: "Den Haag without terrain".into(),
            files: vec![PathBuf::from("data/denhaag/DenHaag_01.json")],
            read: ReadOptions {
                no_terrain: true,
                ..ReadOptions::default()
            },
            flags: "--no-terrain".into(),
            size_sample: None,
        },
        Dataset {
            name: "Salt River".into(),
            files: vec![PathBuf::from(
                "data/capetown/salt_river_footprints_utm34s.geojson",
            )],
            read: ReadOptions {
                height_attr: Some("height".into()),
                base_attr: Some("base_z".into()),
                ..ReadOptions::default()
            },
            flags: "--height-attr height --base-attr base_z".into(),
            size_sample: None,
        },
        Dataset {
            name: "Salt River with the DEM".into(),
            files: vec![PathBuf::from(
                "data/capetown/salt_river_footprints_utm34s.geojson",
            )],
            read: ReadOptions {
                height_attr: Some("height".into()),
                base_attr: Some("base_z".into()),
                terrain: vec![PathBuf::from("data/capetown/capetown_dem25m_utm34s.tif")],
                ..ReadOptions::default()
            },
            flags: "--height-attr height --base-attr base_z --terrain data/capetown/capetown_dem25m_utm34s.tif".into(),
            size_sample: None,
        },
        // Open LoD2 meshes: Den Haag without its ground faces (tools/denhaag_no_ground.py),
        // and Gelderseplein (3DBAG, overlapping levels of detail).
        Dataset {
            name: "Den Haag without ground faces".into(),
            files: vec![PathBuf::from("data/denhaag/DenHaag_01_noground.json")],
            read: ReadOptions::default(),
            flags: String::new(),
            size_sample: None,
        },
        Dataset {
            name: "Gelderseplein".into(),
            files: vec![PathBuf::from("data/gelderseplein/gelderseplein.obj")],
            read: ReadOptions::default(),
            flags: String::new(),
            size_sample: None,
        },
        // A whole city centre (issue 31): 13,699 buildings over 3 x 3 km, towers to 214 m; the
        // cell sizes on the sample, since its ground truth at 50 m on every cell takes hours.
        Dataset {
            name: TOKYO.into(),
            files: vec![PathBuf::from(
                "data/tokyo-central/tokyo_central_utm54n.geojson",
            )],
            read: ReadOptions {
                height_attr: Some("height".into()),
                ..ReadOptions::default()
            },
            flags: "--height-attr height".into(),
            size_sample: Some(a.sample),
        },
    ];
    let mesh_datasets = [
        ("Den Haag", "data/denhaag/DenHaag_01.json"),
        ("Den Haag", "data/denhaag/DenHaag_01_buildings.obj"),
        (
            "Den Haag without ground faces",
            "data/denhaag/DenHaag_01_noground.json",
        ),
        ("Delft", "data/delft/delft.json"),
        ("Delft", "data/delft/delft_buildings.obj"),
        ("Gelderseplein", "data/gelderseplein/gelderseplein.obj"),
    ]
    .map(|(n, f)| (n, PathBuf::from(f)));
    let inputs: Vec<&std::path::Path> = datasets
        .iter()
        .flat_map(|d| d.files.iter().map(PathBuf::as_path))
        .collect();
    check_output(&a.output, &inputs)?;
    let params = SuiteParams {
        truth: a.truth.params(),
        sample: a.sample,
        seed: a.truth.seed,
    };
    if let Some(name) = &a.only {
        let Some(d) = datasets.iter().find(|d| &d.name == name) else {
            let names: Vec<&str> = datasets.iter().map(|d| d.name.as_str()).collect();
            anyhow::bail!(
                "--only {name:?}: no such dataset; the suite's datasets are {}",
                names.join(", ")
            );
        };
        let old = std::fs::read_to_string(&a.output).with_context(|| {
            format!(
                "--only keeps the rest of {}, which must exist (run `vocc results` without --only first)",
                a.output.display()
            )
        })?;
        let sec = dataset_section(d, &params, &img, &|m| eprintln!("{m}"))?;
        // The introduction (what comes before the first section) is today's.
        let rest = if old.starts_with("## ") {
            &old[..]
        } else {
            old.find("\n## ").map_or("", |i| &old[i + 1..])
        };
        let md = splice_section(&format!("{RESULTS_INTRO}{rest}"), &d.name, &sec);
        write_atomically(&a.output, |w| w.write_all(md.as_bytes()))?;
        eprintln!("wrote the section {name:?} of {}", a.output.display());
        return Ok(());
    }
    let mut md = String::from(RESULTS_INTRO);
    md.push_str(&blocker_share_section(&mesh_datasets)?);
    for d in &datasets {
        let sec = dataset_section(d, &params, &img, &|m| eprintln!("{m}"))?;
        md.push_str(&sec);
    }
    write_atomically(&a.output, |w| w.write_all(md.as_bytes()))?;
    eprintln!("wrote {}", a.output.display());
    Ok(())
}

/// What docs/RESULTS.md says of itself, before its sections.
const RESULTS_INTRO: &str = "# Results\n\nEvery figure here comes from `make eval` (`vocc results`), which bakes the bundled datasets, \
     builds each cell's PVS with the runtime culler from the stored bytes, and compares it with the ground-truth \
     visible set sampled by rays against the original geometry (`src/eval/truth.rs`, which never reads VOs). \
     A false cull is an object of the visible set that the PVS misses; there must be none. \
     One dataset's section can be made again alone (`make eval ONLY=NAME`, `vocc results --only`), \
     so each section names the machine it was measured on. \
     Do not edit this file by hand.\n\n";

/// The name of the whole-city dataset of `vocc results`.
const TOKYO: &str = "Tokyo centre";

/// `doc` with its section `## name` (from that heading to the next `## ` heading, or the end)
/// replaced by `section`; appended at the end when `doc` has no such section.
fn splice_section(doc: &str, name: &str, section: &str) -> String {
    let heading = format!("## {name}\n");
    let start = if doc.starts_with(&heading) {
        Some(0)
    } else {
        doc.find(&format!("\n{heading}")).map(|i| i + 1)
    };
    match start {
        Some(i) => {
            let after = i + heading.len();
            let end = doc[after..]
                .find("\n## ")
                .map_or(doc.len(), |j| after + j + 1);
            format!("{}{}{}", &doc[..i], section, &doc[end..])
        }
        None => {
            let sep = if doc.is_empty() || doc.ends_with('\n') {
                ""
            } else {
                "\n"
            };
            format!("{doc}{sep}{section}")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::splice_section;

    const DOC: &str = "# Results\n\nintro\n\n## Lyon\n\nold Lyon\n### Table\n\n## Den Haag\n\nDH\n";

    #[test]
    fn splice_section_replaces_only_its_own_section() {
        let out = splice_section(DOC, "Lyon", "## Lyon\n\nnew Lyon\n\n");
        assert_eq!(
            out,
            "# Results\n\nintro\n\n## Lyon\n\nnew Lyon\n\n## Den Haag\n\nDH\n"
        );
        // The last section, up to the end of the file.
        let out = splice_section(DOC, "Den Haag", "## Den Haag\n\nnew\n");
        assert_eq!(
            out,
            "# Results\n\nintro\n\n## Lyon\n\nold Lyon\n### Table\n\n## Den Haag\n\nnew\n"
        );
    }

    #[test]
    fn splice_section_appends_a_new_section_and_matches_whole_headings() {
        // "## Den" is not the heading "## Den Haag", and "### Table" is no section.
        let out = splice_section(DOC, "Den", "## Den\n\nx\n");
        assert_eq!(out, format!("{DOC}## Den\n\nx\n"));
        let out = splice_section(DOC, "Table", "## Table\n\ny\n");
        assert_eq!(out, format!("{DOC}## Table\n\ny\n"));
        assert_eq!(
            splice_section("no newline", "A", "## A\n"),
            "no newline\n## A\n"
        );
    }
}
