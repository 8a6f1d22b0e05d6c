//! What a bake's grid costs, checked before anything is allocated, and why a grid is too large.
//!
//! Input: a [`Scene`] and the grid a bake would lay over it (cells per axis, cell size).
//! Output: `Ok` when the grid's per-cell tables fit [`MAX_GRID_BYTES`]; else a [`GridTooLarge`]
//! naming the cause a user can act on: two files whose extents do not meet (different coordinate
//! systems), an object far from all the others, or the extent itself (with the smallest cell
//! size that fits).
//! Invariants: the check is arithmetic on the grid's size and allocates nothing per cell; the
//! diagnosis reads object boxes only (O(objects log objects)), so a refusal takes well under a
//! second whatever the grid would have been.

use std::path::PathBuf;

use crate::runtime::format::CellRecord;
use crate::scene::Scene;

/// The most memory the per-cell tables of one bake may take, bytes (2 GiB).
pub const MAX_GRID_BYTES: f64 = 2.0 * 1024.0 * 1024.0 * 1024.0;

/// Memory per grid cell, bytes, when every cell is baked: its record in the job's table, its
/// baked cell ([`super::plan::CellBake`]) and its share of the selection and hash tables
/// (cell id, hash, hash pair), and its index byte in the store.
pub fn bytes_per_cell() -> f64 {
    (std::mem::size_of::<CellRecord>()
        + std::mem::size_of::<super::plan::CellBake>()
        + 4
        + 8
        + 16
        + 1) as f64
}

/// Why a grid is too large, in terms a user can fix.
#[derive(Clone, Debug, PartialEq)]
pub enum Cause {
    /// Two input files lie apart: most likely in different coordinate systems. Extents are world
    /// rectangles `[x0, y0, x1, y1]`.
    FilesApart {
        a: PathBuf,
        a_extent: [f64; 4],
        b: PathBuf,
        b_extent: [f64; 4],
        gap_m: f64,
    },
    /// An object lies far from all the others (`count` objects lie that far out; this is the
    /// farthest).
    Outlier {
        object: u32,
        name: String,
        file: PathBuf,
        location: String,
        /// World position of its box's centre.
        at: [f64; 2],
        /// Distance from the box of the other objects, metres.
        distance_m: f64,
        /// World rectangle of the other objects.
        others: [f64; 4],
        count: usize,
    },
    /// The scene itself is this large for this cell size.
    Extent {
        width_m: f64,
        height_m: f64,
        /// The smallest cell size whose grid fits, metres.
        min_cell_size: f64,
    },
}

/// A grid refused before allocation.
#[derive(Clone, Debug, PartialEq)]
pub struct GridTooLarge {
    pub nx: u64,
    pub ny: u64,
    pub cell_size: f64,
    /// The memory its tables would take, bytes.
    pub bytes: f64,
    pub cause: Cause,
}

fn km(m: f64) -> String {
    if m >= 10_000.0 {
        format!("{:.0} km", m / 1000.0)
    } else {
        format!("{m:.0} m")
    }
}

/// `v` with two significant digits.
fn two_digits(v: f64) -> String {
    let d = (1.0 - v.abs().max(1e-300).log10().floor()).max(0.0) as usize;
    format!("{v:.d$}")
}

fn rect(r: &[f64; 4]) -> String {
    format!("x {:.0}..{:.0}, y {:.0}..{:.0}", r[0], r[2], r[1], r[3])
}

