//! CityJSON reader (versions 0.3 to 0.9, 1.0, 1.1 and 2.0: [`SUPPORTED_VERSIONS`]).
//!
//! Input: a parsed CityJSON document. Output: one [`RawObject`] per `Building` or `BuildingPart`
//! (and per object of the types `ReadOptions::types` adds, such as `Bridge` or an extension's
//! `+GenericCityObject`)
//! that has geometry at the chosen level of detail, in the file order of `CityObjects`; each is a
//! [`Mesh`] in world f64 coordinates (`transform` applied) over only its own vertices, one
//! [`Face`] per surface with its rings (ring 0 outer, the rest holes).
//! Other city object types, and buildings whose geometry lives in their parts, are counted in
//! [`FileRead::other_types`]; buildings with geometry but none usable are [`Skipped`].
//! Invariants:
//! - every vertex of the file is checked with [`check_coord`] after the transform, and a bad one
//!   fails the file at [`Location::Vertex`];
//! - vertex indices and boundary nesting are checked; a violation fails the file at the city
//!   object; an unknown geometry type fails it too;
//! - LoD: `ReadOptions::lod` if given (compared numerically, or as text when not a number),
//!   otherwise the highest LoD the object has; all geometries at that LoD go into one mesh;
//! - nothing here panics on bad input.

use std::collections::HashMap;
use std::path::Path;

use glam::DVec3;
use serde_json::Value;

use super::error::check_coord;
use super::{
    Face, FileRead, LoadError, LoadErrorKind, Location, Mesh, RawObject, ReadOptions, Shape,
    SkipReason, Skipped,
};

const FORMAT: &str = "CityJSON";

