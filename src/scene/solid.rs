//! Solid extraction: convex 2.5D prisms proven to lie inside a closed mesh.
//!
//! Input: a polygon-face [`Mesh`] in local coordinates (values up to a few km).
//! Output: rectangles (strictly convex, counter-clockwise, local XY) each with a base and a top,
//! such that the prism `rectangle x [base, top]` is certainly inside the solid the mesh bounds;
//! or why there is none ([`NoBlocker::OpenMesh`], [`NoBlocker::NoProvableInterior`]).
//!
//! Invariant, and the argument for it (paper 004's idea, in 2.5D): a prism that is not really
//! inside would hide visible objects, so every step errs towards claiming less.
//!
//! 1. *Closedness.* Vertices are welded by bit-identical position. Every undirected edge of
//!    every face ring (zero-length edges skipped) must occur an even number of times; otherwise
//!    the mesh is open and nothing is claimed. With even counts the faces form a cycle mod 2, so
//!    the parity of crossings of any ray avoiding the edges tells inside from outside.
//!    One exception: when every odd edge lies in the horizontal plane z0 of the mesh's lowest
//!    vertex (a building with no floor face), add the cap: the horizontal face at z0 whose rings
//!    are those edges. The capped mesh is closed mod 2 and is what the walls and roof enclose.
//!    A mesh lying wholly in that plane (a lone triangle, a flat footprint group) gets no cap: it
//!    encloses nothing and is reported open.
//!    The cap never changes an answer below: every gap tested lies between face z-ranges, so
//!    above z0, and the upward ray of step 3 never reaches z0. So the cap need not be built.
//! 2. *Columns.* In a frame rotated to the object's dominant horizontal direction, a square grid
//!    of columns covers the footprint. Each face's bounding box in that frame, grown by
//!    [`ROTATION_MARGIN_M`] to absorb the rounding of the rotation, contains every rendering of
//!    the face (any triangulation of its vertices lies in their convex hull). The face's z-range
//!    is pushed into every column whose closed square that box meets, unless an edge normal of
//!    the face separates the square from the face's vertices by more than that margin (separating
//!    axes: disjoint projections on any axis mean disjoint sets, so this only drops columns the
//!    face's hull cannot reach; it keeps slanted walls out of interior columns). The direction
//!    of the frame only affects how much is proven, never soundness. Between the merged z-ranges
//!    of a column lie open gaps; the gap prism (column square x gap) meets no face box, so no
//!    surface point: the prism is connected and entirely inside or entirely outside.
//! 3. *One exact ray per gap.* Take the column centre `c` (rotated back; any point of the column
//!    would do) and, for each face of the column, its crossing parity `w_f(c)` from exact
//!    predicates on its projected rings in the original local coordinates (XOR over rings). If
//!    `c` lies on any projected ring edge, the column is skipped. A face of the column lies
//!    entirely above or entirely below a gap. Replace each face above by "vertical curtain from
//!    its rings up to a height H above everything + the flat region of odd winding at H", and
//!    each face below by the same going down. Each replacement differs from the face by a closed
//!    chain inside the face's box extended vertically away from the gap, a convex set that
//!    misses the gap prism, so the parity of gap points is unchanged. An upward ray from the gap
//!    now meets no curtain (c is on no projected edge) and meets exactly the caps at H of faces
//!    above with odd `w_f(c)`. Odd count: inside. Vertical faces project to zero area and have
//!    `w_f = 0` off their edges, so they are never counted.
//! 4. *Blockers.* Per column the lowest inside gap is kept. Columns merge greedily into
//!    rectangles (runs along rows, then equal runs stacked), whose range is the intersection of
//!    its columns' ranges, and only when that loses at most [`MERGE_HEIGHT_TOLERANCE_M`] of any
//!    column's height: shrinking is conservative. Rectangles are shrunk by
//!    [`SHRINK_MARGIN_M`] before their corners are rotated back, so rounding never pushes them
//!    out of the proven columns; a result that is not strictly convex after rounding is dropped.
//!
//! Work is capped at [`MAX_COLUMNS_PER_AXIS`]² columns per object.

use std::collections::HashMap;

use glam::{DVec2, DVec3};

use super::{Mesh, NoBlocker};
use crate::geom::predicates::{is_strictly_convex_ccw, point_in_ring, Containment};

/// A convex prism proven to lie inside a closed mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct SolidPiece {
    pub polygon: Vec<DVec2>,
    pub base: f64,
    pub top: f64,
}

