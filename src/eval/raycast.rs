//! A CPU ray caster over a scene's original geometry, for the ground-truth visible set.
//!
//! Input: a [`Scene`](crate::scene::Scene). Footprints are prisms: every edge of every ring (exteriors and holes)
//! gives a vertical wall from `base` to `top`, and each polygon is a roof cap at `top` and a floor
//! cap at `base` (even-odd over all its rings, rings used exactly as stored, closed or open,
//! repaired or not). Mesh faces are planar polygons with holes (plane by Newell's method over the
//! outer ring, even-odd over all rings in the projection on the plane's dominant axis).
//! Output: [`Caster::first_hit`], the nearest object a ray segment meets and where; with it, on
//! the same geometry model, [`Caster::contains`] (is a point inside a solid) and
//! [`Caster::sample_surface`] (area-uniform points on an object's surface).
//! Invariants:
//! - shares no code with the occlusion pipeline (bake, verifier, culler): it reads only the scene
//!   model; the blockers are never used;
//! - the grid walk gives the same first hit as testing every primitive
//!   ([`Caster::first_hit_brute`]);
//! - plain f64 arithmetic, no exact predicates: this is a sampling oracle, and a ray that grazes
//!   an edge or a face may go either way;
//! - a point returned by [`Caster::sample_surface`] lies on the very primitive the caster tests, so
//!   a ray aimed at it meets that object at `t ≈ 1` unless something is in front.

use std::cell::RefCell;

use glam::{DVec2, DVec3};

use crate::scene::Shape;

mod build;

/// Items (prisms, faces) per grid cell aimed at, on average over the scene's xy extent.
const ITEMS_PER_CELL: f64 = 2.0;
/// Bounds on the grid cell side, metres.
const MIN_CELL_M: f64 = 1.0;
const MAX_CELL_M: f64 = 200.0;
/// Bound on the number of grid cells.
const MAX_CELLS: f64 = 4.0e6;
/// Tries of rejection sampling in a cap or face before falling back to a boundary point.
const SAMPLE_TRIES: usize = 64;

/// An axis-aligned box; the ones the caster keeps are padded (a hair wider than the geometry),
/// so that the box tests never cut a hit on the box's faces.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    min: DVec3,
    max: DVec3,
}

