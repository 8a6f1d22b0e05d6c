//! The ground-truth visible set and its ray caster.
//!
//! Input: small hand-built scenes (GeoJSON footprints and OBJ boxes written to temp files), a
//! generated city, and the Lyon footprints under `data/`. Output: assertions that hidden objects
//! are not in the VS and visible ones are, that the grid walk matches a brute-force loop, and
//! sanity bounds on a Lyon cell's VS.
//! Invariant: nothing here calls the occlusion pipeline; the VS is built from the scene alone.

use crate::common;

use std::path::PathBuf;

use glam::DVec3;
use vocc::eval::raycast::Caster;
use vocc::eval::truth::{convergence, visible_set, visible_set_counted, TruthParams};
use vocc::scene::gencity::{generate, write_geojson, CityParams};
use vocc::scene::{self, ReadOptions, Scene};

/// World offset of the hand-built scenes (a projected CRS's magnitude).
const W: (f64, f64) = (600_000.0, 5_000_000.0);
const EYES: (f64, f64) = (1.5, 2.0);

fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<(f64, f64)> {
    vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]
}

/// A feature: its rings (offsets from `W`) and height.
type Feature = (Vec<Vec<(f64, f64)>>, f64);

/// A GeoJSON FeatureCollection of one Polygon per feature.
fn geojson(features: &[Feature]) -> String {
    let f: Vec<String> = features
        .iter()
        .enumerate()
        .map(|(i, (rings, h))| {
            let rings: Vec<String> = rings
                .iter()
                .map(|r| {
                    let pts: Vec<String> = r
                        .iter()
                        .map(|(x, y)| format!("[{},{}]", W.0 + x, W.1 + y))
                        .collect();
                    format!("[{}]", pts.join(","))
                })
                .collect();
            format!(
                r#"{{"type":"Feature","properties":{{"id":"f{i}","height":{h}}},"geometry":{{"type":"Polygon","coordinates":[{}]}}}}"#,
                rings.join(",")
            )
        })
        .collect();
    format!(
        r#"{{"type":"FeatureCollection","features":[{}]}}"#,
        f.join(",")
    )
}

fn load_text(test: &str, file: &str, text: &str) -> Scene {
    let dir = common::temp_dir(test);
    let path: PathBuf = dir.join(file);
    std::fs::write(&path, text).unwrap();
    let opts = ReadOptions {
        height_attr: Some("height".into()),
        ..ReadOptions::default()
    };
    scene::load(&[path], &opts).unwrap()
}

/// A cell given as offsets from `W`, in the scene's local frame.
fn local_cell(s: &Scene, c: [f64; 4]) -> [f64; 4] {
    let (ox, oy) = (W.0 - s.origin.x, W.1 - s.origin.y);
    [c[0] + ox, c[1] + oy, c[2] + ox, c[3] + oy]
}

fn params(eyes: usize, samples: usize) -> TruthParams {
    TruthParams {
        eyes,
        samples_per_object: samples,
        radius: None,
        seed: 7,
        eye_above: None,
    }
}

const CELL: [f64; 4] = [40.0, 0.0, 60.0, 10.0];

fn vs_of(s: &Scene, cell: [f64; 4]) -> Vec<u32> {
    let c = Caster::new(s);
    visible_set(&c, s, local_cell(s, cell), EYES, &params(16, 8))
}

#[test]
fn a_wall_hides_what_stands_behind_it() {
    // 0: a long wall, 30 m high; 1: a small building behind it; 2: one beside the cell.
    let s = load_text(
        "truth-wall",
        "wall.geojson",
        &geojson(&[
            (vec![rect(-100.0, 30.0, 200.0, 32.0)], 30.0),
            (vec![rect(45.0, 60.0, 55.0, 70.0)], 10.0),
            (vec![rect(80.0, 0.0, 90.0, 10.0)], 5.0),
        ]),
    );
    assert_eq!(vs_of(&s, CELL), vec![0, 2]);
}

#[test]
fn a_gap_in_the_row_shows_what_stands_behind_it() {
    let s = load_text(
        "truth-gap",
        "gap.geojson",
        &geojson(&[
            (vec![rect(-100.0, 30.0, 45.0, 32.0)], 30.0),
            (vec![rect(55.0, 30.0, 200.0, 32.0)], 30.0),
            (vec![rect(45.0, 60.0, 55.0, 70.0)], 10.0),
        ]),
    );
    assert_eq!(vs_of(&s, CELL), vec![0, 1, 2]);
}

