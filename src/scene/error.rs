//! Typed errors of the scene readers.
//!
//! Input: whatever a reader finds wrong. Output: an error that names the file and the place in
//! it (line, feature index, city object id or vertex) and the rule the input broke.
//! Invariant: readers return these; they never panic and never return a partial scene.

use std::fmt;
use std::path::PathBuf;

/// Where in a file a problem sits.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Location {
    /// The file as a whole.
    File,
    /// A 1-based line (and column when known).
    Line { line: usize, column: Option<usize> },
    /// A GeoJSON feature, 0-based as in the file's `features` array.
    Feature(usize),
    /// A CityJSON city object, by id.
    CityObject(String),
    /// A vertex, 0-based as in the file's vertex list.
    Vertex(usize),
    /// A named element: an OpenStreetMap `way 123` or `relation 45`, a GeoPackage table row.
    Element(String),
    /// A place inside one line of a line-delimited file (CityJSONSeq): the 1-based line, then
    /// the place within that line's document.
    InLine { line: usize, inner: Box<Location> },
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::File => write!(f, "file"),
            Location::Line {
                line,
                column: Some(c),
            } => write!(f, "line {line}, column {c}"),
            Location::Line { line, column: None } => write!(f, "line {line}"),
            Location::Feature(i) => write!(f, "feature {i}"),
            Location::CityObject(id) => write!(f, "city object {id:?}"),
            Location::Vertex(i) => write!(f, "vertex {i}"),
            Location::Element(e) => f.write_str(e),
            Location::InLine { line, inner } => match **inner {
                Location::File => write!(f, "line {line}"),
                ref i => write!(f, "line {line}, {i}"),
            },
        }
    }
}

/// The rule a file broke.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LoadErrorKind {
    #[error("cannot read the file: {0}")]
    Io(String),
    #[error("the file is empty")]
    Empty,
    #[error("unknown file format (vocc reads .geojson/.json GeoJSON, .json/.city.json CityJSON, .city.jsonl/.jsonl CityJSONSeq, .gml/.xml CityGML 2.0, .osm.pbf OpenStreetMap, .gpkg GeoPackage, .fgb FlatGeobuf, .shp Shapefile and .obj)")]
    UnknownFormat,
    /// A format vocc does not read, with a tool that converts it to one it does.
    #[error("{format} files are not read by vocc; convert it first, e.g. {hint}")]
    UnsupportedFormat { format: String, hint: String },
    /// The same file given twice (compared as files, not names).
    #[error("the same file as input {} is given again; give each file once (its objects would be doubled)", first.display())]
    DuplicateFile { first: PathBuf },
    /// Two inputs in CRSs that cannot be put into one.
    #[error("inputs in two coordinate reference systems: {} is in {}, {} is in {}; {}", .0.a_file.display(), .0.a_crs, .0.b_file.display(), .0.b_crs, .0.why)]
    MixedCrs(Box<CrsConflict>),
    /// A point could not be projected, or `--crs` names no projected CRS: `what` says from and
    /// to what (`EPSG:4326 to EPSG:32631`).
    #[error("cannot project {what}: {message}")]
    Projection { what: String, message: String },
    /// A height or base that is a number, but beyond what any building has.
    #[error("attribute {attr:?} has value {} m, beyond the {limit} m a {what} may have; --on-bad-height skip passes over such values", short(*value))]
    AbsurdHeight {
        attr: String,
        what: &'static str,
        value: f64,
        limit: f64,
    },
    /// A companion file a format needs is missing (a Shapefile's `.dbf` for its attributes).
    #[error("{} is missing; {why}", path.display())]
    MissingCompanion { path: PathBuf, why: String },
    #[error("malformed JSON: {0}")]
    MalformedJson(String),
    #[error("malformed OBJ: {0}")]
    MalformedObj(String),
    #[error("malformed {format}: {message}")]
    Malformed {
        format: &'static str,
        message: String,
    },
    #[error("{0} is not a finite number")]
    NonFinite(String),
    /// `what` names the value: "coordinate x", "height", "base", "transform.scale[0]", ...
    #[error("{what} = {} m is out of range (its magnitude must be below {limit:e} m)", short(*value))]
    OutOfRange {
        what: String,
        value: f64,
        limit: f64,
    },
    #[error("unknown geometry type {0:?}")]
    UnknownGeometryType(String),
    /// A walkable area (`bake --walkable`) holds a geometry without area.
    #[error("geometry type {0:?} has no area: a walkable area is made of Polygon and MultiPolygon geometries (buffer points and lines into polygons first)")]
    NotAnArea(String),
    #[error(
        "attribute {attr:?} gives no feature a height (missing, or not usable, everywhere); {hint}"
    )]
    MissingAttribute { attr: String, hint: String },
    /// GeoJSON footprints carry no height, and no attribute to read one from was named.
    #[error("GeoJSON footprints need a height: give --height-attr NAME (or --levels-attr NAME for storey counts)")]
    NoHeightOption,
    #[error("attribute {attr:?} has value {value}, which is not a number (a number may carry a unit, as \"12.13 m\" or \"40 ft\", or a decimal comma, as \"12,5\"); --on-bad-height skip passes over such values")]
    BadAttribute { attr: String, value: String },
    #[error("unsupported CityJSON version {0:?} (this reader knows {known})", known = super::cityjson::SUPPORTED_VERSIONS)]
    UnsupportedVersion(String),
    #[error("the scene has no objects")]
    NoObjects,
    /// CityJSON files with city objects, none of a type read: the types they hold, and how many.
    #[error("no city object of the types read ({}); the files hold {}{}", read.join(", "), held.iter().map(|(t, n)| format!("{t} {n}")).collect::<Vec<_>>().join(", "), types_hint(held))]
    NoObjectsOfTypes {
        read: Vec<String>,
        held: Vec<(String, usize)>,
    },
    /// Every object was skipped for want of geometry at the requested level of detail.
    #[error("no object has geometry at LoD {lod}; the files hold LoD {}", available.join(", "))]
    NoObjectsAtLod { lod: String, available: Vec<String> },
}

