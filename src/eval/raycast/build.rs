//! Building the ray caster ([`super::Caster`]): the scene's footprints as prisms (walls from
//! every ring edge, roof and floor caps), its mesh faces as planar polygons with holes, the
//! per-object sampling tables, and the uniform grid the walk traverses.
//!
//! Input: a [`Scene`]. Output: a [`Caster`] ready for queries.
//! Invariant: reads only the scene model (never the blockers), and every primitive is listed in
//! every grid cell its box meets, so the walk finds what testing every primitive finds.

use glam::{DVec2, DVec3};

use super::*;
use crate::scene::Scene;

impl Caster {
    /// Builds the caster: primitives, sampling tables and the grid.
    pub fn new(scene: &Scene) -> Caster {
        let n = scene.objects.len();
        let mut c = Caster {
            edges: Vec::new(),
            prisms: Vec::new(),
            faces: Vec::new(),
            items: Vec::new(),
            item_box: Vec::new(),
            object_faces: vec![(0, 0); n],
            object_elems: vec![(0, 0); n],
            elems: Vec::new(),
            elem_cum: Vec::new(),
            bounds: Bounds::EMPTY,
            grid: Grid {
                x0: 0.0,
                y0: 0.0,
                cs: 1.0,
                nx: 1,
                ny: 1,
                starts: vec![0, 0],
                list: Vec::new(),
            },
            ground: crate::eval::ground::Ground::new(scene),
        };
        for (oi, o) in scene.objects.iter().enumerate() {
            let e0 = c.elems.len() as u32;
            let f0 = c.faces.len() as u32;
            match &o.shape {
                Shape::Footprint(fp) => c.add_footprint(oi as u32, fp),
                Shape::Mesh(m) => c.add_mesh(oi as u32, m),
            }
            c.object_faces[oi] = (f0, c.faces.len() as u32);
            c.object_elems[oi] = (e0, c.elems.len() as u32);
        }
        for b in &c.item_box {
            c.bounds.include(b.min);
            c.bounds.include(b.max);
        }
        c.bounds = c.bounds.padded();
        c.build_grid();
        c
    }

    fn add_footprint(&mut self, object: u32, fp: &crate::scene::Footprint) {
        let (base, top) = (fp.base.min(fp.top), fp.top.max(fp.base));
        let h = top - base;
        let mut cum = 0.0;
        for rings in &fp.polygons {
            let pi = self.prisms.len() as u32;
            let e0 = self.edges.len();
            let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
            let mut area = 0.0f64;
            for (ri, ring) in rings.iter().enumerate() {
                let r0 = self.edges.len();
                for k in 0..ring.len() {
                    let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
                    lo = lo.min(a);
                    hi = hi.max(a);
                    if a != b {
                        self.edges.push([a, b]);
                    }
                }
                let a2 = ring_area2(&self.edges[r0..]).abs() / 2.0;
                area += if ri == 0 { a2 } else { -a2 };
            }
            let e1 = self.edges.len();
            if e1 == e0 || !(lo.x <= hi.x && lo.y <= hi.y) {
                continue;
            }
            self.prisms.push(Prism {
                object,
                base,
                top,
                edges: (e0 as u32, e1 as u32),
                lo,
                hi,
            });
            self.items.push(Item::Prism(pi));
            self.item_box.push(
                Bounds {
                    min: lo.extend(base),
                    max: hi.extend(top),
                }
                .padded(),
            );
            if h > 0.0 {
                for k in e0..e1 {
                    let [a, b] = self.edges[k];
                    let w = a.distance(b) * h;
                    if w > 0.0 {
                        cum += w;
                        self.elems.push(Elem::Wall {
                            prism: pi,
                            edge: k as u32,
                        });
                        self.elem_cum.push(cum);
                    }
                }
            }
            if area > 0.0 {
                cum += area;
                self.elems.push(Elem::Roof { prism: pi });
                self.elem_cum.push(cum);
            }
        }
    }

