//! Tests of solid extraction ([`super`]): closed boxes covered by their pieces, open meshes
//! refused, L-shaped prisms kept out of the notch, rotated boxes, gable roofs, degenerate meshes,
//! and real meshes' pieces against a brute-force inside test.
//!
//! Input: small meshes built here and the bundled samples. Output: pass or fail.
//! Invariant: a claimed piece is checked against the mesh, never against the extraction.

use super::*;
use crate::geom::predicates::{orient, point_in_convex, Orientation};
use crate::scene::Face;

/// A prism over a simple CCW polygon `base` from z0 to z1, with the given top heights per
/// vertex (a flat top when `tops` is None). Walls are quads, caps are single polygons.
fn prism(base: &[DVec2], z0: f64, tops: &[f64]) -> Mesh {
    let n = base.len();
    let mut vertices = Vec::new();
    for p in base {
        vertices.push(DVec3::new(p.x, p.y, z0));
    }
    for (k, p) in base.iter().enumerate() {
        vertices.push(DVec3::new(p.x, p.y, tops[k]));
    }
    let mut faces = vec![
        Face {
            rings: vec![(0..n as u32).rev().collect()],
        },
        Face {
            rings: vec![(n as u32..2 * n as u32).collect()],
        },
    ];
    for k in 0..n as u32 {
        let k1 = (k + 1) % n as u32;
        faces.push(Face {
            rings: vec![vec![k, k1, k1 + n as u32, k + n as u32]],
        });
    }
    Mesh { vertices, faces }
}

fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<DVec2> {
    vec![
        DVec2::new(x0, y0),
        DVec2::new(x1, y0),
        DVec2::new(x1, y1),
        DVec2::new(x0, y1),
    ]
}

/// Independent inside test: fan-triangulates every face and counts the triangles strictly
/// above `p` whose projection strictly contains it. `None` if the ray grazes an edge.
fn inside_brute(mesh: &Mesh, p: DVec3) -> Option<bool> {
    let q = p.truncate();
    let mut count = 0;
    for f in &mesh.faces {
        let r = &f.rings[0];
        for k in 1..r.len() - 1 {
            let t = [r[0], r[k], r[k + 1]].map(|i| mesh.vertices[i as usize]);
            let t2 = t.map(|v| v.truncate());
            let tri = match orient(t2[0], t2[1], t2[2]) {
                Orientation::Collinear => continue,
                Orientation::Ccw => vec![t2[0], t2[1], t2[2]],
                Orientation::Cw => vec![t2[0], t2[2], t2[1]],
            };
            match point_in_convex(&tri, q) {
                Containment::Outside => continue,
                Containment::Boundary => return None,
                Containment::Inside => {}
            }
            // Height of the triangle's plane at q (float: test-only, points are generic).
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            let z = t[0].z - (n.x * (q.x - t[0].x) + n.y * (q.y - t[0].y)) / n.z;
            if z > p.z {
                count += 1;
            }
        }
    }
    Some(count % 2 == 1)
}

/// Samples each piece prism (corners, edges, interior) and asserts every sample is inside.
fn assert_pieces_inside(mesh: &Mesh, pieces: &[SolidPiece]) {
    assert!(!pieces.is_empty());
    let fr = [0.0137, 0.25, 0.5, 0.75, 0.9871];
    for pc in pieces {
        assert!(is_strictly_convex_ccw(&pc.polygon));
        assert!(pc.top > pc.base);
        let [a, b, _, d] = [pc.polygon[0], pc.polygon[1], pc.polygon[2], pc.polygon[3]];
        for &s in &fr {
            for &t in &fr {
                for &h in &fr {
                    let xy = a + (b - a) * s + (d - a) * t;
                    let z = pc.base + (pc.top - pc.base) * h;
                    if let Some(inside) = inside_brute(mesh, DVec3::new(xy.x, xy.y, z)) {
                        assert!(inside, "sample {xy:?} z {z} of {pc:?} is outside");
                    }
                }
            }
        }
    }
}

fn area(p: &[DVec2]) -> f64 {
    (0..p.len())
        .map(|i| p[i].perp_dot(p[(i + 1) % p.len()]))
        .sum::<f64>()
        / 2.0
}

