//! Terrain: the top of the solid ground, as triangles, and the 2.5D blockers it certainly holds.
//!
//! Input: terrain triangles in world coordinates, from a GeoTIFF DEM ([`super::dem`]: two
//! triangles per square of four valid pixel centres), the `TINRelief` of a CityJSON file, or an
//! OBJ mesh (`--terrain FILE`); the scene's origin and the extent to keep.
//! Output: a [`Terrain`] in the local frame: its triangles (counter-clockwise in xy, those of no
//! area in xy dropped), an index over them, the *terrain blockers* (square columns from the
//! terrain's floor up to the least terrain height over the square, merged in a quadtree where
//! that height varies little), and the queries the bake needs: the least and greatest terrain
//! height over a rectangle ([`Terrain::range`]) and whether the terrain covers it
//! ([`Terrain::covers`]).
//!
//! ## What the terrain is, and why its blockers are solid
//! The terrain is the top of the ground: a point `(p, z)` with `p` in the union `D` of the
//! triangles (in xy) and `z` at or below the terrain's height `T(p)` over `p` (the greatest
//! height of a triangle holding `p`) is inside the ground, which is opaque. The ground truth and
//! the 3D VO check of `vocc eval` test rays against exactly this set, from the triangles
//! themselves (`src/eval/ground.rs`), never from the blockers built here.
//!
//! A terrain blocker is a square `Q` standing from the floor `f` (the least vertex height of the
//! terrain, rounded down to a metre) to `m`, the least height of the terrain over `Q` rounded
//! down. It is certainly solid when `Q` lies in `D`: every point `(p, z)` of it has `p` in `D`
//! and `z <= m <= T(p)`. `m` is computed by clipping every triangle whose box meets `Q` to `Q`
//! and taking the least height of the clipped polygon's vertices on the triangle's plane (a
//! linear function is least over a convex polygon at a vertex), less [`HEIGHT_MARGIN_M`] for
//! the rounding of the clipping, then rounded down to [`HEIGHT_STEP_M`]; a triangle steeper
//! than [`STEEP`] gives its lowest vertex instead.
//!
//! `Q` lies in `D` when no *boundary candidate* meets the closed square and `Q`'s centre lies
//! in a triangle ([`Terrain::covers`]). A boundary candidate is an edge that is not shared by
//! exactly two triangles lying on opposite sides of it (exact orientation tests; edges matched
//! by the exact xy of their ends). Proof: `D` is closed, and a point of its topological boundary
//! lies on no triangle's interior and on no edge shared by two triangles on opposite sides (the
//! two cover a neighbourhood of it), nor on a vertex all of whose edges are such (the triangles
//! around it then leave no angular gap): so it lies on a candidate. If the convex `Q` held a
//! point outside `D`, the segment from its centre (in `D`) to that point would cross the
//! boundary of `D` inside `Q`, on a candidate. Both tests are exact (`geom::predicates`).
//!
//! **Joins.** A building blocker standing from `b` to `t` over `P` whose box lies in `D` and
//! over which the terrain's least height is at least `b` stands on solid ground: the prism
//! from `f` to `b` over `P` lies in the ground (every point has `z <= b <= T(p)`), so the union
//! from `f` to `t` is solid, and the blocker's base becomes `f` ([`Terrain::join`]). The least
//! height is taken over `P` itself, not its box (on a slope a box's low corner may lie off the
//! building, [`Terrain::least_over`]): for `p` in `P`, `T(p)` is at least the height at `p` of
//! any triangle holding `p`, so at least the least, over the triangles meeting `P`, of a
//! triangle's plane over its intersection with `P` (a linear function is least over a convex
//! polygon at a vertex). The intersection is clipped in floating point: its vertices move by
//! rounding only (far below [`HEIGHT_MARGIN_M`] at slopes up to [`STEEP`]), and a triangle
//! whose clipped polygon rounding emptied though it meets `P`'s interior (an exact test) gives
//! its lowest vertex. A wall (no area) keeps its box.
//!
//! Invariants: everything is local; the blockers' squares are aligned on a power-of-two grid
//! from the terrain's minimum corner, never overlap, and each has a top above the floor;
//! nothing here panics on bad triangles (non-finite ones are refused by the readers).

use std::collections::HashMap;
use std::path::PathBuf;

use glam::{DVec2, DVec3};

use super::Blocker;
use crate::geom::predicates::{
    convex_interiors_disjoint, orient, point_in_convex, segment_meets_convex, Containment,
    Orientation,
};

