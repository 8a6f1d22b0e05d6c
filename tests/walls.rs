//! The wall rule against brute-force rays: random open meshes (open boxes, sloped bottoms and
//! tops, gables, triangulated and split walls, duplicated faces, overlapping levels of detail,
//! faces slightly off vertical, leaning walls, roofs) are written as OBJ and loaded; every wall
//! blocker the loader claims is crossed by rays in all directions through points of its
//! rectangle, and each must meet a mesh face there. The ray caster is the ground truth's
//! (`eval::raycast`), which reads only the objects' faces, never the blockers.

use glam::{DVec2, DVec3};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use vocc::eval::raycast::Caster;
use vocc::scene::{self, ReadOptions, Scene};

/// One building's faces, as 3D polygons.
type Faces = Vec<Vec<DVec3>>;

#[derive(Clone, Debug)]
struct Building {
    /// Footprint corner and the two edge directions (small integers, so every point below is
    /// exact), in quarter metres.
    origin: (i32, i32),
    dir: (i32, i32),
    len: (i32, i32),
    /// Per corner: bottom and top heights, quarter metres.
    bottom: [i32; 4],
    top: [i32; 4],
    /// Per side: 0 quad, 1 two triangles, 2 split in two quads at `split`, 3 gable (a ridge
    /// vertex in the middle of the top edge), 4 off vertical (a top corner moved sideways by
    /// `off` micrometres, up to 10 mm), 5 leaning (the top edge moved out by 0.5 m), 6 missing.
    sides: [u8; 4],
    split: i32,
    off: i32,
    /// Repeat the first side (reversed), add a roof, add a second level of detail (the same
    /// box 1 m lower) in the same object.
    duplicate: bool,
    roof: bool,
    second_lod: bool,
}

fn q(v: i32) -> f64 {
    v as f64 * 0.25
}

impl Building {
    fn corners(&self) -> [DVec2; 4] {
        let (ox, oy) = self.origin;
        let (a, b) = self.dir;
        let (w, h) = self.len;
        let p = |i: i32, j: i32| DVec2::new(q(ox + i * a - j * b), q(oy + i * b + j * a));
        [p(0, 0), p(w, 0), p(w, h), p(0, h)]
    }

    fn faces(&self) -> Faces {
        let c = self.corners();
        let centre = (c[0] + c[2]) * 0.5;
        let mut out: Faces = Vec::new();
        let lods: &[f64] = if self.second_lod {
            &[0.0, -1.0]
        } else {
            &[0.0]
        };
        for &drop in lods {
            let z0 = |k: usize| q(self.bottom[k]);
            let z1 = |k: usize| q(self.top[k]).max(z0(k) + 0.5) + drop;
            for s in 0..4 {
                let (i, j) = (s, (s + 1) % 4);
                let (pi, pj) = (c[i], c[j]);
                let b0 = pi.extend(z0(i));
                let b1 = pj.extend(z0(j));
                let t1 = pj.extend(z1(j));
                let t0 = pi.extend(z1(i));
                let side = self.sides[s];
                match side {
                    0 => out.push(vec![b0, b1, t1, t0]),
                    1 => {
                        out.push(vec![b0, b1, t1]);
                        out.push(vec![b0, t1, t0]);
                    }
                    2 => {
                        // An exact point of the edge: corners are lattice points along `dir`.
                        let f = (self.split.rem_euclid(3) + 1) as f64 / 4.0;
                        let m = pi + (pj - pi) * f;
                        let (zb, zt) = (z0(i) + (z0(j) - z0(i)) * f, z1(i) + (z1(j) - z1(i)) * f);
                        out.push(vec![b0, m.extend(zb), m.extend(zt), t0]);
                        out.push(vec![m.extend(zb), b1, t1, m.extend(zt)]);
                    }
                    3 => {
                        let m = (pi + pj) * 0.5;
                        let ridge = z1(i).max(z1(j)) + 3.0;
                        out.push(vec![b0, b1, t1, m.extend(ridge), t0]);
                    }
                    4 => {
                        let n = (pj - pi).perp().normalize() * (self.off as f64 * 1e-6);
                        out.push(vec![b0, b1, t1, (pi + n).extend(z1(i))]);
                    }
                    5 => {
                        let n = (pi + pj) * 0.5 - centre;
                        let n = n.normalize() * 0.5;
                        out.push(vec![b0, b1, (pj + n).extend(z1(j)), (pi + n).extend(z1(i))]);
                    }
                    _ => {}
                }
            }
            if self.roof {
                out.push((0..4).map(|k| c[k].extend(z1(k))).collect());
            }
        }
        if self.duplicate && !out.is_empty() {
            let mut f = out[0].clone();
            f.reverse();
            out.push(f);
        }
        out
    }
}

