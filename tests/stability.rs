//! The numerical-stability suite (issue 6): named hard cases, each written as a GeoJSON file at
//! coordinate offsets of 0, 10^5, 10^6 and 10^7 m, loaded, baked on 100 m cells, and checked.
//!
//! Input: each case's footprints in local metres (centimetre decimals, like surveyed data), with
//! `world = offset + local` rounded once to f64 and printed in shortest round-trip form, which is
//! what a user's file at that position holds.
//! Output: per case and offset, the scene's counts, the store's local frame and records, and each
//! cell's PVS.
//! Invariants checked:
//! - conservativeness at every offset, with the oracles of docs/DESIGN.md section 6: every stored VO,
//!   decoded from the bytes, passes rule 2, the exact verifier and the brute-force ray oracle
//!   (`common::check_stored_vos`); rays from eye points to every stored VO meet real geometry
//!   first (the 3D VO check); the ground-truth visible set lies inside the PVS;
//! - the same local results at every offset: object, blocker, skip and repair counts, the
//!   frame less its origin, every cell's record byte for byte, and every cell's PVS;
//! - each case has something to lose: the suite as a whole stores VOs and culls objects, so
//!   "the same" is not "all empty".

use crate::common;

use std::fmt::Write as _;

use common::{check_stored_vos, temp_dir};
use vocc::eval::metrics::{cell_vs, compare, object_boxes, vo_rays};
use vocc::eval::raycast::Caster;
use vocc::eval::report::bake;
use vocc::eval::truth::TruthParams;
use vocc::runtime::culler::{pvs, BoxTree};
use vocc::runtime::format::{CellRecord, Store};
use vocc::runtime::frame::Frame;
use vocc::scene::{self, ReadOptions};

const OFFSETS: [f64; 4] = [0.0, 1e5, 1e6, 1e7];

/// A footprint: one exterior ring in local metres (as listed, open or closed) and a height.
struct Building {
    ring: Vec<(f64, f64)>,
    h: f64,
}

fn rect(x0: f64, y0: f64, x1: f64, y1: f64, h: f64) -> Building {
    Building {
        ring: vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)],
        h,
    }
}

/// What every case stands in: a street with low houses in front (y < 100), a long tall row
/// across it, and a quarter of shorter blocks behind, so that cells in front get VOs and cull.
fn context() -> Vec<Building> {
    let mut v = vec![rect(0.0, 0.0, 7.31, 9.17, 6.2)];
    for i in 0..5 {
        let x = 40.13 + 110.0 * i as f64;
        v.push(rect(x, 30.27, x + 12.4, 41.9, 7.5));
    }
    v.push(rect(3.21, 120.07, 603.29, 135.44, 24.5));
    for i in 0..10 {
        for j in 0..4 {
            let (x, y) = (12.37 + 58.3 * i as f64, 165.11 + 47.9 * j as f64);
            v.push(rect(
                x,
                y,
                x + 21.53,
                y + 19.87,
                9.0 + 2.5 * ((i + j) % 4) as f64,
            ));
        }
    }
    v
}

fn case_mm_and_km_features() -> Vec<Building> {
    let mut v = context();
    // A kilometre-long, 2.5 m thick wall in front of the row.
    v.push(rect(-200.0, 110.0, 800.0, 112.5, 30.0));
    // Millimetre pillars, a millimetre-thin wall and a building with a 1 mm slot.
    v.push(rect(50.0, 50.0, 50.001, 50.001, 30.0));
    v.push(rect(300.123, 90.456, 300.124, 90.457, 30.0));
    v.push(rect(200.0, 60.0, 210.0, 60.001, 12.0));
    v.push(Building {
        ring: vec![
            (400.0, 60.0),
            (410.0, 60.0),
            (410.0, 70.0),
            (405.0005, 70.0),
            (405.0005, 62.0),
            (404.9995, 62.0),
            (404.9995, 70.0),
            (400.0, 70.0),
        ],
        h: 15.0,
    });
    v
}

