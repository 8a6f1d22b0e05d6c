//! GeoJSON footprint reader.
//!
//! Input: a parsed GeoJSON `FeatureCollection` (or single `Feature`) of Polygon or MultiPolygon
//! footprints, 2D or 3D positions (z is ignored), and the attribute names to read.
//! Output: one footprint object per feature, in feature order, in world coordinates:
//! `base` = the base attribute (0 when none is named), `top` = base + height, where height is the
//! height attribute, or the storey attribute times the storey height when the height is missing.
//! Features without either are skipped and reported, as are features whose geometry is null or
//! has no area.
//! Invariants: every coordinate is range-checked where it enters; errors name the feature index;
//! an unknown geometry type is an error, not a skip.

use std::path::Path;

use glam::DVec2;
use serde_json::{Map, Value};

use super::error::{check_coord, LoadError, LoadErrorKind, Location};
use super::{FileRead, Footprint, RawObject, ReadOptions, Ring, Shape, SkipReason, Skipped};

/// Reads footprints from a parsed GeoJSON document.
pub fn read_geojson(path: &Path, v: &Value, opts: &ReadOptions) -> Result<FileRead, LoadError> {
    let err = |loc, kind| LoadError::new(path, loc, kind);
    let malformed = |loc, message: &str| {
        err(
            loc,
            LoadErrorKind::Malformed {
                format: "GeoJSON",
                message: message.to_string(),
            },
        )
    };
    if opts.height_attr.is_none() && opts.levels_attr.is_none() {
        return Err(err(
            Location::File,
            LoadErrorKind::MissingAttribute {
                attr: "(none given)".into(),
                hint: "GeoJSON footprints need --height-attr NAME or --levels-attr NAME".into(),
            },
        ));
    }
    let features: Vec<&Value> = match v.get("type").and_then(Value::as_str) {
        Some("Feature") => vec![v],
        _ => v
            .get("features")
            .and_then(Value::as_array)
            .ok_or_else(|| {
                malformed(
                    Location::File,
                    "FeatureCollection has no \"features\" array",
                )
            })?
            .iter()
            .collect(),
    };

    let mut out = FileRead::default();
    let empty = Map::new();
    let mut saw_height = false;
    for (i, f) in features.iter().enumerate() {
        let loc = Location::Feature(i);
        let props = match f.get("properties") {
            None | Some(Value::Null) => &empty,
            Some(Value::Object(m)) => m,
            Some(_) => return Err(malformed(loc, "\"properties\" is not an object")),
        };
        let name = feature_name(f, props).unwrap_or_else(|| format!("feature {i}"));
        let skip = |out: &mut FileRead, reason| {
            out.skipped.push(Skipped {
                location: Location::Feature(i),
                name: name.clone(),
                reason,
            })
        };
        let geom = match f.get("geometry") {
            None | Some(Value::Null) => {
                skip(&mut out, SkipReason::EmptyGeometry);
                continue;
            }
            Some(g) => g,
        };
        let gtype = geom
            .get("type")
            .and_then(Value::as_str)
            .ok_or_else(|| malformed(loc.clone(), "geometry has no \"type\""))?;
        let coords = geom.get("coordinates");
        let polygons: Vec<Vec<Ring>> = match gtype {
            "Polygon" => vec![rings(coords, 1).map_err(|m| malformed(loc.clone(), &m))?],
            "MultiPolygon" => {
                let arr = coords.and_then(Value::as_array).ok_or_else(|| {
                    malformed(loc.clone(), "MultiPolygon coordinates are not an array")
                })?;
                arr.iter()
                    .map(|p| rings(Some(p), 2))
                    .collect::<Result<_, _>>()
                    .map_err(|m| malformed(loc.clone(), &m))?
            }
            "Point" | "MultiPoint" | "LineString" | "MultiLineString" | "GeometryCollection" => {
                skip(&mut out, SkipReason::NotAreal(gtype.to_string()));
                continue;
            }
            other => {
                return Err(err(
                    loc,
                    LoadErrorKind::UnknownGeometryType(other.to_string()),
                ));
            }
        };
        for p in polygons.iter().flatten().flatten() {
            check_coord(p.x, "x")
                .and_then(|_| check_coord(p.y, "y"))
                .map_err(|k| err(loc.clone(), k))?;
        }
        let polygons: Vec<Vec<Ring>> = polygons
            .into_iter()
            .map(|p| p.into_iter().filter(|r| !r.is_empty()).collect::<Vec<_>>())
            .filter(|p| !p.is_empty())
            .collect();
        if polygons.is_empty() {
            skip(&mut out, SkipReason::EmptyGeometry);
            continue;
        }

        let number = |attr: &str| -> Result<Option<f64>, LoadError> {
            match props.get(attr) {
                None | Some(Value::Null) => Ok(None),
                Some(Value::Number(n)) => Ok(n.as_f64()),
                Some(Value::String(s)) if s.trim().parse::<f64>().is_ok() => {
                    Ok(s.trim().parse::<f64>().ok())
                }
                Some(Value::String(s)) if s.trim().is_empty() => Ok(None),
                Some(other) => Err(err(
                    Location::Feature(i),
                    LoadErrorKind::BadAttribute {
                        attr: attr.to_string(),
                        value: other.to_string(),
                    },
                )),
            }
        };
        let height = match &opts.height_attr {
            Some(a) => number(a)?,
            None => None,
        };
        let height = match (height, &opts.levels_attr) {
            (Some(h), _) => Some(h),
            (None, Some(a)) => number(a)?.map(|n| n * opts.storey_height),
            (None, None) => None,
        };
        let Some(height) = height else {
            skip(&mut out, SkipReason::NoHeight);
            continue;
        };
        check_coord(height, "height").map_err(|k| err(loc.clone(), k))?;
        saw_height = true;
        let base = match &opts.base_attr {
            None => 0.0,
            Some(a) => match number(a)? {
                Some(b) => check_coord(b, "base").map_err(|k| err(loc.clone(), k))?,
                None => {
                    skip(&mut out, SkipReason::NoBase);
                    continue;
                }
            },
        };
        out.objects.push(RawObject {
            name,
            location: loc,
            shape: Shape::Footprint(Footprint {
                polygons,
                base,
                top: base + height,
            }),
        });
    }
    if !saw_height && !features.is_empty() {
        let attr = opts
            .height_attr
            .clone()
            .or_else(|| opts.levels_attr.clone())
            .unwrap_or_default();
        let mut names: Vec<String> = features
            .iter()
            .find_map(|f| f.get("properties").and_then(Value::as_object))
            .map(|m| m.keys().cloned().collect())
            .unwrap_or_default();
        names.truncate(30);
        return Err(err(
            Location::File,
            LoadErrorKind::MissingAttribute {
                attr,
                hint: format!(
                    "no feature has a usable height; the first feature's attributes are: {}",
                    names.join(", ")
                ),
            },
        ));
    }
    Ok(out)
}