/// Most columns along either axis of the grid.
pub const MAX_COLUMNS_PER_AXIS: usize = 48;
/// Smallest column side, metres.
pub const MIN_COLUMN_M: f64 = 0.25;
/// Growth of each face's box in the rotated frame, metres: far above the rounding of rotating
/// coordinates of a few km (about 1e-12 m).
pub const ROTATION_MARGIN_M: f64 = 1.0e-6;
/// Inward shrink of each output rectangle before rotating it back, metres.
pub const SHRINK_MARGIN_M: f64 = 1.0e-6;
/// Largest height a column may lose when merged into a rectangle, metres.
pub const MERGE_HEIGHT_TOLERANCE_M: f64 = 1.0;

/// The rotated frame: `u = x cos + y sin`, `v = -x sin + y cos`.
#[derive(Clone, Copy)]
struct Frame {
    cos: f64,
    sin: f64,
}

impl Frame {
    fn to_uv(self, p: DVec2) -> DVec2 {
        DVec2::new(
            p.x * self.cos + p.y * self.sin,
            -p.x * self.sin + p.y * self.cos,
        )
    }
    fn to_xy(self, q: DVec2) -> DVec2 {
        DVec2::new(
            q.x * self.cos - q.y * self.sin,
            q.x * self.sin + q.y * self.cos,
        )
    }
}

fn key(p: DVec3) -> [u64; 3] {
    // `+ 0.0` turns -0.0 into 0.0 so both weld.
    [
        (p.x + 0.0).to_bits(),
        (p.y + 0.0).to_bits(),
        (p.z + 0.0).to_bits(),
    ]
}

/// Edges used an odd number of times, with vertices welded by exact position: their count, and
/// whether every one of them lies in the plane of the mesh's lowest vertex (a missing floor).
/// `None` when a face refers to a vertex that does not exist.
fn odd_edges(mesh: &Mesh) -> Option<(usize, bool)> {
    let mut weld: HashMap<[u64; 3], u32> = HashMap::new();
    let ids: Vec<u32> = mesh
        .vertices
        .iter()
        .map(|&p| {
            let n = weld.len() as u32;
            *weld.entry(key(p)).or_insert(n)
        })
        .collect();
    let mut edges: HashMap<(u32, u32), (u32, [usize; 2])> = HashMap::new();
    let mut zmin = f64::INFINITY;
    for f in &mesh.faces {
        for ring in &f.rings {
            let n = ring.len();
            for k in 0..n {
                let (ia, ib) = (ring[k] as usize, ring[(k + 1) % n] as usize);
                let a = *ids.get(ia)?;
                let b = *ids.get(ib)?;
                zmin = zmin.min(mesh.vertices[ia].z);
                if a != b {
                    edges.entry((a.min(b), a.max(b))).or_insert((0, [ia, ib])).0 += 1;
                }
            }
        }
    }
    let odd: Vec<[usize; 2]> = edges
        .values()
        .filter(|(c, _)| c % 2 == 1)
        .map(|&(_, e)| e)
        .collect();
    let at_base = odd
        .iter()
        .all(|e| mesh.vertices[e[0]].z == zmin && mesh.vertices[e[1]].z == zmin);
    Some((odd.len(), at_base))
}

/// Lowest z of the vertices the faces use.
fn mesh_zmin(mesh: &Mesh) -> f64 {
    mesh.faces
        .iter()
        .flat_map(|f| f.rings.iter().flatten())
        .map(|&i| mesh.vertices[i as usize].z)
        .fold(f64::INFINITY, f64::min)
}

/// Width of the direction histogram bins, degrees.
const ANGLE_BIN_DEG: f64 = 1.0;

