//! Terrain (issue 32): DEMs refused with their reason, and a city on a slope (Salt River, Cape
//! Town, on its 25 m DEM) baked and checked by all three oracles, with eyes standing on the
//! terrain over the whole cell: the exact verifier over the stored VOs' rule-2 supporters
//! (terrain columns included), rays from eyes to the VOs, and the ray-sampled visible set
//! against the runtime's PVS; the same oracles on a generated steep hillside with a cliff.

use std::path::PathBuf;

use crate::common;

use vocc::eval::metrics::{cell_vs, eval_cell, object_boxes, sample_cells, vo_rays};
use vocc::eval::raycast::Caster;
use vocc::eval::report::bake;
use vocc::eval::truth::TruthParams;
use vocc::runtime::culler::BoxTree;
use vocc::runtime::format::Store;
use vocc::scene::{load, LoadErrorKind, ReadOptions, Scene};

fn salt_river(terrain: bool) -> Scene {
    let opts = ReadOptions {
        height_attr: Some("height".into()),
        base_attr: Some("base_z".into()),
        terrain: if terrain {
            vec![common::repo("data/capetown/capetown_dem25m_utm34s.tif")]
        } else {
            Vec::new()
        },
        ..ReadOptions::default()
    };
    load(
        &[common::repo(
            "data/capetown/salt_river_footprints_utm34s.geojson",
        )],
        &opts,
    )
    .unwrap()
}

#[test]
fn the_dem_is_read_with_its_georeferencing() {
    let s = salt_river(true);
    let t = s.terrain.as_ref().expect("a terrain");
    assert_eq!(t.sources[0].pixel, Some((25.0, 25.0)));
    assert_eq!(t.sources[0].nodata, 0);
    // The DEM's heights near Salt River: sea level to the lower slopes of Devil's Peak.
    assert!(t.zmin > -20.0 && t.zmax < 700.0, "{} {}", t.zmin, t.zmax);
    let ext = s.extent();
    assert!(t.coverage(ext.min.truncate(), ext.max.truncate()) > 0.999);
    assert!(t.blockers.len() > 1000 && t.joined > 1000);
    // The DEM against the TIN of the same model (0.02 m apart at the TIN's vertices, per
    // data/README.md): the buildings' base_z lie on it.
    let g = vocc::eval::ground::Ground::new(&s).unwrap();
    let mut off = Vec::new();
    for o in s.objects.iter().step_by(50) {
        let c = (o.bbox.min.truncate() + o.bbox.max.truncate()) * 0.5;
        off.push((g.height(c).unwrap() - o.bbox.min.z).abs());
    }
    off.sort_by(f64::total_cmp);
    assert!(
        off[off.len() / 2] < 3.0,
        "median |DEM - base| {}",
        off[off.len() / 2]
    );
}

#[test]
fn bad_dems_are_refused_with_their_reason() {
    let dir = common::repo("fuzz/seeds/dem");
    let read = |name: &str| {
        let opts = ReadOptions {
            height_attr: Some("height".into()),
            terrain: vec![dir.join(name)],
            ..ReadOptions::default()
        };
        load(
            &[common::repo(
                "data/capetown/salt_river_footprints_utm34s.geojson",
            )],
            &opts,
        )
    };
    for (name, want) in [
        ("no_georeferencing.tif", "no georeferencing"),
        ("rotated.tif", "rotated"),
        ("truncated.tif", "GeoTIFF"),
    ] {
        let e = read(name).unwrap_err();
        assert!(
            matches!(e.kind, LoadErrorKind::Malformed { .. }),
            "{name}: {e}"
        );
        assert!(e.to_string().contains(want), "{name}: {e}");
        assert!(e.path.ends_with(name));
    }
    // A DEM in another CRS than the scene's names both.
    let opts = ReadOptions {
        height_attr: Some("HAUTEUR".into()),
        terrain: vec![dir.join("float32_point.tif")],
        ..ReadOptions::default()
    };
    let e = load(&[common::repo("data/lyon1/buildings_lyon1.geojson")], &opts).unwrap_err();
    assert!(e.to_string().contains("EPSG:32734"), "{e}");
    // Not a DEM or a mesh.
    let opts = ReadOptions {
        height_attr: Some("height".into()),
        terrain: vec![PathBuf::from("data/README.md")],
        ..ReadOptions::default()
    };
    let e = load(
        &[common::repo(
            "data/capetown/salt_river_footprints_utm34s.geojson",
        )],
        &opts,
    )
    .unwrap_err();
    assert!(
        matches!(e.kind, LoadErrorKind::UnsupportedFormat { .. }),
        "{e}"
    );
}