impl std::fmt::Display for GridTooLarge {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the grid would have {} x {} cells of {} m, whose tables need about {:.1} GB, more than the {:.0} GiB a bake may use: ",
            self.nx,
            self.ny,
            self.cell_size,
            self.bytes / 1e9,
            MAX_GRID_BYTES / (1024.0 * 1024.0 * 1024.0)
        )?;
        match &self.cause {
            Cause::FilesApart {
                a,
                a_extent,
                b,
                b_extent,
                gap_m,
            } => write!(
                f,
                "the extents of {} ({}) and {} ({}) do not meet, they lie {} apart (world coordinates): are the files in the same coordinate system?",
                a.display(),
                rect(a_extent),
                b.display(),
                rect(b_extent),
                km(*gap_m)
            ),
            Cause::Outlier {
                object,
                name,
                file,
                location,
                at,
                distance_m,
                others,
                count,
            } => {
                write!(
                    f,
                    "object #{object} {name:?} ({}, {location}) lies at ({:.0}, {:.0}), {} from the other objects ({})",
                    file.display(),
                    at[0],
                    at[1],
                    km(*distance_m),
                    rect(others)
                )?;
                if *count > 1 {
                    write!(f, "; {} objects lie that far out", count)?;
                }
                write!(f, ": fix or remove it")
            }
            Cause::Extent {
                width_m,
                height_m,
                min_cell_size,
            } => write!(
                f,
                "the scene spans {} x {}; use cells of {} m or more",
                km(*width_m),
                km(*height_m),
                two_digits(*min_cell_size)
            ),
        }
    }
}

/// The memory of a grid of `nx` x `ny` cells, bytes (in f64: no overflow).
pub fn grid_bytes(nx: u64, ny: u64) -> f64 {
    nx as f64 * ny as f64 * bytes_per_cell()
}

/// Cells per axis for a span of `w` metres at cells of `size` (as `Plan::new` lays them out).
fn cells_for(w: f64, size: f64) -> u64 {
    (w / size).floor() as u64 + 1
}

fn fits(w: f64, h: f64, size: f64) -> bool {
    grid_bytes(cells_for(w, size), cells_for(h, size)) <= MAX_GRID_BYTES
}

/// Checks the grid of `nx` x `ny` cells of `cell_size` over `scene`.
pub fn check(scene: &Scene, nx: u64, ny: u64, cell_size: f64) -> Result<(), Box<GridTooLarge>> {
    let bytes = grid_bytes(nx, ny);
    if bytes <= MAX_GRID_BYTES {
        return Ok(());
    }
    Err(Box::new(GridTooLarge {
        nx,
        ny,
        cell_size,
        bytes,
        cause: diagnose(scene, cell_size),
    }))
}

/// A 2D box `[x0, y0, x1, y1]`, local.
type Rect = [f64; 4];

fn union(a: Rect, b: Rect) -> Rect {
    [
        a[0].min(b[0]),
        a[1].min(b[1]),
        a[2].max(b[2]),
        a[3].max(b[3]),
    ]
}

/// Distance between two boxes (0 when they meet).
fn gap(a: &Rect, b: &Rect) -> f64 {
    let dx = (a[0] - b[2]).max(b[0] - a[2]).max(0.0);
    let dy = (a[1] - b[3]).max(b[1] - a[3]).max(0.0);
    dx.hypot(dy)
}

/// Boxes closer than this are taken to belong together, metres.
const NEAR_M: f64 = 1000.0;