#[test]
fn a_notch_exposes_what_stands_in_it_but_the_back_still_hides() {
    // 0: a U open toward the cell (notch x 40..60, y 30..60); 1: a low building in the notch;
    // 2: a building behind the U's back bar.
    let u = vec![
        (20.0, 30.0),
        (40.0, 30.0),
        (40.0, 60.0),
        (60.0, 60.0),
        (60.0, 30.0),
        (80.0, 30.0),
        (80.0, 70.0),
        (20.0, 70.0),
        (20.0, 30.0),
    ];
    let s = load_text(
        "truth-notch",
        "notch.geojson",
        &geojson(&[
            (vec![u], 20.0),
            (vec![rect(45.0, 50.0, 55.0, 55.0)], 5.0),
            (vec![rect(45.0, 80.0, 55.0, 90.0)], 10.0),
        ]),
    );
    assert_eq!(vs_of(&s, CELL), vec![0, 1]);
}

#[test]
fn a_courtyard_hole_is_not_solid() {
    // 0: a block with a courtyard (hole) that the cell lies in; 1: a building in the courtyard.
    // Eyes stand in the courtyard, so they see its inner walls and the building, nothing else.
    let s = load_text(
        "truth-courtyard",
        "courtyard.geojson",
        &geojson(&[
            (
                vec![
                    rect(-100.0, -100.0, 200.0, 200.0),
                    rect(0.0, -20.0, 100.0, 100.0),
                ],
                20.0,
            ),
            (vec![rect(45.0, 60.0, 55.0, 70.0)], 5.0),
            (vec![rect(300.0, 0.0, 310.0, 10.0)], 50.0),
        ]),
    );
    assert_eq!(vs_of(&s, CELL), vec![0, 1]);
}

#[test]
fn eyes_inside_a_building_see_nothing() {
    let s = load_text(
        "truth-inside",
        "inside.geojson",
        &geojson(&[
            (vec![rect(-50.0, -50.0, 150.0, 60.0)], 30.0),
            (vec![rect(300.0, 0.0, 310.0, 10.0)], 50.0),
        ]),
    );
    assert_eq!(vs_of(&s, CELL), Vec::<u32>::new());
    // The same cell, eyes above the roof: both are seen.
    let c = Caster::new(&s);
    let vs = visible_set(&c, &s, local_cell(&s, CELL), (31.0, 32.0), &params(8, 8));
    assert_eq!(vs, vec![0, 1]);
}

/// An OBJ box as a closed mesh of six quads (counter-clockwise seen from outside).
fn obj_box(name: &str, lo: (f64, f64, f64), hi: (f64, f64, f64), first: usize) -> String {
    let mut s = format!("o {name}\n");
    for k in 0..8 {
        let x = W.0 + if k & 1 == 0 { lo.0 } else { hi.0 };
        let y = W.1 + if k & 2 == 0 { lo.1 } else { hi.1 };
        let z = if k & 4 == 0 { lo.2 } else { hi.2 };
        s += &format!("v {x} {y} {z}\n");
    }
    for f in [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ] {
        let ix: Vec<String> = f.iter().map(|i| (i + first).to_string()).collect();
        s += &format!("f {}\n", ix.join(" "));
    }
    s
}

#[test]
fn a_mesh_box_hides_what_stands_behind_it() {
    let text = obj_box("wall", (-100.0, 30.0, 0.0), (200.0, 32.0, 30.0), 1)
        + &obj_box("hidden", (45.0, 60.0, 0.0), (55.0, 70.0, 10.0), 9)
        + &obj_box("beside", (80.0, 0.0, 0.0), (90.0, 10.0, 5.0), 17);
    let s = load_text("truth-mesh", "boxes.obj", &text);
    assert_eq!(s.objects.len(), 3);
    // Sampled points lie on the boxes' faces, spread over all six.
    let c = Caster::new(&s);
    let mut r = SplitMix(9);
    let b = s.objects[1].bbox;
    let mut faces = [0usize; 6];
    for _ in 0..600 {
        let q = c.sample_surface(1, &mut || r.f64()).unwrap();
        let on: Vec<usize> = (0..6)
            .filter(|&k| {
                let v = if k < 3 { b.min[k] } else { b.max[k - 3] };
                (q[k % 3] - v).abs() < 1e-9
            })
            .collect();
        assert_eq!(on.len(), 1, "{q} on faces {on:?}");
        faces[on[0]] += 1;
    }
    assert!(faces.iter().all(|&n| n > 10), "{faces:?}");
    assert!((c.surface_area(1) - 2.0 * (100.0 + 100.0 + 100.0)).abs() < 1e-6);
    assert_eq!(vs_of(&s, CELL), vec![0, 2]);
    // Eyes inside the closed box are dropped (parity of an upward ray); high above, all three
    // are seen.
    let inside = visible_set(
        &c,
        &s,
        local_cell(&s, [0.0, 30.5, 20.0, 31.5]),
        EYES,
        &params(8, 4),
    );
    assert!(inside.is_empty(), "{inside:?}");
    let high = visible_set(&c, &s, local_cell(&s, CELL), (100.0, 101.0), &params(8, 8));
    assert_eq!(high, vec![0, 1, 2]);
}

