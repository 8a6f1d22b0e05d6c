//! CityGML 2.0 reader (quick-xml), for LoD1 to LoD4 buildings.
//!
//! Input: the bytes of a `.gml`/`.xml` CityGML document (root `CityModel`). Output: one
//! [`Mesh`] per `bldg:Building` and `bldg:BuildingPart` that has geometry, in document order,
//! through the same path as CityJSON (solid prisms where closed, walls from vertical faces).
//! What is read: every `gml:Polygon`, `gml:Triangle`, `gml:PolygonPatch` and `gml:Rectangle`
//! (exterior then interior `gml:LinearRing`s, coordinates in `gml:posList` or `gml:pos`, in 3D,
//! or in 2D with z = 0 where `srsDimension` says so) inside a `lodN...` property of the object
//! (`lod2Solid`, `lod2MultiSurface`, `lod1Solid`, the `lod2MultiSurface` of its `boundedBy`
//! thematic surfaces, openings; LoD 0 outlines and curves give no faces); `xlink:href`
//! references to polygons (`#id`) count as that polygon, and a polygon reached twice (directly
//! and through a solid's reference) counts once. A `BuildingPart` is an object of its own, not a
//! part of its parent's mesh. LoD: `--lod` when given (its integer part), else the highest the
//! object has. Other city objects (`Road`, `TINRelief`, ...) are counted by type. The CRS is the
//! first `srsName` in the document.
//! Invariants: coordinates are range-checked as they are read; a syntax error names its line and
//! column, a bad coordinate list its line; vertices are welded per object by exact position;
//! never panics.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::Path;

use glam::DVec3;
use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;

use super::error::check_coord;
use super::{
    Crs, Face, FileRead, LoadError, LoadErrorKind, Location, Mesh, RawObject, ReadOptions, Shape,
    SkipReason, Skipped,
};

const FORMAT: &str = "CityGML";

/// A polygon as read: its rings of 3D points (closing point dropped).
struct Poly {
    rings: Vec<Vec<DVec3>>,
}

/// One geometry entry of an object, in document order.
enum Item {
    /// Index into the document's polygons.
    Poly(usize),
    /// A reference to a polygon by id.
    Href(String),
}

struct Obj {
    id: String,
    feature: u32,
    line: usize,
    items: Vec<(u8, Item)>,
    has_parts: bool,
    kind: &'static str,
}

/// The LoD of a property element's local name (`lod2Solid` -> 2), if it is one.
fn lod_of(name: &[u8]) -> Option<u8> {
    match name {
        [b'l', b'o', b'd', d, ..] if d.is_ascii_digit() => Some(d - b'0'),
        _ => None,
    }
}

fn attr(e: &BytesStart, local: &[u8]) -> Option<String> {
    e.attributes().flatten().find_map(|a| {
        (a.key.local_name().as_ref() == local)
            .then(|| a.unescape_value().ok().map(|v| v.into_owned()))
            .flatten()
    })
}

