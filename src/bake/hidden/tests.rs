//! Tests of the hidden map ([`super`]): a wall hides what lies behind it and not what lies
//! beside it; maps built for several slices at once equal those built one slice at a time; the
//! edge lists (`EdgeTwins`, merged slice edges, the counting sort of edge keys) equal plain
//! sorted ones for any subset; shared edges of pieces are inside; walls kept both ways.
//!
//! Input: small scenes and seeded random edge sets. Output: pass or fail.
//! Invariant: each fast path is checked against the plain computation it replaces.

use super::*;
use crate::testutil::Lcg;

/// The 100 m cell `[0, 100]²`, counter-clockwise.
fn cell_100() -> [DVec2; 4] {
    let c = sq(0.0, 0.0, 100.0);
    [c[0], c[1], c[2], c[3]]
}

fn sq(x0: f64, y0: f64, s: f64) -> Vec<DVec2> {
    vec![
        DVec2::new(x0, y0),
        DVec2::new(x0 + s, y0),
        DVec2::new(x0 + s, y0 + s),
        DVec2::new(x0, y0 + s),
    ]
}

#[test]
fn the_counting_sort_of_edge_keys_is_the_comparison_sort() {
    // Narrow spans (counting sort), negative keys, repeated keys, and a wide span (fallback).
    let mut g = Lcg(7);
    let mut next = move || (g.next_u64() >> 33) as i64;
    for (n, span) in [(0, 1), (1, 1), (50, 3), (2000, 40), (300, 1 << 40)] {
        let mut keyed: Vec<((i64, i64), u32)> = (0..n)
            .map(|i| ((next() % span - span / 2, next() % span), i as u32))
            .collect();
        let mut want = keyed.clone();
        want.sort_unstable();
        sort_keyed(&mut keyed);
        assert_eq!(keyed, want, "n {n}, span {span}");
    }
}

#[test]
fn pseudo_angle_is_monotone_and_inverts() {
    let mut last = -1.0;
    for k in 0..3600 {
        let a = std::f64::consts::TAU * k as f64 / 3600.0;
        let p = pseudo_angle(DVec2::new(a.cos(), a.sin()));
        assert!(p > last, "at {k}");
        last = p;
        let d = direction(p);
        assert!((d - DVec2::new(a.cos(), a.sin())).length() < 1e-9);
    }
}

#[test]
fn a_wall_hides_what_is_behind_it_and_not_beside_it() {
    let cell = cell_100();
    // A 600 m long, 10 m deep row 30 m north of the cell.
    let row = vec![
        DVec2::new(-250.0, 130.0),
        DVec2::new(350.0, 130.0),
        DVec2::new(350.0, 140.0),
        DVec2::new(-250.0, 140.0),
    ];
    let edges = boundary_edges([row.as_slice()].into_iter());
    let map = HiddenMap::build(&cell, &edges, &MapParams::default());
    assert!(map.hidden(DVec2::new(50.0, 200.0)));
    assert!(map.hidden(DVec2::new(-100.0, 160.0)));
    assert!(!map.hidden(DVec2::new(50.0, 120.0)), "in front of the row");
    assert!(!map.hidden(DVec2::new(500.0, 200.0)), "beyond its end");
    assert!(!map.hidden(DVec2::new(50.0, -200.0)), "the other side");
}

#[test]
fn maps_built_together_are_the_maps_built_one_slice_at_a_time() {
    // Pieces of blocks around a cell, some split in two (their shared edge is inside while
    // both pieces are in a slice, outside once one is left out), at random heights; three
    // slices keep the pieces at least 5, 15 and 25 m tall.
    let cell = cell_100();
    let mut next = lcg(11);
    let mut polys: Vec<Vec<DVec2>> = Vec::new();
    let mut heights: Vec<f64> = Vec::new();
    for bx in -6..8 {
        for by in -6..8 {
            if (0..=1).contains(&bx) && (0..=1).contains(&by) {
                continue;
            }
            let (x, y) = (bx as f64 * 60.0 + 5.0, by as f64 * 60.0 + 5.0);
            let w = 20.0 + next(25) as f64;
            polys.push(sq(x, y, w));
            heights.push(next(30) as f64);
            if next(2) == 0 {
                polys.push(sq(x + w, y, w));
                heights.push(next(30) as f64);
            }
        }
    }
    let twins = EdgeTwins::new(&polys);
    let p = MapParams::default();
    let tops = [5.0, 15.0, 25.0];
    let mut alone = Vec::new();
    let mut slices = Vec::new();
    for &t in &tops {
        let ids: Vec<u32> = (0..polys.len() as u32)
            .filter(|&i| heights[i as usize] >= t)
            .collect();
        alone.push(HiddenMap::build(
            &cell,
            &twins.boundary_edges(&polys, &ids),
            &p,
        ));
        slices.push(ids);
    }
    let (edges, member) = twins.slice_edges(&polys, &slices);
    assert!(
        member.contains(&0b110),
        "an edge exposed above the lowest slice"
    );
    let together = HiddenMap::build_slices(&cell, &edges, &member, tops.len(), &p);
    for (s, (a, b)) in together.iter().zip(&alone).enumerate() {
        assert_eq!(a.visible, b.visible, "slice {s}");
    }
    let shares: Vec<f64> = alone.iter().map(|m| m.hidden_share()).collect();
    assert!(shares[0] > shares[2] && shares[2] > 0.0, "{shares:?}");
}

