//! OpenStreetMap PBF reader (the `osmpbf` crate).
//!
//! Input: the bytes of a `.osm.pbf` extract. Output: one footprint per building, in file order:
//! first the closed ways tagged `building` (any value but `no`), then the multipolygon relations
//! tagged `building`, whose outer and inner rings are assembled from their member ways (joined
//! end to end by node id; each inner ring goes with the outer ring that holds its first point,
//! by the exact point-in-ring predicate). Coordinates are WGS84 longitude/latitude: the file
//! reports EPSG:4326 and `load` projects it ([`super::crs`]).
//! Heights, by the footprint reader's rules ([`super::geojson::HeightKeys`]) with OpenStreetMap's
//! tags: `height` (else `building:height`) less `roof:height` (else `roof:levels` storeys), the
//! solid part standing to the eaves; else `building:levels` storeys (`--storey-height`, which
//! count no roof); else `--default-height`; the bottom at `min_height`, else
//! `building:min_level` storeys. Values may carry units (`"12 m"`, `"40 ft"`). Buildings without
//! any are skipped and counted, with a note naming `--default-height` when they are many.
//! `building:part` ways are not read (a building's outline stands for its parts).
//! Skipped with their reason: ways and relations whose nodes or member ways lie outside the
//! extract, rings that do not close.
//! Invariants: three passes over the bytes (relations, ways, nodes) keep only what buildings use;
//! never panics.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use glam::DVec2;
use osmpbf::{Element, ElementReader, RelMemberType};
use serde_json::{Map, Value};

use super::crs::{Crs, CrsSource};
use super::geojson::{FootprintReader, HeightKeys};
use super::{FileRead, LoadError, LoadErrorKind, Location, ReadOptions, Ring, SkipReason};
use crate::geom::predicates::{point_in_ring, Containment};

const FORMAT: &str = "OpenStreetMap PBF";

/// The tags heights are read from.
pub fn osm_keys() -> HeightKeys {
    HeightKeys {
        height: vec!["height".into(), "building:height".into()],
        base: None,
        levels: Some("building:levels".into()),
        min_height: Some("min_height".into()),
        min_levels: Some("building:min_level".into()),
        roof_height: Some("roof:height".into()),
        roof_levels: Some("roof:levels".into()),
    }
}

fn is_building<'a>(mut tags: impl Iterator<Item = (&'a str, &'a str)>) -> bool {
    tags.any(|(k, v)| k == "building" && v != "no")
}

fn tag_map<'a>(tags: impl Iterator<Item = (&'a str, &'a str)>) -> Map<String, Value> {
    tags.map(|(k, v)| (k.to_string(), Value::String(v.to_string())))
        .collect()
}

struct Relation {
    id: i64,
    tags: Map<String, Value>,
    /// (way id, inner)
    members: Vec<(i64, bool)>,
}

