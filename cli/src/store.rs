//! `vocc inspect`, `vocc pvs` and `vocc export`: reading a store.
//!
//! Input: a store file (and, for `pvs`, the scene whose objects are the occludees).
//! Output: reports on stdout (text or JSON), or the files `export` is asked for (written
//! atomically). Invariant: everything read from the store goes through the runtime decoder, so
//! these commands see exactly what an engine sees.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use clap::error::ErrorKind;
use clap::Args;
use serde_json::json;

use vocc::runtime::culler::{pvs_with_stats, BoxTree};
use vocc::runtime::format::{encode_blob, encode_frame, CellRecord, Store};
use vocc::runtime::frame::{QPoint, QVo, HEIGHT_LEVELS, HEIGHT_LEVELS_V1};
use vocc::runtime::{CellId, Frame};
use vocc::scene::check::{self, SceneCheck, SceneFacts};
use vocc::scene::{self, Scene};

use crate::args::{ReadArgs, SceneCheckArgs};
use crate::files::{check_output, parse, read_store, write_atomically};
use crate::report::plural;

fn cell_record(store: &Store, id: CellId) -> Result<CellRecord> {
    anyhow::ensure!(
        id < store.cell_count(),
        "cell {id} is outside the grid (cells 0..{})",
        store.cell_count()
    );
    Ok(store.cell(id)?)
}

/// A VO's bytes as the store of major `major` holds them, in hex.
fn vo_hex(q: &QVo, major: u16) -> String {
    let bytes = if major == 1 {
        q.to_bytes_v1().to_vec()
    } else {
        q.to_bytes().to_vec()
    };
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// A stored endpoint's fields, as JSON.
fn point_json(p: &QPoint) -> serde_json::Value {
    json!({"e": p.e, "x": p.x, "y": p.y})
}

/// The VOs of a cell in world coordinates, as JSON, with their stored fields and bytes (as the
/// store of major `major` holds them).
fn vos_json(f: &Frame, id: CellId, rec: &CellRecord, major: u16) -> Vec<serde_json::Value> {
    let o = f.origin;
    rec.vos()
        .iter()
        .filter_map(|q| {
            let g = f.dequantize(id, rec.stand(), q)?;
            Some(json!({
                "a": [g.a[0] + o[0], g.a[1] + o[1]],
                "b": [g.b[0] + o[0], g.b[1] + o[1]],
                "bottom": g.g + o[2],
                "top": g.h + o[2],
                "level": q.level,
                "fields": {"a": point_json(&q.a), "b": point_json(&q.b), "level": q.level},
                "bytes": vo_hex(q, major),
            }))
        })
        .collect()
}

fn cell_json(f: &Frame, id: CellId, rec: &CellRecord, major: u16) -> serde_json::Value {
    let o = f.origin;
    let r = f.grid.cell_rect(id).unwrap_or([0.0; 4]);
    let view = f.cell_view(id, rec.stand());
    json!({
        "cell": id,
        "rect": [r[0] + o[0], r[1] + o[1], r[2] + o[0], r[3] + o[1]],
        "skipped": matches!(rec, CellRecord::Skipped),
        "ground": f.ground_z(rec.ground()) + o[2],
        "eyes": view.map(|v| [v.e0 + o[2], v.e1 + o[2]]),
        "vos": vos_json(f, id, rec, major),
    })
}

/// How `inspect --list-cells` orders its rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SortKey {
    /// Ascending cell id.
    Id,
    /// Most VOs first.
    Vos,
    /// Most bytes first.
    Bytes,
    /// Largest culled share first (needs the scene files).
    Culled,
}

#[derive(Args)]
#[command(after_help = "Examples:
  vocc inspect city.vocc
  vocc inspect city.vocc --cell 57
  vocc inspect city.vocc --list-cells --sort vos --top 20
  vocc inspect city.vocc city.geojson --height-attr height --list-cells --sort culled --json")]
