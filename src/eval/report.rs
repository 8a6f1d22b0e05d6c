//! Reports: the evaluation of one store (`vocc eval`), and the results suite behind
//! `docs/RESULTS.md` (`make eval`): per dataset, the default bake against the ground truth, the
//! no-fusion baseline, sweeps over VOs per cell, slices, quantization and cell size, with plots.
//!
//! Input: scenes, bake parameters, sampling parameters. Output: Markdown and SVG files.
//! Invariants: every figure in a report is computed by the run that writes it (never edited by
//! hand); each table names the command and the machine; cells sampled with a fixed seed.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;

use crate::bake::job::{BakeJob, JobError};
use crate::bake::params::{BakeParams, Effort, Generator, Slices};
use crate::bake::plan::{CellBake, Plan};
use crate::runtime::culler::BoxTree;
use crate::runtime::format::{encode_store, CellRecord, Store};
use crate::runtime::CellId;
use crate::scene::{self, ReadOptions, Scene};

use super::bound::{
    ceiling_2d, ceiling_sliced, hidden_2d, BoundParams, CeilingParams, Heights, SLICES_ABOVE_EYE_M,
};
use super::metrics::{
    cell_vs, compare, eval_cell, object_boxes, percentile, pvs_from_geoms, sample_cells, summarize,
    vo_rays_all, CellEval, Summary, VoRays,
};
use super::plot::{cell_map, chart, Series};
use super::raycast::Caster;
use super::truth::TruthParams;

/// A description of the machine: CPU model and core count.
pub fn machine() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{model}, {cores} cores")
}

/// A baked store and what baking it took.
pub struct Baked {
    pub bytes: Vec<u8>,
    pub cells: Vec<CellBake>,
    pub seconds: f64,
}

/// Bakes `cells` (all of the plan's when `None`) into a store, on the current rayon pool
/// ([`BakeJob`]). Refused parameters, cells outside the grid and a failed bake are the job's
/// typed [`JobError`].
pub fn bake(
    scene: &Scene,
    params: BakeParams,
    cells: Option<&[CellId]>,
) -> Result<Baked, JobError> {
    let mut job = BakeJob::new(scene, params)?;
    if let Some(ids) = cells {
        job = job.cells(ids)?;
    }
    let out = job.run(&|_| {})?;
    Ok(Baked {
        bytes: out.store,
        cells: out.cells,
        seconds: out.summary.timings.bake_s,
    })
}