    fn add_mesh(&mut self, object: u32, m: &crate::scene::Mesh) {
        let mut cum = 0.0;
        for f in &m.faces {
            let ring = |r: &Vec<u32>| -> Option<Vec<DVec3>> {
                r.iter()
                    .map(|&i| m.vertices.get(i as usize).copied())
                    .collect()
            };
            let Some(rings) = f.rings.iter().map(ring).collect::<Option<Vec<_>>>() else {
                continue;
            };
            let Some(outer) = rings.first() else { continue };
            if outer.len() < 3 {
                continue;
            }
            // Newell's normal of the outer ring, about its centroid for accuracy.
            let c = outer.iter().copied().sum::<DVec3>() / outer.len() as f64;
            let mut nrm = DVec3::ZERO;
            for k in 0..outer.len() {
                let (a, b) = (outer[k] - c, outer[(k + 1) % outer.len()] - c);
                nrm += a.cross(b);
            }
            if !(nrm.length_squared() > 0.0) || !nrm.is_finite() {
                continue;
            }
            let axis = nrm.abs().max_position();
            let d = nrm.dot(c);
            let fi = self.faces.len() as u32;
            let e0 = self.edges.len();
            let mut bx = Bounds::EMPTY;
            let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
            let mut area2d = 0.0;
            for (ri, r) in rings.iter().enumerate() {
                let r0 = self.edges.len();
                for k in 0..r.len() {
                    let (a, b) = (r[k], r[(k + 1) % r.len()]);
                    bx.include(a);
                    let (pa, pb) = (project(a, axis), project(b, axis));
                    lo = lo.min(pa);
                    hi = hi.max(pa);
                    if pa != pb {
                        self.edges.push([pa, pb]);
                    }
                }
                let a2 = ring_area2(&self.edges[r0..]).abs() / 2.0;
                area2d += if ri == 0 { a2 } else { -a2 };
            }
            if self.edges.len() == e0 {
                continue;
            }
            self.faces.push(Face {
                object,
                n: nrm,
                d,
                axis,
                edges: (e0 as u32, self.edges.len() as u32),
                lo,
                hi,
            });
            self.items.push(Item::Face(fi));
            self.item_box.push(bx.padded());
            // True area from the projected one: |n| / |n_axis|.
            let area = area2d.max(0.0) * nrm.length() / nrm[axis].abs();
            if area > 0.0 && area.is_finite() {
                cum += area;
                self.elems.push(Elem::Face { face: fi });
                self.elem_cum.push(cum);
            }
        }
    }

    fn build_grid(&mut self) {
        let b = self.bounds;
        if self.items.is_empty() || b.is_empty() {
            return;
        }
        let (w, h) = (b.max.x - b.min.x, b.max.y - b.min.y);
        let mut cs = (w * h * ITEMS_PER_CELL / self.items.len() as f64).sqrt();
        cs = cs.clamp(MIN_CELL_M, MAX_CELL_M);
        if !cs.is_finite() {
            cs = MIN_CELL_M;
        }
        while (w / cs).ceil().max(1.0) * (h / cs).ceil().max(1.0) > MAX_CELLS {
            cs *= 2.0;
        }
        let nx = ((w / cs).ceil() as usize).max(1);
        let ny = ((h / cs).ceil() as usize).max(1);
        let mut g = Grid {
            x0: b.min.x,
            y0: b.min.y,
            cs,
            nx,
            ny,
            starts: vec![0; nx * ny + 1],
            list: Vec::new(),
        };
        let ranges: Vec<(usize, usize, usize, usize)> = self
            .item_box
            .iter()
            .map(|bx| {
                (
                    g.col(bx.min.x),
                    g.col(bx.max.x),
                    g.row(bx.min.y),
                    g.row(bx.max.y),
                )
            })
            .collect();
        for &(i0, i1, j0, j1) in &ranges {
            for j in j0..=j1 {
                for i in i0..=i1 {
                    g.starts[j * nx + i + 1] += 1;
                }
            }
        }
        for c in 0..nx * ny {
            g.starts[c + 1] += g.starts[c];
        }
        let mut fill = g.starts.clone();
        g.list = vec![0; g.starts[nx * ny] as usize];
        for (it, &(i0, i1, j0, j1)) in ranges.iter().enumerate() {
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let c = j * nx + i;
                    g.list[fill[c] as usize] = it as u32;
                    fill[c] += 1;
                }
            }
        }
        self.grid = g;
    }
}