/// Reads a CityJSON document. See the module header.
pub fn read_cityjson(path: &Path, v: &Value, opts: &ReadOptions) -> Result<FileRead, LoadError> {
    let err = |location, kind| LoadError::new(path, location, kind);
    let malformed = |location, message: String| {
        LoadError::new(
            path,
            location,
            LoadErrorKind::Malformed {
                format: FORMAT,
                message,
            },
        )
    };

    // Version.
    let version = match v.get("version") {
        Some(Value::String(s)) => s.clone(),
        Some(Value::Number(n)) => n.to_string(),
        Some(other) => {
            return Err(err(
                Location::File,
                LoadErrorKind::UnsupportedVersion(other.to_string()),
            ))
        }
        None => {
            return Err(err(
                Location::File,
                LoadErrorKind::UnsupportedVersion("missing".into()),
            ))
        }
    };
    if !supported_version(&version) {
        return Err(err(
            Location::File,
            LoadErrorKind::UnsupportedVersion(version),
        ));
    }

    // Transform.
    let (scale, translate) = match v.get("transform") {
        None | Some(Value::Null) => ([1.0; 3], [0.0; 3]),
        Some(t) => {
            let triple = |key: &str| -> Result<[f64; 3], LoadError> {
                let a = t
                    .get(key)
                    .and_then(|a| a.as_array())
                    .filter(|a| a.len() == 3);
                let Some(a) = a else {
                    return Err(malformed(
                        Location::File,
                        format!("transform.{key} must be an array of 3 numbers"),
                    ));
                };
                let mut out = [0.0; 3];
                for (k, x) in a.iter().enumerate() {
                    let Some(f) = x.as_f64() else {
                        return Err(malformed(
                            Location::File,
                            format!("transform.{key}[{k}] is not a number"),
                        ));
                    };
                    out[k] = check_coord(f, &format!("transform.{key}[{k}]"))
                        .map_err(|e| err(Location::File, e))?;
                }
                Ok(out)
            };
            (triple("scale")?, triple("translate")?)
        }
    };

    // Vertices.
    let Some(raw_vertices) = v.get("vertices").and_then(|a| a.as_array()) else {
        return Err(malformed(
            Location::File,
            "\"vertices\" is missing or not an array".into(),
        ));
    };
    let mut vertices = Vec::with_capacity(raw_vertices.len());
    for (i, rv) in raw_vertices.iter().enumerate() {
        let a = rv.as_array().filter(|a| a.len() == 3);
        let Some(a) = a else {
            return Err(malformed(
                Location::Vertex(i),
                "a vertex must be an array of 3 numbers".into(),
            ));
        };
        let mut p = [0.0; 3];
        for k in 0..3 {
            let Some(f) = a[k].as_f64() else {
                return Err(malformed(
                    Location::Vertex(i),
                    format!("coordinate {k} is not a number"),
                ));
            };
            let w = f * scale[k] + translate[k];
            p[k] = check_coord(w, ["x", "y", "z"][k]).map_err(|e| err(Location::Vertex(i), e))?;
        }
        vertices.push(DVec3::new(p[0], p[1], p[2]));
    }

    let Some(city_objects) = v.get("CityObjects").and_then(|c| c.as_object()) else {
        return Err(malformed(
            Location::File,
            "\"CityObjects\" is missing or not an object".into(),
        ));
    };

    let wanted_lod = opts.lod.as_deref();
    let mut out = FileRead {
        items: city_objects.len(),
        crs: reference_system(v),
        ..FileRead::default()
    };
    for (item, (id, obj)) in city_objects.iter().enumerate() {
        let feature = item as u32;
        let at = || Location::CityObject(id.clone());
        let ty = obj
            .get("type")
            .and_then(|t| t.as_str())
            .unwrap_or("(no type)");
        if ty == "TINRelief" && !opts.no_terrain && !opts.types.iter().any(|t| t == ty) {
            // The terrain (scene/terrain.rs): every surface of its geometries, as triangles.
            let geoms: &[Value] = match obj.get("geometry") {
                Some(Value::Array(a)) => a,
                None | Some(Value::Null) => &[],
                Some(_) => return Err(malformed(at(), "\"geometry\" is not an array".into())),
            };
            let mut b = MeshBuilder {
                all: &vertices,
                map: HashMap::new(),
                mesh: Mesh::default(),
            };
            for g in geoms {
                let gty = g.get("type").and_then(|t| t.as_str()).unwrap_or("");
                let kind = match kind_of(gty) {
                    Some(k @ (Kind::Surfaces | Kind::Solid | Kind::Solids)) => k,
                    _ => continue,
                };
                let Some(bnd) = g.get("boundaries") else {
                    return Err(malformed(at(), "a geometry has no \"boundaries\"".into()));
                };
                b.geometry(bnd, kind).map_err(|m| malformed(at(), m))?;
            }
            out.terrain.extend(super::terrain::fan_triangles(&b.mesh));
            *out.other_types
                .entry("TINRelief (read as terrain)".into())
                .or_default() += 1;
            continue;
        }
        if ty != "Building" && ty != "BuildingPart" && !opts.types.iter().any(|t| t == ty) {
            *out.other_types.entry(ty.to_string()).or_default() += 1;
            continue;
        }
        let geoms: &[Value] = match obj.get("geometry") {
            None | Some(Value::Null) => &[],
            Some(Value::Array(a)) => a,
            Some(_) => return Err(malformed(at(), "\"geometry\" is not an array".into())),
        };
        if geoms.is_empty() {
            let has_children = obj
                .get("children")
                .and_then(|c| c.as_array())
                .is_some_and(|c| !c.is_empty());
            let label = if has_children {
                format!("{ty} (geometry in parts)")
            } else {
                format!("{ty} (no geometry)")
            };
            *out.other_types.entry(label).or_default() += 1;
            continue;
        }
        // Classify every geometry first, so an unknown type fails whatever LoD is asked for.
        let mut usable: Vec<(&Value, Kind, Option<&Value>)> = Vec::new();
        let mut unsupported: Option<String> = None;
        let mut not_areal: Option<String> = None;
        for g in geoms {
            let gty = g.get("type").and_then(|t| t.as_str());
            let Some(gty) = gty else {
                return Err(malformed(at(), "a geometry has no \"type\"".into()));
            };
            match kind_of(gty) {
                Some(Kind::Instance) => unsupported = Some(gty.to_string()),
                Some(Kind::NotAreal) => not_areal = Some(gty.to_string()),
                Some(k) => {
                    match g.get("lod") {
                        Some(Value::Number(n)) => out.lods.insert(n.to_string()),
                        Some(Value::String(t)) => out.lods.insert(t.trim().to_string()),
                        _ => false,
                    };
                    usable.push((g, k, g.get("lod")))
                }
                None => {
                    return Err(err(
                        at(),
                        LoadErrorKind::UnknownGeometryType(gty.to_string()),
                    ))
                }
            }
        }
        if usable.is_empty() {
            let reason = match (unsupported, not_areal) {
                (Some(t), _) => SkipReason::UnsupportedGeometry(t),
                (None, Some(t)) => SkipReason::NotAreal(t),
                (None, None) => SkipReason::EmptyGeometry,
            };
            out.skipped.push(Skipped {
                location: at(),
                name: id.clone(),
                feature,
                outline: Vec::new(),
                reason,
            });
            continue;
        }
        let chosen: Vec<(&Value, Kind)> = match wanted_lod {
            Some(want) => usable
                .iter()
                .filter(|(_, _, lod)| lod_matches(*lod, want))
                .map(|&(g, k, _)| (g, k))
                .collect(),
            None => {
                let best = usable
                    .iter()
                    .map(|(_, _, lod)| lod_number(*lod))
                    .fold(f64::NEG_INFINITY, f64::max);
                usable
                    .iter()
                    .filter(|(_, _, lod)| lod_number(*lod) == best)
                    .map(|&(g, k, _)| (g, k))
                    .collect()
            }
        };
        if chosen.is_empty() {
            out.skipped.push(Skipped {
                location: at(),
                name: id.clone(),
                feature,
                outline: Vec::new(),
                reason: SkipReason::NoGeometryAtLod(wanted_lod.unwrap_or("").to_string()),
            });
            continue;
        }
        let mut b = MeshBuilder {
            all: &vertices,
            map: HashMap::new(),
            mesh: Mesh::default(),
        };
        for (g, k) in chosen {
            let Some(bnd) = g.get("boundaries") else {
                return Err(malformed(at(), "a geometry has no \"boundaries\"".into()));
            };
            b.geometry(bnd, k).map_err(|m| malformed(at(), m))?;
        }
        if b.mesh.faces.is_empty() {
            out.skipped.push(Skipped {
                location: at(),
                name: id.clone(),
                feature,
                outline: Vec::new(),
                reason: SkipReason::EmptyGeometry,
            });
            continue;
        }
        out.objects.push(RawObject {
            name: id.clone(),
            location: at(),
            feature,
            shape: Shape::Mesh(b.mesh),
        });
    }
    Ok(out)
}

