//! Scenes: readers, the local frame and the 2.5D blocker model.
//!
//! Input: city model files (GeoJSON, GeoPackage, FlatGeobuf and Shapefile footprints,
//! OpenStreetMap PBF, CityJSON 0.3 to 2.0 and CityJSONSeq, CityGML 2.0, OBJ), in the order given.
//! Output: a [`Scene`] in a local frame: every object with its stable index, name, bounding box
//! and cost, plus the convex 2.5D blockers proven solid, plus a report of what was skipped,
//! repaired or gave no blocker, and why.
//! Invariants:
//! - object indices follow input order across files, then order within each file;
//! - all geometry after ingest is local (`world = local + origin`), origin chosen once in f64;
//! - a blocker is a convex, counter-clockwise polygon with a base and a top, and the prism it
//!   spans is certainly solid: a footprint prism, or space proven inside a closed mesh; or a
//!   wall, a 2-vertex segment whose vertical rectangle from base to top certainly lies in the
//!   faces of a mesh, closed or not ([`walls`]);
//! - nothing here panics on bad input: readers return [`LoadError`].

pub mod attr;
pub mod check;
pub mod citygml;
pub mod cityjson;
pub mod crs;
pub mod decompose;
pub mod dem;
pub mod error;
pub mod fgb;
pub mod fingerprint;
pub mod footprint;
pub mod gencity;
pub mod geojson;
pub mod gpkg;
pub mod json;
pub mod load;
pub mod obj;
pub mod osm;
pub mod shp;
pub mod solid;
pub mod summary;
pub mod terrain;
pub mod walkable;
pub mod walls;
pub mod wkb;

use std::collections::BTreeMap;
use std::fmt;
use std::path::PathBuf;

use glam::{DVec2, DVec3};

pub use crs::{Crs, CrsSource};
pub use error::{CrsConflict, LoadError, LoadErrorKind, Location};
pub use load::{load, load_bytes};
pub use terrain::{Terrain, TerrainSource, TERRAIN_OBJECT};

/// Options shared by the readers.
#[derive(Clone, Debug)]
pub struct ReadOptions {
    /// GeoJSON: attribute holding the building height above its base, metres.
    pub height_attr: Option<String>,
    /// GeoJSON: attribute holding the base elevation, metres. Absent: base 0.
    pub base_attr: Option<String>,
    /// GeoJSON: attribute holding the number of storeys, the fallback for a missing height.
    pub levels_attr: Option<String>,
    /// Metres per storey for the `levels_attr` fallback.
    pub storey_height: f64,
    /// CityJSON: the level of detail to read (as written in the file, e.g. "2" or "2.2").
    /// `None` takes the highest one each object has.
    pub lod: Option<String>,
    /// GeoJSON: what a height, storey or base value that is not a number does
    /// ([`attr`] says which strings are numbers): skip (fall back, then skip the feature with
    /// its reason, counted in the report) or fail the load.
    pub on_bad_height: OnBadHeight,
    /// GeoJSON: the height of a feature with no usable height or storey count, metres (the last
    /// fallback). `None`: such features are skipped.
    pub default_height: Option<f64>,
    /// CityJSON: city object types read besides `Building` and `BuildingPart` (as written in the
    /// file, extension types with their `+`: `Bridge`, `+GenericCityObject`, ...).
    pub types: Vec<String>,
    /// Footprints: attribute holding the height of the object's bottom above its base, metres
    /// (OpenStreetMap's `min_height`, the default; read when present).
    pub min_height_attr: Option<String>,
    /// Footprints: attribute holding the storey its bottom starts at, the fallback for a missing
    /// `min_height_attr` (OpenStreetMap's `building:min_level`, the default).
    pub min_levels_attr: Option<String>,
    /// The CRS to project the scene into (`EPSG:N`); `None`: the first projected CRS of the
    /// input, or for longitude/latitude input the UTM zone of its centre ([`crs`]).
    pub crs: Option<String>,
    /// Terrain files read beside the scene (`--terrain`): GeoTIFF DEMs (`.tif`, `.tiff`) and
    /// OBJ meshes ([`terrain`]).
    pub terrain: Vec<PathBuf>,
    /// Leave out the terrain the scene files hold (CityJSON `TINRelief`, `--no-terrain`); the
    /// `terrain` files are read all the same.
    pub no_terrain: bool,
}