/// The `--types` that would read the held types (those a reader could read: not the notes on
/// buildings whose geometry lies in their parts).
fn types_hint(held: &[(String, usize)]) -> String {
    let t: Vec<&str> = held
        .iter()
        .map(|(t, _)| t.as_str())
        .filter(|t| !t.contains(' '))
        .collect();
    if t.is_empty() {
        String::new()
    } else {
        format!("; read them with --types {}", t.join(","))
    }
}

/// Two inputs whose CRSs cannot be put into one: each file and its CRS, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct CrsConflict {
    pub a_file: PathBuf,
    pub a_crs: String,
    pub b_file: PathBuf,
    pub b_crs: String,
    pub why: String,
}

/// A reader error: the file, the place in it, and what is wrong.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}: {location}: {kind}", path.display())]
pub struct LoadError {
    pub path: PathBuf,
    pub location: Location,
    pub kind: LoadErrorKind,
}

impl LoadError {
    pub fn new(path: impl Into<PathBuf>, location: Location, kind: LoadErrorKind) -> Self {
        LoadError {
            path: path.into(),
            location,
            kind,
        }
    }
}

/// Largest accepted coordinate magnitude, metres. Projected coordinates on Earth stay below
/// about 4e7 m; anything beyond 1e9 m is a unit error or garbage, and squaring it in later
/// stages would lose all precision.
pub const MAX_COORD_M: f64 = 1.0e9;

/// A number for a message: plain below 1e6, else in scientific notation with at most 6
/// significant digits (1e300 prints as `1e300`, not 301 digits).
pub fn short(v: f64) -> String {
    if v.abs() < 1e6 {
        format!("{v}")
    } else {
        let s = format!("{v:.5e}");
        // Drop trailing zeros of the mantissa: 1.00000e9 -> 1e9, 1.25000e9 -> 1.25e9.
        match s.split_once('e') {
            Some((m, e)) if m.contains('.') => {
                let m = m.trim_end_matches('0').trim_end_matches('.');
                format!("{m}e{e}")
            }
            _ => s,
        }
    }
}

/// Checks one value where it enters the crate: `what` is "x", "y" or "z" for a coordinate, or
/// the name of what else it is ("height", "base", ...), so messages blame the right thing.
pub fn check_coord(v: f64, what: &str) -> Result<f64, LoadErrorKind> {
    let what = match what {
        "x" | "y" | "z" => format!("coordinate {what}"),
        w => w.to_string(),
    };
    if !v.is_finite() {
        Err(LoadErrorKind::NonFinite(format!("{what} = {v}")))
    } else if v.abs() >= MAX_COORD_M {
        Err(LoadErrorKind::OutOfRange {
            what,
            value: v,
            limit: MAX_COORD_M,
        })
    } else {
        Ok(v)
    }
}
