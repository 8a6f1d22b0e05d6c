//! Loading: files in, a local-frame scene with blockers out.
//!
//! Input: file paths in order (or `(path, bytes)` pairs already in memory: [`load_bytes`]), and
//! reader options. Output: a [`Scene`].
//! Stages, each timed: read (format detection and parsing), localize (one origin for the whole
//! scene: the bounding-box minimum rounded down to 1 km, then subtraction in f64), footprints
//! (ring repair and convex decomposition), meshes (solid extraction).
//! Invariants: object indices follow input order; a failed file fails the whole load (no partial
//! scene); per-object work runs in parallel but results are collected in index order, so the
//! scene is identical for any thread count.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use super::error::{LoadError, LoadErrorKind, Location};
use super::{
    decompose, footprint, json, obj, solid, walls, Aabb3, Blocker, FileRead, FileStats, Footprint,
    NoBlocker, Object, RawObject, ReadOptions, RingRepair, Scene, SceneReport, Shape,
};

/// Size of the grid the scene origin snaps to, metres.
pub const ORIGIN_SNAP_M: f64 = 1000.0;

/// Reads one file, choosing the reader from its extension and content.
pub fn read_file(path: &Path, opts: &ReadOptions) -> Result<(FileRead, &'static str), LoadError> {
    let bytes = std::fs::read(path)
        .map_err(|e| LoadError::new(path, Location::File, LoadErrorKind::Io(e.to_string())))?;
    read_bytes(path, &bytes, opts)
}