#[test]
fn closed_box_gives_covering_pieces() {
    let m = prism(&rect(0.0, 0.0, 10.0, 6.0), 1.0, &[9.0; 4]);
    // The checker itself tells inside from outside.
    assert_eq!(inside_brute(&m, DVec3::new(5.1, 3.1, 5.0)), Some(true));
    assert_eq!(inside_brute(&m, DVec3::new(5.1, 3.1, 9.5)), Some(false));
    assert_eq!(inside_brute(&m, DVec3::new(5.1, 3.1, 0.5)), Some(false));
    assert_eq!(inside_brute(&m, DVec3::new(10.1, 3.1, 5.0)), Some(false));
    let pieces = solid_pieces(&m).unwrap();
    assert_pieces_inside(&m, &pieces);
    let covered: f64 = pieces.iter().map(|p| area(&p.polygon)).sum();
    assert!(covered > 0.8 * 60.0, "covered {covered}");
    for p in &pieces {
        assert!(p.base >= 1.0 && p.top <= 9.0);
        for c in &p.polygon {
            assert!(c.x > 0.0 && c.x < 10.0 && c.y > 0.0 && c.y < 6.0);
        }
    }
}

#[test]
fn open_box_is_rejected() {
    let mut m = prism(&rect(0.0, 0.0, 10.0, 6.0), 0.0, &[5.0; 4]);
    m.faces.remove(1);
    assert_eq!(
        solid_pieces(&m),
        Err(NoBlocker::OpenMesh { boundary_edges: 4 })
    );
}

#[test]
fn box_without_floor_is_capped_but_without_roof_is_open() {
    let mut floorless = prism(&rect(0.0, 0.0, 10.0, 6.0), 0.0, &[5.0; 4]);
    floorless.faces.remove(0);
    let pieces = solid_pieces(&floorless).unwrap();
    assert_pieces_inside(&floorless, &pieces);
    for p in &pieces {
        assert!(p.base >= 0.0 && p.top <= 5.0);
    }
    // Odd edges at the top are not a missing floor.
    let mut roofless = prism(&rect(0.0, 0.0, 10.0, 6.0), 0.0, &[5.0; 4]);
    roofless.faces.remove(1);
    assert!(matches!(
        solid_pieces(&roofless),
        Err(NoBlocker::OpenMesh { .. })
    ));
    // The open edges must lie at the lowest vertex: a floorless box with a (closed,
    // two-sided) fin reaching below its walls stays open.
    let mut sunk = floorless.clone();
    sunk.vertices.push(DVec3::new(5.0, 3.0, -1.0));
    sunk.faces.push(Face {
        rings: vec![vec![0, 1, 8]],
    });
    sunk.faces.push(Face {
        rings: vec![vec![1, 0, 8]],
    });
    assert!(matches!(
        solid_pieces(&sunk),
        Err(NoBlocker::OpenMesh { .. })
    ));
}

#[test]
fn l_prism_pieces_stay_out_of_the_notch() {
    let l = vec![
        DVec2::new(0.0, 0.0),
        DVec2::new(20.0, 0.0),
        DVec2::new(20.0, 5.0),
        DVec2::new(5.0, 5.0),
        DVec2::new(5.0, 15.0),
        DVec2::new(0.0, 15.0),
    ];
    let m = prism(&l, 0.0, &[7.0; 6]);
    let pieces = solid_pieces(&m).unwrap();
    assert_pieces_inside(&m, &pieces);
    for p in &pieces {
        for c in &p.polygon {
            assert_eq!(point_in_ring(&l, *c), Containment::Inside);
        }
        assert!(p.base >= 0.0 && p.top <= 7.0);
    }
    let covered: f64 = pieces.iter().map(|p| area(&p.polygon)).sum();
    assert!(covered > 0.7 * 150.0, "covered {covered}");
}

