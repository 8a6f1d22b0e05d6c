//! `vocc render`: pictures of one cell.
//!
//! Input: a store and its scene files (store mode), or scene files alone (`--debug`). Output: an
//! SVG file, written atomically, and a one-line note on stderr. Invariant: drawing only; the
//! store mode reads the cell as the runtime culler does; the debug mode runs a generator on one
//! cell of the bake's own plan (the long generator's trace, or the growth).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};

use vocc::bake::job::BakeJob;
use vocc::bake::params::{BakeParams, Generator, Reach};
use vocc::runtime::culler::BoxTree;
use vocc::runtime::CellId;
use vocc::scene;

use crate::args::{ReadArgs, SceneCheckArgs};
use crate::files::{check_output, parse, read_store, write_atomically};
use crate::store::{load_checked, which_cell};

/// `vocc render --debug SCENE... --at X,Y`: what a generator does for the cell holding the
/// point, on the bake's own grid and parameters (the bake job's plan, with `cell_size`, `eye`,
/// `reach` and `generator` as `vocc bake` takes them). The long generator (the default): its trace
/// (hidden map, proposals, certified pieces, stored and picked VOs, [`crate::debug_svg`]). The
/// growth: the 2D growth of one slice (`slice`, world metres; default half the median height).
#[allow(clippy::too_many_arguments)]
pub fn render_debug(
    scene_files: &[PathBuf],
    read: &ReadArgs,
    at: (f64, f64),
    cell_size: f64,
    eye: (f64, f64),
    reach: Reach,
    generator: Generator,
    slice: Option<f64>,
    output: &Path,
) -> Result<()> {
    let inputs: Vec<&Path> = scene_files.iter().map(PathBuf::as_path).collect();
    check_output(output, &inputs)?;
    let s = scene::load(scene_files, &read.options())?;
    let params = BakeParams {
        cell_size,
        eye,
        generator,
        ..BakeParams::default().with_reach_for(reach, &s)
    };
    let job = BakeJob::new(&s, params)?;
    let plan = job.plan();
    let local = glam::DVec2::new(at.0 - s.origin.x, at.1 - s.origin.y);
    let id = plan
        .frame
        .grid
        .cell_at(local.x, local.y)
        .with_context(|| format!("({}, {}) lies outside the bake's grid", at.0, at.1))?;
    let cell = plan.cell_polygon(id);
    let t = Instant::now();
    if generator == Generator::Long {
        let Some(trace) = vocc::bake::trace::trace_cell(plan, id) else {
            anyhow::bail!(
                "cell {id}: the long generator has nothing to do there (no eyes, no blocker that may support a VO, or inside a building)"
            );
        };
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let svg = crate::debug_svg::render(&trace);
        write_atomically(output, |w| w.write_all(svg.as_bytes()))?;
        eprintln!(
            "cell {id} at ({:.1}, {:.1}) world: {} slices, {} proposals, {} certified pieces, {} VOs stored, {} picked, {ms:.1} ms; wrote {}",
            cell[0].x + s.origin.x,
            cell[0].y + s.origin.y,
            trace.maps.len(),
            trace.proposals.len(),
            trace.certified.len(),
            trace.stored.len(),
            trace.picked.len(),
            output.display()
        );
        return Ok(());
    }
    let z = match slice {
        Some(z) => z - s.origin.z,
        None => vocc::bake::mid_slice(&s),
    };
    let set = vocc::bake::slice_blockers(&s, z);
    let out = vocc::bake::growth::dense::grow_cell(
        &cell,
        &set,
        &Default::default(),
        vocc::bake::params::SEARCH_M,
    );
    let ms = t.elapsed().as_secs_f64() * 1e3;
    let svg = vocc::bake::growth::svg::render(&cell, &set, &out, 0.1 * cell_size);
    write_atomically(output, |w| w.write_all(svg.as_bytes()))?;
    eprintln!(
        "cell {id} at ({:.1}, {:.1}) world, slice z = {:.1} m: {} blockers in the slice, {} seeds, {} dense VOs, {} rejected by the verifier, {ms:.1} ms; wrote {}",
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

/// `vocc render STORE SCENE... (--cell ID | --at X,Y)`: the cell's top view, with the
/// single-building baseline baked for this one cell to tell fusion's share apart.
pub fn render_store(
    files: Vec<PathBuf>,
    read: &ReadArgs,
    check: &SceneCheckArgs,
    cell: Option<CellId>,
    at: Option<(f64, f64)>,
    radius: f64,
    output: &Path,
) -> Result<()> {
    let (store_path, scene_files) = files
        .split_first()
        .context("give the store, then the scene files")?;
    anyhow::ensure!(
        !scene_files.is_empty(),
        "give the scene files after the store"
    );
    let inputs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    check_output(output, &inputs)?;
    let bytes = read_store(store_path)?;
    let store = parse(store_path, &bytes)?;
    let id = which_cell(&store, cell, at)?;
    let rec = store.cell(id)?;
    let s = load_checked(&store, store_path, scene_files, read, check)?;
    let f = *store.frame();
    anyhow::ensure!(
        f.origin == s.origin.to_array(),
        "the store's origin is not the scene's: give the files the store was baked from"
    );
    let boxes = vocc::eval::metrics::object_boxes(&s);
    let tree = BoxTree::new(&boxes);
    let mut visible = Vec::new();
    vocc::runtime::culler::pvs(&f, id, &rec, &tree, &mut visible);
    // The baseline: this cell baked with single-building chains, same grid and eyes.
    let mut params = vocc::bake::params::BakeParams {
        generator: vocc::bake::params::Generator::Growth,
        cell_size: f.grid.cell_size,
        eye: (f.eye_lo, f.eye_hi),
        ..Default::default()
    };
    params.grow.single_object = true;
    let plan = vocc::bake::plan::Plan::new(&s, params)?;
    let base_rec = plan.bake_cell(id).record;
    let mut base_visible = Vec::new();
    vocc::runtime::culler::pvs(&plan.frame, id, &base_rec, &tree, &mut base_visible);
    let svg =
        vocc::eval::picture::cell_picture(&s, &f, id, &rec, &visible, Some(&base_visible), radius);
    write_atomically(output, |w| w.write_all(svg.as_bytes()))?;
    eprintln!(
        "cell {id}: {}; {} of {} objects potentially visible ({} with single buildings alone); wrote {}",
        crate::report::plural(rec.vos().len(), "VO", "VOs"),
        visible.len(),
        s.objects.len(),
        base_visible.len(),
        output.display()
    );
    Ok(())
}
