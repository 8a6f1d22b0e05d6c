//! Footprints in, convex blockers out: Lyon end to end, random polygons with holes, and the
//! local frame under large coordinate offsets.

use crate::common;

use common::*;
use glam::DVec2;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use vocc::geom::predicates::{
    convex_interiors_disjoint, is_strictly_convex_ccw, point_in_convex, point_in_ring, Containment,
};
use vocc::scene::decompose::{convex_pieces, signed_area};
use vocc::scene::footprint::repair_polygon;
use vocc::scene::{self, Shape};

/// Signed area of a repaired polygon: exterior counter-clockwise, holes clockwise.
fn polygon_area(rings: &[Vec<DVec2>]) -> f64 {
    rings.iter().map(|r| signed_area(r)).sum()
}

#[test]
fn lyon_reports_2576_objects_and_pieces_tile_every_footprint() {
    let s = load_lyon();
    assert_eq!(s.objects.len(), 2576);
    assert!(
        s.report.no_blocker.is_empty(),
        "{:?}",
        &s.report.no_blocker[..3.min(s.report.no_blocker.len())]
    );
    let mut by_object: Vec<Vec<&Vec<DVec2>>> = vec![Vec::new(); s.objects.len()];
    for b in &s.blockers {
        by_object[b.object as usize].push(&b.polygon);
    }
    let mut holes = 0;
    for o in &s.objects {
        let Shape::Footprint(fp) = &o.shape else {
            panic!("footprint expected")
        };
        let want: f64 = fp.polygons.iter().map(|p| polygon_area(p)).sum();
        holes += fp.polygons.iter().map(|p| p.len() - 1).sum::<usize>();
        let pieces = &by_object[o.index as usize];
        let got: f64 = pieces.iter().map(|p| signed_area(p)).sum();
        assert!(want > 0.0);
        assert!(
            ((got - want) / want).abs() <= 1e-9,
            "object {} area {got} vs {want}",
            o.index
        );
        for (i, p) in pieces.iter().enumerate() {
            assert!(is_strictly_convex_ccw(p), "object {} piece {i}", o.index);
            for q in &pieces[i + 1..] {
                assert!(
                    convex_interiors_disjoint(p, q),
                    "object {} overlap",
                    o.index
                );
            }
        }
    }
    // The data README counts 116 footprints with holes; every hole survives.
    assert!(holes >= 116, "{holes} holes");
}

#[test]
fn lyon_is_identical_at_a_1e7_m_offset() {
    let text = std::fs::read_to_string(repo(LYON)).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    const OFF: f64 = 1.0e7;
    for f in v["features"].as_array_mut().unwrap() {
        for poly in f["geometry"]["coordinates"].as_array_mut().unwrap() {
            for ring in poly.as_array_mut().unwrap() {
                for p in ring.as_array_mut().unwrap() {
                    let x = p[0].as_f64().unwrap() + OFF;
                    let y = p[1].as_f64().unwrap() + OFF;
                    p[0] = serde_json::json!(x);
                    p[1] = serde_json::json!(y);
                }
            }
        }
    }
    let dir = temp_dir("lyon_offset");
    let moved = dir.join("lyon_offset.geojson");
    std::fs::write(&moved, serde_json::to_vec(&v).unwrap()).unwrap();
    let a = load_lyon();
    let b = scene::load(&[moved], &lyon_options()).unwrap();
    assert_eq!(b.origin.x - a.origin.x, OFF);
    assert_eq!(b.origin.y - a.origin.y, OFF);
    assert_eq!(a.objects.len(), b.objects.len());
    let mut worst = 0.0f64;
    for (oa, ob) in a.objects.iter().zip(&b.objects) {
        let (Shape::Footprint(fa), Shape::Footprint(fb)) = (&oa.shape, &ob.shape) else {
            panic!()
        };
        for (pa, pb) in fa
            .polygons
            .iter()
            .flatten()
            .flatten()
            .zip(fb.polygons.iter().flatten().flatten())
        {
            worst = worst.max((*pa - *pb).abs().max_element());
        }
        worst = worst.max((oa.bbox.min - ob.bbox.min).abs().max_element());
        worst = worst.max((oa.bbox.max - ob.bbox.max).abs().max_element());
    }
    assert!(worst <= 1e-9, "local geometry moved by {worst:e} m");
    // Blockers: near-collinear vertex triples can flip under the offset's rounding, so the
    // decomposition may pick other diagonals; the pieces must still tile the same footprint.
    let area = |s: &vocc::scene::Scene| {
        let mut a = vec![0.0; s.objects.len()];
        for b in &s.blockers {
            a[b.object as usize] += signed_area(&b.polygon);
        }
        a
    };
    // Vertices moved by at most 1e-9 m, so the area may move by at most perimeter x 1e-9 m.
    for (i, (x, y)) in area(&a).iter().zip(area(&b)).enumerate() {
        let Shape::Footprint(fp) = &a.objects[i].shape else {
            panic!()
        };
        let perimeter: f64 = fp
            .polygons
            .iter()
            .flatten()
            .map(|r| {
                (0..r.len())
                    .map(|k| r[k].distance(r[(k + 1) % r.len()]))
                    .sum::<f64>()
            })
            .sum();
        assert!(
            (x - y).abs() <= perimeter * 1e-9,
            "object {i}: piece area {x} vs {y}"
        );
    }
}

