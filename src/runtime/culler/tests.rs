//! The culler's tests: the hierarchy's build (its depth bound, children tiling their parent,
//! `f32` rounding) and the PVS against the box-by-box rule on walls, random scenes and proptest.
//!
//! Input: hand-made and seeded random scenes. Output: assertions.
//! Invariant: the reference is rule 3 box by box ([`PreparedVo::cover`]), never the hierarchy.

use super::tree::*;
use super::*;

use crate::runtime::frame::{QPoint, QVo};
use crate::runtime::grid::GridDescriptor;
use crate::testutil::Lcg;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

/// `f32_below` against `f32::next_down`'s definition, around zero, at and past the
/// extremes, and on values that are and are not `f32`s.
#[test]
fn f32_below_rounds_down_by_one_step_at_most() {
    let cases = [
        0.0,
        -0.0,
        1e-50,
        -1e-50,
        0.1,
        -0.1,
        1.0,
        -1.0,
        160.25,
        1e38,
        -1e38,
        f64::from(f32::MAX),
        f64::from(f32::MAX) * 2.0,
        -f64::from(f32::MAX),
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    for x in cases {
        let f = f32_below(x);
        assert!(f64::from(f) <= x, "{x}: {f}");
        // No f32 lies strictly between: the next one above is above x.
        let up = if f == f32::MAX {
            f32::INFINITY
        } else if f >= 0.0 {
            f32::from_bits(if f == 0.0 { 1 } else { f.to_bits() + 1 })
        } else if f == -f32::from_bits(1) {
            0.0
        } else {
            f32::from_bits(f.to_bits() - 1)
        };
        assert!(f64::from(up) > x || f64::from(f) == x, "{x}: {f}, {up}");
    }
}

/// A 5×5 grid of 100 m cells, quantum 0.5 m (VO ends within 128 m of the cell centre).
fn frame() -> Frame {
    Frame {
        origin: [843000.0, 6518000.0, 0.0],
        grid: GridDescriptor {
            min_x: 0.0,
            min_y: 0.0,
            cell_size: 100.0,
            nx: 5,
            ny: 5,
        },
        quantum: 0.5,
        eye_lo: 1.5,
        eye_hi: 2.0,
        ground_z0: 160.0,
        ground_step: 0.5,
        h0: 4.0,
        h_ratio: 1.25,
    }
}

/// Grid index of local coordinate `x` for a cell centred at `c`.
fn k(x: f64, c: f64) -> u16 {
    (256.0 + (x - c) / 0.5) as u16
}

/// A VO of the centre cell (id 12, centre (250, 250)) from `a` to `b`.
fn vo(a: [f64; 2], b: [f64; 2], level: u8) -> QVo {
    QVo {
        a: QPoint::fine(k(a[0], 250.0), k(a[1], 250.0)),
        b: QPoint::fine(k(b[0], 250.0), k(b[1], 250.0)),
        level,
        deep: false,
    }
}

/// Ground level 0 is at 160 m.
fn bx(x0: f64, y0: f64, x1: f64, y1: f64, z1: f64) -> [f64; 6] {
    [x0, y0, 160.0, x1, y1, 160.0 + z1]
}

/// Box-by-box rule 3, with its own validity test.
fn brute_force(frame: &Frame, id: CellId, rec: &CellRecord, boxes: &[[f64; 6]]) -> Vec<u32> {
    let ground = rec.ground();
    let Some(view) = frame.cell_view(id, ground) else {
        return (0..boxes.len() as u32).collect();
    };
    let prepared: Vec<PreparedVo> = rec
        .vos()
        .iter()
        .map(|q| PreparedVo::new(&view, &frame.dequantize(id, ground, q).unwrap()))
        .collect();
    (0..boxes.len() as u32)
        .filter(|&i| {
            let b = &boxes[i as usize];
            let valid = b.iter().all(|v| v.is_finite()) && (0..3).all(|a| b[a] <= b[a + 3]);
            !valid || !prepared.iter().any(|p| p.cover(&view, b) == Cover::Hidden)
        })
        .collect()
}

fn touches_cell(frame: &Frame, id: CellId, b: &[f64; 6]) -> bool {
    let [x0, y0, x1, y1] = frame.grid.cell_rect(id).unwrap();
    b[0] <= x1 && b[3] >= x0 && b[1] <= y1 && b[4] >= y0
}

#[test]
fn a_wall_hides_what_is_low_behind_it_and_nothing_else() {
    let f = frame();
    // Cell 12 spans [200, 300]²; a 200 m wall at y = 350, level 8 (about 20 m tall).
    let rec = CellRecord::new(0, &[vo([150.0, 350.0], [350.0, 350.0], 8)]).unwrap();
    let boxes = vec![
        bx(240.0, 360.0, 260.0, 370.0, 5.0), // 0: low, right behind: hidden
        bx(240.0, 360.0, 260.0, 370.0, 60.0), // 1: too tall
        bx(240.0, 320.0, 260.0, 330.0, 5.0), // 2: in front of the wall
        bx(500.0, 360.0, 510.0, 370.0, 5.0), // 3: beside the umbra
        bx(290.0, 290.0, 310.0, 400.0, 1.0), // 4: touches the cell
        [f64::NAN, 360.0, 160.0, 260.0, 370.0, 165.0], // 5: invalid
        [260.0, 370.0, 165.0, 240.0, 360.0, 160.0], // 6: min > max, "inside" the umbra
        bx(245.0, 400.0, 255.0, 410.0, 5.0), // 7: hidden
    ];
    let tree = BoxTree::new(&boxes);
    assert_eq!(tree.len(), 8);
    let mut out = vec![99];
    pvs(&f, 12, &rec, &tree, &mut out);
    assert_eq!(out, vec![1, 2, 3, 4, 5, 6]);
    assert_eq!(out, brute_force(&f, 12, &rec, &boxes));
    // Skipped cells, cells without VOs, cells outside the grid: everything.
    for (id, r) in [
        (12, CellRecord::Skipped),
        (12, CellRecord::EMPTY),
        (25, rec),
    ] {
        pvs(&f, id, &r, &tree, &mut out);
        assert_eq!(out, (0..8).collect::<Vec<u32>>());
    }
    // World coordinates give the same tree.
    let world: Vec<[f64; 6]> = boxes
        .iter()
        .map(|b| {
            let o = f.origin;
            [
                b[0] + o[0],
                b[1] + o[1],
                b[2] + o[2],
                b[3] + o[0],
                b[4] + o[1],
                b[5] + o[2],
            ]
        })
        .collect();
    pvs(
        &f,
        12,
        &rec,
        &BoxTree::from_world(&world, f.origin),
        &mut out,
    );
    assert_eq!(out, vec![1, 2, 3, 4, 5, 6]);
}

#[test]
fn empty_tree_and_only_invalid_boxes() {
    let f = frame();
    let rec = CellRecord::new(0, &[vo([150.0, 350.0], [350.0, 350.0], 8)]).unwrap();
    let mut out = Vec::new();
    pvs(&f, 12, &rec, &BoxTree::new(&[]), &mut out);
    assert!(out.is_empty());
    let bad = [
        [1.0, 0.0, 0.0, 0.0, 1.0, 1.0],
        [0.0, 0.0, 0.0, f64::INFINITY, 1.0, 1.0],
    ];
    pvs(&f, 12, &rec, &BoxTree::new(&bad), &mut out);
    assert_eq!(out, vec![0, 1]);
}

/// A wall of cell 12 on one of its four sides, at `d` metres from the centre.
fn random_wall(r: &mut Lcg) -> QVo {
    let d = r.range(55.0, 125.0);
    let (s0, s1) = (r.range(-127.0, -20.0), r.range(20.0, 127.0));
    let level = 6 + (r.next() * 10.0) as u8;
    let c = 250.0;
    let (a, b) = match (r.next() * 4.0) as u32 {
        0 => ([c + s0, c + d], [c + s1, c + d]),
        1 => ([c + s0, c - d], [c + s1, c - d]),
        2 => ([c + d, c + s0], [c + d, c + s1]),
        _ => ([c - d, c + s0], [c - d, c + s1]),
    };
    vo(a, b, level)
}

fn random_scene(r: &mut Lcg, n_boxes: usize) -> (CellRecord, Vec<[f64; 6]>) {
    let n_vos = 1 + (r.next() * 10.0) as usize;
    let mut vos = Vec::new();
    while vos.len() < n_vos {
        let q = if r.next() < 0.8 {
            random_wall(r)
        } else {
            QVo {
                a: QPoint::fine((r.next() * 512.0) as u16, (r.next() * 512.0) as u16),
                b: QPoint::fine((r.next() * 512.0) as u16, (r.next() * 512.0) as u16),
                level: (r.next() * 16.0) as u8,
                deep: false,
            }
        };
        if !q.is_degenerate() {
            vos.push(q);
        }
    }
    let ground = (r.next() * 8.0) as u8;
    let g = 160.0 + ground as f64 * 0.5;
    let boxes = (0..n_boxes)
        .map(|_| {
            let (x, y) = (r.range(0.0, 500.0), r.range(0.0, 500.0));
            let (w, h) = (r.range(0.0, 20.0), r.range(0.0, 20.0));
            let z = g + r.range(-0.2, 3.0);
            let mut b = [x, y, z, x + w, y + h, z + r.range(0.0, 15.0)];
            if r.next() < 0.02 {
                b[(r.next() * 6.0) as usize] = f64::NAN;
            } else if r.next() < 0.02 {
                b.swap(0, 3);
            }
            b
        })
        .collect();
    (CellRecord::new(ground, &vos).unwrap(), boxes)
}

#[test]
fn bvh_equals_the_box_by_box_rule_on_random_scenes() {
    let f = frame();
    let mut r = Lcg(0x5eed_0007);
    let mut tot = PvsStats::default();
    let mut n = 0;
    let mut out = Vec::new();
    for scene in 0..60 {
        let (rec, boxes) = random_scene(&mut r, 50 + scene * 40);
        let tree = BoxTree::new(&boxes);
        let st = pvs_with_stats(&f, 12, &rec, &tree, &mut out);
        assert_eq!(out, brute_force(&f, 12, &rec, &boxes), "scene {scene}");
        assert!(out.windows(2).all(|w| w[0] < w[1]));
        for (i, b) in boxes.iter().enumerate() {
            if touches_cell(&f, 12, b) {
                assert!(out.binary_search(&(i as u32)).is_ok());
            }
        }
        n += boxes.len();
        tot.subtrees_culled += st.subtrees_culled;
        tot.subtrees_kept += st.subtrees_kept;
        tot.boxes_tested += st.boxes_tested;
        tot.visible += st.visible;
    }
    // The scenes exercise every path: culling (of whole subtrees too), subtrees returned
    // whole, and single box tests; and fewer boxes are tested than there are.
    assert!(
        tot.visible < n * 85 / 100 && tot.visible > n / 2,
        "{tot:?} of {n}"
    );
    assert!(
        tot.subtrees_culled > 500 && tot.subtrees_kept > 500,
        "{tot:?}"
    );
    assert!(tot.boxes_tested < n, "{tot:?} of {n}");
}

/// The bake's weighing walk ([`BoxTree::hidden_runs`]): exact, it finds the boxes rule 3 hides
/// box by box; coarse ([`Coarse`]), it finds a subset of them that holds every hidden box
/// nearer the cell's centre than `far_m` when only far subtrees are passed over.
#[test]
fn hidden_runs_find_the_hidden_boxes_and_pass_over_only_far_subtrees() {
    let f = frame();
    let mut r = Lcg(0x5eed_0009);
    let (mut hidden, mut passed_over) = (0, 0);
    for scene in 0..40 {
        let (rec, mut boxes) = random_scene(&mut r, 100 + scene * 40);
        boxes.retain(box_is_valid);
        let tree = BoxTree::new(&boxes);
        let by_pos: Vec<[f64; 6]> = (0..tree.positions() as u32)
            .map(|p| boxes[tree.id_at(p) as usize])
            .collect();
        let ground = rec.ground();
        let view = f.cell_view(12, ground).unwrap();
        let within = [-1e4, -1e4, 1e4, 1e4];
        let runs = |vo: &PreparedVo, coarse: Coarse| {
            let mut out = Vec::new();
            tree.hidden_runs(&view, vo, within, &by_pos, coarse, |s, e, _| {
                out.extend(s..e)
            });
            out
        };
        for q in rec.vos() {
            let vo = PreparedVo::new(&view, &f.dequantize(12, ground, q).unwrap());
            let exact = runs(&vo, Coarse::EXACT);
            let by_box: Vec<u32> = (0..by_pos.len() as u32)
                .filter(|&p| vo.cover(&view, &by_pos[p as usize]) == Cover::Hidden)
                .collect();
            assert_eq!(exact, by_box, "scene {scene}");
            let far_m = 120.0;
            let coarse = Coarse {
                angle: 0.0,
                far_m,
                far_angle: 0.5,
            };
            let some = runs(&vo, coarse);
            assert!(some.iter().all(|p| exact.binary_search(p).is_ok()));
            let dist = |b: &[f64; 6]| {
                let dx = (b[0] - 250.0).max(250.0 - b[3]).max(0.0);
                let dy = (b[1] - 250.0).max(250.0 - b[4]).max(0.0);
                dx.hypot(dy)
            };
            for &p in &exact {
                if dist(&by_pos[p as usize]) <= far_m {
                    assert!(some.binary_search(&p).is_ok(), "scene {scene}, box {p}");
                }
            }
            hidden += exact.len();
            passed_over += exact.len() - some.len();
        }
    }
    // Both kinds of walk did work: boxes hidden, and some of them passed over.
    assert!(
        hidden > 1000 && passed_over > 50,
        "{hidden} hidden, {passed_over} passed over"
    );
}

/// Most levels of nodes over `n` boxes. Every split leaves at most 90% of a node's boxes
/// on each side ([`MIN_SIDE`]; the median split too, above [`LEAF_SIZE`]), and only the
/// first [`BINNED_LEVELS`] binary levels split by cost; each level of nodes takes two binary
/// levels off a path that goes on below it.
fn depth_bound(n: usize) -> usize {
    let leaves = n.div_ceil(LEAF_SIZE) as f64;
    let shrink = 1 + (leaves.ln() / (1.0 / (1.0 - MIN_SIDE)).ln()).ceil() as usize;
    let median = BINNED_LEVELS + leaves.log2().ceil() as usize;
    1 + shrink.min(median).div_ceil(2)
}

#[test]
fn tree_depth_is_bounded() {
    let mut r = Lcg(1);
    for n in [1usize, 8, 9, 100, 10_000] {
        // Boxes along a line, and a dense cluster with a few far outliers (where a split by
        // cost is most lopsided).
        let line: Vec<[f64; 6]> = (0..n)
            .map(|_| {
                let x = r.range(0.0, 1000.0);
                [x, 0.0, 0.0, x + 1.0, 1.0, 1.0]
            })
            .collect();
        let cluster: Vec<[f64; 6]> = (0..n)
            .map(|i| {
                let x = if i % 50 == 0 {
                    r.range(0.0, 1e5)
                } else {
                    r.range(0.0, 10.0)
                };
                let top = r.range(1.0, 60.0);
                [x, x, 0.0, x + 1.0, x + 1.0, top]
            })
            .collect();
        for boxes in [line, cluster] {
            let t = BoxTree::new(&boxes);
            let bound = depth_bound(n);
            assert!(t.depth() <= bound, "n = {n}: depth {} > {bound}", t.depth());
            assert!(3 * t.depth() + WIDTH <= STACK);
        }
    }
    // Identical boxes split too.
    let t = BoxTree::new(&vec![[0.0, 0.0, 0.0, 1.0, 1.0, 1.0]; 1000]);
    let bound = depth_bound(1000);
    assert!(t.depth() <= bound, "depth {} > {bound}", t.depth());
}

/// Every node's children tile its range of boxes in order, lie within its bounds and have
/// its least top among theirs; leaves hold at most LEAF_SIZE boxes, nodes at most WIDTH
/// children, and every box lies within its leaf's bounds.
#[test]
fn children_tile_their_parent() {
    let mut r = Lcg(7);
    for n in [1usize, 8, 9, 17, 100, 5_000] {
        let (_, boxes) = random_scene(&mut r, n);
        let t = BoxTree::new(&boxes);
        let within =
            |a: &[f64; 6], b: &[f64; 6]| (0..3).all(|k| a[k] >= b[k] && a[k + 3] <= b[k + 3]);
        let mut leaves = 0;
        for node in &t.nodes {
            assert!(node.start < node.end && node.kids().len() <= WIDTH);
            if node.kids().is_empty() {
                leaves += node.end - node.start;
                assert!((node.end - node.start) as usize <= LEAF_SIZE);
                let lanes = &t.lanes[node.lanes()];
                let leaf: Vec<[f64; 6]> = t.ids[node.start as usize..node.end as usize]
                    .iter()
                    .map(|&i| boxes[i as usize])
                    .collect();
                assert_eq!(*lanes, Lanes::new(&leaf));
                for b in &leaf {
                    assert!(within(b, &node.bounds));
                    assert!(b[5] >= f64::from(node.min_top));
                }
                continue;
            }
            assert!(node.kids().len() >= 2);
            // The least top rounded down, and no lower.
            let exact = t.ids[node.start as usize..node.end as usize]
                .iter()
                .map(|&i| boxes[i as usize][5])
                .fold(f64::INFINITY, f64::min);
            assert!(f64::from(node.min_top) <= exact);
            assert!(exact - f64::from(node.min_top) <= exact.abs() * f64::from(f32::EPSILON));
            let mut at = node.start;
            let mut min_top = f32::INFINITY;
            for k in node.kids() {
                let kid = &t.nodes[k as usize];
                assert_eq!(kid.start, at);
                at = kid.end;
                assert!(within(&kid.bounds, &node.bounds));
                min_top = min_top.min(kid.min_top);
            }
            assert_eq!(at, node.end);
            assert_eq!(min_top, node.min_top);
        }
        assert_eq!(leaves as usize, t.positions());
        if let Some(root) = t.nodes.first() {
            assert_eq!(root.end as usize, t.positions());
        }
    }
}

fn arb_box() -> impl Strategy<Value = [f64; 6]> {
    (
        -100.0f64..600.0,
        -100.0f64..600.0,
        159.0f64..166.0,
        0.0f64..30.0,
        0.0f64..30.0,
        0.0f64..40.0,
    )
        .prop_map(|(x, y, z, w, h, t)| [x, y, z, x + w, y + h, z + t])
}

proptest! {
    #![proptest_config(Config {
        cases: 300,
        rng_seed: RngSeed::Fixed(0x5eed_0008),
        failure_persistence: None,
        ..Config::default()
    })]

    #[test]
    fn pvs_equals_the_box_by_box_rule(
        seed in any::<u64>(),
        boxes in prop::collection::vec(arb_box(), 0..200),
        id in 0u32..25,
    ) {
        let f = frame();
        let mut r = Lcg(seed);
        let (rec, _) = random_scene(&mut r, 0);
        // The walls were drawn for cell 12; other cells see them shifted, which is as good
        // a random VO set.
        let tree = BoxTree::new(&boxes);
        let mut out = Vec::new();
        pvs(&f, id, &rec, &tree, &mut out);
        prop_assert_eq!(&out, &brute_force(&f, id, &rec, &boxes));
        for (i, b) in boxes.iter().enumerate() {
            if touches_cell(&f, id, b) {
                prop_assert!(out.binary_search(&(i as u32)).is_ok());
            }
        }
    }
}
