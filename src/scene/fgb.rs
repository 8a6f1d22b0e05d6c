//! FlatGeobuf footprint reader (the `flatgeobuf` crate's verified FlatBuffers tables).
//!
//! Input: the bytes of a `.fgb` file: magic, a size-prefixed header, an optional packed R-tree,
//! then size-prefixed features. Output: one footprint per feature in file order, with its
//! properties as attributes read by the footprint reader's rules (`--height-attr`, ...); the
//! CRS from the header's `crs` (organization code when it is EPSG's, else its WKT or name).
//! This module walks the framing itself, checking every size against the bytes left, and hands
//! each header and feature to the crate's FlatBuffers verifier; properties are decoded here by
//! the specification's column types, every length checked. Polygons, MultiPolygons and the
//! polygons of collections are read; points and lines are skipped as not areal.
//! Invariants: nothing is allocated for a size the file does not hold; never panics.

use std::path::Path;

use flatgeobuf::{ColumnType, Geometry, GeometryType};
use glam::DVec2;
use serde_json::{Map, Number, Value};

use super::geojson::FootprintReader;
use super::{
    Crs, CrsSource, FileRead, LoadError, LoadErrorKind, Location, ReadOptions, Ring, SkipReason,
};

const FORMAT: &str = "FlatGeobuf";

/// Bytes per node of the packed R-tree (four f64 and a u64 offset).
const NODE_ITEM_BYTES: u64 = 40;

/// How deep geometry parts may nest.
const MAX_DEPTH: usize = 8;

/// Reads a FlatGeobuf file. See the module header.
pub fn read_fgb(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<FileRead, LoadError> {
    let malformed = |at: Location, message: String| {
        LoadError::new(
            path,
            at,
            LoadErrorKind::Malformed {
                format: FORMAT,
                message,
            },
        )
    };
    if bytes.len() < 12 || &bytes[..3] != b"fgb" || &bytes[4..7] != b"fgb" {
        return Err(malformed(
            Location::File,
            "no FlatGeobuf magic (the file must start with \"fgb\")".into(),
        ));
    }
    let mut reader = FootprintReader::for_format(path, opts, FORMAT)?;
    let size_at = |at: usize| -> Option<usize> {
        let s: [u8; 4] = bytes.get(at..at + 4)?.try_into().ok()?;
        Some(u32::from_le_bytes(s) as usize)
    };
    let header_size = size_at(8).unwrap_or(0);
    let header_end = 12usize
        .checked_add(header_size)
        .filter(|&e| e <= bytes.len())
        .ok_or_else(|| {
            malformed(
                Location::File,
                format!("header of {header_size} bytes does not fit in the file"),
            )
        })?;
    let header = flatgeobuf::size_prefixed_root_as_header(&bytes[8..header_end])
        .map_err(|e| malformed(Location::File, format!("header: {e}")))?;
    let crs = header.crs().and_then(|c| {
        if c.org().is_none_or(|o| o.eq_ignore_ascii_case("EPSG")) && c.code() > 0 {
            Some(Crs::from_epsg(c.code() as u32, CrsSource::File))
        } else if let Some(w) = c.wkt().filter(|w| !w.trim().is_empty()) {
            Some(Crs::parse(w))
        } else {
            c.code_string()
                .or(c.name())
                .filter(|s| !s.trim().is_empty())
                .map(Crs::parse)
        }
    });
    let columns: Vec<(String, ColumnType)> = header
        .columns()
        .map(|cs| {
            cs.iter()
                .map(|c| (c.name().to_string(), c.type_()))
                .collect()
        })
        .unwrap_or_default();
    let header_type = header.geometry_type();
    let count = header.features_count();
    let node = header.index_node_size() as u64;
    // The packed R-tree: every level's nodes, 40 bytes each.
    let mut at = header_end as u64;
    if node > 0 && count > 0 {
        if node < 2 {
            return Err(malformed(Location::File, format!("index node size {node}")));
        }
        let (mut n, mut nodes) = (count, count);
        while n > 1 {
            n = n.div_ceil(node);
            nodes = nodes.saturating_add(n);
        }
        at = at.saturating_add(nodes.saturating_mul(NODE_ITEM_BYTES));
        if at > bytes.len() as u64 {
            return Err(malformed(
                Location::File,
                format!("the spatial index of {count} features does not fit in the file"),
            ));
        }
    }
    let mut at = at as usize;
    let mut i = 0usize;
    while at < bytes.len() {
        let loc = Location::Feature(i);
        let size = size_at(at).ok_or_else(|| {
            malformed(loc.clone(), "the file ends inside a feature's size".into())
        })?;
        let end = (at + 4)
            .checked_add(size)
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| {
                malformed(
                    loc.clone(),
                    format!("feature of {size} bytes does not fit in the file"),
                )
            })?;
        let f = flatgeobuf::size_prefixed_root_as_feature(&bytes[at..end])
            .map_err(|e| malformed(loc.clone(), e.to_string()))?;
        let mut props = Map::new();
        if let Some(p) = f.properties() {
            properties(p.bytes(), &columns, &mut props).map_err(|m| malformed(loc.clone(), m))?;
        }
        let polygons = match f.geometry() {
            None => Err(SkipReason::EmptyGeometry),
            Some(g) => {
                let mut out = Vec::new();
                match geometry(&g, header_type, &mut out, 0)
                    .map_err(|m| malformed(loc.clone(), m))?
                {
                    Some(t) if out.is_empty() => Err(SkipReason::NotAreal(t)),
                    _ if out.is_empty() => Err(SkipReason::EmptyGeometry),
                    _ => Ok(out),
                }
            }
        };
        reader.item(loc, None, &props, polygons)?;
        at = end;
        i += 1;
    }
    reader.set_crs(crs);
    reader.finish()
}