/// The tallest height a reader accepts, metres: the tallest building stands 828 m. A larger
/// value (`1e6`, `1e300`) is a bad height, skipped or an error by `--on-bad-height`.
pub const MAX_HEIGHT_M: f64 = 1000.0;

/// The largest base elevation magnitude a reader accepts, metres (Everest is 8,849 m). A larger
/// value is a bad base.
pub const MAX_BASE_M: f64 = 10_000.0;

/// What a GeoJSON height value that is not a number does.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OnBadHeight {
    /// Try the next source (storeys, then the default height); with none, skip the feature and
    /// report why.
    #[default]
    Skip,
    /// Fail the load, naming the feature and the value.
    Error,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            height_attr: None,
            base_attr: None,
            levels_attr: None,
            storey_height: 3.0,
            lod: None,
            on_bad_height: OnBadHeight::Skip,
            default_height: None,
            types: Vec::new(),
            min_height_attr: Some("min_height".into()),
            min_levels_attr: Some("building:min_level".into()),
            crs: None,
            terrain: Vec::new(),
            no_terrain: false,
        }
    }
}

/// A ring as read, any orientation. GeoJSON rings repeat their first point at the end.
pub type Ring = Vec<DVec2>;

/// A footprint: polygons (ring 0 the exterior, the rest holes) extruded from `base` to `top`.
#[derive(Clone, Debug, PartialEq)]
pub struct Footprint {
    pub polygons: Vec<Vec<Ring>>,
    pub base: f64,
    pub top: f64,
}

/// A polygon-face mesh. Faces may be non-triangular and carry holes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub vertices: Vec<DVec3>,
    pub faces: Vec<Face>,
}

/// One mesh face: ring 0 is its outer boundary, later rings are holes; indices into
/// [`Mesh::vertices`].
#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    pub rings: Vec<Vec<u32>>,
}

/// The geometry of an object.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    Footprint(Footprint),
    Mesh(Mesh),
}

/// An object as a reader gives it, in world coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct RawObject {
    /// Name or id from the file; the reader makes one up from the position when there is none.
    pub name: String,
    /// Where it sits in its file, for reports.
    pub location: Location,
    /// Its position among its file's items, from 0: the GeoJSON feature, the CityJSON city
    /// object (all types, in file order), the OBJ group; skipped items count too.
    pub feature: u32,
    pub shape: Shape,
}

/// Why a reader skipped an object (it is neither an occludee nor a blocker).
#[derive(Clone, Debug, PartialEq)]
pub enum SkipReason {
    /// No height attribute and no storey count to fall back on.
    NoHeight,
    /// A height (or storey) value that is not a number, or a number beyond [`MAX_HEIGHT_M`],
    /// and no fallback: the attribute, and the value as written with what is wrong with it
    /// (`"tall", not a number`; `1e300 m, beyond the 1000 m a height may have`).
    BadHeight { attr: String, value: String },
    /// A base attribute was asked for and this object has no value for it.
    NoBase,
    /// The base value is not a number: the attribute and the value as written.
    BadBase { attr: String, value: String },
    /// The geometry is `null` or empty.
    EmptyGeometry,
    /// A geometry type that has no area (Point, LineString, ...).
    NotAreal(String),
    /// The city object has no geometry at the requested level of detail.
    NoGeometryAtLod(String),
    /// A geometry kind this reader does not model (e.g. CityJSON GeometryInstance).
    UnsupportedGeometry(String),
    /// Part of the geometry is not in the file (an OpenStreetMap way whose nodes lie outside the
    /// extract, a relation whose member ways do): what is missing.
    IncompleteGeometry(String),
}

/// What is wrong with a bad value, for a label without the value.
fn bad_label(value: &str) -> &'static str {
    if value.ends_with("not a number") {
        "not a number"
    } else {
        "out of range"
    }
}

impl SkipReason {
    /// A short, stable label for grouping in reports (no values).
    pub fn label(&self) -> String {
        match self {
            SkipReason::BadHeight { attr, value } => {
                format!("height attribute {attr:?} {}", bad_label(value))
            }
            SkipReason::BadBase { attr, value } => {
                format!("base attribute {attr:?} {}", bad_label(value))
            }
            SkipReason::IncompleteGeometry(_) => "geometry not all in the file".into(),
            other => other.to_string(),
        }
    }
}