/// The three oracles on a seeded sample of a scene's cells at `size` metres: the VOs the
/// verifier checked and the objects culled over the sample.
fn three_oracles(s: &Scene, size: f64, n: usize) -> (usize, usize) {
    let params = vocc::bake::params::BakeParams {
        cell_size: size,
        ..Default::default()
    };
    let full = bake(s, params.clone(), Some(&[])).expect("the bake runs");
    let grid = Store::parse(&full.bytes).unwrap();
    let ids = sample_cells(&grid, Some(n), 11);
    let baked = bake(s, params, Some(&ids)).expect("the bake runs");
    let store = Store::parse(&baked.bytes).unwrap();
    // 1. The exact verifier over the rule-2 supporters of every stored VO.
    let (checked, _) = common::check_stored_vos(s, &store);
    let caster = Caster::new(s);
    let tree = BoxTree::new(&object_boxes(s));
    let truth = TruthParams {
        eyes: 8,
        samples_per_object: 1,
        radius: None,
        seed: 3,
        eye_above: None,
    };
    let mut culled = 0;
    for &id in &ids {
        // 2. Rays from eyes on the terrain to the stored VOs meet the scene or the ground.
        let r = vo_rays(&caster, &store, id, 8, 8, 3);
        assert_eq!(
            r.reached, 0,
            "{size} m, cell {id}: {} of {} rays",
            r.reached, r.rays
        );
        // 3. The visible set from eyes on the terrain lies in the PVS.
        let vs = cell_vs(s, &store, &caster, id, &truth);
        let e = eval_cell(s, &store, &tree, id, &vs);
        assert!(
            e.false_culls.is_empty(),
            "{size} m, cell {id}: {:?}",
            e.false_culls
        );
        culled += s.objects.len() - e.pvs;
    }
    (checked, culled)
}

#[test]
fn salt_river_on_its_dem_passes_the_three_oracles_at_50_100_and_200_m() {
    let s = salt_river(true);
    let mut vos = 0;
    for (size, n) in [(50.0, 6), (100.0, 6), (200.0, 3)] {
        let (checked, _) = three_oracles(&s, size, n);
        vos += checked;
    }
    assert!(vos >= 10, "{vos} VOs checked");
}

/// `BakeSummary::ground_rise_m` (what `vocc bake` prints as "the ground rises ... m across the
/// median cell"): over the selected cells on the DEM, the median and the greatest rise, each at
/// least the span of the terrain over its cell (the eyes must cover a camera anywhere on the
/// slope); none without a terrain.
#[test]
fn bake_summary_tells_how_far_the_ground_rises_across_the_cells() {
    use vocc::bake::job::BakeJob;
    use vocc::bake::params::BakeParams;
    let s = salt_river(true);
    let job = BakeJob::new(&s, BakeParams::default()).unwrap();
    let grid = job.plan().frame.grid;
    let ids: Vec<u32> = (0..grid.cell_count() as u32).step_by(97).collect();
    let job = job.cells(&ids).unwrap();
    let out = job.run(&|_| {}).unwrap();
    let [median, most] = out.summary.ground_rise_m.expect("on a terrain");
    let terrain = s.terrain.as_ref().unwrap();
    let spans: Vec<f64> = ids
        .iter()
        .filter_map(|&id| {
            let r = grid.cell_rect(id)?;
            let (lo, hi) =
                terrain.range(glam::DVec2::new(r[0], r[1]), glam::DVec2::new(r[2], r[3]))?;
            Some(hi - lo)
        })
        .collect();
    let widest = spans.iter().copied().fold(0.0, f64::max);
    assert!(median > 0.0 && median <= most, "{median} {most}");
    assert!(
        most >= widest - 0.5,
        "rise {most} m, widest ground span {widest} m"
    );
    let flat = salt_river(false);
    let out = BakeJob::new(&flat, BakeParams::default())
        .unwrap()
        .cells(&ids[..2])
        .unwrap()
        .run(&|_| {})
        .unwrap();
    assert_eq!(out.summary.ground_rise_m, None);
}

