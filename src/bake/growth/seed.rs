//! Seeds: which blockers start an aggregate umbra.
//!
//! Input: a cell, the slice's blockers near it, and `k`. Output: blocker ids, best first.
//! Rule: rank blockers by the area-angle of paper 001 (Coorg and Teller), summed over the walls
//! that face the cell centre ([`area_angle`], which also weighs the slices); take the top `k`.
//! Then, so that no direction is left without a seed, split the full turn around the cell centre
//! into [`SECTORS`] sectors and add the best-ranked blocker of every sector that the first seeds'
//! angular intervals leave uncovered.
//! Invariant: deterministic (ties broken by id); blockers that overlap the cell are never seeds
//! (no line separates them from it); blockers that only touch it may be.

use glam::DVec2;

use crate::bake::slice::area_angle;
use crate::bake::BlockerSet;
use crate::geom::predicates::convex_interiors_disjoint;

/// Sectors of the direction rule.
pub const SECTORS: usize = 16;

/// Picks the seeds of one cell among `candidates`.
pub fn seeds(cell: &[DVec2], set: &BlockerSet, candidates: &[u32], k: usize) -> Vec<u32> {
    let centre = cell.iter().copied().sum::<DVec2>() / cell.len() as f64;
    let mut ranked: Vec<(f64, u32)> = candidates
        .iter()
        .filter(|&&id| {
            let p = &set.polys[id as usize];
            convex_interiors_disjoint(p, cell)
        })
        .map(|&id| {
            let i = id as usize;
            (area_angle(&set.polys[i], set.heights[i], centre), id)
        })
        .filter(|(a, _)| *a > 0.0)
        .collect();
    ranked.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut out: Vec<u32> = ranked.iter().take(k).map(|r| r.1).collect();
    // Direction rule: sectors not met by any seed's angular interval get their best blocker.
    let sector_of = |p: DVec2| {
        let a = (p - centre)
            .y
            .atan2((p - centre).x)
            .rem_euclid(std::f64::consts::TAU);
        ((a / std::f64::consts::TAU * SECTORS as f64) as usize).min(SECTORS - 1)
    };
    let mut covered = [false; SECTORS];
    for &id in &out {
        for s in sectors_spanned(&set.polys[id as usize], centre, &sector_of) {
            covered[s] = true;
        }
    }
    for &(_, id) in &ranked {
        let c = set.polys[id as usize].iter().copied().sum::<DVec2>()
            / set.polys[id as usize].len() as f64;
        let s = sector_of(c);
        if !covered[s] && !out.contains(&id) {
            out.push(id);
            for s in sectors_spanned(&set.polys[id as usize], centre, &sector_of) {
                covered[s] = true;
            }
        }
    }
    out
}

/// Sectors a polygon's vertices fall in, and those between (the short way round).
fn sectors_spanned(
    poly: &[DVec2],
    _centre: DVec2,
    sector_of: &dyn Fn(DVec2) -> usize,
) -> Vec<usize> {
    let mut s: Vec<usize> = poly.iter().map(|&p| sector_of(p)).collect();
    s.sort_unstable();
    s.dedup();
    if s.len() <= 1 {
        return s;
    }
    // The largest circular gap between occupied sectors is the outside of the span.
    let mut best_gap = (0, 0);
    for i in 0..s.len() {
        let a = s[i];
        let b = s[(i + 1) % s.len()];
        let gap = (b + SECTORS - a) % SECTORS;
        if gap > best_gap.0 {
            best_gap = (gap, i);
        }
    }
    let start = s[(best_gap.1 + 1) % s.len()];
    let end = s[best_gap.1];
    let mut out = Vec::new();
    let mut k = start;
    loop {
        out.push(k);
        if k == end {
            break;
        }
        k = (k + 1) % SECTORS;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<DVec2> {
        vec![
            DVec2::new(x0, y0),
            DVec2::new(x1, y0),
            DVec2::new(x1, y1),
            DVec2::new(x0, y1),
        ]
    }

    #[test]
    fn nearer_and_wider_blockers_rank_first() {
        let cell = rect(0.0, 0.0, 10.0, 10.0);
        let near = rect(0.0, 20.0, 10.0, 22.0);
        let far = rect(0.0, 60.0, 10.0, 62.0);
        let wide_far = rect(-40.0, 60.0, 50.0, 62.0);
        let c = DVec2::new(5.0, 5.0);
        assert!(area_angle(&near, 10.0, c) > area_angle(&far, 10.0, c));
        assert!(area_angle(&wide_far, 10.0, c) > area_angle(&far, 10.0, c));
        // Walls facing away count nothing: a blocker's back wall adds no area-angle.
        let set = BlockerSet::new(vec![near, far, wide_far], vec![10.0; 3]);
        let s = seeds(&cell, &set, &[0, 1, 2], 1);
        assert_eq!(s[0], 0);
    }

    #[test]
    fn uncovered_directions_get_a_seed() {
        let cell = rect(0.0, 0.0, 10.0, 10.0);
        // Three big blockers ahead (+y), one small behind (-y).
        let set = BlockerSet::new(
            vec![
                rect(-20.0, 20.0, 30.0, 25.0),
                rect(-20.0, 30.0, 30.0, 35.0),
                rect(-20.0, 40.0, 30.0, 45.0),
                rect(4.0, -30.0, 6.0, -28.0),
            ],
            vec![10.0; 4],
        );
        let s = seeds(&cell, &set, &[0, 1, 2, 3], 2);
        assert_eq!(&s[..2], &[0, 1]);
        assert!(
            s.contains(&3),
            "the direction behind gets its own seed: {s:?}"
        );
    }

    #[test]
    fn blockers_overlapping_the_cell_are_not_seeds() {
        let cell = rect(0.0, 0.0, 10.0, 10.0);
        let set = BlockerSet::new(
            vec![rect(8.0, 0.0, 20.0, 10.0), rect(10.0, 0.0, 20.0, 10.0)],
            vec![10.0; 2],
        );
        assert_eq!(seeds(&cell, &set, &[0, 1], 4), vec![1]);
    }
}
