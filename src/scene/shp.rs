//! Shapefile footprint reader (the `shapefile` and `dbase` crates).
//!
//! Input: the bytes of a `.shp`, and when they exist the `.dbf` beside it (attributes) and the
//! `.prj` (the CRS, as WKT). Output: one footprint per shape in file order, its `.dbf` record as
//! attributes read by the footprint reader's rules (`--height-attr`, ...). Polygon, PolygonZ and
//! PolygonM shapes are read: each outer ring starts a polygon and the inner rings after it are
//! its holes (the Shapefile order); null shapes are skipped as empty, points, lines and
//! multipatches as not areal.
//! Invariants: shapes and records must pair one to one; a missing `.dbf` is an error only when
//! an attribute flag asks for attributes; never panics.

use std::io::Cursor;
use std::path::Path;

use glam::DVec2;
use serde_json::{Map, Number, Value};
use shapefile::{PolygonRing, Shape, ShapeReader};

use super::geojson::FootprintReader;
use super::{Crs, FileRead, LoadError, LoadErrorKind, Location, ReadOptions, Ring, SkipReason};

const FORMAT: &str = "Shapefile";

/// Reads a Shapefile. See the module header.
pub fn read_shp(
    path: &Path,
    shp: &[u8],
    dbf: Option<&[u8]>,
    prj: Option<&[u8]>,
    opts: &ReadOptions,
) -> Result<FileRead, LoadError> {
    let malformed = |at: Location, what: &str, message: String| {
        LoadError::new(
            path,
            at,
            LoadErrorKind::Malformed {
                format: FORMAT,
                message: format!("{what}{message}"),
            },
        )
    };
    let mut reader = FootprintReader::for_format(path, opts, FORMAT)?;
    let wants_attributes =
        opts.height_attr.is_some() || opts.levels_attr.is_some() || opts.base_attr.is_some();
    if dbf.is_none() && wants_attributes {
        return Err(LoadError::new(
            path,
            Location::File,
            LoadErrorKind::MissingCompanion {
                path: path.with_extension("dbf"),
                why: "a Shapefile's attributes (heights) are in its .dbf; without it only --default-height reads the shapes".into(),
            },
        ));
    }
    let mut shapes = ShapeReader::new(Cursor::new(shp))
        .map_err(|e| malformed(Location::File, "", e.to_string()))?;
    let mut records = match dbf {
        Some(b) => Some(
            shapefile::dbase::Reader::new(Cursor::new(b))
                .map_err(|e| malformed(Location::File, ".dbf: ", e.to_string()))?,
        ),
        None => None,
    };
    let fields: Vec<String> = records
        .as_ref()
        .map(|r| r.fields().iter().map(|f| f.name().to_string()).collect())
        .unwrap_or_default();
    let mut record_iter = records.as_mut().map(|r| r.iter_records());
    for (i, shape) in shapes.iter_shapes().enumerate() {
        let at = Location::Feature(i);
        let shape = shape.map_err(|e| malformed(at.clone(), "", e.to_string()))?;
        let mut props = Map::new();
        if let Some(it) = record_iter.as_mut() {
            let rec = it
                .next()
                .ok_or_else(|| {
                    malformed(
                        at.clone(),
                        ".dbf: ",
                        format!("has fewer records than the .shp has shapes ({i})"),
                    )
                })?
                .map_err(|e| malformed(at.clone(), ".dbf: ", e.to_string()))?;
            for name in &fields {
                if let Some(v) = rec.get(name) {
                    props.insert(name.clone(), field(v));
                }
            }
        }
        let polygons = match &shape {
            Shape::NullShape => Err(SkipReason::EmptyGeometry),
            Shape::Polygon(p) => Ok(group(p.rings(), |q| DVec2::new(q.x, q.y))),
            Shape::PolygonM(p) => Ok(group(p.rings(), |q| DVec2::new(q.x, q.y))),
            Shape::PolygonZ(p) => Ok(group(p.rings(), |q| DVec2::new(q.x, q.y))),
            other => Err(SkipReason::NotAreal(other.shapetype().to_string())),
        };
        reader.item(at, None, &props, polygons)?;
    }
    let crs = prj
        .map(|b| String::from_utf8_lossy(b).trim().to_string())
        .filter(|t| !t.is_empty())
        .map(|t| Crs::parse(&t));
    reader.set_crs(crs);
    reader.finish()
}

/// Polygons from Shapefile rings: an outer ring starts one, inner rings are its holes.
fn group<P>(rings: &[PolygonRing<P>], xy: impl Fn(&P) -> DVec2) -> Vec<Vec<Ring>> {
    let mut out: Vec<Vec<Ring>> = Vec::new();
    for r in rings {
        let pts: Ring = r.points().iter().map(&xy).collect();
        match r {
            PolygonRing::Outer(_) => out.push(vec![pts]),
            PolygonRing::Inner(_) => match out.last_mut() {
                Some(p) => p.push(pts),
                // A hole before any outer ring: read as its own polygon (repair reorients it).
                None => out.push(vec![pts]),
            },
        }
    }
    out
}

/// A `.dbf` value as JSON.
fn field(v: &shapefile::dbase::FieldValue) -> Value {
    use shapefile::dbase::FieldValue as F;
    let num = |f: f64| Number::from_f64(f).map_or(Value::Null, Value::Number);
    match v {
        F::Character(s) => s.clone().map_or(Value::Null, Value::String),
        F::Numeric(n) => n.map_or(Value::Null, num),
        F::Float(n) => n.map_or(Value::Null, |f| num(f as f64)),
        F::Integer(i) => Value::from(*i),
        F::Currency(f) | F::Double(f) => num(*f),
        F::Logical(b) => b.map_or(Value::Null, Value::Bool),
        F::Memo(s) => Value::String(s.clone()),
        F::Date(d) => d.map_or(Value::Null, |d| Value::String(d.to_string())),
        F::DateTime(_) => Value::Null,
    }
}
