//! `vocc._vocc`, the native half of the Python package (the Python half, `vocc/__init__.py`,
//! turns its bytes into numpy arrays and gives the public API).
//!
//! Input: scene paths, reader options (a dict with the CLI's reader flags, `read_options`) and
//! bake options (`bake`, `scene_boxes`); store bytes, cell ids, world positions and object boxes
//! through the buffer protocol (`RawStore`, `RawTree`).
//! Output: store and hashes bytes with the bake summary as JSON; frames as dicts; VOs, boxes,
//! their input feature numbers and PVS positions as little-endian bytes for `numpy.frombuffer`;
//! a scene's facts (objects, fingerprint, CRS, skipped features) and their check against a
//! store's scene section (`vocc::scene::check`, as the CLI checks).
//! Invariants:
//! - the bake is `vocc::bake::job::BakeJob`, the CLI's own job, so a bake here gives the bytes
//!   `vocc bake` gives for the same options; scene loading and the bake run with the GIL
//!   released, and progress reaches the Python callback from the calling thread only (the
//!   job's workers only bump a counter);
//! - every library error becomes `VoccError` with the library's message, file errors `OSError`;
//!   nothing panics into Python (a panic would surface as pyo3's `PanicException`);
//! - a store object owns its bytes (`OwnedStore`) and was checked whole once; culling is
//!   `vocc::runtime::culler::pvs`, the engine's own.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use pyo3::buffer::PyBuffer;
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyOSError, PyRuntimeError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use vocc::bake::job::{BakeJob, Progress};
use vocc::bake::merge::{merge, ShardBytes};
use vocc::bake::params::{BakeParams, Reach, Slices};
use vocc::runtime::culler::{pvs, BoxTree, MAX_BOXES};
use vocc::runtime::format::{CellRecord, OwnedStore};
use vocc::scene::check::{self, SceneCheck, SceneFacts};
use vocc::scene::{self, OnBadHeight, ReadOptions};

create_exception!(
    _vocc,
    VoccError,
    PyException,
    "An error of the vocc library: bad input files, options or store bytes. The message is the library's."
);

fn lib_err(e: impl std::fmt::Display) -> PyErr {
    VoccError::new_err(e.to_string())
}

/// The reader options of a dict whose keys are the CLI's reader flags in snake case
/// (`height_attr`, `base_attr`, `levels_attr`, `storey_height`, `lod`, `on_bad_height`,
/// `default_height`, `types`, `min_height_attr`, `min_levels_attr`, `crs`), checked as the CLI
/// checks them; a missing key or None keeps the CLI's default, an unknown key is an error.
fn read_options(d: Option<&Bound<'_, PyDict>>) -> PyResult<ReadOptions> {
    let mut o = ReadOptions::default();
    let Some(d) = d else { return Ok(o) };
    let positive = |k: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(VoccError::new_err(format!(
                "{k} must be a number greater than 0, got {v}"
            )))
        }
    };
    for (k, v) in d.iter() {
        let key: String = k.extract()?;
        if v.is_none() {
            // None: the default; for the two bottom attributes, none read (the CLI's "").
            match key.as_str() {
                "min_height_attr" => o.min_height_attr = None,
                "min_levels_attr" => o.min_levels_attr = None,
                _ => {}
            }
            continue;
        }
        let text = |v: &Bound<'_, PyAny>| -> PyResult<Option<String>> {
            let s: String = v.extract()?;
            Ok(Some(s).filter(|s| !s.is_empty()))
        };
        match key.as_str() {
            "height_attr" => o.height_attr = text(&v)?,
            "base_attr" => o.base_attr = text(&v)?,
            "levels_attr" => o.levels_attr = text(&v)?,
            "lod" => o.lod = text(&v)?,
            "crs" => o.crs = text(&v)?,
            "min_height_attr" => o.min_height_attr = text(&v)?,
            "min_levels_attr" => o.min_levels_attr = text(&v)?,
            "storey_height" => o.storey_height = positive(&key, v.extract()?)?,
            "default_height" => o.default_height = Some(positive(&key, v.extract()?)?),
            "on_bad_height" => {
                let s: String = v.extract()?;
                o.on_bad_height = match s.as_str() {
                    "skip" => OnBadHeight::Skip,
                    "error" => OnBadHeight::Error,
                    _ => {
                        return Err(VoccError::new_err(format!(
                            "on_bad_height must be \"skip\" or \"error\", got {s:?}"
                        )))
                    }
                }
            }
            "types" => {
                let t: Vec<String> = v.extract()?;
                o.types = t.iter().map(|t| t.trim().to_string()).collect();
            }
            _ => return Err(VoccError::new_err(format!("unknown reader option {key:?}"))),
        }
    }
    Ok(o)
}