impl fmt::Display for SkipReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SkipReason::NoHeight => write!(f, "no height attribute and no storey count"),
            SkipReason::BadHeight { attr, value } => {
                write!(f, "height attribute {attr:?} is {value}")
            }
            SkipReason::NoBase => write!(f, "no value for the base attribute"),
            SkipReason::BadBase { attr, value } => {
                write!(f, "base attribute {attr:?} is {value}")
            }
            SkipReason::EmptyGeometry => write!(f, "empty or null geometry"),
            SkipReason::NotAreal(t) => write!(f, "geometry type {t} has no area"),
            SkipReason::NoGeometryAtLod(l) => write!(f, "no geometry at LoD {l}"),
            SkipReason::UnsupportedGeometry(t) => write!(f, "unsupported geometry {t}"),
            SkipReason::IncompleteGeometry(t) => write!(f, "geometry not all in the file: {t}"),
        }
    }
}

/// An object a reader skipped.
#[derive(Clone, Debug, PartialEq)]
pub struct Skipped {
    pub location: Location,
    pub name: String,
    pub reason: SkipReason,
    /// As [`RawObject::feature`] in a reader's output; in a [`SceneReport`], the input feature
    /// number across all files ([`Object::feature`]).
    pub feature: u32,
    /// Its footprint rings when the reader had them (a GeoJSON feature skipped for its
    /// height), for pictures; world coordinates from a reader, local in a [`SceneReport`].
    pub outline: Vec<Ring>,
}

/// Where a footprint's height came from when its height attribute gave none.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum HeightSource {
    /// The storey count times the storey height.
    Storeys,
    /// The default height the user gave.
    Default,
}

/// A height taken from a fallback, and the values that were not numbers on the way (attribute,
/// value as written).
#[derive(Clone, Debug, PartialEq)]
pub struct HeightFallback {
    pub source: HeightSource,
    pub passed: Vec<(String, String)>,
}

impl HeightFallback {
    /// A short, stable label for grouping in reports.
    pub fn label(&self) -> &'static str {
        match self.source {
            HeightSource::Storeys => "height from the storey count",
            HeightSource::Default => "height from --default-height",
        }
    }
}

impl fmt::Display for HeightFallback {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.label())?;
        for (a, v) in &self.passed {
            write!(f, "; {a:?} is {v}")?;
        }
        Ok(())
    }
}

/// What one reader returns for one file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FileRead {
    pub objects: Vec<RawObject>,
    pub skipped: Vec<Skipped>,
    /// GeoJSON: objects (index into `objects`) whose height came from a fallback.
    pub fallbacks: Vec<(usize, HeightFallback)>,
    /// CityJSON: city objects of other types, skipped and counted by type.
    pub other_types: BTreeMap<String, usize>,
    /// How many items the file holds (GeoJSON features, CityJSON city objects, OBJ groups):
    /// the span of input feature numbers it takes.
    pub items: usize,
    /// CityJSON: the levels of detail of the geometries of the objects read, as written.
    pub lods: std::collections::BTreeSet<String>,
    /// The CRS the file states ([`crs`]); `None` when it states none.
    pub crs: Option<Crs>,
    /// CityJSON: the triangles of its `TINRelief` objects (world), unless
    /// [`ReadOptions::no_terrain`].
    pub terrain: Vec<[DVec3; 3]>,
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb3 {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb3 {
    /// The empty box (min > max), identity of [`Aabb3::union`].
    pub const EMPTY: Aabb3 = Aabb3 {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    pub fn include(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub fn union(self, o: Aabb3) -> Aabb3 {
        Aabb3 {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }
}

/// An object of the scene: an occludee, and perhaps the source of blockers.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// Stable index: input order across files, then order within the file.
    pub index: u32,
    /// Index into [`Scene::files`].
    pub file: u32,
    /// Input feature number: its position among the items of all files, in input order, with
    /// skipped items counted (the GeoJSON feature index for one GeoJSON file; CityJSON city
    /// objects of every type and OBJ groups in file order). `pvs` and `info` name objects by
    /// it, so a number means the same feature whatever was skipped.
    pub feature: u32,
    pub name: String,
    pub location: Location,
    /// Local bounding box.
    pub bbox: Aabb3,
    /// Triangle count: a mesh's triangles, or the triangles of a footprint's extruded prism.
    pub cost: u64,
    /// Local geometry. Footprints hold their repaired rings when repair succeeded.
    pub shape: Shape,
}

/// A 2.5D blocker: a convex footprint piece standing from `base` to `top`, certainly solid; or
/// a wall segment (2 vertices): the vertical rectangle over it from `base` to `top` is certainly
/// part of the object's surface, so every ray crossing it is blocked.
#[derive(Clone, Debug, PartialEq)]
pub struct Blocker {
    /// The object it comes from.
    pub object: u32,
    /// Strictly convex, counter-clockwise, local coordinates; or exactly 2 distinct points (a
    /// wall), [`crate::geom::predicates::is_convex_piece`].
    pub polygon: Vec<DVec2>,
    pub base: f64,
    pub top: f64,
}

/// A ring repair that was made, per ring.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum RingRepair {
    /// The ring did not end on its first vertex (or was given open); it was closed.
    Closed,
    /// Consecutive repeated points were removed.
    RepeatedPoints,
    /// The ring ran the wrong way (exterior clockwise or hole counter-clockwise); reversed.
    Reoriented,
}

impl fmt::Display for RingRepair {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RingRepair::Closed => "unclosed ring closed",
            RingRepair::RepeatedPoints => "repeated points removed",
            RingRepair::Reoriented => "wrong orientation reversed",
        })
    }
}

