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
use shapefile::{PolygonRing, ReadableShape, Shape};

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
    let contents = records(shp).map_err(|(i, m)| malformed(Location::Feature(i), "", m))?;
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
    for (i, content) in contents.into_iter().enumerate() {
        let at = Location::Feature(i);
        // Each record is read from its own bytes, so a shape that says less or more than its
        // record holds cannot shift the records after it.
        let shape = Shape::read_from(&mut Cursor::new(content), content.len() as i32)
            .map_err(|e| malformed(at.clone(), "", e.to_string()))?;
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

/// The records' contents (shape type onwards), each checked against its header and its part and
/// point counts against the bytes it holds, before the shapefile crate reads it: the crate
/// reserves memory for the counts a record states (a 393-byte file asked for 6.9 GB when fuzzed,
/// `tests/fixtures/broken/shp_fuzz_*`), and reading the file as one stream, a record that holds
/// more bytes than its shape uses would shift the next record's header (16 GB, found next).
/// Returns the record index and what is wrong.
fn records(b: &[u8]) -> Result<Vec<&[u8]>, (usize, String)> {
    let i32_le = |at: usize| -> Option<i64> {
        Some(i32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?) as i64)
    };
    let i32_be = |at: usize| -> Option<i64> {
        Some(i32::from_be_bytes(b.get(at..at + 4)?.try_into().ok()?) as i64)
    };
    if b.len() < 100 {
        return Err((
            0,
            format!("{} bytes: shorter than the 100-byte header", b.len()),
        ));
    }
    if i32_be(0) != Some(9994) {
        return Err((0, "no Shapefile file code (9994) at the start".into()));
    }
    let mut at = 100usize;
    let mut i = 0usize;
    let mut out = Vec::new();
    while at + 8 <= b.len() {
        let words = i32_be(at + 4).unwrap_or(-1);
        if words < 0 {
            return Err((i, format!("record length {words}")));
        }
        let len = words as usize * 2;
        let start = at + 8;
        let Some(end) = start.checked_add(len).filter(|&e| e <= b.len()) else {
            return Err((
                i,
                format!("a record of {len} bytes does not fit in the file"),
            ));
        };
        let ty = if len >= 4 {
            i32_le(start).unwrap_or(0)
        } else {
            0
        };
        // Counts and the bytes per item after them: polylines, polygons, multipatches (parts and
        // points), multipoints (points).
        let need = match ty {
            3 | 5 | 13 | 15 | 23 | 25 | 31 => {
                let parts = i32_le(start + 36).unwrap_or(-1);
                let points = i32_le(start + 40).unwrap_or(-1);
                if parts < 0 || points < 0 {
                    return Err((i, format!("{parts} parts, {points} points")));
                }
                let per_part = if ty == 31 { 8 } else { 4 };
                let need = 44 + per_part * parts + 16 * points;
                if need <= len as i64 {
                    // Each part starts at a point of the record, in order: the crate sizes a
                    // part by the difference of two starts (a start of -9e8 asked for 28 GB).
                    let mut last = 0;
                    for k in 0..parts as usize {
                        let first = i32_le(start + 44 + 4 * k).unwrap_or(-1);
                        if first < last || first > points || (k == 0 && first != 0) {
                            return Err((
                                i,
                                format!("part {k} starts at point {first} (of {points})"),
                            ));
                        }
                        last = first;
                    }
                }
                Some(need)
            }
            8 | 18 | 28 => {
                let points = i32_le(start + 36).unwrap_or(-1);
                if points < 0 {
                    return Err((i, format!("{points} points")));
                }
                Some(40 + 16 * points)
            }
            _ => None,
        };
        if let Some(n) = need {
            if n > len as i64 {
                return Err((
                    i,
                    format!("its counts need {n} bytes, and the record holds {len}"),
                ));
            }
        }
        if len < 4 {
            return Err((i, format!("a record of {len} bytes has no shape type")));
        }
        out.push(&b[start..end]);
        at = end;
        i += 1;
    }
    Ok(out)
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