/// A star-shaped ring around `c`: `radii` at evenly spread, jittered angles, counter-clockwise.
fn star(c: DVec2, radii: &[f64], jitter: &[f64], rot: f64) -> Vec<DVec2> {
    let n = radii.len();
    (0..n)
        .map(|k| {
            let t = rot + std::f64::consts::TAU * (k as f64 + 0.8 * jitter[k]) / n as f64;
            c + radii[k] * DVec2::new(t.cos(), t.sin())
        })
        .collect()
}

/// A random polygon with holes, valid by construction: the exterior is star-shaped with radii in
/// [60, 100] and at least 8 vertices, so no angular gap exceeds 0.45 pi and every edge stays
/// beyond 60 cos(0.225 pi) = 45.6 of the centre; holes are stars of radius below 7 in separate
/// cells of a 4 x 4 grid of pitch 17, so they reach at most 25.5 sqrt 2 + 7 = 43.1 from it.
fn polygon_with_holes() -> impl Strategy<Value = Vec<Vec<DVec2>>> {
    let ext = (8usize..48).prop_flat_map(|n| {
        (
            prop::collection::vec(60.0f64..100.0, n),
            prop::collection::vec(0.0f64..1.0, n),
            0.0f64..6.3,
        )
    });
    let hole = (3usize..12).prop_flat_map(|n| {
        (
            prop::collection::vec(2.0f64..7.0, n),
            prop::collection::vec(0.0f64..1.0, n),
            0.0f64..6.3,
        )
    });
    let holes = prop::collection::vec(prop::option::weighted(0.3, hole), 16);
    (ext, holes).prop_map(|((r, j, rot), holes)| {
        let mut rings = vec![star(DVec2::ZERO, &r, &j, rot)];
        for (k, h) in holes.into_iter().enumerate() {
            if let Some((hr, hj, hrot)) = h {
                let c = DVec2::new(-25.5 + 17.0 * (k % 4) as f64, -25.5 + 17.0 * (k / 4) as f64);
                let mut ring = star(c, &hr, &hj, hrot);
                ring.reverse();
                rings.push(ring);
            }
        }
        rings
    })
}

proptest! {
    #![proptest_config(Config { cases: 300, rng_seed: RngSeed::Fixed(0x5eed_0002), ..Config::default() })]

    #[test]
    fn random_polygons_with_holes_decompose_exactly(
        rings in polygon_with_holes(),
        probes in prop::collection::vec((-110.0f64..110.0, -110.0f64..110.0), 64),
    ) {
        let fixed = repair_polygon(&rings);
        let valid = fixed.result.expect("valid by construction");
        let pieces = convex_pieces(&valid).unwrap();
        let want = polygon_area(&valid);
        let got: f64 = pieces.iter().map(|p| signed_area(p)).sum();
        prop_assert!(((got - want) / want).abs() <= 1e-9);
        for (i, p) in pieces.iter().enumerate() {
            prop_assert!(is_strictly_convex_ccw(p));
            for q in &pieces[i + 1..] {
                prop_assert!(convex_interiors_disjoint(p, q));
            }
        }
        // Pieces cover exactly the polygon: a point strictly inside the polygon is in some piece,
        // and a point strictly outside it is strictly inside none.
        for (x, y) in probes {
            let p = DVec2::new(x, y);
            let in_ext = point_in_ring(&valid[0], p);
            let in_hole = valid[1..].iter().map(|h| point_in_ring(h, p)).collect::<Vec<_>>();
            let strictly_in = in_ext == Containment::Inside
                && in_hole.iter().all(|&c| c == Containment::Outside);
            let strictly_out = in_ext == Containment::Outside
                || in_hole.contains(&Containment::Inside);
            let hits: Vec<Containment> = pieces.iter().map(|q| point_in_convex(q, p)).collect();
            if strictly_in {
                prop_assert!(hits.iter().any(|&c| c != Containment::Outside));
            }
            if strictly_out {
                prop_assert!(hits.iter().all(|&c| c != Containment::Inside));
            }
        }
    }
}

#[test]
fn heights_fall_back_to_levels_and_missing_ones_are_reported() {
    use vocc::scene::{Location, ReadOptions, SkipReason};
    let path = repo("tests/fixtures/scenes/heights_and_levels.geojson");
    let opts = ReadOptions {
        height_attr: Some("height".into()),
        levels_attr: Some("levels".into()),
        storey_height: 3.5,
        ..ReadOptions::default()
    };
    let s = scene::load(std::slice::from_ref(&path), &opts).unwrap();
    let tops: Vec<(String, f64)> = s
        .objects
        .iter()
        .map(|o| (o.name.clone(), o.bbox.max.z - o.bbox.min.z))
        .collect();
    assert_eq!(
        tops,
        vec![
            ("h".to_string(), 12.5),
            ("levels-only".to_string(), 14.0),
            ("string-height".to_string(), 7.5)
        ]
    );
    let skipped: Vec<(Location, SkipReason)> = s
        .report
        .skipped
        .iter()
        .map(|(_, k)| (k.location.clone(), k.reason.clone()))
        .collect();
    assert_eq!(
        skipped,
        vec![
            (Location::Feature(3), SkipReason::NoHeight),
            (Location::Feature(4), SkipReason::NotAreal("Point".into())),
            (Location::Feature(5), SkipReason::EmptyGeometry),
        ]
    );
    // Without the levels fallback, the storey-only feature is skipped too.
    let opts = ReadOptions {
        height_attr: Some("height".into()),
        ..ReadOptions::default()
    };
    let s = scene::load(&[path], &opts).unwrap();
    assert_eq!(s.objects.len(), 2);
    assert!(s
        .report
        .skipped
        .iter()
        .any(|(_, k)| k.location == Location::Feature(1) && k.reason == SkipReason::NoHeight));
}