fn building() -> impl Strategy<Value = Building> {
    (
        (-400i32..400, -400i32..400),
        prop_oneof![
            Just((1, 0)),
            Just((0, 1)),
            Just((3, 4)),
            Just((5, -12)),
            Just((2, 1))
        ],
        (1i32..12, 1i32..12),
        prop::array::uniform4(0i32..8),
        prop::array::uniform4(8i32..80),
        prop::array::uniform4(0u8..7),
        (0i32..3, 1i32..10_000),
        (any::<bool>(), any::<bool>(), any::<bool>()),
    )
        .prop_map(
            |(
                origin,
                dir,
                len,
                bottom,
                top,
                sides,
                (split, off),
                (duplicate, roof, second_lod),
            )| {
                // Scale the direction so that the box is 3 to 40 m wide.
                let n = (dir.0 * dir.0 + dir.1 * dir.1) as f64;
                let k = (16.0 / n.sqrt()).ceil() as i32;
                Building {
                    origin,
                    dir,
                    len: (len.0 * k.max(1), len.1 * k.max(1)),
                    bottom,
                    top,
                    sides,
                    split,
                    off,
                    duplicate,
                    roof,
                    second_lod,
                }
            },
        )
}

fn obj_text(buildings: &[Building]) -> String {
    let mut s = String::new();
    let mut n = 0;
    for (bi, b) in buildings.iter().enumerate() {
        s.push_str(&format!("o b{bi}\n"));
        for f in b.faces() {
            for v in &f {
                s.push_str(&format!("v {} {} {}\n", v.x, v.y, v.z));
            }
            let idx: Vec<String> = (0..f.len()).map(|k| (n + k + 1).to_string()).collect();
            s.push_str(&format!("f {}\n", idx.join(" ")));
            n += f.len();
        }
    }
    s
}

fn load(buildings: &[Building], offset: f64) -> Scene {
    // Shift everything by a large round offset to exercise the local frame.
    let text = obj_text(buildings);
    let shifted: String = text
        .lines()
        .map(|l| match l.strip_prefix("v ") {
            Some(r) => {
                let c: Vec<f64> = r.split(' ').map(|x| x.parse().unwrap()).collect();
                format!("v {} {} {}\n", c[0] + offset, c[1] + offset, c[2])
            }
            None => format!("{l}\n"),
        })
        .collect();
    scene::load_bytes(
        &[("walls.obj".into(), shifted.as_bytes())],
        &ReadOptions::default(),
    )
    .expect("the generated OBJ loads")
}

/// A deterministic generator of numbers in [0, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Rays through `rays` points of every wall blocker, in random directions (at least a
/// milliradian off the wall's plane): (walls checked, rays that met no face near the wall).
fn shoot(s: &Scene, rays: usize, seed: u64) -> (usize, usize, Vec<String>) {
    shoot_with(s, rays, seed, true)
}

/// [`shoot`], by the caster's brute-force loop over every face or by its grid walk.
fn shoot_with(s: &Scene, rays: usize, seed: u64, brute: bool) -> (usize, usize, Vec<String>) {
    let caster = Caster::new(s);
    let mut rng = Rng(seed | 1);
    let (mut walls, mut missed) = (0, 0);
    let mut first = Vec::new();
    for w in s.blockers.iter().filter(|b| b.polygon.len() == 2) {
        walls += 1;
        let (a, b) = (w.polygon[0], w.polygon[1]);
        let along = (b - a).normalize();
        let normal = along.perp();
        for _ in 0..rays {
            // A point well inside the rectangle (1 cm from its sides).
            let len = a.distance(b);
            let h = w.top - w.base;
            let sx = 0.01 + rng.next() * (len - 0.02).max(0.0);
            let sz = 0.01 + rng.next() * (h - 0.02).max(0.0);
            let p = (a + along * sx.min(len)).extend(w.base + sz.min(h));
            // A direction: grazing to head-on, any vertical slope up to 60 degrees.
            let phi = (1e-3 + rng.next() * (std::f64::consts::PI - 2e-3)).max(1e-3);
            let horiz = along * phi.cos() + normal * phi.sin();
            let slope = (rng.next() * 2.0 - 1.0) * 1.7;
            let d = horiz.extend(slope).normalize();
            // The ray segment 5 cm either side of p must meet a face.
            let o = p - d * 0.05;
            let hit = if brute {
                caster.first_hit_brute(o, d, 0.1)
            } else {
                caster.first_hit(o, d, 0.1)
            };
            if hit.is_none() {
                missed += 1;
                if first.len() < 3 {
                    first.push(format!("wall {w:?}: ray {o} dir {d} misses"));
                }
            }
        }
    }
    (walls, missed, first)
}