impl Bounds {
    const EMPTY: Bounds = Bounds {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    fn include(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    fn padded(self) -> Bounds {
        let pad = DVec3::splat(1e-9) + (self.max - self.min).abs() * 1e-9;
        let scale = self.min.abs().max(self.max.abs()) * 1e-12;
        Bounds {
            min: self.min - pad - scale,
            max: self.max + pad + scale,
        }
    }

    fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    /// The part `[t0, t1]` of `[lo, hi]` where the ray is inside, if any.
    fn clip(&self, o: DVec3, inv: DVec3, lo: f64, hi: f64) -> Option<(f64, f64)> {
        let (mut t0, mut t1) = (lo, hi);
        for k in 0..3 {
            if inv[k].is_infinite() {
                // Parallel to this slab (or nearly: 1/d overflowed): inside it or never.
                if o[k] < self.min[k] || o[k] > self.max[k] {
                    return None;
                }
                continue;
            }
            let a = (self.min[k] - o[k]) * inv[k];
            let b = (self.max[k] - o[k]) * inv[k];
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
        if t0 <= t1 {
            Some((t0, t1))
        } else {
            None
        }
    }
}

/// One polygon of a footprint, extruded: walls from its edges, caps at base and top.
#[derive(Clone, Debug)]
struct Prism {
    object: u32,
    base: f64,
    top: f64,
    /// Range into [`Caster::edges`] (xy).
    edges: (u32, u32),
    /// xy bounding box of the polygon.
    lo: DVec2,
    hi: DVec2,
}

/// One mesh face: a planar polygon, its rings projected on the plane's dominant axis.
#[derive(Clone, Debug)]
struct Face {
    object: u32,
    /// Plane `n · p = d` (n not unit).
    n: DVec3,
    d: f64,
    /// Dropped axis (0, 1, 2); the other two are (u, v) in cyclic order.
    axis: usize,
    /// Range into [`Caster::edges`] (uv).
    edges: (u32, u32),
    lo: DVec2,
    hi: DVec2,
}

/// A sampling element of an object's surface.
#[derive(Clone, Copy, Debug)]
enum Elem {
    /// The wall of edge `edge` of prism `prism`.
    Wall { prism: u32, edge: u32 },
    /// The roof cap of a prism.
    Roof { prism: u32 },
    /// A mesh face.
    Face { face: u32 },
}

/// A primitive in the grid: a prism or a face.
#[derive(Clone, Copy, Debug)]
enum Item {
    Prism(u32),
    Face(u32),
}

/// A uniform 2D grid over the scene's xy extent, each cell listing the items whose box meets it.
#[derive(Clone, Debug)]
struct Grid {
    x0: f64,
    y0: f64,
    cs: f64,
    nx: usize,
    ny: usize,
    /// CSR: items of cell `j * nx + i` are `list[starts[c]..starts[c + 1]]`.
    starts: Vec<u32>,
    list: Vec<u32>,
}

impl Grid {
    fn col(&self, x: f64) -> usize {
        let i = ((x - self.x0) / self.cs).floor();
        if i >= 0.0 {
            (i as usize).min(self.nx - 1)
        } else {
            0
        }
    }

    fn row(&self, y: f64) -> usize {
        let j = ((y - self.y0) / self.cs).floor();
        if j >= 0.0 {
            (j as usize).min(self.ny - 1)
        } else {
            0
        }
    }

    fn cell(&self, i: usize, j: usize) -> &[u32] {
        let c = j * self.nx + i;
        &self.list[self.starts[c] as usize..self.starts[c + 1] as usize]
    }
}

thread_local! {
    /// Per thread: the id of the current ray and, per item, the id of the last ray that tested it.
    static MAILBOX: RefCell<(u64, Vec<u64>)> = const { RefCell::new((0, Vec::new())) };
}

/// A ray caster over a scene's original geometry.
#[derive(Clone, Debug)]
pub struct Caster {
    /// All wall edges (xy, prisms) and face ring edges (uv, faces).
    edges: Vec<[DVec2; 2]>,
    prisms: Vec<Prism>,
    faces: Vec<Face>,
    items: Vec<Item>,
    item_box: Vec<Bounds>,
    /// Per object, the range of its faces (meshes; empty for footprints).
    object_faces: Vec<(u32, u32)>,
    /// Per object, the range of its sampling elements in `elems` / `elem_cum`.
    object_elems: Vec<(u32, u32)>,
    elems: Vec<Elem>,
    /// Cumulative area of the elements within their object.
    elem_cum: Vec<f64>,
    bounds: Bounds,
    grid: Grid,
    /// The terrain as solid ground, from its own triangles ([`super::ground`]).
    ground: Option<super::ground::Ground>,
}

/// Twice the signed area of a ring given as edges.
fn ring_area2(edges: &[[DVec2; 2]]) -> f64 {
    edges.iter().map(|[a, b]| a.perp_dot(*b)).sum()
}

/// Even-odd: is `q` inside the region bounded by `edges` (any orientation, any nesting)?
fn inside(edges: &[[DVec2; 2]], q: DVec2) -> bool {
    let mut c = false;
    for [a, b] in edges {
        if (a.y > q.y) != (b.y > q.y) {
            let x = a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if q.x < x {
                c = !c;
            }
        }
    }
    c
}

/// Projection dropping `axis`: the remaining two coordinates in cyclic order.
fn project(p: DVec3, axis: usize) -> DVec2 {
    match axis {
        0 => DVec2::new(p.y, p.z),
        1 => DVec2::new(p.z, p.x),
        _ => DVec2::new(p.x, p.y),
    }
}

/// The point of plane `n · p = d` that projects (dropping `axis`) to `q`.
fn lift(n: DVec3, d: f64, axis: usize, q: DVec2) -> DVec3 {
    match axis {
        0 => DVec3::new((d - n.y * q.x - n.z * q.y) / n.x, q.x, q.y),
        1 => DVec3::new(q.y, (d - n.z * q.x - n.x * q.y) / n.y, q.x),
        _ => DVec3::new(q.x, q.y, (d - n.x * q.x - n.y * q.y) / n.z),
    }
}

/// Component-wise `1 / d` (±inf for a zero component, with the sign of the zero).
fn inverse(d: DVec3) -> DVec3 {
    DVec3::new(1.0 / d.x, 1.0 / d.y, 1.0 / d.z)
}

impl Caster {
    /// Number of objects the caster was built for.
    pub fn objects(&self) -> usize {
        self.object_elems.len()
    }

    /// Grid shape, for reports: (cell side in metres, columns, rows, item references).
    pub fn grid_shape(&self) -> (f64, usize, usize, usize) {
        (
            self.grid.cs,
            self.grid.nx,
            self.grid.ny,
            self.grid.list.len(),
        )
    }

    /// Nearest hit of item `it` with `t` in `[0, best)`.
    fn hit_item(&self, it: usize, o: DVec3, d: DVec3, best: f64) -> Option<f64> {
        match self.items[it] {
            Item::Prism(p) => self.hit_prism(&self.prisms[p as usize], o, d, best),
            Item::Face(f) => self.hit_face(&self.faces[f as usize], o, d, best),
        }
    }

    fn hit_prism(&self, p: &Prism, o: DVec3, d: DVec3, mut best: f64) -> Option<f64> {
        let edges = &self.edges[p.edges.0 as usize..p.edges.1 as usize];
        let (o2, d2) = (o.truncate(), d.truncate());
        let mut hit = None;
        // Walls.
        if p.top > p.base {
            for [a, b] in edges {
                let e = *b - *a;
                let den = d2.perp_dot(e);
                if den == 0.0 {
                    continue;
                }
                let ao = *a - o2;
                let t = ao.perp_dot(e) / den;
                if !(t >= 0.0 && t < best) {
                    continue;
                }
                let s = ao.perp_dot(d2) / den;
                if !(0.0..=1.0).contains(&s) {
                    continue;
                }
                let z = o.z + t * d.z;
                if z >= p.base && z <= p.top {
                    best = t;
                    hit = Some(t);
                }
            }
        }
        // Caps.
        if d.z != 0.0 {
            for z in [p.top, p.base] {
                let t = (z - o.z) / d.z;
                if !(t >= 0.0 && t < best) {
                    continue;
                }
                let q = o2 + d2 * t;
                if q.x < p.lo.x || q.y < p.lo.y || q.x > p.hi.x || q.y > p.hi.y {
                    continue;
                }
                if inside(edges, q) {
                    best = t;
                    hit = Some(t);
                }
            }
        }
        hit
    }

    fn hit_face(&self, f: &Face, o: DVec3, d: DVec3, best: f64) -> Option<f64> {
        let den = f.n.dot(d);
        if den == 0.0 {
            return None;
        }
        let t = (f.d - f.n.dot(o)) / den;
        if !(t >= 0.0 && t < best) {
            return None;
        }
        let q = project(o + d * t, f.axis);
        if q.x < f.lo.x || q.y < f.lo.y || q.x > f.hi.x || q.y > f.hi.y {
            return None;
        }
        inside(&self.edges[f.edges.0 as usize..f.edges.1 as usize], q).then_some(t)
    }

    fn object_of(&self, it: usize) -> u32 {
        match self.items[it] {
            Item::Prism(p) => self.prisms[p as usize].object,
            Item::Face(f) => self.faces[f as usize].object,
        }
    }

    /// The terrain's height over `p` (local xy), where the scene has a terrain that holds `p`:
    /// where the ground truth's eyes stand.
    pub fn ground_height(&self, p: DVec2) -> Option<f64> {
        self.ground.as_ref()?.height(p)
    }

    /// The nearest object met by the ray `origin + t * dir`, `0 <= t < t_max`, and its `t` (in
    /// units of `dir`, which need not be unit); the terrain ([`super::ground`]) is reported as
    /// [`crate::scene::TERRAIN_OBJECT`]. Of two hits at exactly the same `t`, either may be
    /// reported.
    pub fn first_hit(&self, origin: DVec3, dir: DVec3, t_max: f64) -> Option<(u32, f64)> {
        let hit = self.first_object_hit(origin, dir, t_max);
        let Some(g) = &self.ground else { return hit };
        let limit = hit.map_or(t_max, |(_, t)| t);
        match g.first_below(origin, dir, limit) {
            Some(t) if t < limit => Some((crate::scene::TERRAIN_OBJECT, t)),
            _ => hit,
        }
    }

    /// [`Caster::first_hit`] over the objects alone.
    fn first_object_hit(&self, origin: DVec3, dir: DVec3, t_max: f64) -> Option<(u32, f64)> {
        if !(t_max > 0.0) || dir == DVec3::ZERO || !dir.is_finite() || !origin.is_finite() {
            return None;
        }
        let inv = inverse(dir);
        let (t0, t1) = self.bounds.clip(origin, inv, 0.0, t_max)?;
        let g = &self.grid;
        let p = origin + dir * t0;
        let (mut i, mut j) = (g.col(p.x), g.row(p.y));
        let next = |k: usize, o: f64, d: f64, inv: f64, x0: f64| -> (f64, f64) {
            if inv.is_infinite() {
                (f64::INFINITY, f64::INFINITY)
            } else if d > 0.0 {
                ((x0 + (k + 1) as f64 * g.cs - o) * inv, g.cs * inv)
            } else if d < 0.0 {
                ((x0 + k as f64 * g.cs - o) * inv, -g.cs * inv)
            } else {
                (f64::INFINITY, f64::INFINITY)
            }
        };
        let (mut tx, dtx) = next(i, origin.x, dir.x, inv.x, g.x0);
        let (mut ty, dty) = next(j, origin.y, dir.y, inv.y, g.y0);
        let mut best = t_max;
        let mut found: Option<(usize, f64)> = None;
        MAILBOX.with(|m| {
            let mut m = m.borrow_mut();
            let (stamp, marks) = &mut *m;
            *stamp += 1;
            if marks.len() < self.items.len() {
                marks.resize(self.items.len(), 0);
            }
            loop {
                for &it in g.cell(i, j) {
                    let it = it as usize;
                    if marks[it] == *stamp {
                        continue;
                    }
                    marks[it] = *stamp;
                    if self.item_box[it].clip(origin, inv, 0.0, best).is_none() {
                        continue;
                    }
                    if let Some(t) = self.hit_item(it, origin, dir, best) {
                        best = t;
                        found = Some((it, t));
                    }
                }
                let exit = tx.min(ty);
                if (found.is_some() && best <= exit) || exit > t1 {
                    break;
                }
                if tx < ty {
                    if dir.x > 0.0 {
                        i += 1;
                        if i >= g.nx {
                            break;
                        }
                    } else {
                        if i == 0 {
                            break;
                        }
                        i -= 1;
                    }
                    tx += dtx;
                } else {
                    if dir.y > 0.0 {
                        j += 1;
                        if j >= g.ny {
                            break;
                        }
                    } else {
                        if j == 0 {
                            break;
                        }
                        j -= 1;
                    }
                    ty += dty;
                }
            }
        });
        found.map(|(it, t)| (self.object_of(it), t))
    }

    /// [`Caster::first_hit`] by testing every primitive, for tests of the grid walk.
    pub fn first_hit_brute(&self, origin: DVec3, dir: DVec3, t_max: f64) -> Option<(u32, f64)> {
        if !(t_max > 0.0) || dir == DVec3::ZERO || !dir.is_finite() || !origin.is_finite() {
            return None;
        }
        let mut best = t_max;
        let mut found = None;
        for it in 0..self.items.len() {
            if let Some(t) = self.hit_item(it, origin, dir, best) {
                best = t;
                found = Some((it, t));
            }
        }
        let hit = found.map(|(it, t)| (self.object_of(it), t));
        match self
            .ground
            .as_ref()
            .and_then(|g| g.first_below_brute(origin, dir, best))
        {
            Some(t) if t < best => Some((crate::scene::TERRAIN_OBJECT, t)),
            _ => hit,
        }
    }

    /// An object whose solid holds `p`, if any: a footprint polygon with `base <= z <= top` and
    /// `p` inside it (even-odd), or a mesh that an upward ray from `p` crosses an odd number of
    /// times (parity; meaningful for closed meshes, a guess for open ones).
    pub fn contains(&self, p: DVec3) -> Option<u32> {
        if !p.is_finite() || self.items.is_empty() {
            return None;
        }
        let b = self.bounds;
        if p.x < b.min.x || p.y < b.min.y || p.x > b.max.x || p.y > b.max.y {
            return None;
        }
        let g = &self.grid;
        let mut meshes: Vec<u32> = Vec::new();
        for &it in g.cell(g.col(p.x), g.row(p.y)) {
            let bx = &self.item_box[it as usize];
            if p.x < bx.min.x || p.y < bx.min.y || p.x > bx.max.x || p.y > bx.max.y {
                continue;
            }
            match self.items[it as usize] {
                Item::Prism(k) => {
                    let pr = &self.prisms[k as usize];
                    if p.z >= pr.base
                        && p.z <= pr.top
                        && inside(
                            &self.edges[pr.edges.0 as usize..pr.edges.1 as usize],
                            p.truncate(),
                        )
                    {
                        return Some(pr.object);
                    }
                }
                Item::Face(f) => {
                    let o = self.faces[f as usize].object;
                    if !meshes.contains(&o) {
                        meshes.push(o);
                    }
                }
            }
        }
        meshes.sort_unstable();
        // Slightly tilted, so that the ray avoids vertical faces and the usual grid-aligned edges.
        let up = DVec3::new(1.234_567e-3, 7.654_321e-4, 1.0);
        for o in meshes {
            let (f0, f1) = self.object_faces[o as usize];
            let crossings = (f0..f1)
                .filter(|&f| {
                    self.hit_face(&self.faces[f as usize], p, up, f64::INFINITY)
                        .is_some()
                })
                .count();
            if crossings % 2 == 1 {
                return Some(o);
            }
        }
        None
    }

    /// Total surface area of an object as sampled: walls and roofs of footprints (floors
    /// excluded), all faces of meshes.
    pub fn surface_area(&self, object: u32) -> f64 {
        match self.object_elems.get(object as usize) {
            Some(&(e0, e1)) if e1 > e0 => self.elem_cum[e1 as usize - 1],
            _ => 0.0,
        }
    }

    /// A point on `object`'s surface, area-uniform over its walls and roofs (footprints) or
    /// faces (meshes), drawn with `u`, a source of uniform numbers in `[0, 1)`. `None` when the
    /// object has no area.
    pub fn sample_surface(&self, object: u32, u: &mut impl FnMut() -> f64) -> Option<DVec3> {
        let &(e0, e1) = self.object_elems.get(object as usize)?;
        if e1 <= e0 {
            return None;
        }
        let cum = &self.elem_cum[e0 as usize..e1 as usize];
        let total = cum[cum.len() - 1];
        let x = u() * total;
        let k = cum.partition_point(|&c| c <= x).min(cum.len() - 1);
        match self.elems[e0 as usize + k] {
            Elem::Wall { prism, edge } => {
                let p = &self.prisms[prism as usize];
                let [a, b] = self.edges[edge as usize];
                let q = a + (b - a) * u();
                let z = p.base + (p.top - p.base) * u();
                Some(q.extend(z.min(p.top)))
            }
            Elem::Roof { prism } => {
                let p = &self.prisms[prism as usize];
                let edges = &self.edges[p.edges.0 as usize..p.edges.1 as usize];
                for _ in 0..SAMPLE_TRIES {
                    let q = p.lo + (p.hi - p.lo) * DVec2::new(u(), u());
                    if inside(edges, q) {
                        return Some(q.extend(p.top));
                    }
                }
                // A sliver: a point of the roof's boundary.
                let [a, b] = edges[(u() * edges.len() as f64) as usize % edges.len()];
                Some((a + (b - a) * u()).extend(p.top))
            }
            Elem::Face { face } => {
                let f = &self.faces[face as usize];
                let edges = &self.edges[f.edges.0 as usize..f.edges.1 as usize];
                for _ in 0..SAMPLE_TRIES {
                    let q = f.lo + (f.hi - f.lo) * DVec2::new(u(), u());
                    if inside(edges, q) {
                        return Some(lift(f.n, f.d, f.axis, q));
                    }
                }
                let [a, b] = edges[(u() * edges.len() as f64) as usize % edges.len()];
                Some(lift(f.n, f.d, f.axis, a + (b - a) * u()))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x0: f64, y0: f64, s: f64) -> Vec<[DVec2; 2]> {
        let p = [
            DVec2::new(x0, y0),
            DVec2::new(x0 + s, y0),
            DVec2::new(x0 + s, y0 + s),
            DVec2::new(x0, y0 + s),
        ];
        (0..4).map(|k| [p[k], p[(k + 1) % 4]]).collect()
    }

    #[test]
    fn even_odd_with_hole() {
        let mut e = square(0.0, 0.0, 10.0);
        e.extend(square(4.0, 4.0, 2.0));
        assert!(inside(&e, DVec2::new(1.0, 1.0)));
        assert!(!inside(&e, DVec2::new(5.0, 5.0)));
        assert!(!inside(&e, DVec2::new(11.0, 5.0)));
        assert_eq!(ring_area2(&square(0.0, 0.0, 2.0)), 8.0);
    }

    #[test]
    fn lift_inverts_project() {
        let n = DVec3::new(0.3, -2.0, 0.7);
        let p = DVec3::new(1.5, -3.25, 8.0);
        let d = n.dot(p);
        for axis in 0..3 {
            let q = lift(n, d, axis, project(p, axis));
            assert!((q - p).length() < 1e-12, "{axis}: {q} vs {p}");
        }
    }
}
