//! Loading: files in, a local-frame scene with blockers out.
//!
//! Input: file paths in order (or `(path, bytes)` pairs already in memory: [`load_bytes`]), and
//! reader options. Output: a [`Scene`].
//! Stages, each timed: read (format detection and parsing), localize (the CRS of each file and
//! of the scene, projection of input in another CRS or in longitude/latitude ([`super::crs`]),
//! then one origin for the whole scene: the bounding-box minimum rounded down to 1 km, then
//! subtraction in f64), footprints (ring repair and convex decomposition), meshes (solid
//! extraction). The localize stage's CRS rules are in [`localize`], the per-object build in
//! [`build`]; this file detects formats, reads, and puts the scene together.
//! Formats, by extension (then content): `.geojson`, `.json` (GeoJSON, CityJSON, or CityJSONSeq
//! when its first line is a CityJSON header), `.city.jsonl`/`.jsonl` (CityJSONSeq), `.gml`/`.xml`
//! (CityGML 2.0), `.osm.pbf`/`.pbf` (OpenStreetMap), `.gpkg` (GeoPackage), `.fgb` (FlatGeobuf),
//! `.shp` (Shapefile, with the `.dbf` and `.prj` beside it), `.obj`. Formats vocc does not read
//! (`.dxf`, `.kml`, `.ifc`, `.las`, ...) are refused with a tool that converts them.
//! The same file given twice is refused; reader flags no input uses are noted in the report.
//! Invariants: object indices follow input order; a failed file fails the whole load (no partial
//! scene); per-object work runs in parallel but results are collected in index order, so the
//! scene is identical for any thread count.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use super::crs::{self, Crs, CrsSource, Projector};
use super::error::{check_coord, CrsConflict, LoadError, LoadErrorKind, Location};
use super::{
    citygml, decompose, dem, fgb, footprint, gpkg, json, obj, osm, shp, solid, terrain, walls,
    Aabb3, Blocker, FileRead, FileStats, Footprint, NoBlocker, Object, RawObject, ReadOptions,
    RingRepair, Scene, SceneReport, Shape, SkipReason, Terrain, TerrainSource,
};

mod build;
mod localize;

use build::{build_object, translate, Built};
pub use build::{shape_bbox, shape_cost};
use localize::resolve_crs;

/// Size of the grid the scene origin snaps to, metres.
pub const ORIGIN_SNAP_M: f64 = 1000.0;

/// Reads one file, choosing the reader from its extension and content.
pub fn read_file(path: &Path, opts: &ReadOptions) -> Result<(FileRead, &'static str), LoadError> {
    let io = |p: &Path, e: std::io::Error| {
        LoadError::new(p, Location::File, LoadErrorKind::Io(e.to_string()))
    };
    // Refuse what vocc cannot read before reading it (a point cloud may be large).
    if let Some(e) = unsupported(path) {
        return Err(e);
    }
    let bytes = std::fs::read(path).map_err(|e| io(path, e))?;
    if extension(path) == "shp" && !bytes.iter().all(|b| b.is_ascii_whitespace()) {
        // A Shapefile's attributes and CRS are in the files beside it.
        let dbf = sibling(path, "dbf");
        let dbf = match dbf {
            Some(p) => Some(std::fs::read(&p).map_err(|e| io(&p, e))?),
            None => None,
        };
        let prj = match sibling(path, "prj") {
            Some(p) => Some(std::fs::read(&p).map_err(|e| io(&p, e))?),
            None => None,
        };
        return Ok((
            shp::read_shp(path, &bytes, dbf.as_deref(), prj.as_deref(), opts)?,
            "Shapefile",
        ));
    }
    read_bytes(path, &bytes, opts)
}

/// The file beside `path` with extension `ext` (either case), if it exists.
fn sibling(path: &Path, ext: &str) -> Option<PathBuf> {
    [ext.to_string(), ext.to_ascii_uppercase()]
        .into_iter()
        .map(|e| path.with_extension(e))
        .find(|p| p.is_file())
}

/// The lower-case extension of a path (`pbf` for `x.osm.pbf`).
fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default()
}