/// The object id of a terrain blocker (it belongs to no object).
pub const TERRAIN_OBJECT: u32 = u32::MAX;
/// How far around the scene's objects the terrain is kept, metres (the bake reads blockers
/// within 900 m of a cell, and cells lie over the objects).
pub const TERRAIN_MARGIN_M: f64 = 1200.0;
/// Terrain blockers' tops are rounded down to this step, metres.
pub const HEIGHT_STEP_M: f64 = 0.0625;
/// Subtracted from a computed least height (added to a greatest) before rounding, metres: far
/// above the rounding of clipping a triangle of slope at most [`STEEP`].
pub const HEIGHT_MARGIN_M: f64 = 0.001;
/// A triangle steeper than this (height per horizontal metre) gives its lowest (highest) vertex
/// for the least (greatest) height over a rectangle rather than its clipped polygon's.
pub const STEEP: f64 = 100.0;
/// Squares whose least and greatest terrain heights differ by at most this much are one
/// blocker, metres.
pub const MERGE_TOLERANCE_M: f64 = 1.0;
/// At most this many terrain triangles are kept (a DEM is cropped to the scene first).
pub const MAX_TRIANGLES: usize = 8_000_000;

/// Where a terrain came from, for `vocc info`.
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainSource {
    pub path: PathBuf,
    /// "GeoTIFF DEM", "CityJSON TINRelief", "OBJ mesh".
    pub format: &'static str,
    /// Triangles kept from it.
    pub triangles: usize,
    /// Pixel size of a DEM, metres (x, y).
    pub pixel: Option<(f64, f64)>,
    /// DEM pixels with no data within the kept window.
    pub nodata: usize,
}

/// The terrain of a scene, local frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Terrain {
    pub sources: Vec<TerrainSource>,
    /// Counter-clockwise in xy, non-zero area in xy.
    pub triangles: Vec<[DVec3; 3]>,
    /// xy bounds of the triangles, and their height range.
    pub lo: DVec2,
    pub hi: DVec2,
    pub zmin: f64,
    pub zmax: f64,
    /// The floor of the terrain blockers: the least vertex height, rounded down to a metre.
    pub floor: f64,
    /// The terrain blockers (object [`TERRAIN_OBJECT`]).
    pub blockers: Vec<Blocker>,
    /// Building blockers whose base was lowered to the floor ([`Terrain::join`]).
    pub joined: usize,
    /// Area of the triangles in xy, m².
    pub area: f64,
    index: Index,
    /// Boundary candidates (module header), with their own index.
    boundary: Vec<[DVec2; 2]>,
    boundary_index: Index,
}

/// A uniform grid over a box, each cell listing the items whose box meets it.
#[derive(Clone, Debug, PartialEq)]
struct Index {
    lo: DVec2,
    cs: f64,
    nx: usize,
    ny: usize,
    starts: Vec<u32>,
    list: Vec<u32>,
}

impl Index {
    fn new(lo: DVec2, hi: DVec2, boxes: &[(DVec2, DVec2)]) -> Index {
        let (w, h) = ((hi.x - lo.x).max(1.0), (hi.y - lo.y).max(1.0));
        let mut cs = (w * h * 2.0 / boxes.len().max(1) as f64).sqrt().max(1.0);
        while (w / cs).ceil() * (h / cs).ceil() > 4.0e6 {
            cs *= 2.0;
        }
        let nx = ((w / cs).ceil() as usize).max(1);
        let ny = ((h / cs).ceil() as usize).max(1);
        let mut ix = Index {
            lo,
            cs,
            nx,
            ny,
            starts: vec![0; nx * ny + 1],
            list: Vec::new(),
        };
        let ranges: Vec<[usize; 4]> = boxes.iter().map(|&(a, b)| ix.span(a, b)).collect();
        for r in &ranges {
            for j in r[2]..=r[3] {
                for i in r[0]..=r[1] {
                    ix.starts[j * nx + i + 1] += 1;
                }
            }
        }
        for c in 0..nx * ny {
            ix.starts[c + 1] += ix.starts[c];
        }
        let mut fill = ix.starts.clone();
        ix.list = vec![0; ix.starts[nx * ny] as usize];
        for (k, r) in ranges.iter().enumerate() {
            for j in r[2]..=r[3] {
                for i in r[0]..=r[1] {
                    let c = j * nx + i;
                    ix.list[fill[c] as usize] = k as u32;
                    fill[c] += 1;
                }
            }
        }
        ix
    }

