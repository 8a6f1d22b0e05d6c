//! The bake end to end, checked from the store's bytes: every stored VO, decoded as an engine
//! decodes it, passes rule 2 and rule 1 (the exact verifier, and a brute-force ray oracle that
//! shares no code with it), from both generators; the bytes do not depend on the thread
//! count.

use crate::common;

use common::{check_stored_vos, load_lyon};
use vocc::bake::params::{BakeParams, Generator};
use vocc::eval::report::bake;
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
    pool.install(|| bake(s, params, None).expect("the bake runs").bytes)
}

#[test]
fn stored_vos_pass_rule_2_and_rule_1_from_their_bytes() {
    let s = load_lyon();
    let bytes = store_bytes(&s, 2);
    let store = Store::parse(&bytes).expect("the bake writes a valid store");
    let (cells_with_vos, checked) = check_stored_vos(&s, &store);
    assert!(cells_with_vos >= 6, "only {cells_with_vos} cells got VOs");
    assert!(checked >= 30, "only {checked} VOs checked");
}

#[test]
fn store_bytes_do_not_depend_on_the_thread_count() {
    let s = load_lyon();
    assert_eq!(store_bytes(&s, 1), store_bytes(&s, 2));
}

#[test]
fn stored_vos_of_the_growth_generator_pass_rule_2_and_rule_1_from_their_bytes() {
    let s = load_lyon();
    let params = BakeParams {
        region: Some(region(&s)),
        generator: Generator::Growth,
        ..BakeParams::default()
    };
    let baked = bake(&s, params, None).expect("the bake runs");
    assert_ne!(
        baked.bytes,
        store_bytes(&s, 2),
        "the generator changed nothing"
    );
    let store = Store::parse(&baked.bytes).expect("the bake writes a valid store");
    let (cells_with_vos, checked) = check_stored_vos(&s, &store);
    assert!(cells_with_vos >= 6, "only {cells_with_vos} cells got VOs");
    assert!(checked >= 30, "only {checked} VOs checked");
}

/// Lyon with every convex piece replaced by its edges as wall segments (2-vertex blockers) of
/// the same base and top: the walls lie inside the footprint prisms, which the oracles still use.
fn lyon_walls_only() -> Scene {
    let mut s = load_lyon();
    s.blockers = s
        .blockers
        .iter()
        .flat_map(|b| {
            let n = b.polygon.len();
            (0..n).map(move |i| vocc::scene::Blocker {
                polygon: vec![b.polygon[i], b.polygon[(i + 1) % n]],
                ..b.clone()
            })
        })
        .collect();
    s
}

#[test]
fn stored_vos_from_wall_segments_alone_pass_rule_2_and_rule_1_from_their_bytes() {
    // Both generators take 2-vertex blockers without panicking, and every VO they give is
    // stored only after the verifier certified it over the walls.
    let s = lyon_walls_only();
    let [x0, y0, x1, y1] = region(&s);
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    for generator in [Generator::Long, Generator::Growth] {
        let params = BakeParams {
            region: Some([cx - 60.0, cy - 1.0, cx + 1.0, cy + 1.0]),
            generator,
            ..BakeParams::default()
        };
        let baked = bake(&s, params, None).expect("the bake runs");
        let store = Store::parse(&baked.bytes).expect("the bake writes a valid store");
        let (cells_with_vos, checked) = check_stored_vos(&s, &store);
        eprintln!("{generator:?}: {cells_with_vos} cells, {checked} VOs");
        // The growth finds few VOs among walls alone (its seeds are single buildings).
        let (cells, vos) = match generator {
            Generator::Long => (2, 10),
            Generator::Growth => (1, 2),
        };
        assert!(
            cells_with_vos >= cells,
            "{generator:?}: only {cells_with_vos} cells got VOs"
        );
        assert!(checked >= vos, "{generator:?}: only {checked} VOs checked");
    }
}