/// A steep hillside written to files: an OBJ terrain on a 10 m grid (a slope rising 110 m
/// over 600 m, a hill, a ravine, a 25 m cliff a few metres wide, a 45% ramp, ripples) and
/// GeoJSON footprints with `height` and `base_z` (each reaching 0.5 m into the slope below its
/// lowest corner, its roof some metres above its highest). Deterministic ([`common::uniform`]).
fn steep_hillside(dir: &std::path::Path) -> Scene {
    let (w, h) = (700.0f64, 600.0f64);
    let (x0, y0) = (300_000.0, 6_200_000.0);
    let z = |x: f64, y: f64| {
        42.0 + 110.0 * (y / h).powf(1.3)
            + 35.0 * (-((x - 450.0).powi(2) + (y - 300.0).powi(2)) / (2.0 * 90.0f64.powi(2))).exp()
            - 18.0 * (-((x - 200.0 - 0.2 * y).powi(2)) / (2.0 * 30.0f64.powi(2))).exp()
            + 25.0 / (1.0 + (-(x - 350.0)).exp())
            + 0.45 * (x - 560.0).max(0.0)
            + 3.0 * (x / 37.0).sin() * (y / 53.0).cos()
    };
    let mut obj = String::from("o terrain\n");
    let (nx, ny) = (71, 61);
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (i as f64 * 10.0, j as f64 * 10.0);
            obj += &format!("v {:.3} {:.3} {:.3}\n", x0 + x, y0 + y, z(x, y));
        }
    }
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let a = j * nx + i + 1;
            obj += &format!(
                "f {} {} {}\nf {} {} {}\n",
                a,
                a + 1,
                a + nx + 1,
                a,
                a + nx + 1,
                a + nx
            );
        }
    }
    let mut rnd = common::uniform(0x5eed);
    let mut placed: Vec<(f64, f64, f64)> = Vec::new();
    let mut features = Vec::new();
    while features.len() < 120 {
        let (bw, bd, ang) = (
            8.0 + 22.0 * rnd(),
            8.0 + 17.0 * rnd(),
            std::f64::consts::PI * rnd(),
        );
        let (cx, cy) = (30.0 + (w - 60.0) * rnd(), 30.0 + (h - 60.0) * rnd());
        let r = bw.hypot(bd) / 2.0;
        if placed
            .iter()
            .any(|&(px, py, pr)| (cx - px).hypot(cy - py) < r + pr + 3.0)
        {
            continue;
        }
        placed.push((cx, cy, r));
        let (c, s) = (ang.cos(), ang.sin());
        let pts: Vec<(f64, f64)> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .iter()
            .map(|&(u, v)| (u * bw / 2.0, v * bd / 2.0))
            .map(|(u, v)| (cx + c * u - s * v, cy + s * u + c * v))
            .collect();
        let zs: Vec<f64> = pts.iter().map(|&(x, y)| z(x, y)).collect();
        let (lo, hi) = zs
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        let above = [4.0, 6.0, 7.0, 9.0, 12.0, 15.0, 20.0, 30.0][(rnd() * 8.0) as usize % 8];
        let ring: Vec<String> = pts
            .iter()
            .chain(std::iter::once(&pts[0]))
            .map(|&(x, y)| format!("[{:.3},{:.3}]", x0 + x, y0 + y))
            .collect();
        features.push(format!(
            r#"{{"type":"Feature","properties":{{"height":{:.2},"base_z":{:.2}}},"geometry":{{"type":"Polygon","coordinates":[[{}]]}}}}"#,
            above + 2.0 * rnd() + (hi - lo) + 0.5,
            lo - 0.5,
            ring.join(",")
        ));
    }
    let geojson = format!(
        r#"{{"type":"FeatureCollection","crs":{{"type":"name","properties":{{"name":"urn:ogc:def:crs:EPSG::32734"}}}},"features":[{}]}}"#,
        features.join(",")
    );
    let (fp, tp) = (dir.join("hillside.geojson"), dir.join("hillside.obj"));
    std::fs::write(&fp, geojson).unwrap();
    std::fs::write(&tp, obj).unwrap();
    let opts = ReadOptions {
        height_attr: Some("height".into()),
        base_attr: Some("base_z".into()),
        terrain: vec![tp],
        ..ReadOptions::default()
    };
    load(&[fp], &opts).unwrap()
}

/// Issue 32's held-out slope (ground 42 to 166 m) is not bundled; this hillside stands in for
/// it, steeper than Salt River (its 100 m cells' ground rises tens of metres) and with what a
/// DEM rarely shows: a cliff narrower than the terrain's grid, a 45% ramp, a ravine. The three
/// oracles at 50, 100 and 200 m cells.
#[test]
fn a_steep_hillside_with_a_cliff_passes_the_three_oracles_at_50_100_and_200_m() {
    let dir = common::temp_dir("steep_hillside");
    let s = steep_hillside(&dir);
    assert_eq!(s.objects.len(), 120);
    let t = s.terrain.as_ref().expect("the OBJ terrain is read");
    assert!(t.zmin < 40.0 && t.zmax > 190.0, "{} {}", t.zmin, t.zmax);
    let mut vos = 0;
    let mut culled = 0;
    for (size, n) in [(50.0, 24), (100.0, 12), (200.0, 6)] {
        let (checked, c) = three_oracles(&s, size, n);
        vos += checked;
        culled += c;
    }
    // The oracles looked at stored VOs that hide something, not at empty cells.
    assert!(
        vos >= 10 && culled > 0,
        "{vos} VOs checked, {culled} objects culled"
    );
}
