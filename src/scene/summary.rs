//! What `vocc info` reports about a loaded scene.
//!
//! Input: a [`Scene`]. Output: a serializable summary: counts of objects, objects that gave
//! blockers and convex pieces; height statistics; every skipped, repaired or blocker-less object
//! with its reason (and counts per reason); extent and origin; stage timings.
//! Invariant: a pure function of the scene; the CLI only formats it.

use std::collections::BTreeMap;

use serde::Serialize;

use super::{Location, Scene, Shape};

/// One terrain source: path, format, triangles kept, DEM pixel size (m), DEM pixels with no
/// data near the scene.
pub type TerrainSourceRow = (String, String, usize, Option<(f64, f64)>, usize);

/// What `vocc info` says of a terrain.
#[derive(Clone, Debug, Serialize)]
pub struct TerrainSummary {
    /// Per source: path, format, triangles kept, DEM pixel size (m), DEM pixels with no data
    /// near the scene.
    pub sources: Vec<TerrainSourceRow>,
    pub triangles: usize,
    /// Local extent of the terrain kept (within `TERRAIN_MARGIN_M` of the objects).
    pub extent_min: [f64; 2],
    pub extent_max: [f64; 2],
    /// Resolution: a typical triangle's side, metres.
    pub resolution: f64,
    /// Height range, metres (local).
    pub z_min: f64,
    pub z_max: f64,
    /// Share of the objects' xy extent the terrain covers (sampled on 64 x 64 points).
    pub scene_covered: f64,
    /// Terrain blockers (solid columns) and building blockers joined with the ground.
    pub blockers: usize,
    pub joined: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub files: Vec<FileSummary>,
    /// The scene's CRS ([`super::Scene::crs`]), as displayed (`EPSG:32635 (projected on load
    /// from EPSG:4326)`); `None`: unknown.
    pub crs: Option<String>,
    /// Its EPSG code, when known.
    pub crs_epsg: Option<u32>,
    /// Warnings about the load ([`super::SceneReport::notes`]).
    pub notes: Vec<String>,
    pub objects: usize,
    /// Objects that gave at least one blocker.
    pub blocker_objects: usize,
    /// Objects that gave none (they stay occludees).
    pub no_blocker_objects: usize,
    /// All blockers: convex pieces (prisms) and walls (segments).
    pub convex_pieces: usize,
    /// Of them, walls (2-vertex blockers, from vertical mesh faces).
    pub walls: usize,
    /// Objects that gave at least one prism (a convex piece of 3 or more vertices), and objects
    /// that gave at least one wall.
    pub prism_objects: usize,
    pub wall_objects: usize,
    /// Footprint objects and mesh objects.
    pub footprint_objects: usize,
    pub mesh_objects: usize,
    /// Total triangle cost of all objects.
    pub triangles: u64,
    /// Object heights (bounding-box top minus bottom), metres.
    pub heights: Stats,
    /// Blocker piece heights (top minus base), metres.
    pub blocker_heights: Stats,
    /// World coordinates of the local origin.
    pub origin: [f64; 3],
    /// Local extent, min and max corners.
    pub extent_min: [f64; 3],
    pub extent_max: [f64; 3],
    pub skipped_by_reason: BTreeMap<String, usize>,
    pub repaired_rings_by_kind: BTreeMap<String, usize>,
    pub repaired_objects: usize,
    pub no_blocker_by_reason: BTreeMap<String, usize>,
    /// Footprints whose height came from a fallback (storeys, `--default-height`), by source.
    pub height_fallbacks_by_source: BTreeMap<String, usize>,
    pub height_fallbacks: Vec<Entry>,
    pub skipped: Vec<Entry>,
    pub repaired: Vec<Entry>,
    pub no_blocker: Vec<Entry>,
    /// The terrain, when the scene has one.
    pub terrain: Option<TerrainSummary>,
    /// Seconds per stage.
    pub timings: Vec<(String, f64)>,
}

#[derive(Clone, Debug, Serialize)]
pub struct FileSummary {
    pub path: String,
    pub format: String,
    pub objects: usize,
    pub skipped: usize,
    /// Other city object types, skipped and counted.
    pub other_types: BTreeMap<String, usize>,
    /// The file's CRS, as the file states it or as detected; `None`: it states none.
    pub crs: Option<String>,
}