/// The bake summary as JSON, in `vocc info`'s words for the scene (as `vocc bake --json`):
/// `convex_pieces`, `blocker_objects`, `no_blocker_objects`.
fn summary_json(sum: &vocc::bake::job::BakeSummary) -> Result<String, serde_json::Error> {
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
    serde_json::to_string(&v)
}

fn load(py: Python<'_>, paths: Vec<PathBuf>, opts: ReadOptions) -> PyResult<scene::Scene> {
    if paths.is_empty() {
        return Err(VoccError::new_err("give at least one scene file"));
    }
    py.detach(|| scene::load(&paths, &opts)).map_err(lib_err)
}

fn f64_bytes<'py>(py: Python<'py>, v: impl IntoIterator<Item = f64>) -> Bound<'py, PyBytes> {
    let b: Vec<u8> = v.into_iter().flat_map(f64::to_le_bytes).collect();
    PyBytes::new(py, &b)
}

/// A scene's object boxes and what identifies it: `(boxes, ids, (objects, fingerprint, crs,
/// skipped))`. `boxes` is `6 * n` little-endian f64 (world xmin, ymin, zmin, xmax, ymax, zmax per
/// object, in object order), `ids` `n` little-endian u32 (each object's input feature number,
/// the number `vocc pvs` and `vocc info` give), then the facts a store's scene section is
/// checked against.
#[pyfunction]
#[pyo3(signature = (paths, read=None))]
#[allow(clippy::type_complexity)]
fn scene_boxes<'py>(
    py: Python<'py>,
    paths: Vec<PathBuf>,
    read: Option<&Bound<'py, PyDict>>,
) -> PyResult<(
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    (u64, u64, String, u64),
)> {
    let opts = read_options(read)?;
    let s = load(py, paths, opts)?;
    let o = s.origin;
    let boxes = f64_bytes(
        py,
        s.objects.iter().flat_map(|ob| {
            let (a, b) = (ob.bbox.min + o, ob.bbox.max + o);
            [a.x, a.y, a.z, b.x, b.y, b.z]
        }),
    );
    let ids: Vec<u8> = s
        .objects
        .iter()
        .flat_map(|ob| ob.feature.to_le_bytes())
        .collect();
    let f = SceneFacts::of(&s);
    Ok((
        boxes,
        PyBytes::new(py, &ids),
        (f.objects, f.fingerprint, f.crs, f.skipped),
    ))
}