/// Reads one file's bytes, choosing the reader from the extension of `path` and the content;
/// `path` is used for that choice and for error messages only (nothing is opened).
pub fn read_bytes(
    path: &Path,
    bytes: &[u8],
    opts: &ReadOptions,
) -> Result<(FileRead, &'static str), LoadError> {
    let err = |location, kind| LoadError::new(path, location, kind);
    if bytes.iter().all(|b| b.is_ascii_whitespace()) {
        return Err(err(Location::File, LoadErrorKind::Empty));
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    if ext == "obj" {
        return Ok((obj::read_obj(path, bytes, opts)?, "OBJ"));
    }
    if !matches!(ext.as_str(), "json" | "geojson" | "cityjson") {
        return Err(err(Location::File, LoadErrorKind::UnknownFormat));
    }
    json::read_json(path, bytes, opts)
}

/// Loads files into one scene.
pub fn load(paths: &[PathBuf], opts: &ReadOptions) -> Result<Scene, LoadError> {
    let t = Instant::now();
    let reads: Vec<(FileRead, &'static str)> = paths
        .par_iter()
        .map(|p| read_file(p, opts))
        .collect::<Result<_, _>>()?;
    build_scene(
        paths.to_vec(),
        reads,
        t.elapsed().as_secs_f64(),
        &opts.types,
    )
}

/// [`load`] from bytes already in memory: `(path, bytes)` per file, in order. Each path chooses
/// the reader by its extension and names the file in errors and in [`Scene::files`]; nothing is
/// opened. The same stages run as in [`load`] (read, localize, footprint repair and convex
/// decomposition, solid extraction).
pub fn load_bytes(files: &[(PathBuf, &[u8])], opts: &ReadOptions) -> Result<Scene, LoadError> {
    let t = Instant::now();
    let reads: Vec<(FileRead, &'static str)> = files
        .par_iter()
        .map(|(p, b)| read_bytes(p, b, opts))
        .collect::<Result<_, _>>()?;
    let paths = files.iter().map(|(p, _)| p.clone()).collect();
    build_scene(paths, reads, t.elapsed().as_secs_f64(), &opts.types)
}

/// Everything after reading: the local frame, then per-object repair, decomposition and solids.
fn build_scene(
    paths: Vec<PathBuf>,
    reads: Vec<(FileRead, &'static str)>,
    read_secs: f64,
    types: &[String],
) -> Result<Scene, LoadError> {
    let mut report = SceneReport::default();
    report.timings.push(("read", read_secs));

    let t = Instant::now();
    let mut raw: Vec<(u32, RawObject)> = Vec::new();
    let mut lods = std::collections::BTreeSet::new();
    // Input feature numbers: each file's items follow the previous files'.
    let mut offset: u32 = 0;
    for (fi, ((mut read, format), path)) in reads.into_iter().zip(&paths).enumerate() {
        for o in &mut read.objects {
            o.feature = o.feature.saturating_add(offset);
        }
        for s in &mut read.skipped {
            s.feature = s.feature.saturating_add(offset);
        }
        offset = offset.saturating_add(read.items.min(u32::MAX as usize) as u32);
        lods.extend(read.lods);
        report.files.push(FileStats {
            path: path.clone(),
            format,
            objects: read.objects.len(),
            skipped: read.skipped.len(),
            other_types: read.other_types,
        });
        report
            .skipped
            .extend(read.skipped.into_iter().map(|s| (fi as u32, s)));
        let first = raw.len() as u32;
        report.height_fallbacks.extend(
            read.fallbacks
                .into_iter()
                .map(|(k, f)| (first + k as u32, f)),
        );
        raw.extend(read.objects.into_iter().map(|o| (fi as u32, o)));
    }
    if raw.is_empty() {
        let path = paths.first().cloned().unwrap_or_default();
        // Every object skipped for want of the requested LoD: say which LoDs there are.
        let wanted = report.skipped.first().and_then(|(_, s)| match &s.reason {
            super::SkipReason::NoGeometryAtLod(l) => Some(l.clone()),
            _ => None,
        });
        let all_lod = report
            .skipped
            .iter()
            .all(|(_, s)| matches!(s.reason, super::SkipReason::NoGeometryAtLod(_)));
        // CityJSON city objects there are, but none of a type read: say which types there are.
        // (Only types a reader could read: "Building (no geometry)" is a note, not a type.)
        let mut held: std::collections::BTreeMap<String, usize> = Default::default();
        for f in &report.files {
            for (t, n) in &f.other_types {
                *held.entry(t.clone()).or_default() += n;
            }
        }
        let readable = held.keys().any(|t| !t.contains(' '));
        let kind = match wanted {
            Some(lod) if all_lod && !lods.is_empty() => LoadErrorKind::NoObjectsAtLod {
                lod,
                available: lods.into_iter().collect(),
            },
            _ if report.skipped.is_empty() && readable => {
                let mut read = vec!["Building".to_string(), "BuildingPart".to_string()];
                read.extend(types.iter().cloned());
                LoadErrorKind::NoObjectsOfTypes {
                    read,
                    held: held.into_iter().collect(),
                }
            }
            _ => LoadErrorKind::NoObjects,
        };
        return Err(LoadError::new(path, Location::File, kind));
    }
    let world = raw
        .par_iter()
        .map(|(_, o)| shape_bbox(&o.shape))
        .reduce(|| Aabb3::EMPTY, Aabb3::union);
    let origin = (world.min / ORIGIN_SNAP_M).floor() * ORIGIN_SNAP_M;
    raw.par_iter_mut()
        .for_each(|(_, o)| translate(&mut o.shape, -origin));
    let o2 = DVec2::new(origin.x, origin.y);
    for (_, s) in &mut report.skipped {
        for p in s.outline.iter_mut().flatten() {
            *p -= o2;
        }
    }
    report.timings.push(("localize", t.elapsed().as_secs_f64()));

    let t = Instant::now();
    let built: Vec<Built> = raw
        .into_par_iter()
        .enumerate()
        .map(|(i, (file, o))| build_object(i as u32, file, o))
        .collect();
    report
        .timings
        .push(("footprints and meshes", t.elapsed().as_secs_f64()));

    let mut objects = Vec::with_capacity(built.len());
    let mut blockers = Vec::new();
    for b in built {
        let idx = b.object.index;
        report
            .repairs
            .extend(b.repairs.into_iter().map(|(p, r, k)| (idx, p, r, k)));
        report
            .no_blocker
            .extend(b.no_blocker.into_iter().map(|n| (idx, n)));
        blockers.extend(b.blockers);
        objects.push(b.object);
    }
    Ok(Scene {
        origin,
        files: paths,
        objects,
        blockers,
        report,
    })
}

struct Built {
    object: Object,
    blockers: Vec<Blocker>,
    repairs: Vec<(usize, usize, RingRepair)>,
    no_blocker: Vec<NoBlocker>,
}

fn build_object(index: u32, file: u32, raw: RawObject) -> Built {
    let mut repairs = Vec::new();
    let mut no_blocker = Vec::new();
    let mut blockers = Vec::new();
    let shape = match raw.shape {
        Shape::Footprint(fp) => {
            let mut polygons = Vec::with_capacity(fp.polygons.len());
            for (pi, rings) in fp.polygons.into_iter().enumerate() {
                let fixed = footprint::repair_polygon(&rings);
                repairs.extend(fixed.repairs.iter().map(|&(r, k)| (pi, r, k)));
                match fixed.result {
                    Err((ring, why)) => {
                        no_blocker.push(NoBlocker::InvalidRing {
                            polygon: pi,
                            ring,
                            why,
                        });
                        polygons.push(rings);
                    }
                    Ok(valid) => {
                        if fp.top > fp.base {
                            match decompose::convex_pieces(&valid) {
                                Ok(pieces) => {
                                    blockers.extend(pieces.into_iter().map(|polygon| Blocker {
                                        object: index,
                                        polygon,
                                        base: fp.base,
                                        top: fp.top,
                                    }))
                                }
                                Err(e) => no_blocker.push(NoBlocker::Triangulation(e.to_string())),
                            }
                        }
                        polygons.push(valid);
                    }
                }
            }
            if fp.top <= fp.base {
                no_blocker.push(NoBlocker::NoHeight);
            }
            Shape::Footprint(Footprint {
                polygons,
                base: fp.base,
                top: fp.top,
            })
        }
        Shape::Mesh(mesh) => {
            // Solid prisms where the mesh is closed, walls from its vertical faces in any case.
            let solid = solid::solid_pieces(&mesh);
            if let Ok(pieces) = &solid {
                blockers.extend(pieces.iter().map(|p| Blocker {
                    object: index,
                    polygon: p.polygon.clone(),
                    base: p.base,
                    top: p.top,
                }));
            }
            blockers.extend(walls::wall_pieces(&mesh).into_iter().map(|w| Blocker {
                object: index,
                polygon: vec![w.a, w.b],
                base: w.base,
                top: w.top,
            }));
            if blockers.is_empty() {
                no_blocker.push(match solid {
                    Err(why) => why,
                    Ok(_) => NoBlocker::NoProvableInterior,
                });
            }
            Shape::Mesh(mesh)
        }
    };
    Built {
        object: Object {
            index,
            file,
            feature: raw.feature,
            name: raw.name,
            location: raw.location,
            bbox: shape_bbox(&shape),
            cost: shape_cost(&shape),
            shape,
        },
        blockers,
        repairs,
        no_blocker,
    }
}

/// Bounding box of a shape in its own coordinates.
pub fn shape_bbox(shape: &Shape) -> Aabb3 {
    let mut b = Aabb3::EMPTY;
    match shape {
        Shape::Footprint(fp) => {
            for p in fp.polygons.iter().flatten().flatten() {
                b.include(DVec3::new(p.x, p.y, fp.base));
                b.include(DVec3::new(p.x, p.y, fp.top));
            }
        }
        Shape::Mesh(m) => {
            // Only vertices that faces use: stray vertices are not geometry.
            for f in &m.faces {
                for &i in f.rings.iter().flatten() {
                    if let Some(&v) = m.vertices.get(i as usize) {
                        b.include(v);
                    }
                }
            }
        }
    }
    b
}

/// Triangle count. A polygon with V vertices over all its rings and H holes triangulates into
/// V + 2H - 2 triangles; a footprint prism has two such caps and two triangles per wall edge.
pub fn shape_cost(shape: &Shape) -> u64 {
    let poly = |v: usize, h: usize| (v + 2 * h).saturating_sub(2) as u64;
    match shape {
        Shape::Footprint(fp) => fp
            .polygons
            .iter()
            .map(|rings| {
                let v: usize = rings.iter().map(|r| r.len()).sum();
                let h = rings.len().saturating_sub(1);
                2 * poly(v, h) + 2 * v as u64
            })
            .sum(),
        Shape::Mesh(m) => m
            .faces
            .iter()
            .map(|f| {
                let v: usize = f.rings.iter().map(|r| r.len()).sum();
                poly(v, f.rings.len().saturating_sub(1))
            })
            .sum(),
    }
}

fn translate(shape: &mut Shape, d: DVec3) {
    match shape {
        Shape::Footprint(fp) => {
            let d2 = DVec2::new(d.x, d.y);
            for p in fp.polygons.iter_mut().flatten().flatten() {
                *p += d2;
            }
            fp.base += d.z;
            fp.top += d.z;
        }
        Shape::Mesh(m) => {
            for v in &mut m.vertices {
                *v += d;
            }
        }
    }
}
