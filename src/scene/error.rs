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
    #[error("unknown file format (expected .geojson/.json GeoJSON, .json CityJSON or .obj)")]
    UnknownFormat,
    #[error("malformed JSON: {0}")]
    MalformedJson(String),
    #[error("malformed OBJ: {0}")]
    MalformedObj(String),
    #[error("malformed {format}: {message}")]
    Malformed {
        format: &'static str,
        message: String,
    },
    #[error("coordinate is not finite ({0})")]
    NonFinite(String),
    #[error("coordinate {value} is out of range (|x| must be below {limit:e} m)")]
    OutOfRange { value: f64, limit: f64 },
    #[error("unknown geometry type {0:?}")]
    UnknownGeometryType(String),
    #[error("attribute {attr:?} is missing from every feature; {hint}")]
    MissingAttribute { attr: String, hint: String },
    #[error("attribute {attr:?} has value {value}, which is not a number")]
    BadAttribute { attr: String, value: String },
    #[error("unsupported CityJSON version {0:?} (supported: 0.x, 1.x, 2.x)")]
    UnsupportedVersion(String),
    #[error("the scene has no objects")]
    NoObjects,
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

/// Checks one coordinate where it enters the crate.
pub fn check_coord(v: f64, what: &str) -> Result<f64, LoadErrorKind> {
    if !v.is_finite() {
        Err(LoadErrorKind::NonFinite(format!("{what} = {v}")))
    } else if v.abs() >= MAX_COORD_M {
        Err(LoadErrorKind::OutOfRange {
            value: v,
            limit: MAX_COORD_M,
        })
    } else {
        Ok(v)
    }
}