/// Bakes scene files into a store: `(store bytes, hashes bytes, summary JSON)`. `region` is a
/// world rectangle `(x0, y0, x1, y1)`. `progress`, when given, is called as
/// `progress(done, total)` from the calling thread while the bake runs (with the GIL released
/// between calls); an exception it raises stops further calls and is raised when the bake ends.
#[pyfunction]
#[pyo3(signature = (
    paths, read=None, cell_size=100.0, eye=(1.5, 2.0), slices=None, max_vos=10, region=None,
    threads=None, effort="default", progress=None, reach=None
))]
#[allow(clippy::too_many_arguments)]
fn bake<'py>(
    py: Python<'py>,
    paths: Vec<PathBuf>,
    read: Option<&Bound<'py, PyDict>>,
    cell_size: f64,
    eye: (f64, f64),
    slices: Option<u8>,
    max_vos: usize,
    region: Option<(f64, f64, f64, f64)>,
    threads: Option<usize>,
    effort: &str,
    progress: Option<Py<PyAny>>,
    reach: Option<f64>,
) -> PyResult<(Bound<'py, PyBytes>, Bound<'py, PyBytes>, String)> {
    let opts = read_options(read)?;
    let s = load(py, paths, opts)?;
    let o = s.origin;
    let params = BakeParams {
        cell_size,
        eye,
        slices: slices.map_or(Slices::Auto, Slices::Fixed),
        max_vos,
        region: region.map(|(x0, y0, x1, y1)| [x0 - o.x, y0 - o.y, x1 - o.x, y1 - o.y]),
        ..BakeParams::default()
            .with_effort(effort.parse().map_err(VoccError::new_err)?)
            .with_reach_for(reach.map_or(Reach::Auto, Reach::Metres), &s)
    };
    let mut job = BakeJob::new(&s, params).map_err(lib_err)?;
    if let Some(n) = threads {
        if n == 0 {
            return Err(VoccError::new_err("threads must be at least 1"));
        }
        job = job.threads(n);
    }
    let done = AtomicUsize::new(0);
    let total = AtomicUsize::new(usize::MAX);
    let report = |p: Progress| {
        total.store(p.total, Ordering::Relaxed);
        done.fetch_max(p.done, Ordering::Relaxed);
    };
    let (result, callback_error) = py.detach(|| {
        std::thread::scope(|scope| {
            let worker = scope.spawn(|| job.run(&report));
            let mut last = None;
            let mut callback_error: Option<PyErr> = None;
            let mut call = |finished: bool| {
                let t = total.load(Ordering::Relaxed);
                let d = done.load(Ordering::Relaxed);
                if callback_error.is_some() || t == usize::MAX || last == Some(d) {
                    return;
                }
                last = Some(d);
                Python::attach(|py| {
                    let r = match &progress {
                        Some(cb) => cb.call1(py, (d, t)).map(|_| ()),
                        None => Ok(()),
                    };
                    // Ctrl-C: the job cannot be stopped midway, so it is raised when it ends.
                    if let Err(e) =
                        r.and_then(|()| if finished { Ok(()) } else { py.check_signals() })
                    {
                        callback_error = Some(e);
                    }
                });
            };
            while !worker.is_finished() {
                std::thread::sleep(Duration::from_millis(50));
                call(false);
            }
            let result = worker.join();
            call(true);
            (result, callback_error)
        })
    });
    let out = result
        .map_err(|_| PyRuntimeError::new_err("internal error: the bake panicked"))?
        .map_err(lib_err)?;
    if let Some(e) = callback_error {
        return Err(e);
    }
    let summary = summary_json(&out.summary).map_err(lib_err)?;
    Ok((
        PyBytes::new(py, &out.store),
        PyBytes::new(py, &out.hashes),
        summary,
    ))
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename: the path
/// holds the old file or the new one in full, never a part.
#[pyfunction]
fn write_atomically(py: Python<'_>, path: PathBuf, bytes: &[u8]) -> PyResult<()> {
    let data = bytes.to_vec();
    py.detach(|| write_file(&path, &data))
        .map_err(|e| PyOSError::new_err(format!("cannot write {}: {e}", path.display())))
}

fn write_file(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let name = path
        .file_name()
        .ok_or_else(|| std::io::Error::other("the path has no file name"))?;
    let tmp = path.with_file_name(format!(".{}.tmp", name.to_string_lossy()));
    let r = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if r.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    r
}

/// What `merge_shards` gives: the merged store's bytes, its hashes' bytes, the shard count and
/// the cells taken from each shard.
type MergedShards<'py> = (Bound<'py, PyBytes>, Bound<'py, PyBytes>, u32, Vec<usize>);

/// The shards of one bake merged (`vocc::bake::merge`, as `vocc merge`): `(store bytes, hashes
/// bytes, shard count, cells taken from each shard)`; a broken rule is `VoccError` naming it
/// (shards by their position in the list).
#[pyfunction]
fn merge_shards<'py>(
    py: Python<'py>,
    shards: Vec<(Vec<u8>, Vec<u8>)>,
) -> PyResult<MergedShards<'py>> {
    let given: Vec<ShardBytes> = shards
        .iter()
        .map(|(store, hashes)| ShardBytes { store, hashes })
        .collect();
    let m = py.detach(|| merge(&given)).map_err(lib_err)?;
    Ok((
        PyBytes::new(py, &m.store),
        PyBytes::new(py, &m.hashes.encode()),
        m.count,
        m.cells_from,
    ))
}