/// A generated city, loaded.
fn city(test: &str, n: usize) -> Scene {
    let dir = common::temp_dir(test);
    let path = dir.join("city.geojson");
    let b = generate(&CityParams {
        buildings: n,
        seed: 11,
    });
    write_geojson(std::fs::File::create(&path).unwrap(), &b).unwrap();
    let opts = ReadOptions {
        height_attr: Some("height".into()),
        ..ReadOptions::default()
    };
    scene::load(&[path], &opts).unwrap()
}

struct SplitMix(u64);
impl SplitMix {
    fn f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn same_hit(a: Option<(u32, f64)>, b: Option<(u32, f64)>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some((oa, ta)), Some((ob, tb))) => {
            oa == ob && (ta - tb).abs() <= 1e-9 * ta.abs().max(tb.abs())
        }
        _ => false,
    }
}

#[test]
fn the_grid_walk_matches_brute_force() {
    let s = city("truth-brute", 400);
    let c = Caster::new(&s);
    let e = s.extent();
    let mut r = SplitMix(3);
    let mut hits = 0;
    let n = 3000;
    for k in 0..n {
        let o = DVec3::new(
            e.min.x - 20.0 + (e.max.x - e.min.x + 40.0) * r.f64(),
            e.min.y - 20.0 + (e.max.y - e.min.y + 40.0) * r.f64(),
            60.0 * r.f64(),
        );
        let d = match k % 4 {
            // Near-horizontal, long.
            0 => DVec3::new(r.f64() - 0.5, r.f64() - 0.5, 0.05 * (r.f64() - 0.5)),
            // Any direction, scaled.
            1 => DVec3::new(r.f64() - 0.5, r.f64() - 0.5, r.f64() - 0.5) * 37.0,
            // Vertical or nearly, downward.
            2 => DVec3::new(1e-9 * (r.f64() - 0.5), 0.0, -1.0),
            // Exactly vertical.
            _ => DVec3::new(0.0, 0.0, -1.0),
        };
        let t_max = if k % 2 == 0 { 1e4 } else { 100.0 * r.f64() };
        let g = c.first_hit(o, d, t_max);
        let b = c.first_hit_brute(o, d, t_max);
        assert!(
            same_hit(g, b),
            "ray {k}: {o} {d} {t_max}: grid {g:?}, brute {b:?}"
        );
        hits += g.is_some() as usize;
    }
    assert!(hits > n / 5 && hits < n, "{hits} of {n} rays hit");
    // Rays aimed at sampled surface points, from eyes at street level.
    for k in 0..2000 {
        let o = DVec3::new(
            e.min.x + (e.max.x - e.min.x) * r.f64(),
            e.min.y + (e.max.y - e.min.y) * r.f64(),
            1.5,
        );
        if c.contains(o).is_some() {
            continue;
        }
        let x = (r.f64() * s.objects.len() as f64) as u32;
        let q = c.sample_surface(x, &mut || r.f64()).unwrap();
        let g = c.first_hit(o, q - o, 1.0 + 1e-9);
        let b = c.first_hit_brute(o, q - o, 1.0 + 1e-9);
        assert!(same_hit(g, b), "aimed ray {k}: grid {g:?}, brute {b:?}");
    }
}

#[test]
fn rays_reach_sampled_roof_points_from_above() {
    let s = city("truth-roofs", 100);
    let c = Caster::new(&s);
    let mut r = SplitMix(5);
    let mut roofs = 0;
    for o in &s.objects {
        for _ in 0..20 {
            let q = c.sample_surface(o.index, &mut || r.f64()).unwrap();
            assert!(q.z >= o.bbox.min.z && q.z <= o.bbox.max.z);
            if q.z != o.bbox.max.z {
                continue;
            }
            roofs += 1;
            let eye = q + DVec3::new(3.0, -2.0, 200.0);
            let (hit, t) = c
                .first_hit(eye, q - eye, 1.0 + 1e-9)
                .expect("the roof is hit");
            assert_eq!(hit, o.index);
            assert!((t - 1.0).abs() < 1e-9, "{t}");
        }
    }
    assert!(roofs > 100, "{roofs}");
}