/// The object's dominant horizontal direction, folded into [0, 90): edge directions (slope under
/// 45 degrees) are binned mod 90 degrees, weighted by horizontal length, and the longest edge of
/// the heaviest bin gives the angle. Triangulation diagonals scatter over many bins, while the
/// walls and eaves of a building pile up in one. Any angle is sound; this one makes columns
/// follow walls.
fn dominant_angle(mesh: &Mesh) -> f64 {
    let nbins = (90.0 / ANGLE_BIN_DEG) as usize;
    let mut weight = vec![0.0f64; nbins];
    let mut longest = vec![(0.0f64, 0.0f64); nbins];
    for f in &mesh.faces {
        for ring in &f.rings {
            let n = ring.len();
            for k in 0..n {
                let (Some(a), Some(b)) = (
                    mesh.vertices.get(ring[k] as usize),
                    mesh.vertices.get(ring[(k + 1) % n] as usize),
                ) else {
                    continue;
                };
                let d = *b - *a;
                let h = d.x.hypot(d.y);
                if !(h > 0.0 && d.z.abs() < h) {
                    continue;
                }
                let ang = d.y.atan2(d.x).rem_euclid(std::f64::consts::FRAC_PI_2);
                let bin = ((ang.to_degrees() / ANGLE_BIN_DEG) as usize).min(nbins - 1);
                weight[bin] += h;
                if h > longest[bin].0 {
                    longest[bin] = (h, ang);
                }
            }
        }
    }
    let best = (0..nbins).fold(0, |b, k| if weight[k] > weight[b] { k } else { b });
    longest[best].1
}

/// Most edge normals of one face used as separating axes (any subset of axes is sound).
const MAX_AXES_PER_FACE: usize = 32;

struct FaceInfo {
    lo: DVec2,
    hi: DVec2,
    zmin: f64,
    zmax: f64,
}