/// Formats vocc does not read, with a conversion to one it does.
fn unsupported(path: &Path) -> Option<LoadError> {
    let ext = extension(path);
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| "in".into());
    let (format, hint) = match ext.as_str() {
        "dxf" | "dwg" => (
            "CAD (DXF/DWG)",
            format!("ogr2ogr -f GeoJSON {stem}.geojson {} (DXF; DWG through ODA File Converter to DXF first), or export an OBJ from the CAD program", path.display()),
        ),
        "kml" | "kmz" => (
            "KML",
            format!("ogr2ogr -f GeoJSON {stem}.geojson {} (longitude/latitude, projected by vocc on load)", path.display()),
        ),
        "ifc" => (
            "IFC",
            format!("IfcConvert {} {stem}.obj (IfcOpenShell), or ifc2citygml", path.display()),
        ),
        "las" | "laz" | "e57" | "ply" | "xyz" => (
            "point cloud",
            "derive footprints with heights or LoD2 models first (3dfier, geoflow / 3DBAG's pipeline), then give the GeoJSON, CityJSON or OBJ".to_string(),
        ),
        "osm" | "o5m" => (
            "OpenStreetMap XML",
            format!("osmium cat {} -o {stem}.osm.pbf", path.display()),
        ),
        "gltf" | "glb" | "fbx" | "dae" | "3ds" | "stl" | "3dm" | "skp" | "b3dm" => (
            "mesh",
            format!("assimp export {} {stem}.obj (or Blender: export as OBJ)", path.display()),
        ),
        "dbf" | "shx" | "prj" | "cpg" => (
            "Shapefile part",
            format!("give the .shp: {}", path.with_extension("shp").display()),
        ),
        "tif" | "tiff" | "asc" => (
            "raster",
            "vocc reads buildings, not terrain rasters; give the buildings (GeoJSON, CityJSON, OBJ, ...)".to_string(),
        ),
        "tab" | "mif" | "sqlite" | "gdb" | "zip" => (
            "GIS table",
            format!("ogr2ogr -f GPKG {stem}.gpkg {} (or -f GeoJSON)", path.display()),
        ),
        _ => return None,
    };
    Some(LoadError::new(
        path,
        Location::File,
        LoadErrorKind::UnsupportedFormat {
            format: format.to_string(),
            hint,
        },
    ))
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
    let ext = extension(path);
    match ext.as_str() {
        "obj" => return Ok((obj::read_obj(path, bytes, opts)?, "OBJ")),
        "pbf" => return Ok((osm::read_pbf(path, bytes, opts)?, "OpenStreetMap PBF")),
        "gpkg" => return Ok((gpkg::read_gpkg(path, bytes, opts)?, "GeoPackage")),
        "fgb" => return Ok((fgb::read_fgb(path, bytes, opts)?, "FlatGeobuf")),
        "shp" => return Ok((shp::read_shp(path, bytes, None, None, opts)?, "Shapefile")),
        "gml" | "xml" => return Ok((citygml::read_citygml(path, bytes, opts)?, "CityGML")),
        "jsonl" => return Ok((json::read_cityjson_seq(path, bytes, opts)?, "CityJSONSeq")),
        "json" | "geojson" | "cityjson" => {}
        _ => {
            if let Some(e) = unsupported(path) {
                return Err(e);
            }
            return Err(err(Location::File, LoadErrorKind::UnknownFormat));
        }
    }
    if json::is_cityjson_seq(bytes) {
        return Ok((json::read_cityjson_seq(path, bytes, opts)?, "CityJSONSeq"));
    }
    json::read_json(path, bytes, opts)
}

/// Refuses a file given twice: `keys` identify the files (canonical paths).
fn refuse_duplicates(paths: &[PathBuf], keys: &[PathBuf]) -> Result<(), LoadError> {
    for (i, k) in keys.iter().enumerate() {
        if let Some(j) = keys[..i].iter().position(|o| o == k) {
            return Err(LoadError::new(
                &paths[i],
                Location::File,
                LoadErrorKind::DuplicateFile {
                    first: paths[j].clone(),
                },
            ));
        }
    }
    Ok(())
}

