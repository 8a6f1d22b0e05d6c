//! The ground truth's terrain: rays against the terrain's own triangles, as solid ground.
//!
//! Input: the scene's terrain triangles (`Scene::terrain`, the triangles as read, in the local
//! frame); never its blockers, nor any code of `scene/terrain.rs` or the bake.
//! Output: [`Ground::first_below`], the least `t` at which a ray segment is strictly below the
//! terrain (inside the ground: the terrain is the top of opaque ground, ARCHITECTURE.md "Terrain
//! as an occluder"); [`Ground::height`], the terrain's height over a point (the greatest height
//! of a triangle holding it), where eyes stand.
//! Invariants: plain f64 (a sampling oracle, like the rest of the ground truth); its own grid
//! index over the triangles; a triangle with no area in xy is skipped (it is a vertical face of
//! the ground, which the solid around it already holds).

use std::cell::RefCell;

use glam::{DVec2, DVec3};

use crate::scene::Scene;

#[derive(Clone, Debug)]
struct Tri {
    /// xy corners.
    p: [DVec2; 3],
    /// Plane `z = g . p + c`.
    g: DVec2,
    c: f64,
}

/// Triangles per grid cell aimed at.
const PER_CELL: f64 = 2.0;

thread_local! {
    static STAMP: RefCell<(u64, Vec<u64>)> = const { RefCell::new((0, Vec::new())) };
}

/// The terrain of a scene, for rays.
#[derive(Clone, Debug)]
pub struct Ground {
    tris: Vec<Tri>,
    lo: DVec2,
    cs: f64,
    nx: usize,
    ny: usize,
    starts: Vec<u32>,
    list: Vec<u32>,
}

impl Ground {
    /// The ground of a scene; `None` when it has no terrain.
    pub fn new(scene: &Scene) -> Option<Ground> {
        let t = scene.terrain.as_ref()?;
        let mut tris = Vec::new();
        for v in &t.triangles {
            let p = [v[0].truncate(), v[1].truncate(), v[2].truncate()];
            let (u, w) = (v[1] - v[0], v[2] - v[0]);
            let det = u.x * w.y - u.y * w.x;
            if det == 0.0 || !det.is_finite() {
                continue;
            }
            let g = DVec2::new((u.z * w.y - w.z * u.y) / det, (w.z * u.x - u.z * w.x) / det);
            tris.push(Tri {
                p,
                g,
                c: v[0].z - g.dot(p[0]),
            });
        }
        if tris.is_empty() {
            return None;
        }
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for t in &tris {
            for q in t.p {
                lo = lo.min(q);
                hi = hi.max(q);
            }
        }
        let (w, h) = ((hi.x - lo.x).max(1.0), (hi.y - lo.y).max(1.0));
        let cs = (w * h * PER_CELL / tris.len() as f64).sqrt().max(0.5);
        let nx = ((w / cs).ceil() as usize).max(1);
        let ny = ((h / cs).ceil() as usize).max(1);
        let mut g = Ground {
            tris,
            lo,
            cs,
            nx,
            ny,
            starts: vec![0; nx * ny + 1],
            list: Vec::new(),
        };
        let spans: Vec<[usize; 4]> = g
            .tris
            .iter()
            .map(|t| {
                let a = t.p[0].min(t.p[1]).min(t.p[2]);
                let b = t.p[0].max(t.p[1]).max(t.p[2]);
                [g.col(a.x), g.col(b.x), g.row(a.y), g.row(b.y)]
            })
            .collect();
        for s in &spans {
            for j in s[2]..=s[3] {
                for i in s[0]..=s[1] {
                    g.starts[j * nx + i + 1] += 1;
                }
            }
        }
        for c in 0..nx * ny {
            g.starts[c + 1] += g.starts[c];
        }
        let mut fill = g.starts.clone();
        g.list = vec![0; g.starts[nx * ny] as usize];
        for (k, s) in spans.iter().enumerate() {
            for j in s[2]..=s[3] {
                for i in s[0]..=s[1] {
                    g.list[fill[j * nx + i] as usize] = k as u32;
                    fill[j * nx + i] += 1;
                }
            }
        }
        Some(g)
    }

    fn col(&self, x: f64) -> usize {
        let i = ((x - self.lo.x) / self.cs).floor();
        if i >= 0.0 {
            (i as usize).min(self.nx - 1)
        } else {
            0
        }
    }