/// One reported object.
#[derive(Clone, Debug, Serialize)]
pub struct Entry {
    pub file: String,
    /// Object index, when the object made it into the scene.
    pub object: Option<u32>,
    /// Input feature number ([`super::Object::feature`]), skipped objects included.
    pub feature: u32,
    pub name: String,
    pub location: String,
    pub reason: String,
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct Stats {
    pub count: usize,
    pub min: f64,
    pub p50: f64,
    pub mean: f64,
    pub p90: f64,
    pub max: f64,
}

impl Stats {
    pub fn of(mut v: Vec<f64>) -> Stats {
        if v.is_empty() {
            return Stats::default();
        }
        v.sort_by(f64::total_cmp);
        let q = |f: f64| v[((v.len() - 1) as f64 * f).round() as usize];
        Stats {
            count: v.len(),
            min: v[0],
            p50: q(0.5),
            mean: v.iter().sum::<f64>() / v.len() as f64,
            p90: q(0.9),
            max: v[v.len() - 1],
        }
    }
}

fn loc_str(l: &Location) -> String {
    l.to_string()
}

/// Summarizes a scene.
pub fn summarize(scene: &Scene) -> Summary {
    let file_name = |i: u32| scene.files[i as usize].display().to_string();
    let obj_entry = |idx: u32, reason: String| {
        let o = &scene.objects[idx as usize];
        Entry {
            file: file_name(o.file),
            object: Some(idx),
            feature: o.feature,
            name: o.name.clone(),
            location: loc_str(&o.location),
            reason,
        }
    };
    let mut has_blocker = vec![false; scene.objects.len()];
    let mut has_prism = vec![false; scene.objects.len()];
    let mut has_wall = vec![false; scene.objects.len()];
    for b in &scene.blockers {
        has_blocker[b.object as usize] = true;
        if b.polygon.len() == 2 {
            has_wall[b.object as usize] = true;
        } else {
            has_prism[b.object as usize] = true;
        }
    }
    let count = |v: &[bool]| v.iter().filter(|&&b| b).count();
    let blocker_objects = count(&has_blocker);

    let mut skipped_by_reason = BTreeMap::new();
    let skipped: Vec<Entry> = scene
        .report
        .skipped
        .iter()
        .map(|(fi, s)| {
            *skipped_by_reason.entry(s.reason.label()).or_insert(0) += 1;
            Entry {
                file: file_name(*fi),
                object: None,
                feature: s.feature,
                name: s.name.clone(),
                location: loc_str(&s.location),
                reason: s.reason.to_string(),
            }
        })
        .collect();
    let mut repaired_rings_by_kind = BTreeMap::new();
    let mut repaired = Vec::new();
    for &(idx, poly, ring, kind) in &scene.report.repairs {
        *repaired_rings_by_kind.entry(kind.to_string()).or_insert(0) += 1;
        repaired.push(obj_entry(
            idx,
            format!("polygon {poly} ring {ring}: {kind}"),
        ));
    }
    let mut repaired_ids: Vec<u32> = scene.report.repairs.iter().map(|r| r.0).collect();
    repaired_ids.dedup();
    let mut no_blocker_by_reason = BTreeMap::new();
    let no_blocker: Vec<Entry> = scene
        .report
        .no_blocker
        .iter()
        .map(|(idx, why)| {
            *no_blocker_by_reason.entry(why.label()).or_insert(0) += 1;
            obj_entry(*idx, why.to_string())
        })
        .collect();

    let mut height_fallbacks_by_source = BTreeMap::new();
    let height_fallbacks: Vec<Entry> = scene
        .report
        .height_fallbacks
        .iter()
        .map(|(idx, f)| {
            *height_fallbacks_by_source
                .entry(f.label().to_string())
                .or_insert(0) += 1;
            obj_entry(*idx, f.to_string())
        })
        .collect();

    let ext = scene.extent();
    Summary {
        files: scene
            .report
            .files
            .iter()
            .map(|f| FileSummary {
                path: f.path.display().to_string(),
                format: f.format.to_string(),
                objects: f.objects,
                skipped: f.skipped,
                other_types: f.other_types.clone(),
                crs: f.crs.as_ref().map(|c| c.to_string()),
            })
            .collect(),
        crs: scene.crs().map(|c| c.to_string()),
        crs_epsg: scene.crs().and_then(|c| c.epsg),
        notes: scene.report.notes.clone(),
        objects: scene.objects.len(),
        blocker_objects,
        no_blocker_objects: scene.objects.len() - blocker_objects,
        convex_pieces: scene.blockers.len(),
        walls: scene
            .blockers
            .iter()
            .filter(|b| b.polygon.len() == 2)
            .count(),
        prism_objects: count(&has_prism),
        wall_objects: count(&has_wall),
        footprint_objects: scene
            .objects
            .iter()
            .filter(|o| matches!(o.shape, Shape::Footprint(_)))
            .count(),
        mesh_objects: scene
            .objects
            .iter()
            .filter(|o| matches!(o.shape, Shape::Mesh(_)))
            .count(),
        triangles: scene.objects.iter().map(|o| o.cost).sum(),
        heights: Stats::of(
            scene
                .objects
                .iter()
                .map(|o| o.bbox.max.z - o.bbox.min.z)
                .collect(),
        ),
        blocker_heights: Stats::of(scene.blockers.iter().map(|b| b.top - b.base).collect()),
        origin: scene.origin.to_array(),
        extent_min: ext.min.to_array(),
        extent_max: ext.max.to_array(),
        skipped_by_reason,
        repaired_rings_by_kind,
        repaired_objects: repaired_ids.len(),
        no_blocker_by_reason,
        height_fallbacks_by_source,
        height_fallbacks,
        skipped,
        repaired,
        no_blocker,
        terrain: scene.terrain.as_ref().map(|t| TerrainSummary {
            sources: t
                .sources
                .iter()
                .map(|s| {
                    (
                        s.path.display().to_string(),
                        s.format.to_string(),
                        s.triangles,
                        s.pixel,
                        s.nodata,
                    )
                })
                .collect(),
            triangles: t.triangles.len(),
            extent_min: t.lo.to_array(),
            extent_max: t.hi.to_array(),
            resolution: t.resolution(),
            z_min: t.zmin,
            z_max: t.zmax,
            scene_covered: t.coverage(ext.min.truncate(), ext.max.truncate()),
            blockers: t.blockers.len(),
            joined: t.joined,
        }),
        timings: scene
            .report
            .timings
            .iter()
            .map(|(s, t)| (s.to_string(), *t))
            .collect(),
    }
}
