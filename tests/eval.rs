//! The CI check of the whole chain against the ground truth: a seeded sample of Lyon's 100 m
//! cells is baked, each cell's PVS is built by the runtime culler from the store's bytes, and the
//! ground-truth visible set (rays against the original prisms, no VO code) must lie inside it;
//! and rays from eye points to every stored VO must meet the original geometry first.

use crate::common;

use common::load_lyon;
use vocc::eval::metrics::{cell_vs, eval_cell, object_boxes, sample_cells, vo_rays};
use vocc::eval::raycast::Caster;
use vocc::eval::report::bake;
use vocc::eval::truth::TruthParams;
use vocc::runtime::culler::BoxTree;
use vocc::runtime::format::{CellRecord, Store};

#[test]
fn no_false_culls_on_a_seeded_sample_of_lyon_cells() {
    check_sample_culls(Default::default(), 12, 7, 30, 50);
}

/// `vocc bake --reach`: a cell's own search 2 km past its sides (the whole Lyon extract) is as
/// safe as the default's 900 m, by the same oracles.
#[test]
fn no_false_culls_with_a_two_kilometre_reach() {
    let params = vocc::bake::params::BakeParams::default().with_reach(2000.0);
    check_sample_culls(params, 6, 11, 15, 25);
}

/// `vocc bake --far-block 100`: the far field sought for each cell alone (its block is the
/// cell) is as safe as the default's 4 x 4-cell blocks, by the same oracles.
#[test]
fn no_false_culls_with_one_cell_far_blocks() {
    let params = vocc::bake::params::BakeParams::default().with_far_block(100.0);
    check_sample_culls(params, 6, 13, 15, 25);
}

/// [`check_sample`], which must have something to check: at least `min_vos` VOs stored, half
/// of their 8 x 8 rays cast, and at least `min_culled` objects culled over the sample.
fn check_sample_culls(
    params: vocc::bake::params::BakeParams,
    n: usize,
    seed: u64,
    min_vos: usize,
    min_culled: usize,
) {
    let (vos, rays, culled) = check_sample(params, n, seed);
    assert!(vos >= min_vos, "{vos} VOs");
    assert!(
        rays >= (min_vos * 8 * 8 / 2) as u64,
        "{rays} rays checked the VOs"
    );
    assert!(
        culled >= min_culled,
        "{culled} objects culled over the sample"
    );
}

/// Bakes `n` Lyon cells sampled with `seed` and checks each against the oracles: rays from eyes
/// to its stored VOs meet real geometry first, and its PVS holds its ground-truth visible set.
/// Returns the VOs stored, the rays cast to them and the objects culled, summed over the cells.
fn check_sample(
    params: vocc::bake::params::BakeParams,
    n: usize,
    seed: u64,
) -> (usize, u64, usize) {
    let s = load_lyon();
    // Sample on the grid first (an empty store has the same grid), then bake those cells.
    let full = bake(&s, params.clone(), Some(&[])).expect("the bake runs");
    let grid = Store::parse(&full.bytes).unwrap();
    let ids = sample_cells(&grid, Some(n), seed);
    let baked = bake(&s, params, Some(&ids)).expect("the bake runs");
    let store = Store::parse(&baked.bytes).unwrap();
    let caster = Caster::new(&s);
    let tree = BoxTree::new(&object_boxes(&s));
    let truth = TruthParams {
        eyes: 8,
        samples_per_object: 1,
        radius: None,
        seed: 7,
        eye_above: None,
    };
    let mut culled = 0;
    let mut vos = 0;
    let mut rays = 0;
    for &id in &ids {
        // The 3D check: rays from eyes to the stored VOs meet real geometry first (rule 2).
        let r = vo_rays(&caster, &store, id, 8, 8, 7);
        assert_eq!(
            r.reached, 0,
            "cell {id}: {} of {} rays reached a VO",
            r.reached, r.rays
        );
        rays += r.rays;
        let vs = cell_vs(&s, &store, &caster, id, &truth);
        let e = eval_cell(&s, &store, &tree, id, &vs);
        assert!(
            e.false_culls.is_empty(),
            "cell {id}: visible objects {:?} were culled",
            e.false_culls
        );
        assert!(
            e.vs > 0 && e.vs <= e.pvs,
            "cell {id}: VS {} PVS {}",
            e.vs,
            e.pvs
        );
        // Every object kept yet hidden falls in exactly one distance band.
        assert_eq!(
            e.excess_by_distance.iter().sum::<usize>(),
            e.pvs - e.vs,
            "cell {id}: excess by distance {:?}",
            e.excess_by_distance
        );
        culled += s.objects.len() - e.pvs;
        vos += store
            .cell(id)
            .map(|r: CellRecord| r.vos().len())
            .unwrap_or(0);
    }
    (vos, rays, culled)
}

/// Issue 34: `eval::report::bake` panicked on bad parameters; it returns the job's typed error.
#[test]
fn report_bake_refuses_bad_parameters_with_a_typed_error() {
    use vocc::bake::job::JobError;
    use vocc::bake::params::BakeParams;
    let s = load_lyon();
    let bad = BakeParams {
        cell_size: -1.0,
        ..BakeParams::default()
    };
    let e = bake(&s, bad, Some(&[]))
        .err()
        .expect("a negative cell size is refused");
    assert!(matches!(e, JobError::Plan(_)), "{e:?}");
    assert!(e.to_string().contains("cell size"), "{e}");
    let e = bake(&s, BakeParams::default(), Some(&[u32::MAX]))
        .err()
        .expect("a cell outside the grid is refused");
    assert!(matches!(e, JobError::CellOutsideGrid { .. }), "{e:?}");
}