/// Loads files into one scene.
pub fn load(paths: &[PathBuf], opts: &ReadOptions) -> Result<Scene, LoadError> {
    let t = Instant::now();
    let keys: Vec<PathBuf> = paths
        .iter()
        .map(|p| std::fs::canonicalize(p).unwrap_or_else(|_| p.clone()))
        .collect();
    refuse_duplicates(paths, &keys)?;
    let reads: Vec<(FileRead, &'static str)> = paths
        .par_iter()
        .map(|p| read_file(p, opts))
        .collect::<Result<_, _>>()?;
    build_scene(paths.to_vec(), reads, t.elapsed().as_secs_f64(), opts)
}

/// [`load`] from bytes already in memory: `(path, bytes)` per file, in order. Each path chooses
/// the reader by its extension and names the file in errors and in [`Scene::files`]; nothing is
/// opened. The same stages run as in [`load`] (read, localize, footprint repair and convex
/// decomposition, solid extraction).
pub fn load_bytes(files: &[(PathBuf, &[u8])], opts: &ReadOptions) -> Result<Scene, LoadError> {
    let t = Instant::now();
    let names: Vec<PathBuf> = files.iter().map(|(p, _)| p.clone()).collect();
    refuse_duplicates(&names, &names)?;
    let reads: Vec<(FileRead, &'static str)> = files
        .par_iter()
        .map(|(p, b)| read_bytes(p, b, opts))
        .collect::<Result<_, _>>()?;
    let paths = files.iter().map(|(p, _)| p.clone()).collect();
    build_scene(paths, reads, t.elapsed().as_secs_f64(), opts)
}

/// Everything after reading: the local frame, then per-object repair, decomposition and solids.
fn build_scene(
    paths: Vec<PathBuf>,
    reads: Vec<(FileRead, &'static str)>,
    read_secs: f64,
    opts: &ReadOptions,
) -> Result<Scene, LoadError> {
    let types = &opts.types;
    let mut report = SceneReport::default();
    report.timings.push(("read", read_secs));

    let t = Instant::now();
    let mut reads = reads;
    let (scene_crs, file_crs) = resolve_crs(&paths, &mut reads, opts)?;
    report.notes = notes(&paths, &reads, opts);
    let mut raw: Vec<(u32, RawObject)> = Vec::new();
    let mut lods = std::collections::BTreeSet::new();
    // Input feature numbers: each file's items follow the previous files'.
    let mut offset: u32 = 0;
    // CityJSON TINReliefs: (file, triangles), world.
    let mut tins: Vec<(PathBuf, Vec<[DVec3; 3]>)> = Vec::new();
    for (fi, ((mut read, format), path)) in reads.into_iter().zip(&paths).enumerate() {
        if !read.terrain.is_empty() {
            tins.push((path.clone(), std::mem::take(&mut read.terrain)));
        }
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
            crs: file_crs[fi].clone(),
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

    let t = Instant::now();
    let mut terrain = build_terrain(tins, opts, origin, world, scene_crs.as_ref())?;
    report.timings.push(("terrain", t.elapsed().as_secs_f64()));

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
    if let Some(t) = &mut terrain {
        t.join(&mut blockers);
    }
    Ok(Scene {
        origin,
        files: paths,
        objects,
        blockers,
        report,
        crs: scene_crs,
        terrain,
    })
}

/// The scene's terrain: the TINReliefs the scene files hold and the `--terrain` files (GeoTIFF
/// DEMs, OBJ meshes), kept within [`terrain::TERRAIN_MARGIN_M`] of the objects' extent `world`,
/// in the local frame of `origin`. `None` when there is none.
fn build_terrain(
    tins: Vec<(PathBuf, Vec<[DVec3; 3]>)>,
    opts: &ReadOptions,
    origin: DVec3,
    world: Aabb3,
    crs: Option<&Crs>,
) -> Result<Option<Terrain>, LoadError> {
    let m = DVec2::splat(terrain::TERRAIN_MARGIN_M);
    let (lo, hi) = (world.min.truncate() - m, world.max.truncate() + m);
    let keep = |t: &[DVec3; 3]| {
        let (a, b) = (
            t[0].truncate().min(t[1].truncate()).min(t[2].truncate()),
            t[0].truncate().max(t[1].truncate()).max(t[2].truncate()),
        );
        a.x <= hi.x && a.y <= hi.y && b.x >= lo.x && b.y >= lo.y
    };
    let mut sources = Vec::new();
    let mut all: Vec<[DVec3; 3]> = Vec::new();
    let mut add =
        |path: PathBuf, format, tris: Vec<[DVec3; 3]>, pixel, nodata, all: &mut Vec<[DVec3; 3]>| {
            let before = all.len();
            all.extend(tris.into_iter().filter(keep).map(|t| t.map(|p| p - origin)));
            sources.push(TerrainSource {
                path,
                format,
                triangles: all.len() - before,
                pixel,
                nodata,
            });
        };
    for (path, tris) in tins {
        add(path, "CityJSON TINRelief", tris, None, 0, &mut all);
    }
    for path in &opts.terrain {
        let io = |e: std::io::Error| {
            LoadError::new(path, Location::File, LoadErrorKind::Io(e.to_string()))
        };
        let bytes = std::fs::read(path).map_err(io)?;
        match extension(path).as_str() {
            "tif" | "tiff" => {
                let d = dem::read_dem(path, &bytes, Some((lo, hi)))?;
                if let (Some(e), Some(c)) = (d.epsg, crs.and_then(|c| c.epsg)) {
                    if e != c {
                        return Err(LoadError::new(
                            path,
                            Location::File,
                            LoadErrorKind::Malformed {
                                format: "GeoTIFF",
                                message: format!("the DEM is in EPSG:{e} and the scene in EPSG:{c}: reproject the DEM (gdalwarp -t_srs EPSG:{c})"),
                            },
                        ));
                    }
                }
                add(path.clone(), "GeoTIFF DEM", d.triangles, Some(d.pixel), d.nodata, &mut all);
            }
            "obj" => {
                let read = obj::read_obj(path, &bytes, opts)?;
                let mut tris = Vec::new();
                for o in read.objects {
                    if let Shape::Mesh(mesh) = o.shape {
                        tris.extend(terrain::fan_triangles(&mesh));
                    }
                }
                add(path.clone(), "OBJ mesh", tris, None, 0, &mut all);
            }
            _ => {
                return Err(LoadError::new(
                    path,
                    Location::File,
                    LoadErrorKind::UnsupportedFormat {
                        format: "terrain".into(),
                        hint: "--terrain reads GeoTIFF DEMs (.tif) and OBJ meshes (.obj); convert others with gdal_translate -of GTiff".into(),
                    },
                ))
            }
        }
        if all.len() > terrain::MAX_TRIANGLES {
            return Err(LoadError::new(
                path,
                Location::File,
                LoadErrorKind::Malformed {
                    format: "terrain",
                    message: format!(
                        "more than {} triangles near the scene; use a coarser DEM",
                        terrain::MAX_TRIANGLES
                    ),
                },
            ));
        }
    }
    Ok(Terrain::new(sources, all))
}

/// Formats whose footprints take the attribute flags.
const FOOTPRINT_FORMATS: [&str; 4] = ["GeoJSON", "GeoPackage", "FlatGeobuf", "Shapefile"];

/// Notes on the load: many features skipped for want of a height, and reader flags no input
/// uses (each naming the flag and the files).
fn notes(paths: &[PathBuf], reads: &[(FileRead, &'static str)], opts: &ReadOptions) -> Vec<String> {
    let mut notes = Vec::new();
    for ((r, format), path) in reads.iter().zip(paths) {
        let no_height = r
            .skipped
            .iter()
            .filter(|s| {
                matches!(
                    s.reason,
                    SkipReason::NoHeight | SkipReason::BadHeight { .. }
                )
            })
            .count();
        if opts.default_height.is_none()
            && no_height > 0
            && (no_height >= 10 || no_height * 10 >= r.items)
        {
            let flags = if *format == "OpenStreetMap PBF" {
                "no height, building:levels or usable value"
            } else {
                "no usable height or storey count"
            };
            notes.push(format!(
                "{}: {no_height} of {} {format} features skipped for want of a height ({flags}); --default-height M reads them at M metres",
                path.display(),
                r.items
            ));
        }
    }
    let names = |pred: &dyn Fn(&str) -> bool| -> Vec<String> {
        reads
            .iter()
            .zip(paths)
            .filter(|((_, f), _)| pred(f))
            .map(|(_, p)| p.display().to_string())
            .collect()
    };
    let all = names(&|_| true).join(", ");
    let footprint = !names(&|f| FOOTPRINT_FORMATS.contains(&f)).is_empty();
    let osm = !names(&|f| f == "OpenStreetMap PBF").is_empty();
    let lod = !names(&|f| matches!(f, "CityJSON" | "CityJSONSeq" | "CityGML")).is_empty();
    let types = !names(&|f| matches!(f, "CityJSON" | "CityJSONSeq")).is_empty();
    let mut unused = |flag: &str, given: bool, used: bool, applies: &str| {
        if given && !used {
            notes.push(format!(
                "{flag} applies to {applies}, and no input is one ({all}): it was not used"
            ));
        }
    };
    let fp = "GeoJSON, GeoPackage, FlatGeobuf and Shapefile footprints";
    unused("--height-attr", opts.height_attr.is_some(), footprint, fp);
    unused("--base-attr", opts.base_attr.is_some(), footprint, fp);
    unused("--levels-attr", opts.levels_attr.is_some(), footprint, fp);
    unused(
        "--default-height",
        opts.default_height.is_some(),
        footprint || osm,
        "footprints and OpenStreetMap buildings",
    );
    unused(
        "--lod",
        opts.lod.is_some(),
        lod,
        "CityJSON, CityJSONSeq and CityGML",
    );
    unused(
        "--types",
        !opts.types.is_empty(),
        types,
        "CityJSON and CityJSONSeq",
    );
    notes
}