/// Why a ring, and with it its polygon, was rejected as a blocker.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum RingRejection {
    /// Fewer than three distinct points.
    TooFewPoints,
    /// Zero area: all points on one line.
    ZeroArea,
    /// Two edges of the polygon's rings cross or touch away from their shared vertex.
    SelfIntersection,
    /// A hole does not lie inside the exterior ring, or lies inside another hole.
    HoleOutside,
    /// So many edges pass near one another that validation would cost more than
    /// `footprint::WORK_PER_EDGE` candidate tests per edge; refused rather than checked slowly.
    TooComplex,
}

impl fmt::Display for RingRejection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RingRejection::TooFewPoints => "fewer than 3 distinct points",
            RingRejection::ZeroArea => "zero area",
            RingRejection::SelfIntersection => "self-intersection (edges cross or touch)",
            RingRejection::HoleOutside => "hole outside its exterior or inside another hole",
            RingRejection::TooComplex => {
                "too complex to validate (too many edges pass near one another)"
            }
        })
    }
}

/// Why an object gave no blocker (it stays an occludee).
#[derive(Clone, Debug, PartialEq)]
pub enum NoBlocker {
    /// A footprint ring was rejected.
    InvalidRing {
        polygon: usize,
        ring: usize,
        why: RingRejection,
    },
    /// Top not above base.
    NoHeight,
    /// The mesh is open (some edges are not shared by an even number of faces), and no face of
    /// it is vertical.
    OpenMesh { boundary_edges: usize },
    /// No column of the mesh could be proven solid (too thin, degenerate, or every test point
    /// on a face edge), and no face of it gives a wall.
    NoProvableInterior,
    /// The constrained triangulation refused the rings (should not happen after validation).
    Triangulation(String),
}

impl fmt::Display for NoBlocker {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NoBlocker::InvalidRing { polygon, ring, why } => {
                write!(f, "polygon {polygon} ring {ring}: {why}")
            }
            NoBlocker::NoHeight => write!(f, "top not above base"),
            NoBlocker::OpenMesh { boundary_edges } => {
                write!(f, "open mesh ({boundary_edges} edges not shared by an even number of faces): no provable interior, and no vertical face gives a wall")
            }
            NoBlocker::NoProvableInterior => {
                write!(
                    f,
                    "no column could be proven solid, and no vertical face gives a wall"
                )
            }
            NoBlocker::Triangulation(m) => write!(f, "triangulation failed: {m}"),
        }
    }
}

