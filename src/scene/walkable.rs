//! The walkable area: which view cells a bake covers, read from a GeoJSON of polygons.
//!
//! Input: a GeoJSON FeatureCollection (or a single Feature or geometry) of Polygon and
//! MultiPolygon geometries in the scene's world coordinates, and the scene's origin.
//! Output: the polygons' outer rings in the local frame (holes are ignored: a cell that meets
//! the outer ring is baked, so the area is covered generously, never short).
//! Invariants: every coordinate is range-checked where it enters ([`check_coord`]); a bad file
//! gives a [`LoadError`] naming the feature, never a panic; the selection
//! ([`rect_meets_area`]) errs on the side of baking a cell.

use std::path::Path;

use glam::{DVec2, DVec3};
use serde_json::Value;

use super::error::{check_coord, LoadError, LoadErrorKind, Location};

/// Outer rings of the walkable area, local frame.
pub type Area = Vec<Vec<DVec2>>;

/// Reads the walkable area of `path`; `origin` is the scene's local origin.
pub fn read(path: &Path, origin: DVec3) -> Result<Area, LoadError> {
    let bytes = std::fs::read(path)
        .map_err(|e| LoadError::new(path, Location::File, LoadErrorKind::Io(e.to_string())))?;
    read_bytes(path, &bytes, origin)
}

/// [`read`] from bytes in memory; `path` names the file in errors only.
pub fn read_bytes(path: &Path, bytes: &[u8], origin: DVec3) -> Result<Area, LoadError> {
    let err = |loc: Location, kind: LoadErrorKind| LoadError::new(path, loc, kind);
    let v: Value = serde_json::from_slice(bytes).map_err(|e| {
        err(
            Location::Line {
                line: e.line(),
                column: Some(e.column()),
            },
            LoadErrorKind::MalformedJson(e.to_string()),
        )
    })?;
    let geometries: Vec<(usize, &Value)> = match v.get("type").and_then(Value::as_str) {
        Some("FeatureCollection") => v
            .get("features")
            .and_then(Value::as_array)
            .ok_or_else(|| {
                err(
                    Location::File,
                    malformed("a FeatureCollection needs a \"features\" array"),
                )
            })?
            .iter()
            .enumerate()
            .map(|(i, f)| (i, f.get("geometry").unwrap_or(&Value::Null)))
            .collect(),
        Some("Feature") => vec![(0, v.get("geometry").unwrap_or(&Value::Null))],
        _ => vec![(0, &v)],
    };
    let mut area = Area::new();
    for (i, g) in geometries {
        let at = Location::Feature(i);
        let kind = g.get("type").and_then(Value::as_str).unwrap_or("");
        let coords = g.get("coordinates");
        let polygons: Vec<&Value> = match (kind, coords) {
            ("Polygon", Some(c)) => vec![c],
            ("MultiPolygon", Some(Value::Array(ps))) => ps.iter().collect(),
            ("Polygon" | "MultiPolygon", _) => {
                return Err(err(at, malformed("geometry without valid coordinates")))
            }
            (other, _) => return Err(err(at, LoadErrorKind::NotAnArea(other.to_string()))),
        };
        for p in polygons {
            let outer = p
                .as_array()
                .and_then(|rings| rings.first())
                .and_then(Value::as_array)
                .ok_or_else(|| err(at.clone(), malformed("a polygon needs an outer ring")))?;
            let mut ring = Vec::with_capacity(outer.len());
            for pt in outer {
                let xy = pt.as_array().filter(|a| a.len() >= 2).ok_or_else(|| {
                    err(at.clone(), malformed("a position needs at least x and y"))
                })?;
                let num = |k: usize, what: &str| -> Result<f64, LoadError> {
                    let x = xy[k].as_f64().ok_or_else(|| {
                        err(at.clone(), malformed("a coordinate is not a number"))
                    })?;
                    check_coord(x, what).map_err(|kind| err(at.clone(), kind))
                };
                ring.push(DVec2::new(num(0, "x")? - origin.x, num(1, "y")? - origin.y));
            }
            if ring.len() < 3 {
                return Err(err(at, malformed("a ring needs at least 3 positions")));
            }
            area.push(ring);
        }
    }
    if area.is_empty() {
        return Err(err(
            Location::File,
            malformed("no polygon: the walkable area is empty"),
        ));
    }
    Ok(area)
}

fn malformed(message: &str) -> LoadErrorKind {
    LoadErrorKind::Malformed {
        format: "walkable-area GeoJSON",
        message: message.into(),
    }
}

/// Whether the rectangle `[x0, y0, x1, y1]` meets the area (its boundary counts): a ring vertex
/// inside the rectangle, the rectangle's centre inside a ring (crossing count), or a ring edge
/// crossing a rectangle edge. Floating point; near-ties make a cell count as meeting.
pub fn rect_meets_area(r: [f64; 4], area: &Area) -> bool {
    let inside_rect = |p: DVec2| p.x >= r[0] && p.x <= r[2] && p.y >= r[1] && p.y <= r[3];
    let corners = [
        DVec2::new(r[0], r[1]),
        DVec2::new(r[2], r[1]),
        DVec2::new(r[2], r[3]),
        DVec2::new(r[0], r[3]),
    ];
    let centre = (corners[0] + corners[2]) * 0.5;
    area.iter().any(|ring| {
        if ring.iter().any(|&p| inside_rect(p)) {
            return true;
        }
        let n = ring.len();
        let mut inside = false;
        for i in 0..n {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            if (a.y > centre.y) != (b.y > centre.y) {
                let x = a.x + (centre.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if x > centre.x {
                    inside = !inside;
                }
            }
            for k in 0..4 {
                if segments_meet(a, b, corners[k], corners[(k + 1) % 4]) {
                    return true;
                }
            }
        }
        inside
    })
}

fn segments_meet(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let o = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    let (d1, d2, d3, d4) = (o(a, b, c), o(a, b, d), o(c, d, a), o(c, d, b));
    d1 * d2 <= 0.0 && d3 * d4 <= 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_meeting_an_l_shaped_area() {
        // An L: the bottom row and the left column of a 3 x 3 grid of 10 m cells.
        let area = vec![vec![
            DVec2::new(1.0, 1.0),
            DVec2::new(29.0, 1.0),
            DVec2::new(29.0, 9.0),
            DVec2::new(9.0, 9.0),
            DVec2::new(9.0, 29.0),
            DVec2::new(1.0, 29.0),
        ]];
        let meets = |i: f64, j: f64| {
            rect_meets_area(
                [10.0 * i, 10.0 * j, 10.0 * i + 10.0, 10.0 * j + 10.0],
                &area,
            )
        };
        assert!(meets(0.0, 0.0) && meets(1.0, 0.0) && meets(2.0, 0.0));
        assert!(meets(0.0, 1.0) && meets(0.0, 2.0));
        assert!(!meets(1.0, 1.0) && !meets(2.0, 2.0) && !meets(1.0, 2.0));
        // A cell wholly inside a big area.
        let big = vec![vec![
            DVec2::new(-100.0, -100.0),
            DVec2::new(100.0, -100.0),
            DVec2::new(0.0, 100.0),
        ]];
        assert!(rect_meets_area([-5.0, -5.0, 5.0, 5.0], &big));
    }
}
