//! `vocc info`: load scene files and report what was read.
//!
//! Input: scene files and reader options. Output: the load report on stdout, as text (the first
//! ten entries of each list) or JSON (all of them). Invariant: reporting only; every figure is
//! the library's (`scene::summary`).

use std::io::Write;
use std::path::PathBuf;

use anyhow::Result;

use vocc::scene::{self, summary};

use crate::args::ReadArgs;

pub fn info(files: &[PathBuf], read: &ReadArgs, json: bool) -> Result<()> {
    let s = scene::load(files, &read.options())?;
    let sum = summary::summarize(&s);
    // What `vocc bake --reach auto` picks for this scene, and from what.
    let path = vocc::bake::reach::mean_free_path(&s);
    let reach = vocc::bake::reach::auto_reach(&s);
    let mut out = std::io::stdout().lock();
    if json {
        let mut v = serde_json::to_value(&sum)?;
        v["free_path_m"] = path.into();
        v["auto_reach_m"] = reach.into();
        serde_json::to_writer_pretty(&mut out, &v)?;
        writeln!(out)?;
    } else {
        print_summary(&mut out, &sum)?;
        if let Some(p) = path {
            writeln!(
                out,
                "sight lines: {p:.0} m between buildings on average; `vocc bake --reach auto` reaches {reach:.0} m past a cell's sides"
            )?;
        }
    }
    Ok(())
}

fn print_summary(out: &mut impl Write, s: &summary::Summary) -> std::io::Result<()> {
    const LIST: usize = 10;
    for f in &s.files {
        write!(
            out,
            "file {} ({}, CRS {}): {} objects, {} skipped",
            f.path,
            f.format,
            f.crs.as_deref().unwrap_or("not stated"),
            f.objects,
            f.skipped
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
        "CRS: {}",
        s.crs.as_deref().unwrap_or("unknown (no input states one)")
    )?;
    for n in &s.notes {
        writeln!(out, "note: {n}")?;
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
        "convex pieces: {} ({:.2} per blocker object), of them {} walls",
        s.convex_pieces,
        s.convex_pieces as f64 / s.blocker_objects.max(1) as f64,
        s.walls
    )?;
    if s.mesh_objects > 0 {
        writeln!(
            out,
            "mesh blockers: {} objects gave solid prisms, {} gave walls",
            s.prism_objects, s.wall_objects
        )?;
    }
    let st = |x: &summary::Stats| {
        format!(
            "min {:.1}, median {:.1}, mean {:.1}, p90 {:.1}, max {:.1}",
            x.min, x.p50, x.mean, x.p90, x.max
        )
    };
    if let Some(t) = &s.terrain {
        for (path, format, n, pixel, nodata) in &t.sources {
            let px = pixel.map_or(String::new(), |(x, y)| {
                format!(", {x} x {y} m pixels, {nodata} without data near the scene")
            });
            writeln!(out, "terrain: {path} ({format}): {n} triangles kept{px}")?;
        }
        writeln!(
            out,
            "terrain: {} triangles, x {:.0}..{:.0}, y {:.0}..{:.0} (local), resolution {:.1} m, z {:.2}..{:.2} m, {:.1}% of the scene covered; {} solid ground blockers, {} building blockers joined with the ground",
            t.triangles, t.extent_min[0], t.extent_max[0], t.extent_min[1], t.extent_max[1], t.resolution, t.z_min, t.z_max, 100.0 * t.scene_covered, t.blockers, t.joined
        )?;
    } else {
        writeln!(out, "terrain: none")?;
    }
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
            // Objects and skips alike by input feature number (the numbers `pvs` prints).
            let obj = format!("#{} ", e.feature);
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
    if !s.height_fallbacks.is_empty() {
        section(
            out,
            "heights from a fallback",
            &s.height_fallbacks_by_source,
            &s.height_fallbacks,
        )?;
    }
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