/// Grid walk against brute force on real data, where buildings touch and meshes share faces:
/// the first `t` must agree; the object may differ only on an exact tie.
fn matches_brute_on(s: &Scene, rays: usize, seed: u64) {
    let c = Caster::new(s);
    let e = s.extent();
    let mut r = SplitMix(seed);
    let (mut hits, mut other) = (0, 0);
    for k in 0..rays {
        let o = DVec3::new(
            e.min.x + (e.max.x - e.min.x) * r.f64(),
            e.min.y + (e.max.y - e.min.y) * r.f64(),
            e.min.z + (e.max.z - e.min.z) * r.f64() * 1.2,
        );
        let q = DVec3::new(
            e.min.x + (e.max.x - e.min.x) * r.f64(),
            e.min.y + (e.max.y - e.min.y) * r.f64(),
            e.min.z + (e.max.z - e.min.z) * r.f64(),
        );
        let g = c.first_hit(o, q - o, 1.0);
        let b = c.first_hit_brute(o, q - o, 1.0);
        match (g, b) {
            (None, None) => {}
            (Some((og, tg)), Some((ob, tb))) => {
                assert!(
                    (tg - tb).abs() <= 1e-9 * tg.max(tb),
                    "ray {k}: {g:?} vs {b:?}"
                );
                hits += 1;
                other += (og != ob) as usize;
            }
            _ => panic!("ray {k}: grid {g:?}, brute {b:?}"),
        }
    }
    assert!(hits > rays / 10, "{hits} of {rays}");
    assert!(other * 100 <= hits, "{other} ties of {hits}");
}

#[test]
fn the_grid_walk_matches_brute_force_on_real_meshes_and_footprints() {
    let opts = ReadOptions::default();
    let delft = scene::load(&[common::repo("data/delft/delft_buildings.obj")], &opts).unwrap();
    matches_brute_on(&delft, 2000, 1);
    let lyon = common::load_lyon();
    matches_brute_on(&lyon, 500, 2);
}

/// The Lyon cell around world (1842000, 5176050): a 100 m square, local frame.
fn lyon_cell(s: &Scene, wx: f64, wy: f64) -> [f64; 4] {
    let (x, y) = ((wx / 100.0).floor() * 100.0, (wy / 100.0).floor() * 100.0);
    [
        x - s.origin.x,
        y - s.origin.y,
        x + 100.0 - s.origin.x,
        y + 100.0 - s.origin.y,
    ]
}

#[test]
fn lyon_cell_visible_set_is_plausible_and_deterministic() {
    let s = common::load_lyon();
    let c = Caster::new(&s);
    let cell = lyon_cell(&s, 1_842_000.0, 5_176_050.0);
    let p = TruthParams {
        eyes: 16,
        samples_per_object: 2,
        radius: Some(600.0),
        seed: 1,
        eye_above: None,
    };
    let (vs, rays) = visible_set_counted(&c, &s, cell, EYES, &p);
    eprintln!(
        "Lyon cell {cell:?}: |VS| = {} of {}, {rays} rays",
        vs.len(),
        s.objects.len()
    );
    assert!(
        vs.len() >= 30 && vs.len() < s.objects.len() / 2,
        "{}",
        vs.len()
    );
    assert!(vs.windows(2).all(|w| w[0] < w[1]));
    // Deterministic, also on one thread.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| visible_set(&c, &s, cell, EYES, &p));
    assert_eq!(one, vs);
    // Nested: fewer eyes give a subset.
    let fewer = visible_set(
        &c,
        &s,
        cell,
        EYES,
        &TruthParams {
            eyes: 4,
            ..p.clone()
        },
    );
    assert!(fewer.iter().all(|i| vs.binary_search(i).is_ok()));
    assert!(fewer.len() < vs.len());
    // Most objects standing in the cell are seen from it (their walls face its streets).
    let near: Vec<u32> = s
        .objects
        .iter()
        .filter(|o| {
            o.bbox.min.x < cell[2]
                && o.bbox.max.x > cell[0]
                && o.bbox.min.y < cell[3]
                && o.bbox.max.y > cell[1]
        })
        .map(|o| o.index)
        .collect();
    let seen = near.iter().filter(|i| vs.binary_search(i).is_ok()).count();
    eprintln!("objects meeting the cell: {}, seen {seen}", near.len());
    assert!(
        !near.is_empty() && seen * 2 >= near.len(),
        "{seen} of {}",
        near.len()
    );
    // Only targets (bounding box within 600 m) and what stands in front of them are hit: a
    // blocker's hit point lies between the eye and a target point, so within 600 m plus a
    // target's size of the cell.
    for &i in &vs {
        let b = s.objects[i as usize].bbox;
        let dx = (cell[0] - b.max.x).max(b.min.x - cell[2]).max(0.0);
        let dy = (cell[1] - b.max.y).max(b.min.y - cell[3]).max(0.0);
        assert!(
            dx.hypot(dy) <= 800.0,
            "object {i} is {} m away",
            dx.hypot(dy)
        );
    }
}