/// Why a dataset's section of the results could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error(transparent)]
    Load(#[from] scene::LoadError),
    #[error(transparent)]
    Bake(#[from] JobError),
}

/// Per-cell bake times, ms: (median, p95).
pub fn bake_ms(cells: &[CellBake]) -> (f64, f64) {
    let ms: Vec<f64> = cells.iter().map(|c| c.stats.ms).collect();
    (percentile(&ms, 0.5), percentile(&ms, 0.95))
}

/// Evaluates `ids` of a store given their visible sets.
/// The 2.5D ceiling of each cell `ids[k]` ([`ceiling_sliced`] with `params`), at the heights
/// `store` declares for it, compared with its visible set `vs[k]`: what ideal VOs could cull,
/// as the bake's cells are evaluated (an estimate, never a PVS to use).
pub fn sliced_ceiling_cells(
    s: &Scene,
    store: &Store,
    ids: &[CellId],
    vs: &[Vec<u32>],
    params: &CeilingParams,
) -> Vec<CellEval> {
    ids.iter()
        .zip(vs)
        .map(|(&id, vs)| {
            let f = store.frame();
            let r = f.grid.cell_rect(id).expect("in grid");
            let ground = store.cell(id).map_or(Default::default(), |c| c.stand());
            let view = f.cell_view(id, ground).expect("in grid");
            let h = Heights {
                g: f.ground_z(ground.level),
                e0: view.e0,
                e1: view.e1,
            };
            let c = ceiling_sliced(s, r, h, params);
            let pvs: Vec<u32> = (0..s.objects.len() as u32)
                .filter(|i| c.culled.binary_search(i).is_err())
                .collect();
            compare(s, id, c.vos.len(), vs, &pvs)
        })
        .collect()
}

pub fn eval_cells(
    scene: &Scene,
    store: &Store,
    tree: &BoxTree,
    ids: &[CellId],
    vs: &[Vec<u32>],
) -> Vec<CellEval> {
    ids.iter()
        .zip(vs)
        .map(|(&id, v)| eval_cell(scene, store, tree, id, v))
        .collect()
}

/// Visible sets of `ids`, in parallel.
pub fn visible_sets(
    scene: &Scene,
    store: &Store,
    caster: &Caster,
    ids: &[CellId],
    truth: &TruthParams,
) -> Vec<Vec<u32>> {
    ids.par_iter()
        .map(|&id| cell_vs(scene, store, caster, id, truth))
        .collect()
}

/// One dataset of the suite.
pub struct Dataset {
    pub name: String,
    pub files: Vec<PathBuf>,
    pub read: ReadOptions,
    /// The reader flags as a user types them, for the tables' commands.
    pub flags: String,
    /// The cell-size sweep at 50 and 200 m on this many sampled cells, not every cell (a large
    /// scene, whose ground truth at 50 m would take hours); `None`: every cell.
    pub size_sample: Option<usize>,
}

/// Objects that give blockers, per bundled mesh dataset: (objects, with solid prisms, with any
/// blocker, walls). Solid prisms are what closed-mesh extraction proves (`scene/solid.rs`), the
/// only mesh blockers before walls; walls come from vertical faces (`scene/walls.rs`).
pub fn blocker_shares(scene: &Scene) -> (usize, usize, usize, usize) {
    let n = scene.objects.len();
    let (mut prism, mut any) = (vec![false; n], vec![false; n]);
    let mut walls = 0;
    for b in &scene.blockers {
        let o = b.object as usize;
        any[o] = true;
        if b.polygon.len() > 2 {
            prism[o] = true;
        } else {
            walls += 1;
        }
    }
    let count = |v: &[bool]| v.iter().filter(|&&x| x).count();
    (n, count(&prism), count(&any), walls)
}

/// The Markdown table of [`blocker_shares`] for the given mesh datasets (name, files): loads
/// each, so its figures are this run's.
pub fn blocker_share_section(datasets: &[(&str, PathBuf)]) -> Result<String, scene::LoadError> {
    let mut md = String::from(
        "## Mesh objects that give blockers\n\n\
         Per bundled mesh dataset, the share of objects that give blockers: before walls, only \
         the solid prisms proven inside closed meshes (`src/scene/solid.rs`); after, solid prisms \
         or walls from vertical faces (`src/scene/walls.rs`, ARCHITECTURE.md). Command: \
         `vocc info FILE`.\n\n\
         | dataset | objects | with solid prisms (before) | with prisms or walls (after) | walls |\n\
         |---|---|---|---|---|\n",
    );
    for (name, file) in datasets {
        let s = scene::load(std::slice::from_ref(file), &ReadOptions::default())?;
        let (n, prism, any, walls) = blocker_shares(&s);
        let pct = |k: usize| 100.0 * k as f64 / n.max(1) as f64;
        let _ = writeln!(
            md,
            "| {name} (`{}`) | {n} | {prism} ({:.1}%) | {any} ({:.1}%) | {walls} |",
            file.display(),
            pct(prism),
            pct(any)
        );
    }
    md.push('\n');
    Ok(md)
}

/// Sampling of the suite.
pub struct SuiteParams {
    pub truth: TruthParams,
    /// Cells sampled for the sweeps (the default bake is evaluated on every cell).
    pub sample: usize,
    pub seed: u64,
}

fn row(out: &mut String, label: &str, s: &Summary, extra: &str) {
    let _ = writeln!(
        out,
        "| {label} | {} | {} | {:.2} | {:.2} | {:.1}% | {:.1}% | {:.1} | {:.1} |{extra}",
        s.cells,
        s.false_culls,
        s.median_ratio,
        s.median_ratio_triangles,
        100.0 * s.occluded_share,
        100.0 * s.occluded_share_triangles,
        s.mean_vs,
        s.mean_pvs,
    );
}

const HEAD: &str = "| variant | cells | false culls | PVS/VS objects (median) | PVS/VS triangles (median) | objects culled (mean) | triangles culled (mean) | mean VS | mean PVS |";
const RULE: &str = "|---|---|---|---|---|---|---|---|---|";

/// Runs the suite on one dataset; writes plots into `img` and returns its Markdown section.
pub fn dataset_section(
    d: &Dataset,
    p: &SuiteParams,
    img: &Path,
    progress: &dyn Fn(&str),
) -> Result<String, ReportError> {
    let s = scene::load(&d.files, &d.read)?;
    let caster = Caster::new(&s);
    let tree = BoxTree::new(&object_boxes(&s));
    let files: Vec<String> = d.files.iter().map(|f| f.display().to_string()).collect();
    let cmd = format!("vocc bake {} {}", files.join(" "), d.flags);
    let mut md = String::new();
    let _ = writeln!(md, "## {}\n", d.name);
    let _ = writeln!(
        md,
        "{} objects ({} triangles), {} blockers. Ground truth: {} eye points per cell, {} rays aimed at each object from each eye point{}; seed {}.\n",
        s.objects.len(),
        s.objects.iter().map(|o| o.cost).sum::<u64>(),
        s.blockers.len(),
        p.truth.eyes,
        p.truth.samples_per_object,
        p.truth.radius.map_or(String::new(), |r| format!(" (objects within {r} m of the cell)")),
        p.truth.seed
    );

    // The default bake, every cell: `vocc bake`'s defaults, its reach chosen from the scene.
    let defaults = BakeParams::default().with_auto_reach(&s);
    progress(&format!("{}: default bake", d.name));
    let main = bake(&s, defaults.clone(), None)?;
    let store = Store::parse(&main.bytes).expect("valid store");
    let all = sample_cells(&store, None, p.seed);
    progress(&format!("{}: ground truth of {} cells", d.name, all.len()));
    let t = Instant::now();
    let vs_all = visible_sets(&s, &store, &caster, &all, &p.truth);
    let truth_s = t.elapsed().as_secs_f64();
    let ev = eval_cells(&s, &store, &tree, &all, &vs_all);
    let sm = summarize(&s, &ev);
    let (med, p95) = bake_ms(&main.cells);
    let rays = vo_rays_all(&caster, &store, &all, 16, 16, p.seed);
    let nbytes = main.bytes.len() as f64 / store.cell_count().max(1) as f64;

    let _ = writeln!(md, "### Default bake, 100 m cells, every cell\n");
    let _ = writeln!(
        md,
        "Command: `{cmd} -o store.vocc` then `vocc eval store.vocc {} {}`. Machine: {}.\n",
        files.join(" "),
        d.flags,
        machine()
    );
    let _ = writeln!(md, "{HEAD}\n{RULE}");
    row(&mut md, "vocc, 10 VOs", &sm, "");
    let _ = writeln!(
        md,
        "\n3D check of the stored VOs (docs/DESIGN.md 6.2): {} rays from 16 eye points per cell to 16 points of each VO quad; {} reached a VO without meeting the original geometry first.",
        rays.rays, rays.reached
    );
    let _ = writeln!(
        md,
        "\nStore: {:.1} bytes per cell ({} bytes, {:.2} VOs per cell). Bake: {:.1} ms per cell median, {:.1} ms p95, {:.1} s for the whole scene on {} threads. Culler: {:.0} µs median, {:.0} µs p95 per cell entry. Ground truth: {:.1} s.\n",
        nbytes,
        main.bytes.len(),
        sm.mean_vos,
        med,
        p95,
        main.seconds,
        rayon::current_num_threads(),
        sm.median_pvs_us,
        sm.p95_pvs_us,
        truth_s
    );

    let (prop_m, cert_m) = main.cells.iter().fold((0.0, 0.0), |(p, c), b| {
        (p + b.stats.proposed_m, c + b.stats.certified_m)
    });
    let (tried, stored, raised) = main.cells.iter().fold((0, 0, 0), |(t, s, r), b| {
        (
            t + b.stats.tried,
            s + b.stats.tried - b.stats.dropped,
            r + b.stats.raised,
        )
    });
    let _ = writeln!(
        md,
        "Verifier completeness: of {:.1} km of proposals sent to the exact verifier, {:.1} km ({:.1}%) were certified hidden, in pieces of at least 8 m, over {tried} proposals; {stored} VOs were stored after quantization and the check of their stored form, and raised {raised} height levels in all by rule 2 after it.\n",
        prop_m / 1e3,
        cert_m / 1e3,
        100.0 * cert_m / prop_m.max(1e-9)
    );

    // How the visible set grows with the sampling, for the three cells of the sample's start.
    let _ = writeln!(md, "### Ground-truth convergence\n");
    let _ = writeln!(md, "|VS| of three cells as eye points and rays per object grow (the defaults above are 64 x 4). The set only grows with more samples, so it is a lower bound of the true visible set; every object of it must be in the PVS.\n");
    let eyes = [4usize, 16, 64, 256];
    let samples = [1usize, 4];
    let mut head = String::from("| cell |");
    for e in eyes {
        for k in samples {
            let _ = write!(head, " {e} x {k} |");
        }
    }
    let _ = writeln!(
        md,
        "{head}\n|---|{}",
        "---|".repeat(eyes.len() * samples.len())
    );
    for &id in sample_cells(&store, Some(3), p.seed + 1).iter() {
        let rec = store.cell(id).unwrap_or(CellRecord::EMPTY);
        let rect = store.frame().grid.cell_rect(id).unwrap_or([0.0; 4]);
        let v = store.frame().cell_view(id, rec.stand()).expect("in grid");
        let pts =
            super::truth::convergence(&caster, &s, rect, (v.e0, v.e1), &p.truth, &eyes, &samples);
        let cells: Vec<String> = pts.iter().map(|c| c.vs.to_string()).collect();
        let _ = writeln!(md, "| {id} | {} |", cells.join(" | "));
    }
    let _ = writeln!(md);

    // The sample for the sweeps.
    let sample = sample_cells(&store, Some(p.sample), p.seed);
    let pick = |ids: &[CellId]| -> Vec<Vec<u32>> {
        ids.iter()
            .map(|id| vs_all[all.binary_search(id).expect("sampled from all")].clone())
            .collect()
    };
    let vs_sample = pick(&sample);
    // A variant's PVS holds for the eyes its own store declares: where its ground level for a
    // cell differs from the default store's (a cell without VOs stores none, so its ground is
    // level 0), that cell's VS is cast again from the variant's eyes.
    let own_vs = |st: &Store| -> Vec<Vec<u32>> {
        sample
            .par_iter()
            .zip(&vs_sample)
            .map(|(&id, vs)| {
                let ground = |st: &Store| st.cell(id).map(|r| r.stand()).ok();
                if ground(st) == ground(&store) {
                    vs.clone()
                } else {
                    cell_vs(&s, st, &caster, id, &p.truth)
                }
            })
            .collect()
    };

    // Table 1: VOs per cell (prefixes of the stored order).
    let _ = writeln!(
        md,
        "### Occlusion against the number of VOs (the paper's Table 1), every cell\n"
    );
    let _ = writeln!(md, "The first k stored VOs of each cell (the stored order is most effective first). Command as above.\n");
    let _ = writeln!(md, "| VOs | objects culled (mean) |\n|---|---|");
    for (k, o) in sm.occluded_by_vos.iter().enumerate() {
        let _ = writeln!(md, "| {k} | {:.1}% |", 100.0 * o);
    }
    let _ = writeln!(md);
    let vo_plot = chart(
        &format!("{}: occlusion against VOs per cell", d.name),
        "VOs per cell (first k stored)",
        "objects culled, % (mean over cells)",
        &[Series {
            label: "vocc".into(),
            points: sm
                .occluded_by_vos
                .iter()
                .enumerate()
                .map(|(k, o)| (k as f64, 100.0 * o))
                .collect(),
            line: true,
        }],
    );
    let slug = d.name.to_lowercase().replace(' ', "_");
    write_file(&img.join(format!("{slug}_vos.svg")), &vo_plot);
    let _ = writeln!(md, "![occlusion against VOs](img/{slug}_vos.svg)\n");

    // Baseline, quantization off, slices.
    let _ = writeln!(
        md,
        "### Variants on a sample of {} cells (seed {})\n",
        sample.len(),
        p.seed
    );
    let _ = writeln!(md, "Commands: the default bake with `--slices N`; the baseline bakes VOs from single buildings with the growth generator (chains never leave one object: no fusion); `--generator growth` is the generator before 0.2 (aggregate umbrae grown from seeds); `--effort fast|tight` are the default generator at less and more effort; quantization off evaluates each stored VO's unquantized segment by rule 3. The 2D fusion bound is no bake: it counts as culled every object whose sampled footprint points are cut off, in 2D, from {} points of the cell's boundary by the blockers outside the cell, heights ignored; no VO set of the cell can cull an object outside it, and its \"false culls\" are objects seen over roofs, which heights keep VOs from culling (`src/eval/bound.rs`). The ceiling of 10 ideal VOs is no bake either: on lines at 24 directions every 24 m out to 600 m, the runs hidden in 2D from 16 points of the cell's boundary (sampled every 4 m) are candidates, and 10 are picked greedily by the objects whose boxes lie in their 2D umbra, heights ignored (`eval::bound::ceiling_2d`): what the representation could cull if heights cost nothing. The 2.5D ceiling does the same at VO tops of {:?} m above the highest eye, with the blockers that support such a VO on each line by rule 2 (its bound from the line, ARCHITECTURE.md) and rule 3's heights for the objects (`eval::bound::ceiling_sliced`): what 10 VOs could cull once heights count. Bake ms per cell: every row's bake of the sample's cells alone, each seeking its block's far field for itself (a bake of every cell shares a block's far field among its cells, so it costs less per cell: the section above); and a sampled cell shares its group's bytes (`src/bake/share.rs`) only with the group's other sampled cells, so the rows keep about each cell's own cap of VOs (8 on a large flat grid) where a bake of every cell keeps a little more. Every variant is checked against the VS seen from the eyes its own store declares: where its ground level for a cell differs from the default bake's (a cell without VOs stores no ground, level 0), that cell's VS is cast again. Machine: {}.\n", BoundParams::default().cell_points, SLICES_ABOVE_EYE_M, machine());
    let _ = writeln!(md, "{HEAD} bake ms/cell (median) |\n{RULE}---|");
    let mut speed: Vec<(String, f64, f64)> = Vec::new();
    let sample_main: Vec<CellEval> = eval_cells(&s, &store, &tree, &sample, &vs_sample);
    // Timed as every variant is: the sample's cells baked alone, each block's far field sought
    // for them (in the bake of every cell above, a block's far field is shared by all its cells,
    // so its cells cost less each: compare like with like). The same records: a block's far
    // pieces depend on the block alone.
    progress(&format!("{}: default bake of the sample", d.name));
    let main_sample_ms = bake_ms(&bake(&s, defaults.clone(), Some(&sample))?.cells);
    let sm_main = summarize(&s, &sample_main);
    row(
        &mut md,
        "vocc (auto slices, 10 VOs)",
        &sm_main,
        &format!(" {:.1} |", main_sample_ms.0),
    );
    speed.push((
        "default".into(),
        main_sample_ms.0,
        100.0 * sm_main.occluded_share,
    ));

    progress(&format!("{}: no-fusion baseline", d.name));
    let mut bp = BakeParams {
        generator: Generator::Growth,
        ..defaults.clone()
    };
    bp.grow.single_object = true;
    let base = bake(&s, bp, Some(&sample))?;
    let bstore = Store::parse(&base.bytes).expect("valid store");
    let sb = summarize(
        &s,
        &eval_cells(&s, &bstore, &tree, &sample, &own_vs(&bstore)),
    );
    row(
        &mut md,
        "single buildings, no fusion",
        &sb,
        &format!(" {:.1} |", bake_ms(&base.cells).0),
    );

    // The generator before this one, and the effort settings of this one.
    let variants: [(&str, &str, BakeParams); 3] = [
        (
            "growth",
            "growth generator (`--generator growth`, the default before 0.2)",
            BakeParams {
                generator: Generator::Growth,
                ..defaults.clone()
            },
        ),
        (
            "fast",
            "`--effort fast`",
            defaults.clone().with_effort(Effort::Fast),
        ),
        (
            "tight",
            "`--effort tight`",
            defaults.clone().with_effort(Effort::Tight),
        ),
    ];
    for (key, label, params) in variants {
        progress(&format!("{}: {key}", d.name));
        let v = bake(&s, params, Some(&sample))?;
        let st = Store::parse(&v.bytes).expect("valid store");
        let sv = summarize(&s, &eval_cells(&s, &st, &tree, &sample, &own_vs(&st)));
        let ms = bake_ms(&v.cells).0;
        row(&mut md, label, &sv, &format!(" {ms:.1} |"));
        speed.push((key.into(), ms, 100.0 * sv.occluded_share));
    }

    // The 2D fusion bound: what occluders from the blockers outside each cell could cull at
    // most, heights ignored (eval::bound), as a PVS against the same VS.
    progress(&format!("{}: 2D fusion bound", d.name));
    let bound: Vec<CellEval> = sample
        .iter()
        .zip(&vs_sample)
        .map(|(&id, vs)| {
            let r = store.frame().grid.cell_rect(id).expect("in grid");
            let hidden = hidden_2d(&s, r, &BoundParams::default());
            let pvs: Vec<u32> = (0..s.objects.len() as u32)
                .filter(|i| hidden.binary_search(i).is_err())
                .collect();
            compare(&s, id, 0, vs, &pvs)
        })
        .collect();
    let sbound = summarize(&s, &bound);
    row(
        &mut md,
        "2D fusion bound (estimate; not conservative)",
        &sbound,
        " – |",
    );
    // The ceiling of 10 ideal VOs in 2D (eval::bound::ceiling_2d): the best long hidden
    // segments, greedily, heights ignored.
    progress(&format!("{}: ceiling of 10 ideal VOs", d.name));
    let cp = CeilingParams::default();
    let ceiling: Vec<CellEval> = sample
        .iter()
        .zip(&vs_sample)
        .map(|(&id, vs)| {
            let r = store.frame().grid.cell_rect(id).expect("in grid");
            let c = ceiling_2d(&s, r, &cp);
            let pvs: Vec<u32> = (0..s.objects.len() as u32)
                .filter(|i| c.culled.binary_search(i).is_err())
                .collect();
            compare(&s, id, c.vos.len(), vs, &pvs)
        })
        .collect();
    let sceil = summarize(&s, &ceiling);
    row(
        &mut md,
        "ceiling: 10 ideal VOs in 2D (estimate; not conservative)",
        &sceil,
        " – |",
    );
    // The same in 2.5D, sliced (eval::bound::ceiling_sliced), at the heights the default store
    // declares for each cell.
    progress(&format!("{}: ceiling of 10 ideal VOs in 2.5D", d.name));
    let sliced = sliced_ceiling_cells(&s, &store, &sample, &vs_sample, &cp);
    let ssliced = summarize(&s, &sliced);
    row(
        &mut md,
        "ceiling: 10 ideal VOs in 2.5D, sliced (estimate; not conservative)",
        &ssliced,
        " – |",
    );

    // Quantization off.
    let boxes = object_boxes(&s);
    let f = *store.frame();
    let unq: Vec<CellEval> = sample
        .iter()
        .zip(&vs_sample)
        .map(|(&id, vs)| {
            let c = &main.cells[main
                .cells
                .binary_search_by_key(&id, |c| c.id)
                .expect("baked")];
            let rec = store.cell(id).unwrap_or(CellRecord::EMPTY);
            let view = f.cell_view(id, rec.stand()).expect("in grid");
            let pvs = pvs_from_geoms(&view, &c.stats.unquantized, &boxes);
            compare(&s, id, c.stats.unquantized.len(), vs, &pvs)
        })
        .collect();
    row(
        &mut md,
        "quantization off",
        &summarize(&s, &unq),
        &format!(" {:.1} |", main_sample_ms.0),
    );

    let mut slice_pts = Vec::new();
    for n in [1u8, 2, 3, 4, 5, crate::bake::slice::MAX_SLICES as u8] {
        progress(&format!("{}: {n} slices", d.name));
        let v = bake(
            &s,
            BakeParams {
                slices: Slices::Fixed(n),
                ..defaults.clone()
            },
            Some(&sample),
        )?;
        let st = Store::parse(&v.bytes).expect("valid store");
        let sv = summarize(&s, &eval_cells(&s, &st, &tree, &sample, &own_vs(&st)));
        let ms = bake_ms(&v.cells).0;
        row(
            &mut md,
            &format!("{n} slice{}", if n > 1 { "s" } else { "" }),
            &sv,
            &format!(" {ms:.1} |"),
        );
        slice_pts.push((n as f64, 100.0 * sv.occluded_share));
        speed.push((format!("{n} slices"), ms, 100.0 * sv.occluded_share));
    }
    let _ = writeln!(md);

    // Cell sizes.
    match d.size_sample {
        None => {
            let _ = writeln!(md, "### Cell size, every cell\n");
        }
        Some(n) => {
            let _ = writeln!(
                md,
                "### Cell size, every cell at 100 m, a sample of {n} cells (seed {}) at 50 and 200 m\n",
                p.seed
            );
            let _ = writeln!(
                md,
                "At 50 and 200 m the sample's cells are baked alone, each seeking its block's far field for itself, so their bake ms per cell are higher than in a bake of every cell (as at 100 m here), where a block's cells share it.\n"
            );
        }
    }
    let _ = writeln!(
        md,
        "Command: the default bake with `--cell-size 50`, `100`, `200`. Machine: {}.\n",
        machine()
    );
    let _ = writeln!(
        md,
        "{HEAD} bake ms/cell (median) | bytes/cell |\n{RULE}---|---|"
    );
    let mut size_rays: Vec<(f64, VoRays)> = Vec::new();
    for size in [50.0, 100.0, 200.0] {
        progress(&format!("{}: {size} m cells", d.name));
        let params = BakeParams {
            cell_size: size,
            ..defaults.clone()
        };
        let plan = Plan::new(&s, params.clone()).expect("valid");
        // Sample over the grid of this size.
        let empty: Vec<CellRecord> = vec![CellRecord::EMPTY; plan.frame.grid.cell_count() as usize];
        let grid_bytes = encode_store(&plan.frame, &empty).expect("encodes");
        let grid_store = Store::parse(&grid_bytes).expect("valid");
        let ids = if size == 100.0 {
            all.clone()
        } else {
            sample_cells(&grid_store, d.size_sample, p.seed)
        };
        let v = bake(&s, params, Some(&ids))?;
        let st = Store::parse(&v.bytes).expect("valid store");
        let vs = if size == 100.0 {
            vs_all.clone()
        } else {
            visible_sets(&s, &st, &caster, &ids, &p.truth)
        };
        let sv = summarize(&s, &eval_cells(&s, &st, &tree, &ids, &vs));
        // At 100 m this bake is the default bake of every cell above (the same bytes: the bake
        // is deterministic), whose rays were already cast.
        size_rays.push((
            size,
            if size == 100.0 {
                rays
            } else {
                vo_rays_all(&caster, &st, &ids, 16, 16, p.seed)
            },
        ));
        let ms = bake_ms(&v.cells).0;
        // Bytes per baked cell: index byte plus its record.
        let bytes = v
            .cells
            .iter()
            .map(|c| 1.0 + 5.0 * c.record.vos().len() as f64)
            .sum::<f64>()
            / v.cells.len().max(1) as f64;
        row(
            &mut md,
            &format!("{size} m"),
            &sv,
            &format!(" {ms:.1} | {bytes:.1} |"),
        );
        speed.push((format!("{size} m cells"), ms, 100.0 * sv.occluded_share));
    }
    let _ = writeln!(
        md,
        "\n3D check of the stored VOs at each size (docs/DESIGN.md 6.2; 16 eye points per cell to 16 points of each VO quad): {}.",
        size_rays
            .iter()
            .map(|(size, r)| format!(
                "{size} m, {} rays, {} reached a VO without meeting the original geometry first",
                r.rays, r.reached
            ))
            .collect::<Vec<_>>()
            .join("; ")
    );
    let _ = writeln!(md);

    // Plots: speed against error; the cell map.
    let speed_plot = chart(
        &format!("{}: culled share against bake time", d.name),
        "bake ms per cell (median, sample)",
        "objects culled, % (mean over cells)",
        &speed
            .iter()
            .map(|(l, ms, r)| Series {
                label: l.clone(),
                points: vec![(*ms, *r)],
                line: false,
            })
            .collect::<Vec<_>>(),
    );
    write_file(&img.join(format!("{slug}_speed_error.svg")), &speed_plot);
    let slices_plot = chart(
        &format!("{}: occlusion against slices", d.name),
        "slices",
        "objects culled, % (mean, sample)",
        &[Series {
            label: "vocc".into(),
            points: slice_pts,
            line: true,
        }],
    );
    write_file(&img.join(format!("{slug}_slices.svg")), &slices_plot);
    let ratio_of = |id: CellId| {
        all.binary_search(&id)
            .ok()
            .map(|k| ev[k].ratio())
            .filter(|r| r.is_finite())
    };
    let g = store.frame().grid;
    let map = cell_map(
        &format!("{}: PVS/VS per 100 m cell", d.name),
        g.nx,
        g.ny,
        &ratio_of,
        1.0,
        percentile(&ev.iter().map(|e| e.ratio()).collect::<Vec<_>>(), 0.95).max(1.5),
        "PVS/VS",
    );
    write_file(&img.join(format!("{slug}_map.svg")), &map);
    let _ = writeln!(md, "![culled share against bake time](img/{slug}_speed_error.svg)\n\n![occlusion against slices](img/{slug}_slices.svg)\n\n![PVS/VS per cell](img/{slug}_map.svg)\n");
    Ok(md)
}

fn write_file(path: &Path, text: &str) {
    if let Some(d) = path.parent() {
        let _ = std::fs::create_dir_all(d);
    }
    let _ = std::fs::write(path, text);
}

/// Markdown for `vocc eval`: the summary, the VO sweep and the worst cells.
pub fn eval_markdown(
    title: &str,
    s: &Summary,
    cells: &[CellEval],
    truth: &TruthParams,
    command: &str,
) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# {title}\n");
    let _ = writeln!(md, "Command: `{command}`. Machine: {}. Ground truth: {} eye points per cell, {} rays aimed at each object per eye point, seed {}.\n", machine(), truth.eyes, truth.samples_per_object, truth.seed);
    let _ = writeln!(md, "{HEAD}\n{RULE}");
    row(&mut md, "store", s, "");
    let _ = writeln!(
        md,
        "\nCuller: {:.0} µs median, {:.0} µs p95 per cell entry; {:.2} VOs per cell.\n",
        s.median_pvs_us, s.p95_pvs_us, s.mean_vos
    );
    let _ = writeln!(md, "| VOs | objects culled (mean) |\n|---|---|");
    for (k, o) in s.occluded_by_vos.iter().enumerate() {
        let _ = writeln!(md, "| {k} | {:.1}% |", 100.0 * o);
    }
    let mut worst: Vec<&CellEval> = cells.iter().collect();
    worst.sort_by(|a, b| b.ratio().total_cmp(&a.ratio()));
    let _ = writeln!(
        md,
        "\nLoosest cells:\n\n| cell | VOs | VS | PVS | PVS/VS |\n|---|---|---|---|---|"
    );
    for c in worst.iter().take(10) {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {:.2} |",
            c.cell,
            c.vos,
            c.vs,
            c.pvs,
            c.ratio()
        );
    }
    if s.false_culls > 0 {
        let _ = writeln!(
            md,
            "\n**FALSE CULLS: {}** (cells: {:?})",
            s.false_culls,
            cells
                .iter()
                .filter(|c| !c.false_culls.is_empty())
                .map(|c| c.cell)
                .collect::<Vec<_>>()
        );
    }
    md
}