    fn col(&self, x: f64, n: usize) -> usize {
        let i = (x / self.cs).floor();
        if i >= 0.0 {
            (i as usize).min(n - 1)
        } else {
            0
        }
    }

    /// Columns and rows `[i0, i1, j0, j1]` that the box `[a, b]` meets.
    fn span(&self, a: DVec2, b: DVec2) -> [usize; 4] {
        [
            self.col(a.x - self.lo.x, self.nx),
            self.col(b.x - self.lo.x, self.nx),
            self.col(a.y - self.lo.y, self.ny),
            self.col(b.y - self.lo.y, self.ny),
        ]
    }

    /// Items whose box may meet `[a, b]`, each once, ascending.
    fn query(&self, a: DVec2, b: DVec2, out: &mut Vec<u32>) {
        out.clear();
        let [i0, i1, j0, j1] = self.span(a, b);
        for j in j0..=j1 {
            for i in i0..=i1 {
                let c = j * self.nx + i;
                out.extend_from_slice(
                    &self.list[self.starts[c] as usize..self.starts[c + 1] as usize],
                );
            }
        }
        out.sort_unstable();
        out.dedup();
    }
}

fn tri_box(t: &[DVec3; 3]) -> (DVec2, DVec2) {
    let lo = t[0].truncate().min(t[1].truncate()).min(t[2].truncate());
    let hi = t[0].truncate().max(t[1].truncate()).max(t[2].truncate());
    (lo, hi)
}

/// The plane `z = g . p + c` of a triangle (non-zero area in xy).
fn plane(t: &[DVec3; 3]) -> (DVec2, f64) {
    let (a, b, c) = (t[0], t[1], t[2]);
    let (u, v) = (b - a, c - a);
    let det = u.x * v.y - u.y * v.x;
    let gx = (u.z * v.y - v.z * u.y) / det;
    let gy = (v.z * u.x - u.z * v.x) / det;
    let g = DVec2::new(gx, gy);
    (g, a.z - g.dot(a.truncate()))
}

/// The triangle's xy clipped to the rectangle `[lo, hi]` (Sutherland–Hodgman).
fn clip(t: &[DVec3; 3], lo: DVec2, hi: DVec2) -> Vec<DVec2> {
    let mut poly: Vec<DVec2> = t.iter().map(|p| p.truncate()).collect();
    for k in 0..4 {
        let inside = |p: DVec2| match k {
            0 => p.x >= lo.x,
            1 => p.x <= hi.x,
            2 => p.y >= lo.y,
            _ => p.y <= hi.y,
        };
        let cut = |a: DVec2, b: DVec2| -> DVec2 {
            let s = match k {
                0 => (lo.x - a.x) / (b.x - a.x),
                1 => (hi.x - a.x) / (b.x - a.x),
                2 => (lo.y - a.y) / (b.y - a.y),
                _ => (hi.y - a.y) / (b.y - a.y),
            };
            let mut p = a + (b - a) * s;
            match k {
                0 => p.x = lo.x,
                1 => p.x = hi.x,
                2 => p.y = lo.y,
                _ => p.y = hi.y,
            }
            p
        };
        let n = poly.len();
        if n == 0 {
            return poly;
        }
        let mut out = Vec::with_capacity(n + 2);
        for i in 0..n {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            match (inside(a), inside(b)) {
                (true, true) => out.push(b),
                (true, false) => out.push(cut(a, b)),
                (false, true) => {
                    out.push(cut(a, b));
                    out.push(b);
                }
                (false, false) => {}
            }
        }
        poly = out;
    }
    poly
}

/// The triangles of a mesh's faces (world or local, as the mesh): each face's outer ring as a
/// fan from its first vertex. A terrain's faces are triangles; a larger face is kept only when
/// it is strictly convex in xy, and a face with holes not at all (less terrain is safe).
pub fn fan_triangles(m: &super::Mesh) -> Vec<[DVec3; 3]> {
    let mut out = Vec::new();
    for f in &m.faces {
        let Some(r) = f.rings.first() else { continue };
        let v: Vec<DVec3> = r
            .iter()
            .filter_map(|&i| m.vertices.get(i as usize).copied())
            .collect();
        if v.len() < 3 || f.rings.len() > 1 {
            continue;
        }
        if v.len() > 3 {
            // A fan covers the face only when it is convex in xy.
            let xy: Vec<DVec2> = v.iter().map(|p| p.truncate()).collect();
            let rev: Vec<DVec2> = xy.iter().rev().copied().collect();
            if !(crate::geom::predicates::is_strictly_convex_ccw(&xy)
                || crate::geom::predicates::is_strictly_convex_ccw(&rev))
            {
                continue;
            }
        }
        for k in 1..v.len() - 1 {
            out.push([v[0], v[k], v[k + 1]]);
        }
    }
    out
}