/// Reads an OpenStreetMap PBF extract. See the module header.
///
/// osmpbf 0.3.7 panics on a relation member of an unknown type (its `RelMemberType::from`
/// unwraps the protobuf enum; found by fuzzing, `tests/fixtures/broken/osm_fuzz_*`): the passes
/// run under `catch_unwind`, and such a panic is a malformed-file error like any other. (Under
/// cargo-fuzz, whose panic hook aborts, that input still shows as a crash.)
pub fn read_pbf(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<FileRead, LoadError> {
    match std::panic::catch_unwind(|| read_pbf_inner(path, bytes, opts)) {
        Ok(r) => r,
        Err(p) => {
            let why = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic".into());
            Err(LoadError::new(
                path,
                Location::File,
                LoadErrorKind::Malformed {
                    format: FORMAT,
                    message: format!("the PBF decoder (osmpbf) failed: {why}"),
                },
            ))
        }
    }
}

fn read_pbf_inner(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<FileRead, LoadError> {
    let malformed = |e: osmpbf::Error| {
        LoadError::new(
            path,
            Location::File,
            LoadErrorKind::Malformed {
                format: FORMAT,
                message: e.to_string(),
            },
        )
    };
    // Pass 1: building multipolygons and the ways they need.
    let mut relations: Vec<Relation> = Vec::new();
    ElementReader::new(bytes)
        .for_each(|e| {
            if let Element::Relation(r) = e {
                let multipolygon = r.tags().any(|(k, v)| k == "type" && v == "multipolygon");
                if multipolygon && is_building(r.tags()) {
                    let members = r
                        .members()
                        .filter(|m| m.member_type == RelMemberType::Way)
                        .map(|m| (m.member_id, m.role().map(|s| s == "inner").unwrap_or(false)))
                        .collect();
                    relations.push(Relation {
                        id: r.id(),
                        tags: tag_map(r.tags()),
                        members,
                    });
                }
            }
        })
        .map_err(malformed)?;
    let member_ways: HashSet<i64> = relations
        .iter()
        .flat_map(|r| r.members.iter().map(|m| m.0))
        .collect();
    // Pass 2: building ways, and member ways.
    let mut buildings: Vec<(i64, Map<String, Value>, Vec<i64>)> = Vec::new();
    let mut refs: HashMap<i64, Vec<i64>> = HashMap::new();
    ElementReader::new(bytes)
        .for_each(|e| {
            if let Element::Way(w) = e {
                let building = is_building(w.tags());
                let member = member_ways.contains(&w.id());
                if building || member {
                    let r: Vec<i64> = w.refs().collect();
                    if member {
                        refs.insert(w.id(), r.clone());
                    }
                    if building {
                        buildings.push((w.id(), tag_map(w.tags()), r));
                    }
                }
            }
        })
        .map_err(malformed)?;
    let wanted: HashSet<i64> = buildings
        .iter()
        .flat_map(|b| b.2.iter().copied())
        .chain(refs.values().flatten().copied())
        .collect();
    // Pass 3: the nodes they use.
    let mut nodes: HashMap<i64, DVec2> = HashMap::with_capacity(wanted.len());
    ElementReader::new(bytes)
        .for_each(|e| {
            let (id, lon, lat) = match e {
                Element::Node(n) => (n.id(), n.lon(), n.lat()),
                Element::DenseNode(n) => (n.id(), n.lon(), n.lat()),
                _ => return,
            };
            if wanted.contains(&id) {
                nodes.insert(id, DVec2::new(lon, lat));
            }
        })
        .map_err(malformed)?;

    let mut reader = FootprintReader::with_keys(path, opts, FORMAT, osm_keys());
    let ring_of = |ids: &[i64]| -> Result<Ring, String> {
        let missing = ids.iter().filter(|i| !nodes.contains_key(i)).count();
        if missing > 0 {
            return Err(format!(
                "{missing} of its {} nodes are not in the extract",
                ids.len()
            ));
        }
        Ok(ids.iter().map(|i| nodes[i]).collect())
    };
    for (id, tags, r) in &buildings {
        let at = Location::Element(format!("way {id}"));
        let name = Some(format!("way {id}"));
        match ring_of(r) {
            Ok(ring) => reader.item(at, name, tags, Ok(vec![vec![ring]]))?,
            Err(why) => {
                reader.skip_item(at, format!("way {id}"), SkipReason::IncompleteGeometry(why))
            }
        }
    }
    for rel in &relations {
        let at = Location::Element(format!("relation {}", rel.id));
        let name = format!("relation {}", rel.id);
        match assemble(rel, &refs).and_then(|(outer, inner)| {
            let outer: Vec<Ring> = outer.iter().map(|r| ring_of(r)).collect::<Result<_, _>>()?;
            let inner: Vec<Ring> = inner.iter().map(|r| ring_of(r)).collect::<Result<_, _>>()?;
            Ok(nest(outer, inner))
        }) {
            Ok(polygons) => reader.item(at, Some(name), &rel.tags, Ok(polygons))?,
            Err(why) => reader.skip_item(at, name, SkipReason::IncompleteGeometry(why)),
        }
    }
    reader.set_crs(Some(Crs::wgs84(CrsSource::File)));
    reader.finish()
}

/// Joins a relation's member ways into closed rings of node ids: (outer, inner).
type Rings = (Vec<Vec<i64>>, Vec<Vec<i64>>);

fn assemble(rel: &Relation, refs: &HashMap<i64, Vec<i64>>) -> Result<Rings, String> {
    let mut out: Rings = (Vec::new(), Vec::new());
    for inner in [false, true] {
        let mut ways: Vec<&[i64]> = Vec::new();
        for (w, is_inner) in &rel.members {
            if *is_inner != inner {
                continue;
            }
            match refs.get(w) {
                Some(r) if r.len() >= 2 => ways.push(r),
                Some(_) => {}
                None => return Err(format!("member way {w} is not in the extract")),
            }
        }
        let mut used = vec![false; ways.len()];
        for start in 0..ways.len() {
            if used[start] {
                continue;
            }
            used[start] = true;
            let mut ring: Vec<i64> = ways[start].to_vec();
            while ring.first() != ring.last() {
                let end = *ring.last().unwrap_or(&0);
                let next = (0..ways.len()).find(|&k| {
                    !used[k] && (ways[k].first() == Some(&end) || ways[k].last() == Some(&end))
                });
                let Some(k) = next else {
                    return Err(format!(
                        "an {} ring does not close (it ends at node {end})",
                        if inner { "inner" } else { "outer" }
                    ));
                };
                used[k] = true;
                if ways[k].first() == Some(&end) {
                    ring.extend_from_slice(&ways[k][1..]);
                } else {
                    ring.extend(ways[k].iter().rev().skip(1));
                }
            }
            if inner {
                out.1.push(ring);
            } else {
                out.0.push(ring);
            }
        }
    }
    if out.0.is_empty() {
        return Err("no outer ring".into());
    }
    Ok(out)
}

/// Polygons from outer and inner rings: each inner ring goes with the first outer ring that holds
/// its first point (else with the first outer ring, where validation will reject it).
fn nest(outer: Vec<Ring>, inner: Vec<Ring>) -> Vec<Vec<Ring>> {
    let mut polygons: Vec<Vec<Ring>> = outer.into_iter().map(|r| vec![r]).collect();
    for hole in inner {
        let Some(&p) = hole.first() else { continue };
        let k = polygons
            .iter()
            .position(|poly| point_in_ring(&poly[0], p) == Containment::Inside)
            .unwrap_or(0);
        polygons[k].push(hole);
    }
    polygons
}