/// The CRS in `metadata.referenceSystem` (a URN or URL with an EPSG code), or `None`.
pub fn reference_system(v: &Value) -> Option<super::Crs> {
    let rs = v.get("metadata")?.get("referenceSystem")?.as_str()?;
    Some(super::Crs::parse(rs))
}

/// The versions this reader knows, as `MAJOR.MINOR` with an optional patch number: 0.3 to 0.9
/// (the oldest tested is 0.3, `tests/fixtures/cityjson/`), 1.0, 1.1 and 2.0. What the reader
/// uses (`CityObjects`, `vertices`, `transform`, geometry `type`, `lod` and `boundaries`) kept
/// its layout through all of them; older drafts and newer versions are refused.
pub const SUPPORTED_VERSIONS: &str = "0.3 to 0.9, 1.0, 1.1, 2.0";

fn supported_version(v: &str) -> bool {
    let parts: Vec<&str> = v.split('.').collect();
    if parts.len() < 2
        || parts.len() > 3
        || parts
            .iter()
            .any(|p| p.is_empty() || p.len() > 4 || !p.bytes().all(|b| b.is_ascii_digit()))
    {
        return false;
    }
    let (major, minor): (u32, u32) = match (parts[0].parse(), parts[1].parse()) {
        (Ok(a), Ok(b)) => (a, b),
        _ => return false,
    };
    matches!((major, minor), (0, 3..=9) | (1, 0) | (1, 1) | (2, 0))
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// [surface][ring][vertex]
    Surfaces,
    /// [shell][surface][ring][vertex]
    Solid,
    /// [solid][shell][surface][ring][vertex]
    Solids,
    Instance,
    NotAreal,
}