/// The xy of triangle `t` clipped to the convex counter-clockwise polygon `poly`, one
/// half-plane per edge, into `out` (`scratch` is a buffer reused between the steps), in
/// floating point: empty when rounding leaves nothing (the caller checks that case exactly).
fn clip_convex(t: &[DVec3; 3], poly: &[DVec2], out: &mut Vec<DVec2>, scratch: &mut Vec<DVec2>) {
    out.clear();
    out.extend(t.iter().map(|p| p.truncate()));
    let n = poly.len();
    for k in 0..n {
        let (u, v) = (poly[k], poly[(k + 1) % n]);
        let side = |x: DVec2| (v - u).perp_dot(x - u);
        scratch.clear();
        for j in 0..out.len() {
            let (a, b) = (out[j], out[(j + 1) % out.len()]);
            let (sa, sb) = (side(a), side(b));
            let cut = || a + (b - a) * (sa / (sa - sb));
            match (sa >= 0.0, sb >= 0.0) {
                (true, true) => scratch.push(b),
                (true, false) => scratch.push(cut()),
                (false, true) => {
                    scratch.push(cut());
                    scratch.push(b);
                }
                (false, false) => {}
            }
        }
        std::mem::swap(out, scratch);
        if out.is_empty() {
            return;
        }
    }
}

/// Smallest power of two (times 1 m) at least `x`.
fn pow2_at_least(x: f64) -> f64 {
    let mut s = 1.0f64 / 64.0;
    while s < x {
        s *= 2.0;
    }
    s
}