/// Why the scene's grid is too large at cells of `size`.
pub fn diagnose(scene: &Scene, size: f64) -> Cause {
    let o = scene.origin;
    let world = |r: Rect| [r[0] + o.x, r[1] + o.y, r[2] + o.x, r[3] + o.y];
    let boxes: Vec<Rect> = scene
        .objects
        .iter()
        .map(|ob| [ob.bbox.min.x, ob.bbox.min.y, ob.bbox.max.x, ob.bbox.max.y])
        .collect();
    let empty = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];

    // Files whose extents lie apart: group the files whose extents come within NEAR_M of each
    // other; two groups mean two places (or two coordinate systems).
    let nf = scene.files.len();
    if nf >= 2 {
        let mut ext = vec![empty; nf];
        for (ob, b) in scene.objects.iter().zip(&boxes) {
            if let Some(e) = ext.get_mut(ob.file as usize) {
                *e = union(*e, *b);
            }
        }
        let used: Vec<usize> = (0..nf).filter(|&i| ext[i][0] <= ext[i][2]).collect();
        let mut group: Vec<usize> = (0..nf).collect();
        let root = |g: &Vec<usize>, mut i: usize| {
            while g[i] != i {
                i = g[i];
            }
            i
        };
        for (k, &i) in used.iter().enumerate() {
            for &j in &used[k + 1..] {
                if gap(&ext[i], &ext[j]) <= NEAR_M {
                    let (ri, rj) = (root(&group, i), root(&group, j));
                    group[ri.max(rj)] = ri.min(rj);
                }
            }
        }
        if let Some(&first) = used.first() {
            let r0 = root(&group, first);
            if let Some(&other) = used.iter().find(|&&j| root(&group, j) != r0) {
                // The extent of the first file's group alone should fit, else the files are not
                // the whole story.
                let g0 = used
                    .iter()
                    .filter(|&&j| root(&group, j) == r0)
                    .fold(empty, |acc, &j| union(acc, ext[j]));
                if fits(g0[2] - g0[0], g0[3] - g0[1], size) {
                    return Cause::FilesApart {
                        a: scene.files[first].clone(),
                        a_extent: world(ext[first]),
                        b: scene.files[other].clone(),
                        b_extent: world(ext[other]),
                        gap_m: gap(&ext[first], &ext[other]),
                    };
                }
            }
        }
    }

    // Outliers: objects far beyond the box of the central 98% of object centres.
    let n = boxes.len();
    if n >= 3 {
        let mut xs: Vec<f64> = boxes.iter().map(|b| 0.5 * (b[0] + b[2])).collect();
        let mut ys: Vec<f64> = boxes.iter().map(|b| 0.5 * (b[1] + b[3])).collect();
        xs.sort_by(f64::total_cmp);
        ys.sort_by(f64::total_cmp);
        let lo = ((n - 1) as f64 * 0.01).floor() as usize;
        let hi = ((n - 1) as f64 * 0.99).ceil() as usize;
        let hi = if hi == n - 1 { n - 2 } else { hi };
        let lo = if lo == 0 { 1.min(hi) } else { lo };
        let core = [xs[lo], ys[lo], xs[hi], ys[hi]];
        let reach = (core[2] - core[0]).max(core[3] - core[1]).max(NEAR_M);
        let far = |b: &Rect| {
            gap(
                b,
                &[
                    core[0] - reach,
                    core[1] - reach,
                    core[2] + reach,
                    core[3] + reach,
                ],
            ) > 0.0
        };
        let others = boxes
            .iter()
            .filter(|b| !far(b))
            .fold(empty, |acc, b| union(acc, *b));
        let out: Vec<usize> = (0..n).filter(|&i| far(&boxes[i])).collect();
        if !out.is_empty()
            && others[0] <= others[2]
            && fits(others[2] - others[0], others[3] - others[1], size)
        {
            let &worst = out
                .iter()
                .max_by(|&&a, &&b| gap(&boxes[a], &others).total_cmp(&gap(&boxes[b], &others)))
                .expect("not empty");
            let ob = &scene.objects[worst];
            let b = boxes[worst];
            return Cause::Outlier {
                object: ob.index,
                name: ob.name.clone(),
                file: scene
                    .files
                    .get(ob.file as usize)
                    .cloned()
                    .unwrap_or_default(),
                location: ob.location.to_string(),
                at: [0.5 * (b[0] + b[2]) + o.x, 0.5 * (b[1] + b[3]) + o.y],
                distance_m: gap(&b, &others),
                others: world(others),
                count: out.len(),
            };
        }
    }

    let all = boxes.iter().fold(empty, |acc, b| union(acc, *b));
    let (w, h) = ((all[2] - all[0]).max(0.0), (all[3] - all[1]).max(0.0));
    // The smallest size that fits, rounded up to two significant digits.
    let mut s = (w * h * bytes_per_cell() / MAX_GRID_BYTES).sqrt().max(size);
    loop {
        let p = 10f64.powf(s.log10().floor() - 1.0);
        let r = (s / p).ceil() * p;
        if fits(w, h, r) {
            break Cause::Extent {
                width_m: w,
                height_m: h,
                min_cell_size: r,
            };
        }
        s = r * 1.01;
    }
}