fn case_degenerate_rings() -> Vec<Building> {
    let mut v = context();
    let ring = |pts: &[(f64, f64)], h| Building {
        ring: pts.to_vec(),
        h,
    };
    // Repeated consecutive vertices.
    v.push(ring(
        &[
            (60.0, 60.0),
            (60.0, 60.0),
            (70.5, 60.0),
            (70.5, 70.5),
            (70.5, 70.5),
            (60.0, 70.5),
        ],
        10.0,
    ));
    // Collinear vertices along every side.
    v.push(ring(
        &[
            (150.1, 60.2),
            (155.1, 60.2),
            (160.1, 60.2),
            (160.1, 65.2),
            (160.1, 70.2),
            (150.1, 70.2),
        ],
        10.0,
    ));
    // A zero-area spike out of a square.
    v.push(ring(
        &[
            (250.0, 60.0),
            (260.0, 60.0),
            (260.0, 65.0),
            (290.0, 65.0),
            (260.0, 65.0),
            (260.0, 70.0),
            (250.0, 70.0),
        ],
        10.0,
    ));
    // Only two distinct points; all points collinear; a bow tie.
    v.push(ring(&[(350.0, 60.0), (360.0, 60.0), (350.0, 60.0)], 10.0));
    v.push(ring(&[(370.0, 60.0), (380.0, 61.0), (390.0, 62.0)], 10.0));
    v.push(ring(
        &[
            (450.3, 60.3),
            (460.7, 70.7),
            (460.7, 60.3),
            (450.3, 70.7),
            (450.3, 60.3),
        ],
        10.0,
    ));
    // A ring closed twice over.
    v.push(ring(
        &[
            (500.0, 60.0),
            (510.0, 60.0),
            (510.0, 70.0),
            (500.0, 60.0),
            (500.0, 60.0),
        ],
        10.0,
    ));
    v
}

fn case_touching_overlapping_duplicated() -> Vec<Building> {
    let mut v = context();
    // Row houses sharing walls exactly.
    for i in 0..8 {
        let x = 100.0 + 9.37 * i as f64;
        v.push(rect(x, 80.11, x + 9.37, 95.42, 9.0 + i as f64));
    }
    // Overlapping pair, an exact duplicate, one building inside another, a corner touch.
    v.push(rect(300.0, 80.0, 320.0, 95.0, 12.0));
    v.push(rect(310.0, 85.0, 330.0, 100.0, 14.0));
    v.push(rect(400.17, 80.23, 420.29, 97.31, 16.0));
    v.push(rect(400.17, 80.23, 420.29, 97.31, 16.0));
    v.push(rect(500.0, 80.0, 530.0, 99.0, 11.0));
    v.push(rect(505.0, 85.0, 515.0, 95.0, 18.0));
    v.push(rect(530.0, 99.0, 540.0, 105.0, 11.0));
    v
}

fn case_zero_height_buildings() -> Vec<Building> {
    let mut v = context();
    // A zero-height slab as long as the row, in front of it, and zero- and 1 mm-high houses.
    v.push(rect(3.21, 100.5, 603.29, 115.0, 0.0));
    for i in 0..6 {
        let x = 20.0 + 90.0 * i as f64;
        v.push(rect(
            x,
            60.0,
            x + 15.0,
            75.0,
            if i % 2 == 0 { 0.0 } else { 0.001 },
        ));
    }
    v
}

fn case_cell_edges_along_walls() -> Vec<Building> {
    // The grid starts at the context's corner (0, 0), so cell edges lie on multiples of 100 m.
    let mut v = context();
    // Walls on the lines x = 100, 200, 300 and y = 100, from either side, and one straddling.
    v.push(rect(90.0, 50.0, 100.0, 100.0, 20.0));
    v.push(rect(200.0, 50.0, 210.0, 100.0, 20.0));
    v.push(rect(290.0, 90.0, 300.0, 100.0, 20.0));
    v.push(rect(300.0, 100.0, 400.0, 110.0, 22.0));
    v.push(rect(450.0, 95.0, 550.0, 105.0, 22.0));
    // A wall along the whole row's front, on the cell line y = 200 behind the row.
    v.push(rect(0.0, 200.0, 600.0, 201.37, 8.0));
    v
}