/// The boundary edges of all of `polys`.
fn boundary_edges<'a>(polys: impl Iterator<Item = &'a [DVec2]>) -> Vec<(DVec2, DVec2)> {
    let polys: Vec<&[DVec2]> = polys.collect();
    let ids: Vec<u32> = (0..polys.len() as u32).collect();
    EdgeTwins::new(&polys).boundary_edges(&polys, &ids)
}

/// The sorting form [`EdgeTwins`] replaced, kept as its oracle.
fn boundary_edges_by_sorting(polys: &[&[DVec2]]) -> Vec<(DVec2, DVec2)> {
    let mut edges: Vec<(DVec2, DVec2)> = Vec::new();
    let mut walls: Vec<(DVec2, DVec2)> = Vec::new();
    for p in polys {
        match p.len() {
            0 | 1 => {}
            2 => {
                walls.push((p[0], p[1]));
                walls.push((p[1], p[0]));
            }
            n => edges.extend((0..n).map(|i| (p[i], p[(i + 1) % n]))),
        }
    }
    let key = |u: DVec2, v: DVec2| (u.x.to_bits(), u.y.to_bits(), v.x.to_bits(), v.y.to_bits());
    let mut keys: Vec<_> = edges.iter().map(|&(u, v)| key(u, v)).collect();
    keys.sort_unstable();
    edges
        .into_iter()
        .filter(|&(u, v)| keys.binary_search(&key(v, u)).is_err())
        .chain(walls)
        .collect()
}

/// A seeded generator of integers below `n`.
fn lcg(seed: u64) -> impl FnMut(u64) -> u64 {
    let mut g = Lcg(seed);
    move |n| (g.next_u64() >> 33) % n
}

/// A 5 x 4 grid of unit squares (every inner edge shared), a duplicated square, and two
/// walls along edges of the squares.
fn grid_with_walls() -> Vec<Vec<DVec2>> {
    let mut polys: Vec<Vec<DVec2>> = Vec::new();
    for x in 0..5 {
        for y in 0..4 {
            polys.push(sq(x as f64, y as f64, 1.0));
        }
    }
    polys.push(sq(2.0, 2.0, 1.0));
    polys.push(vec![DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0)]);
    polys.push(vec![DVec2::new(3.0, 3.0), DVec2::new(4.0, 3.0)]);
    polys
}

#[test]
fn edge_twins_give_the_edges_sorting_gives_for_every_subset() {
    // A grid of unit squares (every inner edge shared), walls along some of their edges, a
    // duplicated square: every subset drawn gives the sorting form's edges, in its order.
    let polys = grid_with_walls();
    let twins = EdgeTwins::new(&polys);
    let mut g = Lcg(7);
    for _ in 0..300 {
        let ids: Vec<u32> = (0..polys.len() as u32)
            .filter(|_| g.next_u64() >> 62 != 0)
            .collect();
        let sub: Vec<&[DVec2]> = ids.iter().map(|&i| polys[i as usize].as_slice()).collect();
        assert_eq!(
            twins.boundary_edges(&polys, &ids),
            boundary_edges_by_sorting(&sub)
        );
    }
    // All of them: the outline of the 5 x 4 block and the walls' 4 directions.
    let all: Vec<u32> = (0..polys.len() as u32).collect();
    assert_eq!(twins.boundary_edges(&polys, &all).len(), 2 * (5 + 4) + 4);
}