impl Terrain {
    /// The terrain of `triangles` (local frame; any orientation; triangles of no area in xy are
    /// dropped), with the blockers built.
    pub fn new(sources: Vec<TerrainSource>, triangles: Vec<[DVec3; 3]>) -> Option<Terrain> {
        let mut tris: Vec<[DVec3; 3]> = Vec::with_capacity(triangles.len());
        for mut t in triangles {
            if !t.iter().all(|p| p.is_finite()) {
                continue;
            }
            match orient(t[0].truncate(), t[1].truncate(), t[2].truncate()) {
                Orientation::Collinear => continue,
                Orientation::Cw => t.swap(1, 2),
                Orientation::Ccw => {}
            }
            tris.push(t);
        }
        if tris.is_empty() {
            return None;
        }
        let boxes: Vec<(DVec2, DVec2)> = tris.iter().map(tri_box).collect();
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        let (mut zmin, mut zmax) = (f64::INFINITY, f64::NEG_INFINITY);
        let mut area = 0.0;
        for (t, b) in tris.iter().zip(&boxes) {
            lo = lo.min(b.0);
            hi = hi.max(b.1);
            for p in t {
                zmin = zmin.min(p.z);
                zmax = zmax.max(p.z);
            }
            area += 0.5 * (t[1] - t[0]).truncate().perp_dot((t[2] - t[0]).truncate());
        }
        // Boundary candidates: every edge not shared by exactly two triangles on opposite sides.
        let key = |p: DVec2| (p.x.to_bits(), p.y.to_bits());
        // Edge (its ends' xy bits, ordered) -> (triangle, edge index) of its uses.
        type EdgeKey = ((u64, u64), (u64, u64));
        let mut edges: HashMap<EdgeKey, Vec<(usize, usize)>> = HashMap::new();
        for (ti, t) in tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (key(t[k].truncate()), key(t[(k + 1) % 3].truncate()));
                let e = if a < b { (a, b) } else { (b, a) };
                edges.entry(e).or_default().push((ti, k));
            }
        }
        let mut boundary: Vec<[DVec2; 2]> = Vec::new();
        for uses in edges.values() {
            let (ti, k) = uses[0];
            let (a, b) = (tris[ti][k].truncate(), tris[ti][(k + 1) % 3].truncate());
            let interior = uses.len() == 2 && {
                let third = |(t, k): (usize, usize)| tris[t][(k + 2) % 3].truncate();
                let (s0, s1) = (orient(a, b, third(uses[0])), orient(a, b, third(uses[1])));
                matches!(
                    (s0, s1),
                    (Orientation::Ccw, Orientation::Cw) | (Orientation::Cw, Orientation::Ccw)
                )
            };
            if !interior {
                boundary.push([a, b]);
            }
        }
        boundary.sort_by(|p, q| {
            (p[0].x, p[0].y, p[1].x, p[1].y)
                .partial_cmp(&(q[0].x, q[0].y, q[1].x, q[1].y))
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        let bboxes: Vec<(DVec2, DVec2)> = boundary
            .iter()
            .map(|[a, b]| (a.min(*b), a.max(*b)))
            .collect();
        let mut t = Terrain {
            sources,
            index: Index::new(lo, hi, &boxes),
            boundary_index: Index::new(lo, hi, &bboxes),
            boundary,
            triangles: tris,
            lo,
            hi,
            zmin,
            zmax,
            floor: zmin.floor() - 1.0,
            blockers: Vec::new(),
            joined: 0,
            area,
        };
        t.blockers = t.build_blockers();
        Some(t)
    }

    /// A typical triangle's side, metres: the side of a right isosceles triangle of the mean area.
    pub fn resolution(&self) -> f64 {
        (2.0 * self.area / self.triangles.len().max(1) as f64).sqrt()
    }

    /// The triangles whose boxes meet the closed rectangle `[lo, hi]`, in the index's order.
    fn meeting_box(&self, lo: DVec2, hi: DVec2) -> Vec<&[DVec3; 3]> {
        let mut ids = Vec::new();
        self.index.query(lo, hi, &mut ids);
        ids.iter()
            .map(|&i| &self.triangles[i as usize])
            .filter(|t| {
                let (b0, b1) = tri_box(t);
                !(b0.x > hi.x || b0.y > hi.y || b1.x < lo.x || b1.y < lo.y)
            })
            .collect()
    }

    /// The least and greatest terrain height over the closed rectangle `[lo, hi]`, over the
    /// triangles that meet it (a lower and an upper bound, [`HEIGHT_MARGIN_M`] outward); `None`
    /// when no triangle meets it. Says nothing of whether the terrain covers the rectangle.
    pub fn range(&self, lo: DVec2, hi: DVec2) -> Option<(f64, f64)> {
        let (mut m, mut big) = (f64::INFINITY, f64::NEG_INFINITY);
        for t in self.meeting_box(lo, hi) {
            let (g, c) = plane(t);
            let poly = clip(t, lo, hi);
            if poly.is_empty() {
                continue;
            }
            if !(g.length() <= STEEP) {
                for p in t {
                    m = m.min(p.z);
                    big = big.max(p.z);
                }
                continue;
            }
            for p in poly {
                let z = g.dot(p) + c;
                m = m.min(z);
                big = big.max(z);
            }
        }
        (m <= big).then_some((m - HEIGHT_MARGIN_M, big + HEIGHT_MARGIN_M))
    }

    /// Whether the terrain certainly covers the closed rectangle `[lo, hi]` (module header):
    /// exact.
    pub fn covers(&self, lo: DVec2, hi: DVec2) -> bool {
        if !(lo.x <= hi.x && lo.y <= hi.y) {
            return false;
        }
        // A rectangle of no width (a wall's box) is tested grown by a millimetre, a larger
        // rectangle, so that the exact tests below see a proper convex polygon.
        let (lo, hi) = if lo.x < hi.x && lo.y < hi.y {
            (lo, hi)
        } else {
            (lo - DVec2::splat(0.001), hi + DVec2::splat(0.001))
        };
        let rect = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
        let mut ids = Vec::new();
        self.boundary_index.query(lo, hi, &mut ids);
        for &i in &ids {
            let [a, b] = self.boundary[i as usize];
            let (bl, bh) = (a.min(b), a.max(b));
            if bl.x > hi.x || bl.y > hi.y || bh.x < lo.x || bh.y < lo.y {
                continue;
            }
            if segment_meets_convex(a, b, &rect) {
                return false;
            }
        }
        let c = (lo + hi) * 0.5;
        self.index.query(c, c, &mut ids);
        ids.iter().any(|&i| {
            let t = &self.triangles[i as usize];
            let tri = [t[0].truncate(), t[1].truncate(), t[2].truncate()];
            point_in_convex(&tri, c) != Containment::Outside
        })
    }

    /// The least terrain height over `[lo, hi]` when the terrain covers it, rounded down to
    /// [`HEIGHT_STEP_M`]: the top of a solid column there.
    pub fn solid_top(&self, lo: DVec2, hi: DVec2) -> Option<f64> {
        if !self.covers(lo, hi) {
            return None;
        }
        let (m, _) = self.range(lo, hi)?;
        Some((m / HEIGHT_STEP_M).floor() * HEIGHT_STEP_M)
    }

    /// The quadtree of terrain blockers (module header).
    fn build_blockers(&self) -> Vec<Blocker> {
        let min_side = pow2_at_least(self.resolution().max(4.0));
        let side = pow2_at_least((self.hi - self.lo).max_element().max(min_side));
        let mut out = Vec::new();
        let mut stack = vec![(self.lo, side)];
        let mut ids = Vec::new();
        while let Some((o, s)) = stack.pop() {
            let (lo, hi) = (o, o + DVec2::splat(s));
            self.index.query(lo, hi, &mut ids);
            if ids.is_empty() || lo.x > self.hi.x || lo.y > self.hi.y {
                continue;
            }
            if self.covers(lo, hi) {
                if let Some((m, big)) = self.range(lo, hi) {
                    if big - m <= MERGE_TOLERANCE_M || s <= min_side {
                        let top = (m / HEIGHT_STEP_M).floor() * HEIGHT_STEP_M;
                        if top > self.floor {
                            out.push(Blocker {
                                object: TERRAIN_OBJECT,
                                polygon: vec![
                                    lo,
                                    DVec2::new(hi.x, lo.y),
                                    hi,
                                    DVec2::new(lo.x, hi.y),
                                ],
                                base: self.floor,
                                top,
                            });
                        }
                        continue;
                    }
                }
            }
            if s <= min_side {
                continue;
            }
            let h = s * 0.5;
            for (dx, dy) in [(1.0, 1.0), (0.0, 1.0), (1.0, 0.0), (0.0, 0.0)] {
                stack.push((o + DVec2::new(dx * h, dy * h), h));
            }
        }
        // Deterministic order: by position.
        out.sort_by(|a, b| {
            (a.polygon[0].y, a.polygon[0].x)
                .partial_cmp(&(b.polygon[0].y, b.polygon[0].x))
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        out
    }

    /// The least terrain height over the convex polygon `poly` (counter-clockwise, at least 3
    /// vertices), a lower bound less [`HEIGHT_MARGIN_M`]: every triangle whose box meets the
    /// polygon's is clipped to it (floating point, one half-plane per edge) and gives the least
    /// height of its plane over the clipped polygon's vertices; a triangle that the exact test
    /// finds meeting the polygon's interior, yet whose clipped polygon came out empty, or a
    /// triangle steeper than [`STEEP`], gives its lowest vertex. `None` when no triangle meets
    /// it. Says nothing of whether the terrain covers it. (The module header, "Joins".)
    pub fn least_over(&self, poly: &[DVec2]) -> Option<f64> {
        let (lo, hi) = crate::bake::bounds(poly);
        let mut m = f64::INFINITY;
        let mut clipped: Vec<DVec2> = Vec::new();
        let mut next: Vec<DVec2> = Vec::new();
        for t in self.meeting_box(lo, hi) {
            let (g, c) = plane(t);
            let lowest = t[0].z.min(t[1].z).min(t[2].z);
            if !(g.length() <= STEEP) {
                m = m.min(lowest);
                continue;
            }
            clip_convex(t, poly, &mut clipped, &mut next);
            if clipped.is_empty() {
                let tri = [t[0].truncate(), t[1].truncate(), t[2].truncate()];
                if !convex_interiors_disjoint(&tri, poly) {
                    m = m.min(lowest);
                }
                continue;
            }
            for p in &clipped {
                m = m.min(g.dot(*p) + c);
            }
        }
        m.is_finite().then_some(m - HEIGHT_MARGIN_M)
    }

    /// [`Self::solid_top`] over a blocker's footprint: over its polygon itself when it has an
    /// area ([`Self::least_over`]; its box must still be covered), over its box for a wall.
    pub fn solid_top_under(&self, poly: &[DVec2]) -> Option<f64> {
        let (lo, hi) = crate::bake::bounds(poly);
        if poly.len() < 3 {
            return self.solid_top(lo, hi);
        }
        if !self.covers(lo, hi) {
            return None;
        }
        let m = self.least_over(poly)?;
        Some((m / HEIGHT_STEP_M).floor() * HEIGHT_STEP_M)
    }

    /// Joins building blockers with the solid ground under them (module header): lowers to the
    /// floor the base of every blocker whose box the terrain covers with a least height, over
    /// the blocker's own polygon, at or above its base. Returns how many were joined.
    pub fn join(&mut self, blockers: &mut [Blocker]) -> usize {
        let mut n = 0;
        for b in blockers.iter_mut() {
            if b.base <= self.floor || b.top <= b.base {
                continue;
            }
            if let Some(m) = self.solid_top_under(&b.polygon) {
                if m >= b.base {
                    b.base = self.floor;
                    n += 1;
                }
            }
        }
        self.joined = n;
        n
    }

    /// Share of the rectangle `[lo, hi]` the terrain covers, sampled on a 64 x 64 grid of
    /// squares (for reports).
    pub fn coverage(&self, lo: DVec2, hi: DVec2) -> f64 {
        let n = 64;
        let d = (hi - lo) / n as f64;
        let mut c = 0;
        let mut ids = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let p = lo + DVec2::new((i as f64 + 0.5) * d.x, (j as f64 + 0.5) * d.y);
                self.index.query(p, p, &mut ids);
                if ids.iter().any(|&k| {
                    let t = &self.triangles[k as usize];
                    let tri = [t[0].truncate(), t[1].truncate(), t[2].truncate()];
                    point_in_convex(&tri, p) != Containment::Outside
                }) {
                    c += 1;
                }
            }
        }
        c as f64 / (n * n) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A height field on a grid of `n x n` squares of side `s`, two triangles each.
    fn grid(
        n: usize,
        s: f64,
        f: impl Fn(f64, f64) -> f64,
        hole: Option<(usize, usize)>,
    ) -> Vec<[DVec3; 3]> {
        let p = |i: usize, j: usize| {
            let (x, y) = (i as f64 * s, j as f64 * s);
            DVec3::new(x, y, f(x, y))
        };
        let mut out = Vec::new();
        for j in 0..n {
            for i in 0..n {
                if hole == Some((i, j)) {
                    continue;
                }
                out.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                out.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
        out
    }

    fn height(t: &Terrain, p: DVec2) -> Option<f64> {
        t.triangles
            .iter()
            .filter(|tr| {
                let q = [tr[0].truncate(), tr[1].truncate(), tr[2].truncate()];
                point_in_convex(&q, p) != Containment::Outside
            })
            .map(|tr| {
                let (g, c) = plane(tr);
                g.dot(p) + c
            })
            .reduce(f64::max)
    }

    /// The sampling test: every terrain blocker lies under the terrain's own triangles.
    #[test]
    fn blockers_lie_under_the_triangles() {
        let f = |x: f64, y: f64| 10.0 + 0.08 * x + 3.0 * (y / 37.0).sin() + 0.01 * x * y / 50.0;
        let t = Terrain::new(Vec::new(), grid(24, 10.0, f, Some((7, 9)))).unwrap();
        assert!(!t.blockers.is_empty());
        let mut r = crate::testutil::Lcg(5);
        for b in &t.blockers {
            assert_eq!(b.base, t.floor);
            let (lo, hi) = (b.polygon[0], b.polygon[2]);
            for _ in 0..200 {
                let p = lo + (hi - lo) * DVec2::new(r.next(), r.next());
                let h = height(&t, p).expect("a blocker over a hole");
                assert!(
                    b.top <= h,
                    "top {} over {p:?} where the terrain is {h}",
                    b.top
                );
            }
            // Nothing over the hole (70..80, 90..100).
            assert!(hi.x <= 70.0 || lo.x >= 80.0 || hi.y <= 90.0 || lo.y >= 100.0);
        }
    }

    #[test]
    fn coverage_is_refused_over_holes_and_outside() {
        let t = Terrain::new(Vec::new(), grid(8, 10.0, |_, _| 0.0, Some((3, 3)))).unwrap();
        assert!(t.covers(DVec2::new(0.5, 0.5), DVec2::new(29.5, 29.5)));
        // Touching the hole, or the terrain's outer edge, is refused: the closed square meets
        // the boundary.
        assert!(!t.covers(DVec2::new(0.5, 0.5), DVec2::new(30.0, 30.0)));
        assert!(!t.covers(DVec2::new(0.0, 0.5), DVec2::new(29.5, 29.5)));
        assert!(!t.covers(DVec2::new(25.0, 25.0), DVec2::new(35.0, 35.0)));
        assert!(!t.covers(DVec2::new(31.0, 31.0), DVec2::new(39.0, 39.0)));
        assert!(!t.covers(DVec2::new(70.0, 70.0), DVec2::new(81.0, 75.0)));
        assert!(t.covers(DVec2::new(40.5, 0.5), DVec2::new(79.5, 79.5)));
        // A wall's box, of no width: covered away from the hole, not across it.
        assert!(t.covers(DVec2::new(45.0, 5.0), DVec2::new(45.0, 60.0)));
        assert!(!t.covers(DVec2::new(35.0, 5.0), DVec2::new(35.0, 60.0)));
        // A flat terrain merges into few squares.
        assert!(t.blockers.len() < 30, "{}", t.blockers.len());
    }

    /// The least height over a polygon bounds the terrain from below at every point of it
    /// (sampled against the triangles themselves), and is close to the least sampled height.
    #[test]
    fn least_over_a_polygon_lies_under_the_terrain_in_it() {
        let f = |x: f64, y: f64| 10.0 + 0.3 * x + 3.0 * (y / 17.0).sin() + 0.01 * x * y;
        let t = Terrain::new(Vec::new(), grid(12, 10.0, f, None)).unwrap();
        let mut r = crate::testutil::Lcg(11);
        for _ in 0..60 {
            // A rotated rectangle (counter-clockwise) inside the grid.
            let c = DVec2::new(20.0 + 80.0 * r.next(), 20.0 + 80.0 * r.next());
            let (w, h, a) = (2.0 + 15.0 * r.next(), 2.0 + 15.0 * r.next(), 6.3 * r.next());
            let (u, v) = (DVec2::new(a.cos(), a.sin()), DVec2::new(-a.sin(), a.cos()));
            let poly: Vec<DVec2> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .iter()
                .map(|&(i, j)| c + u * (i * w * 0.5) + v * (j * h * 0.5))
                .collect();
            let m = t.least_over(&poly).unwrap();
            let mut least = f64::INFINITY;
            for _ in 0..300 {
                let (i, j) = (r.next(), r.next());
                let p = poly[0] + (poly[1] - poly[0]) * i + (poly[3] - poly[0]) * j;
                let z = height(&t, p).unwrap();
                assert!(m <= z, "least {m} above the terrain {z} at {p:?}");
                least = least.min(z);
            }
            // Corners included: the least lies at a vertex of some clipped triangle.
            for p in &poly {
                least = least.min(height(&t, *p).unwrap());
            }
            assert!(least - m < 0.5, "least {m}, sampled {least}");
            // Never above the box's least either (the box holds the polygon).
            let (lo, hi) = crate::bake::bounds(&poly);
            assert!(t.range(lo, hi).unwrap().0 <= m + 1e-9);
        }
    }

    /// On a slope, a building set into it whose base is its lowest ground: its box's low corner
    /// lies off the building and below the base, so only the least over its own polygon joins
    /// it. A building standing above its ground at some point of it is not joined.
    #[test]
    fn a_rotated_building_on_a_slope_joins_over_its_polygon_not_its_box() {
        let mut t =
            Terrain::new(Vec::new(), grid(10, 10.0, |x, y| 0.5 * x + 0.5 * y, None)).unwrap();
        // A square turned 45 degrees about (50, 50): corners (50, 40), (60, 50), (50, 60),
        // (40, 50); its least terrain height is 45 at (50, 40) and (40, 50), its box's 40.
        let poly = vec![
            DVec2::new(50.0, 40.0),
            DVec2::new(60.0, 50.0),
            DVec2::new(50.0, 60.0),
            DVec2::new(40.0, 50.0),
        ];
        let (lo, hi) = crate::bake::bounds(&poly);
        assert!(t.solid_top(lo, hi).unwrap() < 40.01);
        let top = t.solid_top_under(&poly).unwrap();
        assert!((44.9..=45.0).contains(&top), "{top}");
        let b = |base: f64| Blocker {
            object: 0,
            polygon: poly.clone(),
            base,
            top: base + 8.0,
        };
        let mut bs = vec![b(44.5), b(45.5)];
        assert_eq!(t.join(&mut bs), 1);
        assert_eq!(bs[0].base, t.floor);
        assert_eq!(bs[1].base, 45.5);
    }

    #[test]
    fn range_is_exact_on_a_plane() {
        let t = Terrain::new(Vec::new(), grid(4, 10.0, |x, y| x + 2.0 * y, None)).unwrap();
        let (m, big) = t
            .range(DVec2::new(5.0, 5.0), DVec2::new(15.0, 25.0))
            .unwrap();
        assert!((m - 15.0).abs() < 0.01 && m <= 15.0, "{m}");
        assert!((big - 65.0).abs() < 0.01 && big >= 65.0, "{big}");
    }
}