#[test]
fn rotated_box_pieces_inside() {
    let (s, c) = 20f64.to_radians().sin_cos();
    let base: Vec<DVec2> = rect(0.0, 0.0, 12.0, 4.0)
        .into_iter()
        .map(|p| DVec2::new(1000.0 + p.x * c - p.y * s, 2000.0 + p.x * s + p.y * c))
        .collect();
    let m = prism(&base, 3.0, &[11.0; 4]);
    let pieces = solid_pieces(&m).unwrap();
    assert_pieces_inside(&m, &pieces);
    for p in &pieces {
        for q in &p.polygon {
            assert_eq!(point_in_ring(&base, *q), Containment::Inside);
        }
    }
    // The frame follows the box: a few rectangles cover most of it.
    let covered: f64 = pieces.iter().map(|p| area(&p.polygon)).sum();
    assert!(covered > 0.8 * 48.0, "covered {covered}");
}

#[test]
fn gable_roof_pieces_stay_under_the_roof() {
    // A house 10 x 8: walls to 4 m, ridge at 7 m along x at y = 4.
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let vertices = vec![
        v(0., 0., 0.),
        v(10., 0., 0.),
        v(10., 8., 0.),
        v(0., 8., 0.),
        v(0., 0., 4.),
        v(10., 0., 4.),
        v(10., 8., 4.),
        v(0., 8., 4.),
        v(0., 4., 7.),
        v(10., 4., 7.),
    ];
    let f = |r: &[u32]| Face {
        rings: vec![r.to_vec()],
    };
    let faces = vec![
        f(&[3, 2, 1, 0]),
        f(&[0, 1, 5, 4]),
        f(&[1, 2, 6, 9, 5]),
        f(&[2, 3, 7, 6]),
        f(&[3, 0, 4, 8, 7]),
        f(&[4, 5, 9, 8]),
        f(&[6, 7, 8, 9]),
    ];
    let m = Mesh { vertices, faces };
    let pieces = solid_pieces(&m).unwrap();
    assert_pieces_inside(&m, &pieces);
    for p in &pieces {
        assert!(p.base >= 0.0 && p.top <= 4.0 + 1e-9, "{p:?}");
    }
}

#[test]
fn degenerate_meshes_give_no_blocker() {
    assert_eq!(
        solid_pieces(&Mesh::default()),
        Err(NoBlocker::NoProvableInterior)
    );
    // A flat closed "pillow": two coincident squares.
    let m = Mesh {
        vertices: rect(0.0, 0.0, 1.0, 1.0)
            .into_iter()
            .map(|p| p.extend(0.0))
            .collect(),
        faces: vec![
            Face {
                rings: vec![vec![0, 1, 2, 3]],
            },
            Face {
                rings: vec![vec![3, 2, 1, 0]],
            },
        ],
    };
    assert_eq!(solid_pieces(&m), Err(NoBlocker::NoProvableInterior));
    // Bad index.
    let m = Mesh {
        vertices: vec![DVec3::ZERO],
        faces: vec![Face {
            rings: vec![vec![0, 5, 6]],
        }],
    };
    assert!(solid_pieces(&m).is_err());
}

/// Every piece of every object of the real mesh datasets passes the independent sampling
/// check: Den Haag (closed LoD2), Delft (LoD1 without floors, capped) and Gelderseplein
/// (open footprint groups, overlapping LoD groups).
#[test]
fn real_mesh_pieces_pass_the_brute_force_check() {
    use crate::scene::{load, ReadOptions, Shape};
    for (rel, min_pieces) in [
        ("data/denhaag/DenHaag_01_buildings.obj", 5000),
        ("data/delft/delft_buildings.obj", 160),
        ("data/gelderseplein/gelderseplein.obj", 1000),
    ] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
        let scene = load(&[path], &ReadOptions::default()).unwrap();
        let mut by_object: Vec<Vec<SolidPiece>> = vec![Vec::new(); scene.objects.len()];
        // The solid prisms (walls, 2-vertex blockers, are checked in tests/walls.rs).
        for b in scene.blockers.iter().filter(|b| b.polygon.len() > 2) {
            by_object[b.object as usize].push(SolidPiece {
                polygon: b.polygon.clone(),
                base: b.base,
                top: b.top,
            });
        }
        for (o, pieces) in scene.objects.iter().zip(&by_object) {
            let Shape::Mesh(m) = &o.shape else { panic!() };
            if !pieces.is_empty() {
                assert_pieces_inside(m, pieces);
            }
        }
        assert!(
            scene.blockers.len() >= min_pieces,
            "{rel}: {}",
            scene.blockers.len()
        );
    }
}