/// Pieces of certainly solid space inside `mesh`. See the module header.
pub fn solid_pieces(mesh: &Mesh) -> Result<Vec<SolidPiece>, NoBlocker> {
    let Some((odd, at_base)) = odd_edges(mesh) else {
        return Err(NoBlocker::NoProvableInterior);
    };
    // A mesh open only along edges in the plane of its lowest vertex (extruded footprints
    // without a floor, as in Delft's LoD1) is closed by the floor cap those edges bound; see the
    // module header, step 1.
    let floor_cap = (odd > 0).then(|| mesh_zmin(mesh));
    // A mesh lying wholly in that plane (a lone triangle, a flat footprint) is no building
    // without a floor: it is open, and bounds no volume.
    let flat = floor_cap.is_some_and(|z0| {
        mesh.faces
            .iter()
            .flat_map(|f| f.rings.iter().flatten())
            .all(|&i| mesh.vertices[i as usize].z == z0)
    });
    if odd > 0 && (!at_base || flat) {
        return Err(NoBlocker::OpenMesh {
            boundary_edges: odd,
        });
    }
    let theta = dominant_angle(mesh);
    let frame = Frame {
        cos: theta.cos(),
        sin: theta.sin(),
    };

    // Every vertex in the rotated frame; face boxes there, and the footprint extent.
    let uv: Vec<DVec2> = mesh
        .vertices
        .iter()
        .map(|p| frame.to_uv(p.truncate()))
        .collect();
    let mut infos: Vec<FaceInfo> = Vec::with_capacity(mesh.faces.len());
    let (mut emin, mut emax) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for f in &mesh.faces {
        let mut fi = FaceInfo {
            lo: DVec2::splat(f64::INFINITY),
            hi: DVec2::splat(f64::NEG_INFINITY),
            zmin: f64::INFINITY,
            zmax: f64::NEG_INFINITY,
        };
        for &i in f.rings.iter().flatten() {
            // Indices were checked by `odd_edges`.
            let q = uv[i as usize];
            let z = mesh.vertices[i as usize].z;
            fi.lo = fi.lo.min(q);
            fi.hi = fi.hi.max(q);
            fi.zmin = fi.zmin.min(z);
            fi.zmax = fi.zmax.max(z);
        }
        if fi.lo.x <= fi.hi.x && fi.lo.y <= fi.hi.y {
            emin = emin.min(fi.lo);
            emax = emax.max(fi.hi);
            fi.lo -= DVec2::splat(ROTATION_MARGIN_M);
            fi.hi += DVec2::splat(ROTATION_MARGIN_M);
        }
        // A face without vertices keeps an empty box and touches no column.
        infos.push(fi);
    }
    if !(emin.x < emax.x && emin.y < emax.y) {
        return Err(NoBlocker::NoProvableInterior);
    }
    let ext = emax - emin;
    let side = (ext.x.max(ext.y) / MAX_COLUMNS_PER_AXIS as f64).max(MIN_COLUMN_M);
    let cells = |e: f64| ((e / side).ceil() as usize).clamp(1, MAX_COLUMNS_PER_AXIS);
    let (nu, nv) = (cells(ext.x), cells(ext.y));
    // Column edges, computed by one formula everywhere (tests and output alike).
    let u_at = |i: usize| emin.x + i as f64 * side;
    let v_at = |j: usize| emin.y + j as f64 * side;

    // Faces per column: those whose vertices' convex hull (which holds any rendering of the
    // face) may meet the closed column square. Candidates come from the grown box; a candidate
    // is dropped only when the projections of the face's vertices and of the square's corners on
    // some edge normal of the face are apart by more than ROTATION_MARGIN_M (separating axis: the
    // sets are then disjoint, whatever the shape of the face). All quantities are relative to
    // `emin`, so rounding stays near 1e-12 m, far under the margin.
    let mut cols: Vec<Vec<u32>> = vec![Vec::new(); nu * nv];
    let range = |lo: f64, hi: f64, origin: f64, n: usize, at: &dyn Fn(usize) -> f64| {
        let a = ((lo - origin) / side).floor() - 1.0;
        let b = ((hi - origin) / side).floor() + 1.0;
        let a = a.max(0.0).min(n as f64) as usize;
        let b = b.max(-1.0).min(n as f64 - 1.0);
        let mut out = Vec::new();
        if b >= 0.0 {
            for i in a..=(b as usize) {
                if lo <= at(i + 1) && hi >= at(i) {
                    out.push(i);
                }
            }
        }
        out
    };
    let mut axes: Vec<(DVec2, f64, f64)> = Vec::new();
    for (fi_idx, (fi, face)) in infos.iter().zip(&mesh.faces).enumerate() {
        if !(fi.lo.x <= fi.hi.x) {
            continue;
        }
        let us = range(fi.lo.x, fi.hi.x, emin.x, nu, &u_at);
        let vs = range(fi.lo.y, fi.hi.y, emin.y, nv, &v_at);
        if us.is_empty() || vs.is_empty() {
            continue;
        }
        axes.clear();
        if us.len() * vs.len() > 4 {
            'edges: for ring in &face.rings {
                let n = ring.len();
                for k in 0..n {
                    if axes.len() >= MAX_AXES_PER_FACE {
                        break 'edges;
                    }
                    let d = uv[ring[(k + 1) % n] as usize] - uv[ring[k] as usize];
                    let len = d.length();
                    if !(len > 0.0) {
                        continue;
                    }
                    let nrm = d.perp() / len;
                    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
                    for &i in face.rings.iter().flatten() {
                        let t = (uv[i as usize] - emin).dot(nrm);
                        lo = lo.min(t);
                        hi = hi.max(t);
                    }
                    axes.push((nrm, lo, hi));
                }
            }
        }
        for &j in &vs {
            for &i in &us {
                let corners = [
                    DVec2::new(u_at(i), v_at(j)) - emin,
                    DVec2::new(u_at(i + 1), v_at(j)) - emin,
                    DVec2::new(u_at(i + 1), v_at(j + 1)) - emin,
                    DVec2::new(u_at(i), v_at(j + 1)) - emin,
                ];
                let separated = axes.iter().any(|&(nrm, lo, hi)| {
                    let ts = corners.map(|c| c.dot(nrm));
                    let smin = ts.iter().copied().fold(f64::INFINITY, f64::min);
                    let smax = ts.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    smin > hi + ROTATION_MARGIN_M || smax < lo - ROTATION_MARGIN_M
                });
                if !separated {
                    cols[j * nu + i].push(fi_idx as u32);
                }
            }
        }
    }

    // Projected rings in original local coordinates, for the exact parity tests.
    let rings2d: Vec<Vec<Vec<DVec2>>> = mesh
        .faces
        .iter()
        .map(|f| {
            f.rings
                .iter()
                .map(|r| {
                    r.iter()
                        .map(|&i| mesh.vertices[i as usize].truncate())
                        .collect()
                })
                .collect()
        })
        .collect();

    // Per column: the lowest gap proven inside.
    let mut solid: Vec<Option<(f64, f64)>> = vec![None; nu * nv];
    for j in 0..nv {
        for i in 0..nu {
            let faces = &cols[j * nu + i];
            if faces.len() + usize::from(floor_cap.is_some()) < 2 {
                continue;
            }
            let centre = frame.to_xy(DVec2::new(
                (u_at(i) + u_at(i + 1)) * 0.5,
                (v_at(j) + v_at(j + 1)) * 0.5,
            ));
            // Crossing parity of each face at the centre; give up on the column if the centre
            // is on a projected edge.
            let mut odd_faces: Vec<u32> = Vec::new();
            let mut on_edge = false;
            'faces: for &f in faces {
                let mut w = false;
                for ring in &rings2d[f as usize] {
                    if ring.is_empty() {
                        continue;
                    }
                    match point_in_ring(ring, centre) {
                        Containment::Boundary => {
                            on_edge = true;
                            break 'faces;
                        }
                        Containment::Inside => w = !w,
                        Containment::Outside => {}
                    }
                }
                if w {
                    odd_faces.push(f);
                }
            }
            if on_edge {
                continue;
            }
            // Merge the closed z-ranges; open gaps lie between them.
            let mut zs: Vec<(f64, f64)> = faces
                .iter()
                .map(|&f| (infos[f as usize].zmin, infos[f as usize].zmax))
                .collect();
            // The implicit floor cap (step 1), pushed into every column: an extra range only
            // splits gaps, and the cap lies below every gap, so no ray reaches it.
            zs.extend(floor_cap.map(|z0| (z0, z0)));
            zs.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut merged: Vec<(f64, f64)> = Vec::new();
            for (lo, hi) in zs {
                match merged.last_mut() {
                    Some(last) if lo <= last.1 => last.1 = last.1.max(hi),
                    _ => merged.push((lo, hi)),
                }
            }
            for w in merged.windows(2) {
                let (lo, hi) = (w[0].1, w[1].0);
                // Every face of the column is entirely above or below (lo, hi).
                let above = odd_faces
                    .iter()
                    .filter(|&&f| infos[f as usize].zmin >= hi)
                    .count();
                if above % 2 == 1 {
                    solid[j * nu + i] = Some((lo, hi));
                    break;
                }
            }
        }
    }
    if solid.iter().all(|s| s.is_none()) {
        return Err(NoBlocker::NoProvableInterior);
    }

    // Greedy rectangles.
    let fits = |range: (f64, f64), col: (f64, f64)| {
        range.1 > range.0 && (col.1 - col.0) - (range.1 - range.0) <= MERGE_HEIGHT_TOLERANCE_M
    };
    let mut used = vec![false; nu * nv];
    let mut pieces = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let Some(first) = solid[j * nu + i].filter(|_| !used[j * nu + i]) else {
                continue;
            };
            let mut range = first;
            let mut members = vec![first];
            // Run along the row.
            let mut i1 = i;
            while i1 + 1 < nu {
                let k = j * nu + i1 + 1;
                let Some(c) = solid[k].filter(|_| !used[k]) else {
                    break;
                };
                let r = (range.0.max(c.0), range.1.min(c.1));
                if !members.iter().chain([&c]).all(|&m| fits(r, m)) {
                    break;
                }
                range = r;
                members.push(c);
                i1 += 1;
            }
            // Stack equal runs.
            let mut j1 = j;
            'rows: while j1 + 1 < nv {
                let row: Vec<(f64, f64)> = (i..=i1)
                    .map(|ii| {
                        let k = (j1 + 1) * nu + ii;
                        solid[k].filter(|_| !used[k])
                    })
                    .collect::<Option<_>>()
                    .unwrap_or_default();
                if row.len() != i1 - i + 1 {
                    break 'rows;
                }
                let r = row.iter().fold(range, |r, c| (r.0.max(c.0), r.1.min(c.1)));
                if !members.iter().chain(row.iter()).all(|&m| fits(r, m)) {
                    break 'rows;
                }
                range = r;
                members.extend(row);
                j1 += 1;
            }
            for jj in j..=j1 {
                for ii in i..=i1 {
                    used[jj * nu + ii] = true;
                }
            }
            let (u0, u1) = (u_at(i) + SHRINK_MARGIN_M, u_at(i1 + 1) - SHRINK_MARGIN_M);
            let (v0, v1) = (v_at(j) + SHRINK_MARGIN_M, v_at(j1 + 1) - SHRINK_MARGIN_M);
            if !(u0 < u1 && v0 < v1) {
                continue;
            }
            let polygon: Vec<DVec2> = [(u0, v0), (u1, v0), (u1, v1), (u0, v1)]
                .iter()
                .map(|&(u, v)| frame.to_xy(DVec2::new(u, v)))
                .collect();
            if !is_strictly_convex_ccw(&polygon) {
                continue;
            }
            pieces.push(SolidPiece {
                polygon,
                base: range.0,
                top: range.1,
            });
        }
    }
    if pieces.is_empty() {
        return Err(NoBlocker::NoProvableInterior);
    }
    Ok(pieces)
}

#[cfg(test)]
mod tests;