    fn row(&self, y: f64) -> usize {
        let j = ((y - self.lo.y) / self.cs).floor();
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

    /// The terrain's height over `p`: the greatest height of a triangle holding it (closed,
    /// plain f64); `None` where no triangle does.
    pub fn height(&self, p: DVec2) -> Option<f64> {
        if p.x < self.lo.x || p.y < self.lo.y {
            return None;
        }
        let (i, j) = (self.col(p.x), self.row(p.y));
        let mut best: Option<f64> = None;
        for &k in self.cell(i, j) {
            let t = &self.tris[k as usize];
            if inside(t, p) {
                let z = t.g.dot(p) + t.c;
                best = Some(best.map_or(z, |b: f64| b.max(z)));
            }
        }
        best
    }

    /// The least `t` in `(0, t_max)` at which `o + t d` lies strictly below a triangle of the
    /// terrain (inside the ground), if any.
    pub fn first_below(&self, o: DVec3, d: DVec3, t_max: f64) -> Option<f64> {
        let (o2, d2) = (o.truncate(), d.truncate());
        // The 2D walk covers the segment's xy box cells along the way: a DDA over the grid.
        let (mut t, end) = (0.0f64, t_max);
        // Clip to the grid's box.
        let hi = self.lo + DVec2::new(self.nx as f64, self.ny as f64) * self.cs;
        for k in 0..2 {
            if d2[k] == 0.0 && (o2[k] < self.lo[k] || o2[k] > hi[k]) {
                return None;
            }
        }
        let (mut t0, mut t1) = (t, end);
        for k in 0..2 {
            if d2[k] != 0.0 {
                let a = (self.lo[k] - o2[k]) / d2[k];
                let b = (hi[k] - o2[k]) / d2[k];
                t0 = t0.max(a.min(b));
                t1 = t1.min(a.max(b));
            }
        }
        if t0 > t1 {
            return None;
        }
        t = t0;
        let p = o2 + d2 * t;
        let (mut i, mut j) = (self.col(p.x), self.row(p.y));
        let step = |k: usize, o: f64, d: f64, x0: f64| -> (f64, f64) {
            if d > 0.0 {
                ((x0 + (k + 1) as f64 * self.cs - o) / d, self.cs / d)
            } else if d < 0.0 {
                ((x0 + k as f64 * self.cs - o) / d, -self.cs / d)
            } else {
                (f64::INFINITY, f64::INFINITY)
            }
        };
        let (mut tx, dtx) = step(i, o2.x, d2.x, self.lo.x);
        let (mut ty, dty) = step(j, o2.y, d2.y, self.lo.y);
        let mut best = f64::INFINITY;
        STAMP.with(|s| {
            let mut s = s.borrow_mut();
            let (stamp, marks) = &mut *s;
            *stamp += 1;
            if marks.len() < self.tris.len() {
                marks.resize(self.tris.len(), 0);
            }
            loop {
                for &k in self.cell(i, j) {
                    if marks[k as usize] == *stamp {
                        continue;
                    }
                    marks[k as usize] = *stamp;
                    if let Some(u) = below(&self.tris[k as usize], o, d, t_max) {
                        best = best.min(u);
                    }
                }
                let exit = tx.min(ty);
                if best <= exit || exit > t1 {
                    break;
                }
                if tx < ty {
                    if d2.x > 0.0 {
                        i += 1;
                        if i >= self.nx {
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
                    if d2.y > 0.0 {
                        j += 1;
                        if j >= self.ny {
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
        (best < t_max).then_some(best)
    }

    /// [`Ground::first_below`] by testing every triangle, for tests.
    pub fn first_below_brute(&self, o: DVec3, d: DVec3, t_max: f64) -> Option<f64> {
        self.tris
            .iter()
            .filter_map(|t| below(t, o, d, t_max))
            .reduce(f64::min)
    }
}

fn cross(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// `p` in the closed triangle (either orientation).
fn inside(t: &Tri, p: DVec2) -> bool {
    let s = [
        cross(t.p[0], t.p[1], p),
        cross(t.p[1], t.p[2], p),
        cross(t.p[2], t.p[0], p),
    ];
    s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
}

/// The least `t` in `(0, t_max)` at which the ray lies strictly below the triangle's plane
/// within the triangle's xy.
fn below(t: &Tri, o: DVec3, d: DVec3, t_max: f64) -> Option<f64> {
    let (o2, d2) = (o.truncate(), d.truncate());
    // The parameter range where the ray's xy is in the triangle: three half-planes.
    let orient = cross(t.p[0], t.p[1], t.p[2]).signum();
    let (mut a, mut b) = (0.0f64, t_max);
    for k in 0..3 {
        let (p, q) = (t.p[k], t.p[(k + 1) % 3]);
        // f(s) = orient * cross(p, q, o2 + s d2) >= 0, linear in s.
        let f0 = orient * cross(p, q, o2);
        let f1 = orient * (q - p).perp_dot(d2);
        if f1 == 0.0 {
            if f0 < 0.0 {
                return None;
            }
        } else {
            let s = -f0 / f1;
            if f1 > 0.0 {
                a = a.max(s);
            } else {
                b = b.min(s);
            }
        }
    }
    if !(a <= b) {
        return None;
    }
    // h(s) = ray z - plane z, linear: negative somewhere in [a, b]?
    let h = |s: f64| o.z + s * d.z - (t.g.dot(o2 + d2 * s) + t.c);
    let (ha, hb) = (h(a), h(b));
    if ha < 0.0 {
        return Some(a);
    }
    if hb < 0.0 {
        // The root, where the ray enters the ground.
        let s = a + (b - a) * ha / (ha - hb);
        return Some(s.clamp(a, b));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene_with(tris: Vec<[DVec3; 3]>) -> Scene {
        let text = r#"{"type":"FeatureCollection","features":[{"type":"Feature","properties":{"h":5},"geometry":{"type":"Polygon","coordinates":[[[0,0],[1,0],[1,1],[0,1],[0,0]]]}}]}"#;
        let opts = crate::scene::ReadOptions {
            height_attr: Some("h".into()),
            ..Default::default()
        };
        let mut s =
            crate::scene::load_bytes(&[("a.geojson".into(), text.as_bytes())], &opts).unwrap();
        s.terrain = crate::scene::Terrain::new(Vec::new(), tris);
        s
    }

    #[test]
    fn a_ray_into_a_hill_is_below_and_the_walk_equals_brute_force() {
        // A ridge along y at x = 50: heights 0 at x = 0 and 100, 20 at x = 50.
        let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let mut tris = Vec::new();
        for j in 0..10 {
            let (y0, y1) = (j as f64 * 10.0, j as f64 * 10.0 + 10.0);
            tris.push([p(0.0, y0, 0.0), p(50.0, y0, 20.0), p(50.0, y1, 20.0)]);
            tris.push([p(0.0, y0, 0.0), p(50.0, y1, 20.0), p(0.0, y1, 0.0)]);
            tris.push([p(50.0, y0, 20.0), p(100.0, y0, 0.0), p(100.0, y1, 0.0)]);
            tris.push([p(50.0, y0, 20.0), p(100.0, y1, 0.0), p(50.0, y1, 20.0)]);
        }
        let s = scene_with(tris);
        let g = Ground::new(&s).unwrap();
        assert!((g.height(DVec2::new(25.0, 33.0)).unwrap() - 10.0).abs() < 1e-9);
        // From (10, 50, 5.5) to (90, 50, 5.5): through the hill.
        let (o, d) = (p(10.0, 50.0, 5.5), p(80.0, 0.0, 0.0));
        let t = g.first_below(o, d, 1.0).unwrap();
        assert!((o + d * t).x > 10.0 && (o + d * t).x < 15.0, "{t}");
        // Over the ridge: free.
        assert!(g
            .first_below(p(10.0, 50.0, 30.0), p(80.0, 3.0, 0.0), 1.0)
            .is_none());
        let mut r = crate::testutil::Lcg(3);
        for _ in 0..2000 {
            let o = p(
                r.range(-10.0, 110.0),
                r.range(-10.0, 110.0),
                r.range(0.0, 30.0),
            );
            let d = p(
                r.range(-100.0, 100.0),
                r.range(-100.0, 100.0),
                r.range(-20.0, 20.0),
            );
            let (a, b) = (g.first_below(o, d, 1.0), g.first_below_brute(o, d, 1.0));
            assert_eq!(a.is_some(), b.is_some(), "{o:?} {d:?}");
            if let (Some(a), Some(b)) = (a, b) {
                assert!((a - b).abs() < 1e-9);
            }
        }
    }
}