impl NoBlocker {
    /// A short, stable label for grouping in reports.
    pub fn label(&self) -> String {
        match self {
            NoBlocker::InvalidRing { why, .. } => format!("invalid ring: {why}"),
            NoBlocker::NoHeight => "top not above base".into(),
            NoBlocker::OpenMesh { .. } => "open mesh".into(),
            NoBlocker::NoProvableInterior => "no provable interior".into(),
            NoBlocker::Triangulation(_) => "triangulation failed".into(),
        }
    }
}

/// Per-file counts.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FileStats {
    pub path: PathBuf,
    pub format: &'static str,
    pub objects: usize,
    pub skipped: usize,
    pub other_types: BTreeMap<String, usize>,
    /// The file's CRS: stated by the file, or detected ([`crs`]); `None`: unknown.
    pub crs: Option<Crs>,
}

/// What loading did: per-file counts, and every skip, repair and blocker failure with its reason.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneReport {
    pub files: Vec<FileStats>,
    /// (file index, skipped object)
    pub skipped: Vec<(u32, Skipped)>,
    /// (object index, polygon, ring, repair)
    pub repairs: Vec<(u32, usize, usize, RingRepair)>,
    /// (object index, reason)
    pub no_blocker: Vec<(u32, NoBlocker)>,
    /// (object index, where its height came from) for footprints whose height attribute gave
    /// none.
    pub height_fallbacks: Vec<(u32, HeightFallback)>,
    /// Wall-clock seconds per stage, in pipeline order.
    pub timings: Vec<(&'static str, f64)>,
    /// Warnings about the load as a whole, for `info` and `bake` to print: many features
    /// skipped for want of a height (with the flag that would read them), reader flags that no
    /// input uses.
    pub notes: Vec<String>,
}

/// A loaded scene in its local frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// World position of the local origin: `world = local + origin`.
    pub origin: DVec3,
    pub files: Vec<PathBuf>,
    pub objects: Vec<Object>,
    /// All blockers, grouped by object in object order.
    pub blockers: Vec<Blocker>,
    pub report: SceneReport,
    /// The CRS of the world coordinates ([`Scene::crs`]).
    pub crs: Option<Crs>,
    /// The terrain, local frame, with its blockers ([`terrain`]); `None` without one.
    pub terrain: Option<Terrain>,
}

impl Scene {
    /// The coordinate reference system of the scene's world coordinates (`world = local +
    /// origin`): the CRS the input states, or the metric CRS longitude/latitude input was
    /// projected into on load (then [`Crs::projected_from`] names the input's CRSs). `None` when
    /// no input states a CRS and none was detected. Display it with `{}`; its `name` is
    /// `EPSG:N` when the code is known.
    pub fn crs(&self) -> Option<&Crs> {
        self.crs.as_ref()
    }

    /// The terrain's blockers (none without a terrain): square columns of solid ground, object
    /// [`TERRAIN_OBJECT`]. The bake uses them after [`Scene::blockers`].
    pub fn terrain_blockers(&self) -> &[Blocker] {
        self.terrain.as_ref().map_or(&[], |t| &t.blockers)
    }

    /// Local bounding box of all objects.
    pub fn extent(&self) -> Aabb3 {
        self.objects
            .iter()
            .fold(Aabb3::EMPTY, |acc, o| acc.union(o.bbox))
    }
}

/// A scene of axis-aligned boxes `[x0, y0, x1, y1]` (world metres) with their heights, read from
/// GeoJSON as a user's file is. Tests only (`eval::bound`, `bake::reach`).
#[cfg(test)]
pub(crate) fn boxes_scene(boxes: &[([f64; 4], f64)]) -> Scene {
    let features: Vec<String> = boxes
        .iter()
        .map(|([x0, y0, x1, y1], h)| {
            format!(
                r#"{{"type":"Feature","properties":{{"height":{h}}},"geometry":{{"type":"Polygon","coordinates":[[[{x0},{y0}],[{x1},{y0}],[{x1},{y1}],[{x0},{y1}],[{x0},{y0}]]]}}}}"#
            )
        })
        .collect();
    let json = format!(
        r#"{{"type":"FeatureCollection","features":[{}]}}"#,
        features.join(",")
    );
    load_bytes(
        &[("boxes.geojson".into(), json.as_bytes())],
        &ReadOptions {
            height_attr: Some("height".into()),
            ..ReadOptions::default()
        },
    )
    .unwrap()
}
