//! The bake end to end, checked from the store's bytes: every stored VO, decoded as an engine
//! decodes it, passes rule 2 and rule 1 (the exact verifier, and a brute-force ray oracle that
//! shares no code with it); the bytes do not depend on the thread count.

mod common;

use common::{brute_hidden, load_lyon};
use glam::DVec2;
use vocc::bake::pipeline::BakeParams;
use vocc::eval::report::bake;
use vocc::geom::predicates::convex_interiors_disjoint;
use vocc::geom::verify::Verifier;
use vocc::runtime::format::Store;
use vocc::scene::Scene;

/// The centre of Lyon's extract: 3 x 3 cells of 100 m around the cell of the README's picture.
fn region(s: &Scene) -> [f64; 4] {
    let (x, y) = (1842000.0 - s.origin.x, 5176050.0 - s.origin.y);
    [x - 100.0, y - 100.0, x + 100.0, y + 100.0]
}

fn store_bytes(s: &Scene, threads: usize) -> Vec<u8> {
    let params = BakeParams {
        region: Some(region(s)),
        ..BakeParams::default()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| bake(s, params, None).bytes)
}

/// Least distance between an axis-aligned rectangle and a segment that misses it (written here
/// again, apart from the bake's own).
fn rect_segment_distance(r: [f64; 4], a: DVec2, b: DVec2) -> f64 {
    let to_rect = |p: DVec2| {
        let dx = (r[0] - p.x).max(p.x - r[2]).max(0.0);
        let dy = (r[1] - p.y).max(p.y - r[3]).max(0.0);
        dx.hypot(dy)
    };
    let to_seg = |p: DVec2| {
        let d = b - a;
        let t = ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
        p.distance(a + d * t)
    };
    let corners = [
        DVec2::new(r[0], r[1]),
        DVec2::new(r[2], r[1]),
        DVec2::new(r[2], r[3]),
        DVec2::new(r[0], r[3]),
    ];
    corners
        .iter()
        .map(|&c| to_seg(c))
        .chain([to_rect(a), to_rect(b)])
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn stored_vos_pass_rule_2_and_rule_1_from_their_bytes() {
    let s = load_lyon();
    let bytes = store_bytes(&s, 2);
    let store = Store::parse(&bytes).expect("the bake writes a valid store");
    let f = *store.frame();
    let mut checked = 0;
    let mut cells_with_vos = 0;
    for id in 0..store.cell_count() {
        let rec = store.cell(id).unwrap();
        assert!(rec.vos().len() <= 10);
        if rec.vos().is_empty() {
            continue;
        }
        cells_with_vos += 1;
        let r = f.grid.cell_rect(id).unwrap();
        let cell = [
            DVec2::new(r[0], r[1]),
            DVec2::new(r[2], r[1]),
            DVec2::new(r[2], r[3]),
            DVec2::new(r[0], r[3]),
        ];
        let view = f.cell_view(id, rec.ground()).unwrap();
        for q in rec.vos() {
            let vo = f.dequantize(id, rec.ground(), q).unwrap();
            let (a, b) = (DVec2::from(vo.a), DVec2::from(vo.b));
            assert!(vo.h >= view.e1 && vo.g <= view.e0);
            // Rule 2, with the brief's bound and lambda <= 1 (ARCHITECTURE.md).
            let d_near = rect_segment_distance(r, a, b);
            assert!(d_near > 0.0, "cell {id}: a VO touches its cell");
            // Blockers outside the box of the cell and the VO meet no segment between them.
            let lo = cell[0].min(a).min(b);
            let hi = cell[2].max(a).max(b);
            let used: Vec<Vec<DVec2>> = s
                .blockers
                .iter()
                .filter(|bl| {
                    let (bl_lo, bl_hi) = bl
                        .polygon
                        .iter()
                        .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(l, h), v| {
                            (l.min(*v), h.max(*v))
                        });
                    bl_lo.x <= hi.x && bl_hi.x >= lo.x && bl_lo.y <= hi.y && bl_hi.y >= lo.y
                })
                .filter(|bl| {
                    let d_far = cell
                        .iter()
                        .flat_map(|c| bl.polygon.iter().map(move |v| c.distance(*v)))
                        .fold(0.0, f64::max);
                    let bound = view.e1 + (vo.h - view.e1) * (d_far / d_near).min(1.0);
                    bl.base <= view.e0.min(vo.g)
                        && bl.top >= bound
                        && convex_interiors_disjoint(&bl.polygon, &cell)
                })
                .map(|bl| bl.polygon.clone())
                .collect();
            let refs: Vec<&[DVec2]> = used.iter().map(|p| p.as_slice()).collect();
            assert!(
                Verifier::new(&cell, refs.iter().copied()).is_hidden(a, b),
                "cell {id}: stored VO {q:?} ({a} - {b}, top {}) is not certified hidden",
                vo.h
            );
            // The brute-force oracle, on points along the VO.
            for k in 0..=8 {
                let p = a + (b - a) * (k as f64 / 8.0);
                assert!(
                    brute_hidden(&cell, &used, p, 400),
                    "cell {id}: a ray reaches {p} on VO {q:?}"
                );
            }
            checked += 1;
        }
    }
    assert!(cells_with_vos >= 6, "only {cells_with_vos} cells got VOs");
    assert!(checked >= 30, "only {checked} VOs checked");
}

#[test]
fn store_bytes_do_not_depend_on_the_thread_count() {
    let s = load_lyon();
    assert_eq!(store_bytes(&s, 1), store_bytes(&s, 2));
}