/// Appends a geometry's polygons; returns the type name of one with no area.
fn geometry(
    g: &Geometry,
    header_type: GeometryType,
    out: &mut Vec<Vec<Ring>>,
    depth: usize,
) -> Result<Option<String>, String> {
    if depth > MAX_DEPTH {
        return Err("geometry parts nest too deep".into());
    }
    let t = if header_type == GeometryType::Unknown || depth > 0 {
        g.type_()
    } else {
        header_type
    };
    match t {
        GeometryType::Polygon | GeometryType::Triangle => {
            out.push(rings(g)?);
            Ok(None)
        }
        GeometryType::MultiPolygon
        | GeometryType::GeometryCollection
        | GeometryType::PolyhedralSurface
        | GeometryType::TIN => {
            let mut none = None;
            for part in g.parts().iter().flatten() {
                // A MultiPolygon's parts are polygons whether or not they say so.
                let pt = if t == GeometryType::MultiPolygon {
                    GeometryType::Polygon
                } else {
                    GeometryType::Unknown
                };
                let r = if pt == GeometryType::Polygon {
                    out.push(rings(&part)?);
                    None
                } else {
                    geometry(&part, GeometryType::Unknown, out, depth + 1)?
                };
                if let Some(n) = r {
                    none.get_or_insert(n);
                }
            }
            Ok(none)
        }
        other => Ok(Some(
            other
                .variant_name()
                .unwrap_or("an unknown geometry type")
                .to_string(),
        )),
    }
}

/// A polygon's rings: `xy` pairs cut at `ends` (point counts; none: one ring).
fn rings(g: &Geometry) -> Result<Vec<Ring>, String> {
    let Some(xy) = g.xy() else {
        return Ok(Vec::new());
    };
    if xy.len() % 2 != 0 {
        return Err(format!("{} xy values: not pairs", xy.len()));
    }
    let pts: Vec<DVec2> = (0..xy.len() / 2)
        .map(|k| DVec2::new(xy.get(2 * k), xy.get(2 * k + 1)))
        .collect();
    let ends: Vec<usize> = match g.ends() {
        Some(e) if !e.is_empty() => e.iter().map(|v| v as usize).collect(),
        _ => vec![pts.len()],
    };
    let mut out = Vec::with_capacity(ends.len());
    let mut start = 0;
    for e in ends {
        if e < start || e > pts.len() {
            return Err(format!(
                "ring end {e} is outside the polygon's {} points",
                pts.len()
            ));
        }
        out.push(pts[start..e].to_vec());
        start = e;
    }
    Ok(out)
}

/// Decodes a feature's properties: a column index (u16), then the value by the column's type.
fn properties(
    b: &[u8],
    columns: &[(String, ColumnType)],
    out: &mut Map<String, Value>,
) -> Result<(), String> {
    let mut at = 0usize;
    let take = |at: &mut usize, n: usize| -> Result<&[u8], String> {
        let end = at
            .checked_add(n)
            .filter(|&e| e <= b.len())
            .ok_or_else(|| format!("properties end inside a value at byte {at}"))?;
        let s = &b[*at..end];
        *at = end;
        Ok(s)
    };
    while at + 1 < b.len() {
        let idx = u16::from_le_bytes([b[at], b[at + 1]]) as usize;
        at += 2;
        let Some((name, t)) = columns.get(idx) else {
            return Err(format!(
                "property of column {idx}, beyond the {} columns",
                columns.len()
            ));
        };
        let num = |f: f64| Number::from_f64(f).map_or(Value::Null, Value::Number);
        let v = match *t {
            ColumnType::Byte => Value::from(take(&mut at, 1)?[0] as i8),
            ColumnType::UByte => Value::from(take(&mut at, 1)?[0]),
            ColumnType::Bool => Value::Bool(take(&mut at, 1)?[0] != 0),
            ColumnType::Short => Value::from(i16::from_le_bytes(
                take(&mut at, 2)?.try_into().unwrap_or_default(),
            )),
            ColumnType::UShort => Value::from(u16::from_le_bytes(
                take(&mut at, 2)?.try_into().unwrap_or_default(),
            )),
            ColumnType::Int => Value::from(i32::from_le_bytes(
                take(&mut at, 4)?.try_into().unwrap_or_default(),
            )),
            ColumnType::UInt => Value::from(u32::from_le_bytes(
                take(&mut at, 4)?.try_into().unwrap_or_default(),
            )),
            ColumnType::Long => Value::from(i64::from_le_bytes(
                take(&mut at, 8)?.try_into().unwrap_or_default(),
            )),
            ColumnType::ULong => Value::from(u64::from_le_bytes(
                take(&mut at, 8)?.try_into().unwrap_or_default(),
            )),
            ColumnType::Float => {
                num(f32::from_le_bytes(take(&mut at, 4)?.try_into().unwrap_or_default()) as f64)
            }
            ColumnType::Double => num(f64::from_le_bytes(
                take(&mut at, 8)?.try_into().unwrap_or_default(),
            )),
            _ => {
                // String, Json, DateTime, Binary: a u32 length, then the bytes.
                let n =
                    u32::from_le_bytes(take(&mut at, 4)?.try_into().unwrap_or_default()) as usize;
                let s = take(&mut at, n)?;
                if *t == ColumnType::Binary {
                    continue;
                }
                Value::String(String::from_utf8_lossy(s).into_owned())
            }
        };
        out.insert(name.clone(), v);
    }
    Ok(())
}