/// The form of [`EdgeTwins::slice_edges`] that its merge replaced, kept as its oracle: each
/// slice's edges with their keys, sorted by key and slice, each key once with its slices.
fn slice_edges_by_sorting(
    twins: &EdgeTwins,
    polys: &[Vec<DVec2>],
    slices: &[Vec<u32>],
) -> (Vec<(DVec2, DVec2)>, Vec<u8>) {
    let mut all: Vec<(u64, u8, DVec2, DVec2)> = Vec::new();
    for (s, ids) in slices.iter().enumerate() {
        twins.each_boundary_edge(polys, ids, |key, u, v| all.push((key, s as u8, u, v)));
    }
    all.sort_unstable_by_key(|x| (x.0, x.1));
    let (mut edges, mut member) = (Vec::new(), Vec::<u8>::new());
    let mut last = None;
    for (key, s, u, v) in all {
        if last != Some(key) {
            last = Some(key);
            edges.push((u, v));
            member.push(0);
        }
        *member.last_mut().unwrap() |= 1 << s;
    }
    (edges, member)
}

#[test]
fn slice_edges_merged_are_the_sorted_ones_for_any_slices() {
    // The grid of the test above, with walls and a duplicated square; up to 8 slices drawn
    // independently (not nested, some empty).
    let polys = grid_with_walls();
    let twins = EdgeTwins::new(&polys);
    let mut next = lcg(11);
    let mut exposed_above = 0;
    for _ in 0..200 {
        let k = 1 + next(8) as usize;
        let slices: Vec<Vec<u32>> = (0..k)
            .map(|_| {
                let keep = next(4);
                (0..polys.len() as u32).filter(|_| next(4) < keep).collect()
            })
            .collect();
        let got = twins.slice_edges(&polys, &slices);
        assert_eq!(got, slice_edges_by_sorting(&twins, &polys, &slices));
        assert!(got.1.iter().all(|&m| m != 0 && (m as u32) < 1 << k));
        exposed_above += got.1.iter().filter(|&&m| m & 1 == 0).count();
    }
    assert!(exposed_above > 0, "some edge is not in the first slice");
}

#[test]
fn shared_edges_of_pieces_are_inside() {
    let a = sq(0.0, 0.0, 10.0);
    let b = sq(10.0, 0.0, 10.0);
    let e = boundary_edges([a.as_slice(), b.as_slice()].into_iter());
    assert_eq!(e.len(), 6);
}

/// Every wall dropped itself when its two directions were taken as a shared edge, so a scene
/// of walls alone (an open LoD2 mesh) hid nothing in the map.
#[test]
fn regression_walls_are_kept_in_both_directions() {
    let wall = [DVec2::new(0.0, 20.0), DVec2::new(100.0, 20.0)];
    let e = boundary_edges([wall.as_slice()].into_iter());
    assert_eq!(e, vec![(wall[0], wall[1]), (wall[1], wall[0])]);
    // A wall along a polygon's edge cancels nothing either.
    let a = sq(0.0, 0.0, 10.0);
    let w = [DVec2::new(10.0, 0.0), DVec2::new(10.0, 10.0)];
    let e = boundary_edges([a.as_slice(), w.as_slice()].into_iter());
    assert_eq!(e.len(), 6);
    // And a row of walls hides what lies behind it.
    let cell = cell_100();
    let wall = [DVec2::new(-250.0, 130.0), DVec2::new(350.0, 130.0)];
    let e = boundary_edges([wall.as_slice()].into_iter());
    let map = HiddenMap::build(&cell, &e, &MapParams::default());
    assert!(map.hidden(DVec2::new(50.0, 200.0)));
    assert!(!map.hidden(DVec2::new(50.0, 120.0)));
}

/// The eight-bytes-at-a-time gather of [`slice_bits`] against the plain one, on random bytes and
/// on a short tail.
#[test]
fn slice_bits_gathers_bit_s_of_each_byte() {
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    let mut bytes = [0u8; 64];
    for round in 0..200 {
        for b in bytes.iter_mut() {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            *b = x as u8;
        }
        let n = if round % 2 == 0 { 64 } else { 1 + round % 63 };
        for s in 0..8 {
            let plain = bytes[..n]
                .iter()
                .enumerate()
                .fold(0u64, |w, (j, &b)| w | (((b >> s) & 1) as u64) << j);
            assert_eq!(
                super::slice_bits(&bytes[..n], s),
                plain,
                "round {round}, bit {s}"
            );
        }
    }
}