pub struct InspectArgs {
    /// Store file.
    pub store: PathBuf,
    /// The scene files the store was baked from (optional): with --list-cells, each cell's share
    /// of objects culled (checked against the store's scene, as `vocc pvs` does).
    pub scene: Vec<PathBuf>,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub check: SceneCheckArgs,
    /// Show this cell's VOs, in world coordinates.
    #[arg(long, value_name = "ID", conflicts_with = "list_cells")]
    pub cell: Option<u32>,
    /// List every cell: VOs, bytes, ground; with scene files, the objects culled. (`--cells`,
    /// its old spelling, still works.)
    #[arg(long, alias = "cells")]
    pub list_cells: bool,
    /// With --list-cells: the order of the rows.
    #[arg(long, value_enum, default_value = "id", requires = "list_cells")]
    pub sort: SortKey,
    /// With --list-cells: only the first N rows.
    #[arg(long, value_name = "N", value_parser = crate::args::parse_count, requires = "list_cells")]
    pub top: Option<usize>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Checks `scene` against the scene the store at `store_path` was baked from (its scene
/// section): an error naming what differs and the likely cause, or with `--allow-other-scene` a
/// warning; a note when the store records no scene (1.0), so the check could not be made.
pub fn check_scene(
    store: &Store,
    store_path: &Path,
    scene: &Scene,
    args: &SceneCheckArgs,
) -> Result<()> {
    match check::check(&store.scene_section(), &SceneFacts::of(scene)) {
        SceneCheck::Same => Ok(()),
        SceneCheck::NotRecorded => {
            let (major, minor) = store.version();
            eprintln!(
                "note: {} (store {major}.{minor}) records no scene, so whether these files and reader flags are the ones baked could not be checked",
                store_path.display()
            );
            Ok(())
        }
        SceneCheck::Differs(m) if args.allow_other_scene => {
            eprintln!(
                "warning: {}: {m}. Going on (--allow-other-scene): the store's VOs were certified against another scene, so its PVSs are not guaranteed",
                store_path.display()
            );
            Ok(())
        }
        SceneCheck::Differs(m) => anyhow::bail!(
            "{}: {m}. Give the files and reader flags of the bake (or --allow-other-scene to go on anyway)",
            store_path.display()
        ),
    }
}

/// Loads the scene files and checks them against the store's scene ([`check_scene`]).
pub fn load_checked(
    store: &Store,
    store_path: &Path,
    files: &[PathBuf],
    read: &ReadArgs,
    args: &SceneCheckArgs,
) -> Result<Scene> {
    let s = scene::load(files, &read.options())?;
    check_scene(store, store_path, &s, args)?;
    Ok(s)
}

/// The scene's object boxes in the store's local frame, with each object's input feature
/// number (by object index); refused when none of them meets the store's grid (a scene in
/// another coordinate system than the store).
fn scene_boxes_and_features(
    store: &Store,
    store_path: &Path,
    s: &Scene,
) -> Result<(usize, BoxTree, Vec<u32>)> {
    let features: Vec<u32> = s.objects.iter().map(|ob| ob.feature).collect();
    let o = s.origin;
    let world: Vec<[f64; 6]> = s
        .objects
        .iter()
        .map(|ob| {
            let (a, b) = (ob.bbox.min + o, ob.bbox.max + o);
            [a.x, a.y, a.z, b.x, b.y, b.z]
        })
        .collect();
    let f = store.frame();
    let g = &f.grid;
    let (x0, y0) = (g.min_x + f.origin[0], g.min_y + f.origin[1]);
    let (x1, y1) = (
        x0 + g.cell_size * g.nx as f64,
        y0 + g.cell_size * g.ny as f64,
    );
    if !world.is_empty()
        && !world
            .iter()
            .any(|b| b[0] <= x1 && b[3] >= x0 && b[1] <= y1 && b[4] >= y0)
    {
        let e = s.extent();
        anyhow::bail!(
            "no object of the scene meets the grid of {} (x {x0:.0}..{x1:.0}, y {y0:.0}..{y1:.0}, world); the scene lies at x {:.0}..{:.0}, y {:.0}..{:.0}: give the files the store was baked from, in the same coordinate system",
            store_path.display(),
            e.min.x + o.x,
            e.max.x + o.x,
            e.min.y + o.y,
            e.max.y + o.y
        );
    }
    Ok((world.len(), BoxTree::from_world(&world, f.origin), features))
}

/// `inspect --list-cells`: one row per cell.
fn list_cells(a: &InspectArgs, store: &Store) -> Result<()> {
    let f = *store.frame();
    let scene = if a.scene.is_empty() {
        None
    } else {
        let s = load_checked(store, &a.store, &a.scene, &a.read, &a.check)?;
        let (n, tree, _) = scene_boxes_and_features(store, &a.store, &s)?;
        Some((n, tree))
    };
    struct Row {
        id: CellId,
        rec: CellRecord,
        bytes: usize,
        culled: Option<f64>,
    }
    let mut visible = Vec::new();
    let mut rows = Vec::with_capacity(store.cell_count() as usize);
    for id in 0..store.cell_count() {
        let rec = store.cell(id)?;
        let culled = scene.as_ref().map(|(n, tree)| {
            vocc::runtime::culler::pvs(&f, id, &rec, tree, &mut visible);
            1.0 - visible.len() as f64 / (*n).max(1) as f64
        });
        rows.push(Row {
            id,
            rec,
            bytes: store.cell_bytes(id) as usize,
            culled,
        });
    }
    match a.sort {
        SortKey::Id => {}
        SortKey::Vos => rows.sort_by_key(|r| std::cmp::Reverse(r.rec.vos().len())),
        SortKey::Bytes => rows.sort_by_key(|r| std::cmp::Reverse(r.bytes)),
        SortKey::Culled => {
            rows.sort_by(|x, y| y.culled.unwrap_or(0.0).total_cmp(&x.culled.unwrap_or(0.0)))
        }
    }
    rows.truncate(a.top.unwrap_or(usize::MAX));
    let o = f.origin;
    let mut out = std::io::stdout().lock();
    if a.json {
        let v: Vec<serde_json::Value> = rows
            .iter()
            .map(|r| {
                let c = f.grid.cell_rect(r.id).unwrap_or([0.0; 4]);
                json!({
                    "cell": r.id,
                    "rect": [c[0] + o[0], c[1] + o[1], c[2] + o[0], c[3] + o[1]],
                    "skipped": matches!(r.rec, CellRecord::Skipped),
                    "vos": r.rec.vos().len(),
                    "bytes": r.bytes,
                    "ground": f.ground_z(r.rec.ground()) + o[2],
                    "culled": r.culled,
                })
            })
            .collect();
        serde_json::to_writer_pretty(
            &mut out,
            &json!({"file": a.store.display().to_string(), "cells": v}),
        )?;
        writeln!(out)?;
        return Ok(());
    }
    writeln!(
        out,
        "{:>8}  {:>12} {:>12}  {:>3}  {:>5}  {:>8}{}",
        "cell",
        "x (world)",
        "y (world)",
        "VOs",
        "bytes",
        "ground",
        if scene.is_some() { "  culled" } else { "" }
    )?;
    for r in &rows {
        let c = f.grid.cell_rect(r.id).unwrap_or([0.0; 4]);
        let vos = match r.rec {
            CellRecord::Skipped => "-".to_string(),
            _ => r.rec.vos().len().to_string(),
        };
        write!(
            out,
            "{:>8}  {:>12.1} {:>12.1}  {vos:>3}  {:>5}  {:>8.2}",
            r.id,
            c[0] + o[0],
            c[1] + o[1],
            r.bytes,
            f.ground_z(r.rec.ground()) + o[2]
        )?;
        if let Some(k) = r.culled {
            write!(out, "  {:>5.1}%", 100.0 * k)?;
        }
        writeln!(out)?;
    }
    Ok(())
}

pub fn inspect(a: InspectArgs) -> Result<()> {
    // Usage first, before anything is read.
    if a.list_cells && a.sort == SortKey::Culled && a.scene.is_empty() {
        return Err(crate::args::usage(
            "inspect",
            ErrorKind::MissingRequiredArgument,
            "--sort culled needs the scene files after the store",
        ));
    }
    if !a.list_cells && !a.scene.is_empty() {
        return Err(crate::args::usage(
            "inspect",
            ErrorKind::ArgumentConflict,
            "scene files are read only with --list-cells (each cell's share of objects culled)",
        ));
    }
    let path = &a.store;
    let bytes = read_store(path)?;
    let store = parse(path, &bytes)?;
    let f = *store.frame();
    if a.list_cells {
        return list_cells(&a, &store);
    }
    let mut out = std::io::stdout().lock();
    if let Some(id) = a.cell {
        let rec = cell_record(&store, id)?;
        if a.json {
            serde_json::to_writer_pretty(&mut out, &cell_json(&f, id, &rec, store.major()))?;
            writeln!(out)?;
            return Ok(());
        }
        let o = f.origin;
        let r = f.grid.cell_rect(id).unwrap_or([0.0; 4]);
        writeln!(
            out,
            "cell {id}: x {:.1}..{:.1}, y {:.1}..{:.1} (world); {}",
            r[0] + o[0],
            r[2] + o[0],
            r[1] + o[1],
            r[3] + o[1],
            match rec {
                CellRecord::Skipped => "skipped (inside a building), no VOs".to_string(),
                _ => format!(
                    "ground {:.2} m, {}, {} bytes",
                    f.ground_z(rec.ground()) + o[2],
                    plural(rec.vos().len(), "VO", "VOs"),
                    store.cell_bytes(id)
                ),
            }
        )?;
        if let Some(v) = f.cell_view(id, rec.stand()) {
            writeln!(out, "eyes {:.2}..{:.2} m", v.e0 + o[2], v.e1 + o[2])?;
        }
        for (k, q) in rec.vos().iter().enumerate() {
            let Some(g) = f.dequantize(id, rec.stand(), q) else {
                continue;
            };
            writeln!(
                out,
                "  VO {k}: ({:.3}, {:.3}) - ({:.3}, {:.3}), {:.1} m long, {:.2}..{:.2} m, level {}; a (e {}, x {}, y {}), b (e {}, x {}, y {}), bytes {}",
                g.a[0] + o[0],
                g.a[1] + o[1],
                g.b[0] + o[0],
                g.b[1] + o[1],
                (g.b[0] - g.a[0]).hypot(g.b[1] - g.a[1]),
                g.g + o[2],
                g.h + o[2],
                q.level,
                q.a.e,
                q.a.x,
                q.a.y,
                q.b.e,
                q.b.x,
                q.b.y,
                vo_hex(q, store.major())
            )?;
        }
        return Ok(());
    }
    let as_json = a.json;
    let n = store.cell_count();
    let mut hist = [0usize; 11];
    let mut skipped = 0;
    let mut vos = 0;
    for id in 0..n {
        match store.cell(id)? {
            CellRecord::Skipped => skipped += 1,
            r => {
                hist[r.vos().len()] += 1;
                vos += r.vos().len();
            }
        }
    }
    let most = (0..=10).rev().find(|&k| hist[k] > 0).unwrap_or(0);
    let (major, minor) = store.version();
    let levels = if major == 1 {
        HEIGHT_LEVELS_V1
    } else {
        HEIGHT_LEVELS
    };
    let v = json!({
        "file": path.display().to_string(),
        "version": format!("{major}.{minor}"),
        "objects": store.objects(),
        "scene": format!("{:016x}", store.scene()),
        "crs": store.crs(),
        "bytes": bytes.len(),
        "cells": n,
        "bytes_per_cell": bytes.len() as f64 / n.max(1) as f64,
        "skipped_cells": skipped,
        "vos": vos,
        "vos_per_cell": vos as f64 / n.max(1) as f64,
        "max_vos_per_cell": most,
        "cells_by_vo_count": hist,
        "origin": f.origin,
        "grid": {"min_x": f.grid.min_x, "min_y": f.grid.min_y, "cell_size": f.grid.cell_size, "nx": f.grid.nx, "ny": f.grid.ny},
        "quantum_m": f.quantum,
        "eye": [f.eye_lo, f.eye_hi],
        "ground": {"z0": f.ground_z0, "step": f.ground_step},
        "vo_top_levels_above_eye_m": (0..levels).map(|k| f.vo_top(0.0, k)).collect::<Vec<f64>>(),
    });
    if as_json {
        serde_json::to_writer_pretty(&mut out, &v)?;
        writeln!(out)?;
        return Ok(());
    }
    writeln!(
        out,
        "{}: vocc store {major}.{minor}, {} bytes, {} ({:.1} bytes per cell)",
        path.display(),
        bytes.len(),
        plural(n as usize, "cell", "cells"),
        bytes.len() as f64 / n.max(1) as f64
    )?;
    writeln!(
        out,
        "scene: {}; fingerprint {}; CRS {}",
        match store.objects() {
            0 => "object count not recorded".to_string(),
            k => format!("baked for {k} objects"),
        },
        match store.scene() {
            0 => "not recorded".to_string(),
            h => format!("{h:016x}"),
        },
        match store.crs() {
            "" => "unknown".to_string(),
            c => format!("{c:?}"),
        }
    )?;
    writeln!(
        out,
        "grid: {} x {} cells of {} m from local ({}, {}); origin (world) {:.3}, {:.3}, {:.3}",
        f.grid.nx,
        f.grid.ny,
        f.grid.cell_size,
        f.grid.min_x,
        f.grid.min_y,
        f.origin[0],
        f.origin[1],
        f.origin[2]
    )?;
    writeln!(
        out,
        "VOs: {vos} ({:.2} per cell, at most {most}); {} skipped (inside a building)",
        vos as f64 / n.max(1) as f64,
        plural(skipped, "cell", "cells")
    )?;
    let h: Vec<String> = hist
        .iter()
        .enumerate()
        .filter(|(_, &c)| c > 0)
        .map(|(k, c)| format!("{k}: {c}"))
        .collect();
    writeln!(out, "cells by VO count: {}", h.join(", "))?;
    writeln!(
        out,
        "quantization: {} m grid; eyes {}..{} m above the ground; ground {}",
        f.quantum,
        f.eye_lo,
        f.eye_hi,
        if f.per_cell_ground() {
            format!("per cell, {} + k * {} m", f.ground_z0, f.ground_step)
        } else {
            format!("flat at {} m (local)", f.ground_z0)
        }
    )?;
    Ok(())
}

/// Which cell a command is about: `--cell ID`, or `--at X,Y` in world coordinates.
pub fn which_cell(store: &Store, cell: Option<CellId>, at: Option<(f64, f64)>) -> Result<CellId> {
    match (cell, at) {
        (Some(id), _) => {
            anyhow::ensure!(
                id < store.cell_count(),
                "cell {id} is outside the grid (cells 0..{})",
                store.cell_count()
            );
            Ok(id)
        }
        (None, Some((x, y))) => {
            let o = store.frame().origin;
            store
                .cell_at(x - o[0], y - o[1])
                .with_context(|| format!("({x}, {y}) lies outside the store's grid"))
        }
        // The commands require one of the two (clap, or a usage check before any reading).
        (None, None) => anyhow::bail!("give --cell ID or --at X,Y"),
    }
}

/// The cells `vocc pvs` answers for: one (`--cell ID` or `--at X,Y`), or every cell of the
/// store (`--all-cells`).
pub enum Cells {
    One(Option<CellId>, Option<(f64, f64)>),
    All,
}

pub fn pvs(
    path: PathBuf,
    scene_files: Vec<PathBuf>,
    read: &ReadArgs,
    check: &SceneCheckArgs,
    cells: Cells,
    as_json: bool,
) -> Result<()> {
    let bytes = read_store(&path)?;
    let store = parse(&path, &bytes)?;
    let ids: Vec<CellId> = match cells {
        Cells::One(cell, at) => {
            let id = which_cell(&store, cell, at)?;
            store.cell(id)?;
            vec![id]
        }
        Cells::All => (0..store.cell_count()).collect(),
    };
    let s = load_checked(&store, &path, &scene_files, read, check)?;
    let (objects, tree, features) = scene_boxes_and_features(&store, &path, &s)?;
    let mut visible = Vec::new();
    let mut out = std::io::stdout().lock();
    for id in ids {
        let rec = store.cell(id)?;
        let t = Instant::now();
        let st = pvs_with_stats(store.frame(), id, &rec, &tree, &mut visible);
        let us = t.elapsed().as_secs_f64() * 1e6;
        // Input feature numbers, so that an object has the same number whatever was skipped.
        let numbered: Vec<u32> = visible
            .iter()
            .map(|&i| features.get(i as usize).copied().unwrap_or(i))
            .collect();
        if as_json {
            serde_json::to_writer(
                &mut out,
                &json!({"cell": id, "objects": objects, "pvs": numbered}),
            )?;
            writeln!(out)?;
        } else {
            writeln!(
                out,
                "cell {id}: {} of {} objects potentially visible ({:.1}%), {}, built in {us:.0} µs ({} nodes tested)",
                numbered.len(),
                objects,
                100.0 * numbered.len() as f64 / objects.max(1) as f64,
                plural(st.vos, "VO", "VOs"),
                st.nodes_tested
            )?;
        }
    }
    Ok(())
}

pub enum ExportTo {
    Json,
    Obj(PathBuf),
    Blob(PathBuf),
}

/// Where `export --blob FILE` writes the frame: beside it, `FILE.frame`.
pub fn frame_path(blob: &Path) -> PathBuf {
    let mut s = blob.as_os_str().to_owned();
    s.push(".frame");
    PathBuf::from(s)
}

pub fn export(path: PathBuf, id: CellId, to: ExportTo) -> Result<()> {
    match &to {
        ExportTo::Json => {}
        ExportTo::Obj(f) => check_output(f, &[&path])?,
        ExportTo::Blob(f) => {
            check_output(f, &[&path])?;
            check_output(&frame_path(f), &[&path])?;
        }
    }
    let bytes = read_store(&path)?;
    let store = parse(&path, &bytes)?;
    let rec = cell_record(&store, id)?;
    let f = *store.frame();
    match to {
        ExportTo::Json => {
            let mut out = std::io::stdout().lock();
            serde_json::to_writer_pretty(&mut out, &cell_json(&f, id, &rec, store.major()))?;
            writeln!(out)?;
        }
        ExportTo::Obj(file) => {
            let o = f.origin;
            write_atomically(&file, |w| {
                writeln!(
                    w,
                    "# vocc: the virtual occluders of cell {id}, world coordinates"
                )?;
                let mut v = 0;
                for (k, q) in rec.vos().iter().enumerate() {
                    let Some(g) = f.dequantize(id, rec.stand(), q) else {
                        continue;
                    };
                    writeln!(w, "o vo_{k}")?;
                    for (p, z) in [(g.a, g.g), (g.b, g.g), (g.b, g.h), (g.a, g.h)] {
                        writeln!(w, "v {} {} {}", p[0] + o[0], p[1] + o[1], z + o[2])?;
                    }
                    writeln!(w, "f {} {} {} {}", v + 1, v + 2, v + 3, v + 4)?;
                    v += 4;
                }
                Ok(())
            })?;
            eprintln!("wrote {} VO quads to {}", rec.vos().len(), file.display());
        }
        ExportTo::Blob(file) => {
            let blob = encode_blob(&f, id, &rec)?;
            write_atomically(&file, |w| w.write_all(&blob))?;
            // The frame an engine needs beside its blobs, once per store.
            let frame_file = frame_path(&file);
            write_atomically(&frame_file, |w| w.write_all(&encode_frame(&f)))?;
            eprintln!(
                "wrote cell {id} ({}) as a {}-byte blob to {}, and the {}-byte frame it decodes with to {}",
                plural(rec.vos().len(), "VO", "VOs"),
                blob.len(),
                file.display(),
                encode_frame(&f).len(),
                frame_file.display()
            );
        }
    }
    Ok(())
}