proptest! {
    #![proptest_config(Config { cases: 48, rng_seed: RngSeed::Fixed(0x5eed_0120), failure_persistence: None, ..Config::default() })]

    #[test]
    fn no_ray_passes_through_a_claimed_wall(
        bs in prop::collection::vec(building(), 1..5),
        offset in prop_oneof![Just(0.0), Just(85_000.0), Just(4_500_000.0)],
    ) {
        let s = load(&bs, offset);
        let (walls, missed, first) = shoot(&s, 24, 7);
        prop_assert_eq!(missed, 0, "{} of {} walls: {:?}", missed, walls, first);
        // A vertical side (quad, triangles, split, gable) gives at least one wall.
        let vertical_sides = bs
            .iter()
            .map(|b| b.sides.iter().filter(|&&k| k <= 3).count())
            .sum::<usize>();
        prop_assert!(walls >= vertical_sides.min(1), "{walls} walls from {vertical_sides} vertical sides");
    }
}

#[test]
fn no_ray_passes_through_a_wall_of_the_bundled_meshes() {
    // Every wall of Gelderseplein (3DBAG, open, triangulated) and of the triangulated Den Haag
    // OBJ, 4 rays each.
    for (rel, min_walls) in [
        ("data/gelderseplein/gelderseplein.obj", 2000),
        ("data/denhaag/DenHaag_01_buildings.obj", 10000),
    ] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
        let s = scene::load(&[path], &ReadOptions::default()).unwrap();
        let (walls, missed, first) = shoot_with(&s, 4, 11, false);
        assert!(walls >= min_walls, "{rel}: {walls} walls");
        assert_eq!(missed, 0, "{rel}: {first:?}");
    }
}

#[test]
fn every_vertical_side_gives_a_wall_and_no_other_face_does() {
    // One box per kind of side, each side of that kind: the count of walls per object.
    for (kind, expect_walls) in [
        (0u8, true),
        (1, true),
        (2, true),
        (3, true),
        (4, false),
        (5, false),
    ] {
        let b = Building {
            origin: (0, 0),
            dir: (3, 4),
            len: (8, 6),
            bottom: [0, 1, 2, 3],
            top: [40, 44, 48, 52],
            sides: [kind; 4],
            split: 1,
            off: 500,
            duplicate: false,
            roof: true,
            second_lod: false,
        };
        let s = load(&[b], 85_000.0);
        let walls = s.blockers.iter().filter(|w| w.polygon.len() == 2).count();
        if expect_walls {
            assert!(walls >= 4, "side kind {kind}: {walls} walls");
        } else {
            assert_eq!(walls, 0, "side kind {kind}");
        }
        let (_, missed, first) = shoot(&s, 64, 3);
        assert_eq!(missed, 0, "{first:?}");
    }
}

#[test]
fn a_ray_misses_a_leaning_face_through_the_vertical_rectangle_at_its_middle() {
    // Why leaning faces give no wall (src/scene/walls.rs, "What is dropped"): a face leaning
    // 1 mm over 6 m (bottom edge at y = 0, top edge at y = 0.001), and the vertical rectangle
    // through its middle (y = 0.0005, where the face is at z = 3). At z = 1.5 the face is the
    // line y = 0.00025; a horizontal ray through the rectangle there, 1e-5 off the wall's
    // direction, meets that line only at x = -20, beyond the face's end.
    let obj = "o lean\nv 0 0 0\nv 10 0 0\nv 10 0.001 6\nv 0 0.001 6\nf 1 2 3 4\n";
    let s = scene::load_bytes(
        &[("lean.obj".into(), obj.as_bytes())],
        &ReadOptions::default(),
    )
    .unwrap();
    assert!(
        s.blockers.iter().all(|w| w.polygon.len() != 2),
        "a leaning face gave a wall"
    );
    let caster = Caster::new(&s);
    let p = DVec3::new(5.0, 0.0005, 1.5) - s.origin;
    let d = DVec3::new(1.0, 1e-5, 0.0).normalize();
    assert!(caster.first_hit_brute(p - d * 20.0, d, 40.0).is_none());
    // The same ray at z = 3, where the rectangle meets the face, hits it.
    let p3 = DVec3::new(5.0, 0.0005, 3.0) - s.origin;
    assert!(caster.first_hit_brute(p3 - d * 20.0, d, 40.0).is_some());
}