/// Not run by default: convergence and ray speed on Lyon, single thread, for the report.
/// `cargo test --release --test all truth:: -- --ignored --nocapture`
#[test]
#[ignore]
fn lyon_convergence_report() {
    let s = common::load_lyon();
    let c = Caster::new(&s);
    eprintln!("grid {:?}", c.grid_shape());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    for (wx, wy) in [
        (1_842_000.0, 5_176_050.0),
        (1_842_350.0, 5_176_550.0),
        (1_841_650.0, 5_175_450.0),
    ] {
        let cell = lyon_cell(&s, wx, wy);
        let base = TruthParams {
            eyes: 1,
            samples_per_object: 1,
            radius: None,
            seed: 1,
            eye_above: None,
        };
        let t = std::time::Instant::now();
        let pts = pool.install(|| {
            convergence(
                &c,
                &s,
                cell,
                EYES,
                &base,
                &[1, 4, 16, 64, 256],
                &[1, 2, 4, 8],
            )
        });
        let secs = t.elapsed().as_secs_f64();
        let rays: u64 = pts.iter().map(|p| p.rays).sum();
        eprintln!(
            "cell at ({wx}, {wy}): {rays} rays in {secs:.2} s, {:.0} rays/s single thread",
            rays as f64 / secs
        );
        for p in &pts {
            eprintln!(
                "  eyes {:3} samples {} rays {:8} |VS| {}",
                p.eyes, p.samples_per_object, p.rays, p.vs
            );
        }
    }
}

#[test]
fn the_ground_truth_reads_mesh_faces_never_blockers() {
    // Gelderseplein (open 3DBAG meshes, overlapping levels of detail): the visible set and the
    // first hits of rays are the same when every blocker (solid prism or wall) is replaced by a
    // wall across the whole scene: the caster sees the original faces only.
    let mut s = scene::load(
        &[common::repo("data/gelderseplein/gelderseplein.obj")],
        &ReadOptions::default(),
    )
    .unwrap();
    assert!(
        s.blockers.iter().any(|b| b.polygon.len() == 2),
        "no walls to ignore"
    );
    let ext = s.extent();
    let cell = [
        ext.min.x + 150.0,
        ext.min.y + 120.0,
        ext.min.x + 200.0,
        ext.min.y + 170.0,
    ];
    let p = TruthParams {
        eyes: 6,
        samples_per_object: 1,
        radius: None,
        seed: 12,
        eye_above: None,
    };
    let rays: Vec<(DVec3, DVec3)> = (0..200)
        .map(|k| {
            let f = k as f64 / 200.0;
            let o = DVec3::new(cell[0] + 50.0 * f, cell[1] + 25.0, 1.8);
            let a = std::f64::consts::TAU * f * 7.0;
            (o, DVec3::new(a.cos(), a.sin(), 0.05 * (f - 0.5)))
        })
        .collect();
    let look = |s: &Scene| {
        let c = Caster::new(s);
        let hits: Vec<_> = rays
            .iter()
            .map(|&(o, d)| c.first_hit(o, d, 500.0))
            .collect();
        (visible_set(&c, s, cell, EYES, &p), hits)
    };
    let before = look(&s);
    assert!(!before.0.is_empty());
    let fake = vocc::scene::Blocker {
        object: 0,
        polygon: vec![
            glam::DVec2::new(ext.min.x, cell[3] + 1.0),
            glam::DVec2::new(ext.max.x, cell[3] + 1.0),
        ],
        base: ext.min.z - 10.0,
        top: ext.max.z + 10.0,
    };
    s.blockers = vec![fake];
    assert_eq!(look(&s), before);
}