/// A store's bytes, checked whole once, and the queries an engine makes.
#[pyclass(frozen)]
struct RawStore {
    owned: OwnedStore<Box<[u8]>>,
}

#[pymethods]
impl RawStore {
    #[new]
    fn new(data: &[u8]) -> PyResult<RawStore> {
        let owned = OwnedStore::parse(Box::<[u8]>::from(data)).map_err(lib_err)?;
        Ok(RawStore { owned })
    }

    fn bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, self.owned.bytes())
    }

    fn frame<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let f = *self.owned.store().frame();
        let d = PyDict::new(py);
        d.set_item("origin", (f.origin[0], f.origin[1], f.origin[2]))?;
        d.set_item("min_x", f.grid.min_x)?;
        d.set_item("min_y", f.grid.min_y)?;
        d.set_item("cell_size", f.grid.cell_size)?;
        d.set_item("nx", f.grid.nx)?;
        d.set_item("ny", f.grid.ny)?;
        d.set_item("quantum", f.quantum)?;
        d.set_item("eye_lo", f.eye_lo)?;
        d.set_item("eye_hi", f.eye_hi)?;
        d.set_item("ground_z0", f.ground_z0)?;
        d.set_item("ground_step", f.ground_step)?;
        d.set_item("h0", f.h0)?;
        d.set_item("h_ratio", f.h_ratio)?;
        Ok(d)
    }

    fn cell_count(&self) -> u32 {
        self.owned.store().cell_count()
    }

    /// `(major, minor)`: 2.0, or 1.x for a store written before 2.0 (read all the same).
    fn version(&self) -> (u16, u16) {
        self.owned.store().version()
    }

    /// The scene section `(objects, scene fingerprint, CRS name)`: `(0, 0, "")` when not
    /// recorded (every 1.0 store).
    fn scene(&self) -> (u32, u64, String) {
        let s = self.owned.store().scene_section();
        (s.objects, s.scene, s.crs.to_string())
    }

    /// Checks a scene's facts (`scene_boxes`' last item) against the store's scene section:
    /// `("same", "")`, `("not_recorded", message)` (a 1.0 store: the check could not be made) or
    /// `("differs", message naming what differs and the likely cause)`.
    fn check_scene(
        &self,
        objects: u64,
        fingerprint: u64,
        crs: String,
        skipped: u64,
    ) -> (&'static str, String) {
        let facts = SceneFacts {
            objects,
            fingerprint,
            crs,
            skipped,
        };
        match check::check(&self.owned.store().scene_section(), &facts) {
            SceneCheck::Same => ("same", String::new()),
            SceneCheck::NotRecorded => {
                let (major, minor) = self.owned.store().version();
                (
                    "not_recorded",
                    format!("the store ({major}.{minor}) records no scene, so whether these boxes are of the scene baked could not be checked"),
                )
            }
            SceneCheck::Differs(m) => ("differs", m.to_string()),
        }
    }

    /// The cell holding local position (x, y), or None.
    fn cell_at(&self, x: f64, y: f64) -> Option<u32> {
        self.owned.store().cell_at(x, y)
    }

    /// `(skipped, ground level, VO geometry bytes, VO grid bytes)`: per VO 6 f64 (local ax, ay,
    /// bx, by, bottom, top) and 7 u16 (x1, y1, x2, y2, level, exponent of a, exponent of b).
    fn cell<'py>(
        &self,
        py: Python<'py>,
        id: u32,
    ) -> PyResult<(bool, u8, Bound<'py, PyBytes>, Bound<'py, PyBytes>)> {
        let rec = self.owned.store().cell(id).map_err(lib_err)?;
        let f = *self.owned.store().frame();
        let mut geom = Vec::new();
        let mut grid: Vec<u8> = Vec::new();
        for q in rec.vos() {
            let g = f
                .dequantize(id, rec.stand(), q)
                .ok_or_else(|| VoccError::new_err(format!("cell {id} is outside the grid")))?;
            geom.extend([g.a[0], g.a[1], g.b[0], g.b[1], g.g, g.h]);
            for v in [
                q.a.x,
                q.a.y,
                q.b.x,
                q.b.y,
                q.level as u16,
                q.a.e as u16,
                q.b.e as u16,
            ] {
                grid.extend(v.to_le_bytes());
            }
        }
        Ok((
            matches!(rec, CellRecord::Skipped),
            rec.ground(),
            f64_bytes(py, geom),
            PyBytes::new(py, &grid),
        ))
    }

    /// The PVS of cell `id` over `tree`'s objects: ascending ids as little-endian u32 bytes.
    fn pvs<'py>(&self, py: Python<'py>, id: u32, tree: &RawTree) -> PyResult<Bound<'py, PyBytes>> {
        let rec = self.owned.store().cell(id).map_err(lib_err)?;
        let mut out = Vec::new();
        py.detach(|| pvs(self.owned.store().frame(), id, &rec, &tree.tree, &mut out));
        let b: Vec<u8> = out.iter().flat_map(|v| v.to_le_bytes()).collect();
        Ok(PyBytes::new(py, &b))
    }
}