fn kind_of(t: &str) -> Option<Kind> {
    Some(match t {
        "MultiSurface" | "CompositeSurface" => Kind::Surfaces,
        "Solid" => Kind::Solid,
        "MultiSolid" | "CompositeSolid" => Kind::Solids,
        "GeometryInstance" => Kind::Instance,
        "MultiPoint" | "MultiLineString" => Kind::NotAreal,
        _ => return None,
    })
}

/// The LoD as a number for ranking: numbers as they are, strings parsed; anything else lowest.
fn lod_number(lod: Option<&Value>) -> f64 {
    match lod {
        Some(Value::Number(n)) => n.as_f64().unwrap_or(f64::NEG_INFINITY),
        Some(Value::String(s)) => s.trim().parse().unwrap_or(f64::NEG_INFINITY),
        _ => f64::NEG_INFINITY,
    }
}

/// Whether a geometry's LoD is the requested one: numerically when both are numbers ("2" = 2 =
/// "2.0"), as text otherwise.
fn lod_matches(lod: Option<&Value>, want: &str) -> bool {
    let text = match lod {
        Some(Value::Number(n)) => n.to_string(),
        Some(Value::String(s)) => s.trim().to_string(),
        _ => return false,
    };
    match (text.parse::<f64>(), want.trim().parse::<f64>()) {
        (Ok(a), Ok(b)) => a == b,
        _ => text == want.trim(),
    }
}

struct MeshBuilder<'a> {
    all: &'a [DVec3],
    /// File vertex index -> object vertex index.
    map: HashMap<usize, u32>,
    mesh: Mesh,
}

fn arr<'v>(v: &'v Value, what: &str) -> Result<&'v Vec<Value>, String> {
    v.as_array()
        .ok_or_else(|| format!("{what} must be an array (wrong boundary nesting)"))
}