/// Reads a CityGML document. See the module header.
pub fn read_citygml(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<FileRead, LoadError> {
    let line_of = |pos: u64| -> usize {
        let pos = (pos as usize).min(bytes.len());
        1 + bytes[..pos].iter().filter(|&&b| b == b'\n').count()
    };
    let malformed = |pos: u64, message: String| {
        LoadError::new(
            path,
            Location::Line {
                line: line_of(pos),
                column: None,
            },
            LoadErrorKind::Malformed {
                format: FORMAT,
                message,
            },
        )
    };
    let mut r = Reader::from_reader(bytes);
    // Element stack: (local name, LoD in effect, srsDimension in effect).
    let mut stack: Vec<(Vec<u8>, Option<u8>, usize)> = Vec::new();
    let mut objs: Vec<Obj> = Vec::new();
    let mut open_objs: Vec<usize> = Vec::new();
    let mut polys: Vec<Poly> = Vec::new();
    let mut by_id: HashMap<String, usize> = HashMap::new();
    let mut cur_poly: Option<(Option<String>, Vec<Vec<DVec3>>)> = None;
    let mut cur_ring: Option<Vec<DVec3>> = None;
    let mut text: Option<String> = None;
    let mut crs: Option<Crs> = None;
    let mut items = 0u32;
    let mut other_types: BTreeMap<String, usize> = BTreeMap::new();
    let mut root_checked = false;
    loop {
        let pos = r.buffer_position();
        let ev = r.read_event().map_err(|e| {
            let at = r.error_position();
            let line = line_of(at);
            let col = {
                let p = (at as usize).min(bytes.len());
                p - bytes[..p]
                    .iter()
                    .rposition(|&b| b == b'\n')
                    .map_or(0, |i| i + 1)
                    + 1
            };
            LoadError::new(
                path,
                Location::Line {
                    line,
                    column: Some(col),
                },
                LoadErrorKind::Malformed {
                    format: "XML",
                    message: e.to_string(),
                },
            )
        })?;
        let (start, empty) = match &ev {
            Event::Start(e) => (Some(e), false),
            Event::Empty(e) => (Some(e), true),
            _ => (None, false),
        };
        if let Some(e) = start {
            let name = e.local_name().as_ref().to_vec();
            if !root_checked {
                root_checked = true;
                if name != b"CityModel" {
                    return Err(malformed(
                        pos,
                        format!(
                            "the root element is {:?}, not a CityGML CityModel",
                            String::from_utf8_lossy(&name)
                        ),
                    ));
                }
            }
            if crs.is_none() {
                if let Some(s) = attr(e, b"srsName") {
                    crs = Some(Crs::parse(&s));
                }
            }
            let (parent_lod, parent_dim) = stack.last().map_or((None, 3), |s| (s.1, s.2));
            let lod = lod_of(&name).or(parent_lod);
            let dim = attr(e, b"srsDimension")
                .and_then(|d| d.trim().parse().ok())
                .filter(|d| *d == 2 || *d == 3)
                .unwrap_or(parent_dim);
            let parent_name = stack.last().map(|s| s.0.as_slice());
            match name.as_slice() {
                b"Building" | b"BuildingPart" => {
                    if let Some(&p) = open_objs.last() {
                        if name == b"BuildingPart" {
                            objs[p].has_parts = true;
                        }
                    }
                    let kind = if name == b"Building" {
                        "Building"
                    } else {
                        "BuildingPart"
                    };
                    objs.push(Obj {
                        id: attr(e, b"id").unwrap_or_else(|| format!("{kind} {}", objs.len())),
                        feature: items,
                        line: line_of(pos),
                        items: Vec::new(),
                        has_parts: false,
                        kind,
                    });
                    items += 1;
                    if !empty {
                        open_objs.push(objs.len() - 1);
                    }
                }
                other if parent_name == Some(b"cityObjectMember".as_slice()) => {
                    *other_types
                        .entry(String::from_utf8_lossy(other).into_owned())
                        .or_default() += 1;
                    items += 1;
                }
                b"Polygon" | b"Triangle" | b"PolygonPatch" | b"Rectangle" => {
                    cur_poly = Some((attr(e, b"id"), Vec::new()));
                }
                b"LinearRing" => cur_ring = Some(Vec::new()),
                b"posList" | b"pos" => text = Some(String::new()),
                _ => {}
            }
            // A reference to a polygon inside an object's geometry.
            if let (Some(l), Some(&o)) = (lod, open_objs.last()) {
                if let Some(h) = attr(e, b"href") {
                    if l >= 1 && cur_poly.is_none() {
                        objs[o]
                            .items
                            .push((l, Item::Href(h.trim_start_matches('#').to_string())));
                    }
                }
            }
            if !empty {
                stack.push((name, lod, dim));
            } else if name == b"Building" || name == b"BuildingPart" {
                // An empty element: nothing inside.
            }
            continue;
        }
        match ev {
            Event::Text(t) => {
                if let Some(s) = text.as_mut() {
                    s.push_str(&String::from_utf8_lossy(&t));
                }
            }
            Event::End(e) => {
                let Some((name, lod, dim)) = stack.pop() else {
                    return Err(malformed(pos, "an end tag without its start".into()));
                };
                if name.as_slice() != e.local_name().as_ref() {
                    return Err(malformed(pos, "an end tag that does not match".into()));
                }
                match name.as_slice() {
                    b"posList" | b"pos" => {
                        let t = text.take().unwrap_or_default();
                        let mut nums = Vec::new();
                        for w in t.split_ascii_whitespace() {
                            let v: f64 = w.parse().map_err(|_| {
                                malformed(
                                    pos,
                                    format!("{w:?} in a coordinate list is not a number"),
                                )
                            })?;
                            nums.push(v);
                        }
                        if nums.len() % dim != 0 {
                            return Err(malformed(
                                pos,
                                format!(
                                    "{} numbers in a coordinate list of dimension {dim}",
                                    nums.len()
                                ),
                            ));
                        }
                        if let Some(ring) = cur_ring.as_mut() {
                            for c in nums.chunks(dim) {
                                let z = if dim == 3 { c[2] } else { 0.0 };
                                let p = [c[0], c[1], z];
                                for (k, v) in p.iter().enumerate() {
                                    check_coord(*v, ["x", "y", "z"][k]).map_err(|kind| {
                                        LoadError::new(
                                            path,
                                            Location::Line {
                                                line: line_of(pos),
                                                column: None,
                                            },
                                            kind,
                                        )
                                    })?;
                                }
                                ring.push(DVec3::from(p));
                            }
                        }
                    }
                    b"LinearRing" => {
                        if let (Some(mut ring), Some((_, rings))) =
                            (cur_ring.take(), cur_poly.as_mut())
                        {
                            if ring.len() > 1 && ring.first() == ring.last() {
                                ring.pop();
                            }
                            rings.push(ring);
                        }
                    }
                    b"Polygon" | b"Triangle" | b"PolygonPatch" | b"Rectangle" => {
                        if let Some((id, rings)) = cur_poly.take() {
                            let k = polys.len();
                            polys.push(Poly { rings });
                            if let Some(id) = id {
                                by_id.entry(id).or_insert(k);
                            }
                            if let (Some(l), Some(&o)) = (lod, open_objs.last()) {
                                if l >= 1 {
                                    objs[o].items.push((l, Item::Poly(k)));
                                }
                            }
                        }
                    }
                    b"Building" | b"BuildingPart" => {
                        open_objs.pop();
                    }
                    _ => {}
                }
            }
            Event::Eof => {
                if let Some((open, _, _)) = stack.last() {
                    return Err(malformed(
                        pos,
                        format!(
                            "the document ends inside <{}> (truncated?)",
                            String::from_utf8_lossy(open)
                        ),
                    ));
                }
                break;
            }
            _ => {}
        }
    }
    if !root_checked {
        return Err(malformed(0, "no element: not a CityGML document".into()));
    }

    let wanted: Option<u8> = opts
        .lod
        .as_deref()
        .and_then(|l| l.trim().parse::<f64>().ok())
        .filter(|l| (0.0..10.0).contains(l))
        .map(|l| l as u8);
    let mut out = FileRead {
        items: items as usize,
        crs,
        other_types,
        ..FileRead::default()
    };
    for o in &objs {
        let at = Location::CityObject(o.id.clone());
        let resolve = |it: &Item| match it {
            Item::Poly(k) => Some(*k),
            Item::Href(h) => by_id.get(h).copied(),
        };
        let lods: HashSet<u8> = o
            .items
            .iter()
            .filter(|(_, it)| resolve(it).is_some())
            .map(|(l, _)| *l)
            .collect();
        for l in &lods {
            out.lods.insert(l.to_string());
        }
        if lods.is_empty() {
            let label = if o.has_parts {
                format!("{} (geometry in parts)", o.kind)
            } else {
                format!("{} (no geometry)", o.kind)
            };
            *out.other_types.entry(label).or_default() += 1;
            continue;
        }
        let lod = match wanted {
            Some(w) => w,
            None => lods.iter().copied().max().unwrap_or(0),
        };
        let mut seen = HashSet::new();
        let mut mesh = Mesh::default();
        let mut weld: HashMap<[u64; 3], u32> = HashMap::new();
        for (l, it) in &o.items {
            if *l != lod {
                continue;
            }
            let Some(k) = resolve(it) else { continue };
            if !seen.insert(k) {
                continue;
            }
            let mut rings = Vec::new();
            for ring in &polys[k].rings {
                let idx: Vec<u32> = ring
                    .iter()
                    .map(|p| {
                        let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
                        let next = mesh.vertices.len() as u32;
                        let i = *weld.entry(key).or_insert(next);
                        if i == next {
                            mesh.vertices.push(*p);
                        }
                        i
                    })
                    .collect();
                if !idx.is_empty() {
                    rings.push(idx);
                }
            }
            if !rings.is_empty() {
                mesh.faces.push(Face { rings });
            }
        }
        if mesh.faces.is_empty() {
            out.skipped.push(Skipped {
                location: at,
                name: o.id.clone(),
                reason: SkipReason::NoGeometryAtLod(lod.to_string()),
                feature: o.feature,
                outline: Vec::new(),
            });
            continue;
        }
        let _ = o.line;
        out.objects.push(RawObject {
            name: o.id.clone(),
            location: at,
            feature: o.feature,
            shape: Shape::Mesh(mesh),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const DOC: &str = r##"<?xml version="1.0" encoding="UTF-8"?>
<core:CityModel xmlns:core="http://www.opengis.net/citygml/2.0" xmlns:bldg="http://www.opengis.net/citygml/building/2.0" xmlns:gml="http://www.opengis.net/gml" xmlns:xlink="http://www.w3.org/1999/xlink">
 <gml:boundedBy><gml:Envelope srsName="urn:ogc:def:crs,crs:EPSG::28992,crs:EPSG::5109" srsDimension="3"/></gml:boundedBy>
 <core:cityObjectMember>
  <bldg:Building gml:id="b1">
   <bldg:lod2Solid><gml:Solid><gml:exterior><gml:CompositeSurface>
     <gml:surfaceMember xlink:href="#p1"/>
     <gml:surfaceMember><gml:Polygon gml:id="p2"><gml:exterior><gml:LinearRing>
       <gml:pos>0 0 0</gml:pos><gml:pos>1 0 0</gml:pos><gml:pos>1 0 3</gml:pos><gml:pos>0 0 0</gml:pos>
     </gml:LinearRing></gml:exterior></gml:Polygon></gml:surfaceMember>
   </gml:CompositeSurface></gml:exterior></gml:Solid></bldg:lod2Solid>
   <bldg:boundedBy><bldg:WallSurface><bldg:lod2MultiSurface><gml:MultiSurface><gml:surfaceMember>
     <gml:Polygon gml:id="p1"><gml:exterior><gml:LinearRing><gml:posList>0 0 0 0 1 0 0 1 3 0 0 0</gml:posList></gml:LinearRing></gml:exterior></gml:Polygon>
   </gml:surfaceMember></gml:MultiSurface></bldg:lod2MultiSurface></bldg:WallSurface></bldg:boundedBy>
   <bldg:consistsOfBuildingPart><bldg:BuildingPart gml:id="bp1">
     <bldg:lod1Solid><gml:Solid><gml:exterior><gml:CompositeSurface><gml:surfaceMember>
       <gml:Polygon><gml:exterior><gml:LinearRing><gml:posList>5 5 0 6 5 0 6 6 0 5 5 0</gml:posList></gml:LinearRing></gml:exterior></gml:Polygon>
     </gml:surfaceMember></gml:CompositeSurface></gml:exterior></gml:Solid></bldg:lod1Solid>
   </bldg:BuildingPart></bldg:consistsOfBuildingPart>
  </bldg:Building>
 </core:cityObjectMember>
 <core:cityObjectMember><tran:Road xmlns:tran="x" gml:id="r1"/></core:cityObjectMember>
</core:CityModel>"##;

    #[test]
    fn reads_solids_references_and_parts() {
        let r = read_citygml(Path::new("t.gml"), DOC.as_bytes(), &ReadOptions::default()).unwrap();
        assert_eq!(r.items, 3);
        assert_eq!(r.crs.as_ref().unwrap().epsg, Some(28992));
        let names: Vec<&str> = r.objects.iter().map(|o| o.name.as_str()).collect();
        assert_eq!(names, ["b1", "bp1"]);
        let Shape::Mesh(m) = &r.objects[0].shape else {
            panic!()
        };
        // p1 through the reference first, then p2; p1 again in boundedBy counts once.
        assert_eq!(m.faces.len(), 2);
        assert_eq!(m.vertices.len(), 5);
        assert_eq!(r.other_types["Road"], 1);
        assert_eq!(r.objects[1].feature, 1);
    }

    #[test]
    fn errors_name_the_line() {
        let bad = DOC.replace("1 0 3", "1 0 x");
        let e =
            read_citygml(Path::new("t.gml"), bad.as_bytes(), &ReadOptions::default()).unwrap_err();
        assert!(matches!(e.location, Location::Line { line: 9, .. }), "{e}");
        let bad = DOC.replace("</bldg:lod2Solid>", "");
        let e =
            read_citygml(Path::new("t.gml"), bad.as_bytes(), &ReadOptions::default()).unwrap_err();
        assert!(matches!(e.location, Location::Line { .. }), "{e}");
        let e = read_citygml(Path::new("t.xml"), b"<a/>", &ReadOptions::default()).unwrap_err();
        assert!(e.to_string().contains("CityModel"), "{e}");
    }
}