type Case = (&'static str, fn() -> Vec<Building>);

const CASES: [Case; 5] = [
    ("mm_and_km_features", case_mm_and_km_features),
    ("degenerate_rings", case_degenerate_rings),
    (
        "touching_overlapping_duplicated",
        case_touching_overlapping_duplicated,
    ),
    ("zero_height_buildings", case_zero_height_buildings),
    ("cell_edges_along_walls", case_cell_edges_along_walls),
];

fn geojson(buildings: &[Building], offset: f64) -> String {
    let mut s = String::from("{\"type\":\"FeatureCollection\",\"features\":[\n");
    for (i, b) in buildings.iter().enumerate() {
        let ring: Vec<String> = b
            .ring
            .iter()
            .map(|&(x, y)| format!("[{:?},{:?}]", offset + x, offset + y))
            .collect();
        let _ = writeln!(
            s,
            "{}{{\"type\":\"Feature\",\"properties\":{{\"h\":{:?}}},\"geometry\":{{\"type\":\"Polygon\",\"coordinates\":[[{}]]}}}}",
            if i == 0 { "" } else { "," },
            b.h,
            ring.join(",")
        );
    }
    s.push_str("]}\n");
    s
}

/// What must not depend on the offset.
#[derive(Debug, PartialEq)]
struct Local {
    objects: usize,
    blockers: usize,
    skipped: usize,
    repairs: usize,
    no_blocker: usize,
    frame: Frame,
    records: Vec<CellRecord>,
    pvs: Vec<Vec<u32>>,
}

/// Totals over a case at one offset, for the report and the "something to lose" check.
#[derive(Debug, Default)]
struct Checked {
    vos: usize,
    culled: usize,
    rays: u64,
    vs: usize,
}

fn run(name: &str, buildings: &[Building], offset: f64) -> (Local, Checked) {
    let dir = temp_dir(&format!("stability-{name}-{offset:e}"));
    let path = dir.join("scene.geojson");
    std::fs::write(&path, geojson(buildings, offset)).unwrap();
    let opts = ReadOptions {
        height_attr: Some("h".into()),
        ..ReadOptions::default()
    };
    let s =
        scene::load(&[path], &opts).unwrap_or_else(|e| panic!("{name} at offset {offset:e}: {e}"));
    for o in [s.origin.x, s.origin.y] {
        assert!(
            o % 1000.0 == 0.0 && (o - offset).abs() <= 1000.0,
            "{name} at offset {offset:e}: origin {o}"
        );
    }
    let baked = bake(&s, Default::default(), None).expect("the bake runs");
    let store = Store::parse(&baked.bytes).expect("a valid store");
    let mut frame = *store.frame();
    frame.origin = [0.0; 3];

    // Oracle 1 and 2: every stored VO passes rule 2, the verifier and the brute ray oracle.
    check_stored_vos(&s, &store);
    let caster = Caster::new(&s);
    let tree = BoxTree::new(&object_boxes(&s));
    let truth = TruthParams {
        eyes: 16,
        samples_per_object: 2,
        radius: None,
        seed: 11,
        eye_above: None,
    };
    let mut checked = Checked::default();
    let mut records = Vec::new();
    let mut pvs_all = Vec::new();
    for id in 0..store.cell_count() {
        let rec = store.cell(id).unwrap();
        // Oracle 3 (the 3D VO check): no ray from the cell reaches a stored VO unblocked.
        let r = vo_rays(&caster, &store, id, 8, 8, 11);
        assert_eq!(
            r.reached, 0,
            "{name} at {offset:e}, cell {id}: rays reach a VO"
        );
        checked.rays += r.rays;
        // The ground truth lies inside the PVS.
        let mut out = Vec::new();
        pvs(store.frame(), id, &rec, &tree, &mut out);
        let vs = cell_vs(&s, &store, &caster, id, &truth);
        let e = compare(&s, id, rec.vos().len(), &vs, &out);
        assert!(
            e.false_culls.is_empty(),
            "{name} at offset {offset:e}, cell {id}: visible objects {:?} culled",
            e.false_culls
        );
        checked.vos += rec.vos().len();
        checked.culled += s.objects.len() - out.len();
        checked.vs += vs.len();
        records.push(rec);
        pvs_all.push(out);
    }
    let local = Local {
        objects: s.objects.len(),
        blockers: s.blockers.len(),
        skipped: s.report.skipped.len(),
        repairs: s.report.repairs.len(),
        no_blocker: s.report.no_blocker.len(),
        frame,
        records,
        pvs: pvs_all,
    };
    (local, checked)
}

#[test]
fn hard_cases_are_conservative_and_give_the_same_local_results_at_every_offset() {
    let mut report = String::new();
    let (mut vos, mut culled) = (0, 0);
    for (name, case) in CASES {
        let buildings = case();
        let (at_zero, c0) = run(name, &buildings, 0.0);
        let _ = writeln!(
            report,
            "{name}: {} objects, {} blockers, {} cells, {} VOs, {} culls over all cells, \
             VS {} , {} VO rays",
            at_zero.objects,
            at_zero.blockers,
            at_zero.records.len(),
            c0.vos,
            c0.culled,
            c0.vs,
            c0.rays
        );
        vos += c0.vos;
        culled += c0.culled;
        for offset in &OFFSETS[1..] {
            let (local, c) = run(name, &buildings, *offset);
            assert_eq!(
                (c.vos, c.culled, c.vs),
                (c0.vos, c0.culled, c0.vs),
                "{name}: totals at offset {offset:e} differ from offset 0"
            );
            assert!(
                local == at_zero,
                "{name}: local results at offset {offset:e} differ from offset 0"
            );
        }
    }
    println!("{report}");
    assert!(vos >= 50, "the cases store only {vos} VOs:\n{report}");
    assert!(
        culled >= 100,
        "the cases cull only {culled} objects:\n{report}"
    );
}