impl MeshBuilder<'_> {
    fn geometry(&mut self, bnd: &Value, kind: Kind) -> Result<(), String> {
        match kind {
            Kind::Surfaces => self.surfaces(bnd),
            Kind::Solid => self.solid(bnd),
            Kind::Solids => {
                for s in arr(bnd, "boundaries")? {
                    self.solid(s)?;
                }
                Ok(())
            }
            Kind::Instance | Kind::NotAreal => Ok(()),
        }
    }

    fn solid(&mut self, v: &Value) -> Result<(), String> {
        for shell in arr(v, "a solid")? {
            self.surfaces(shell)?;
        }
        Ok(())
    }

    fn surfaces(&mut self, v: &Value) -> Result<(), String> {
        for surface in arr(v, "a shell or surface list")? {
            let mut rings = Vec::new();
            for ring in arr(surface, "a surface")? {
                let mut r = Vec::new();
                for idx in arr(ring, "a ring")? {
                    let i = idx
                        .as_u64()
                        .ok_or_else(|| format!("vertex index {idx} is not a non-negative integer (wrong boundary nesting?)"))?;
                    if i >= self.all.len() as u64 {
                        return Err(format!(
                            "vertex index {i} is out of range ({} vertices)",
                            self.all.len()
                        ));
                    }
                    let i = i as usize;
                    let next = self.mesh.vertices.len() as u32;
                    let local = *self.map.entry(i).or_insert(next);
                    if local == next {
                        self.mesh.vertices.push(self.all[i]);
                    }
                    r.push(local);
                }
                if !r.is_empty() {
                    rings.push(r);
                }
            }
            if !rings.is_empty() {
                self.mesh.faces.push(Face { rings });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn read(v: Value, lod: Option<&str>) -> Result<FileRead, LoadError> {
        let opts = ReadOptions {
            lod: lod.map(String::from),
            ..ReadOptions::default()
        };
        read_cityjson(Path::new("t.json"), &v, &opts)
    }

    fn doc(objects: Value) -> Value {
        json!({
            "type": "CityJSON", "version": "1.1",
            "transform": {"scale": [0.5, 0.5, 1.0], "translate": [100.0, 200.0, 0.0]},
            "vertices": [[0,0,0],[2,0,0],[2,2,0],[0,2,0],[0,0,3],[2,0,3],[2,2,3],[0,2,3]],
            "CityObjects": objects
        })
    }

    #[test]
    fn reads_buildings_in_order_with_lod_choice() {
        let sq = json!([[[[0, 1, 2, 3]], [[4, 5, 6, 7]]]]);
        let v = doc(json!({
            "b": {"type": "Building", "geometry": [
                {"type": "Solid", "lod": "1", "boundaries": sq},
                {"type": "MultiSurface", "lod": "2.2", "boundaries": [[[4,5,6]]]}]},
            "a": {"type": "BuildingPart", "geometry": [{"type": "Solid", "lod": 2, "boundaries": sq}]},
            "p": {"type": "Building", "children": ["a"], "geometry": []},
            "r": {"type": "Road", "geometry": []},
            "i": {"type": "Building", "geometry": [{"type": "GeometryInstance", "boundaries": [0]}]}
        }));
        let r = read(v.clone(), None).unwrap();
        assert_eq!(
            r.objects
                .iter()
                .map(|o| o.name.as_str())
                .collect::<Vec<_>>(),
            ["b", "a"]
        );
        let Shape::Mesh(m) = &r.objects[0].shape else {
            panic!()
        };
        assert_eq!(m.faces.len(), 1);
        assert_eq!(m.vertices.len(), 3);
        assert_eq!(m.vertices[1], DVec3::new(101.0, 200.0, 3.0));
        assert_eq!(r.other_types["Road"], 1);
        assert_eq!(r.other_types["Building (geometry in parts)"], 1);
        assert_eq!(r.skipped.len(), 1);
        assert!(matches!(
            r.skipped[0].reason,
            SkipReason::UnsupportedGeometry(_)
        ));
        let r = read(v.clone(), Some("1")).unwrap();
        assert_eq!(r.objects.len(), 1);
        let Shape::Mesh(m) = &r.objects[0].shape else {
            panic!()
        };
        assert_eq!(m.faces.len(), 2);
        assert_eq!(r.skipped.len(), 2);
        let r = read(v, Some("2.0")).unwrap();
        assert_eq!(r.objects.len(), 1);
        assert_eq!(r.objects[0].name, "a");
    }

    #[test]
    fn errors() {
        let e = read(doc(json!({"x": {"type": "Building", "geometry": [{"type": "Blob", "lod": 1, "boundaries": []}]}})), None).unwrap_err();
        assert_eq!(e.location, Location::CityObject("x".into()));
        assert!(matches!(e.kind, LoadErrorKind::UnknownGeometryType(_)));
        let e = read(doc(json!({"x": {"type": "Building", "geometry": [{"type": "Solid", "lod": 1, "boundaries": [[[[0,1,99]]]]}]}})), None).unwrap_err();
        assert!(matches!(e.kind, LoadErrorKind::Malformed { .. }));
        let e = read(doc(json!({"x": {"type": "Building", "geometry": [{"type": "Solid", "lod": 1, "boundaries": [[[0,1,2]]]}]}})), None).unwrap_err();
        assert!(matches!(e.kind, LoadErrorKind::Malformed { .. }));
        let mut d = doc(json!({}));
        d["version"] = json!("3.0");
        assert!(matches!(
            read(d, None).unwrap_err().kind,
            LoadErrorKind::UnsupportedVersion(_)
        ));
        let mut d = doc(json!({}));
        d["vertices"][5] = json!([0, 0, 2e9]);
        let e = read(d, None).unwrap_err();
        assert_eq!(e.location, Location::Vertex(5));
        assert!(matches!(e.kind, LoadErrorKind::OutOfRange { .. }));
    }
}