/// The feature's id or name: the feature `id`, else a property `id`, `ID`, `name` or `NAME`.
fn feature_name(f: &Value, props: &Map<String, Value>) -> Option<String> {
    let as_name = |v: &Value| match v {
        Value::String(s) => Some(s.clone()),
        Value::Number(n) => Some(n.to_string()),
        _ => None,
    };
    f.get("id").and_then(as_name).or_else(|| {
        ["id", "ID", "name", "NAME"]
            .iter()
            .find_map(|k| props.get(*k).and_then(as_name))
    })
}

/// Parses a Polygon's coordinates: an array of rings, each an array of positions.
/// `depth_hint` only shapes the error message.
fn rings(coords: Option<&Value>, depth_hint: usize) -> Result<Vec<Ring>, String> {
    let what = if depth_hint == 1 {
        "Polygon"
    } else {
        "MultiPolygon part"
    };
    let arr = coords
        .and_then(Value::as_array)
        .ok_or_else(|| format!("{what} coordinates are not an array of rings"))?;
    arr.iter()
        .enumerate()
        .map(|(ri, r)| {
            r.as_array()
                .ok_or_else(|| format!("{what} ring {ri} is not an array of positions"))?
                .iter()
                .map(|p| position(p).ok_or_else(|| format!("{what} ring {ri} has a position that is not an array of 2 or 3 numbers: {p}")))
                .collect()
        })
        .collect()
}

fn position(p: &Value) -> Option<DVec2> {
    let a = p.as_array()?;
    if a.len() < 2 || a.len() > 4 {
        return None;
    }
    Some(DVec2::new(a[0].as_f64()?, a[1].as_f64()?))
}