/// The box hierarchy over object boxes (a buffer of `6 * n` f64, world coordinates), in the
/// local frame of `origin`.
#[pyclass(frozen)]
struct RawTree {
    tree: BoxTree,
}

#[pymethods]
impl RawTree {
    #[new]
    fn new(py: Python<'_>, boxes: PyBuffer<f64>, origin: (f64, f64, f64)) -> PyResult<RawTree> {
        let flat = boxes.to_vec(py)?;
        if flat.len() % 6 != 0 {
            return Err(VoccError::new_err(format!(
                "boxes hold {} numbers, not a multiple of 6",
                flat.len()
            )));
        }
        if flat.len() / 6 > MAX_BOXES {
            return Err(VoccError::new_err(format!(
                "{} boxes: at most {MAX_BOXES}",
                flat.len() / 6
            )));
        }
        let world: Vec<[f64; 6]> = flat
            .chunks_exact(6)
            .map(|c| [c[0], c[1], c[2], c[3], c[4], c[5]])
            .collect();
        let tree = py.detach(|| BoxTree::from_world(&world, [origin.0, origin.1, origin.2]));
        Ok(RawTree { tree })
    }

    fn __len__(&self) -> usize {
        self.tree.len()
    }
}

#[pymodule]
fn _vocc(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("VoccError", m.py().get_type::<VoccError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(scene_boxes, m)?)?;
    m.add_function(wrap_pyfunction!(bake, m)?)?;
    m.add_function(wrap_pyfunction!(write_atomically, m)?)?;
    m.add_function(wrap_pyfunction!(merge_shards, m)?)?;
    m.add_class::<RawStore>()?;
    m.add_class::<RawTree>()?;
    Ok(())
}
