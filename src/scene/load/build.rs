//! The load's build stage, per object: footprints repaired and split into convex blockers,
//! meshes into solid prisms and walls, with the object's box and cost in the local frame.
//!
//! Input: one raw object (already in the scene's local frame) with its index and file. Output:
//! the [`Object`], its blockers, and what was repaired, skipped or could give no blocker.
//! Invariant: a function of the object alone, so objects build in parallel and collect in index
//! order (the scene is the same for any thread count).

use super::*;

/// One object built: the object, its blockers, the ring repairs made (polygon, ring, what) and
/// why parts of it could give no blocker.
pub(super) struct Built {
    pub(super) object: Object,
    pub(super) blockers: Vec<Blocker>,
    pub(super) repairs: Vec<(usize, usize, RingRepair)>,
    pub(super) no_blocker: Vec<NoBlocker>,
}

pub(super) fn build_object(index: u32, file: u32, raw: RawObject) -> Built {
    let mut repairs = Vec::new();
    let mut no_blocker = Vec::new();
    let mut blockers = Vec::new();
    let shape = match raw.shape {
        Shape::Footprint(fp) => {
            let mut polygons = Vec::with_capacity(fp.polygons.len());
            for (pi, rings) in fp.polygons.into_iter().enumerate() {
                let fixed = footprint::repair_polygon(&rings);
                repairs.extend(fixed.repairs.iter().map(|&(r, k)| (pi, r, k)));
                match fixed.result {
                    Err((ring, why)) => {
                        no_blocker.push(NoBlocker::InvalidRing {
                            polygon: pi,
                            ring,
                            why,
                        });
                        polygons.push(rings);
                    }
                    Ok(valid) => {
                        if fp.top > fp.base {
                            match decompose::convex_pieces(&valid) {
                                Ok(pieces) => {
                                    blockers.extend(pieces.into_iter().map(|polygon| Blocker {
                                        object: index,
                                        polygon,
                                        base: fp.base,
                                        top: fp.top,
                                    }))
                                }
                                Err(e) => no_blocker.push(NoBlocker::Triangulation(e.to_string())),
                            }
                        }
                        polygons.push(valid);
                    }
                }
            }
            if fp.top <= fp.base {
                no_blocker.push(NoBlocker::NoHeight);
            }
            Shape::Footprint(Footprint {
                polygons,
                base: fp.base,
                top: fp.top,
            })
        }
        Shape::Mesh(mesh) => {
            // Solid prisms where the mesh is closed, walls from its vertical faces in any case.
            let solid = solid::solid_pieces(&mesh);
            if let Ok(pieces) = &solid {
                blockers.extend(pieces.iter().map(|p| Blocker {
                    object: index,
                    polygon: p.polygon.clone(),
                    base: p.base,
                    top: p.top,
                }));
            }
            blockers.extend(walls::wall_pieces(&mesh).into_iter().map(|w| Blocker {
                object: index,
                polygon: vec![w.a, w.b],
                base: w.base,
                top: w.top,
            }));
            if blockers.is_empty() {
                no_blocker.push(match solid {
                    Err(why) => why,
                    Ok(_) => NoBlocker::NoProvableInterior,
                });
            }
            Shape::Mesh(mesh)
        }
    };
    Built {
        object: Object {
            index,
            file,
            feature: raw.feature,
            name: raw.name,
            location: raw.location,
            bbox: shape_bbox(&shape),
            cost: shape_cost(&shape),
            shape,
        },
        blockers,
        repairs,
        no_blocker,
    }
}

/// Bounding box of a shape in its own coordinates.
pub fn shape_bbox(shape: &Shape) -> Aabb3 {
    let mut b = Aabb3::EMPTY;
    match shape {
        Shape::Footprint(fp) => {
            for p in fp.polygons.iter().flatten().flatten() {
                b.include(DVec3::new(p.x, p.y, fp.base));
                b.include(DVec3::new(p.x, p.y, fp.top));
            }
        }
        Shape::Mesh(m) => {
            // Only vertices that faces use: stray vertices are not geometry.
            for f in &m.faces {
                for &i in f.rings.iter().flatten() {
                    if let Some(&v) = m.vertices.get(i as usize) {
                        b.include(v);
                    }
                }
            }
        }
    }
    b
}

/// Triangle count. A polygon with V vertices over all its rings and H holes triangulates into
/// V + 2H - 2 triangles; a footprint prism has two such caps and two triangles per wall edge.
pub fn shape_cost(shape: &Shape) -> u64 {
    let poly = |v: usize, h: usize| (v + 2 * h).saturating_sub(2) as u64;
    match shape {
        Shape::Footprint(fp) => fp
            .polygons
            .iter()
            .map(|rings| {
                let v: usize = rings.iter().map(|r| r.len()).sum();
                let h = rings.len().saturating_sub(1);
                2 * poly(v, h) + 2 * v as u64
            })
            .sum(),
        Shape::Mesh(m) => m
            .faces
            .iter()
            .map(|f| {
                let v: usize = f.rings.iter().map(|r| r.len()).sum();
                poly(v, f.rings.len().saturating_sub(1))
            })
            .sum(),
    }
}

pub(super) fn translate(shape: &mut Shape, d: DVec3) {
    match shape {
        Shape::Footprint(fp) => {
            let d2 = DVec2::new(d.x, d.y);
            for p in fp.polygons.iter_mut().flatten().flatten() {
                *p += d2;
            }
            fp.base += d.z;
            fp.top += d.z;
        }
        Shape::Mesh(m) => {
            for v in &mut m.vertices {
                *v += d;
            }
        }
    }
}
