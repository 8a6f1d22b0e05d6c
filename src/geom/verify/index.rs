//! The verifier's blockers: an index over their boxes built once per cell and shared by its
//! verifiers ([`BlockerIndex`], [`super::Verifier::subset`]), and the blockers near one stretch
//! of a swept segment, nearest first.
//!
//! Input: convex counter-clockwise blockers or 2-vertex segments; a segment's stretch and the
//! cell. Output: the blockers that may block a segment from the cell to the stretch: every
//! blocker meeting the convex hull of the cell and the stretch is listed, and only those whose
//! boxes are clear of that hull by a floating-point margin are left out.
//!
//! Invariant: leaving a blocker out can only certify less; the order of the list (by distance,
//! ties by id) is deterministic.

use glam::DVec2;

use super::sweep::Param;
use super::{Blockers, Verifier, END};
use crate::geom::predicates::{orient, Orientation};

/// The blockers near one stretch of the swept segment, `span` in parameters.
pub(super) struct NearCache<'a> {
    pub(super) span: (u64, u64),
    /// How far past a requested piece a new stretch reaches, in parameter steps.
    pub(super) ahead: u64,
    pub(super) ids: Vec<u32>,
    /// The blockers of `ids`, in the same order, and their boxes.
    pub(super) polys: Vec<&'a [DVec2]>,
    pub(super) boxes: Vec<(DVec2, DVec2)>,
    /// The positions in `ids` of the blockers whose boxes meet the box of the stretch (grown
    /// by [`ALONG_PAD_M`]), ascending: only these can hold a point of the stretch.
    pub(super) along: Vec<u32>,
    /// Scratch: `ids` keyed by distance, while they are put in order.
    pub(super) keyed: Vec<(f64, u32)>,
}

/// How many of a stretch's blockers are put in order of distance (the rest follow unordered).
pub const NEAREST_SORTED: usize = 48;
/// How far ahead of the sweep the blockers near the segment are gathered at once, metres.
pub const NEAR_AHEAD_M: f64 = 48.0;
/// How far the box of a stretch is grown before the boxes that meet it are listed
/// ([`NearCache::along`]), metres: far above the rounding of its float corners, so that every
/// exact point of the stretch lies inside.
pub const ALONG_PAD_M: f64 = 1e-3;

/// A uniform grid of buckets over the blockers' boxes (bucket `k` holds
/// `ids[start[k]..start[k + 1]]`; a box is listed in every bucket it meets).
pub(super) struct Grid {
    pub(super) lo: DVec2,
    pub(super) size: f64,
    pub(super) nx: usize,
    pub(super) ny: usize,
    pub(super) start: Vec<u32>,
    pub(super) ids: Vec<u32>,
}

impl Grid {
    const SIZE_M: f64 = 32.0;

    pub(super) fn new(boxes: &[(DVec2, DVec2)]) -> Grid {
        let (lo, hi) = boxes.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(l, h), b| (l.min(b.0), h.max(b.1)),
        );
        if boxes.is_empty() || !(lo.is_finite() && hi.is_finite()) {
            return Grid {
                lo: DVec2::ZERO,
                size: 1.0,
                nx: 0,
                ny: 0,
                start: vec![0],
                ids: Vec::new(),
            };
        }
        let ext = hi - lo;
        // At most about 4 buckets per box on average, so the grid stays small for wide scenes.
        let budget = (4 * boxes.len()).max(64) as f64;
        let size = Self::SIZE_M.max((ext.x * ext.y / budget).sqrt()).max(1e-9);
        let nx = (ext.x / size) as usize + 1;
        let ny = (ext.y / size) as usize + 1;
        let mut g = Grid {
            lo,
            size,
            nx,
            ny,
            start: vec![0; nx * ny + 1],
            ids: Vec::new(),
        };
        for b in boxes {
            let (x0, y0, x1, y1) = g.range(b.0, b.1);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    g.start[y * nx + x + 1] += 1;
                }
            }
        }
        for k in 0..nx * ny {
            g.start[k + 1] += g.start[k];
        }
        let mut fill = g.start.clone();
        g.ids = vec![0; g.start[nx * ny] as usize];
        for (i, b) in boxes.iter().enumerate() {
            let (x0, y0, x1, y1) = g.range(b.0, b.1);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let k = y * nx + x;
                    g.ids[fill[k] as usize] = i as u32;
                    fill[k] += 1;
                }
            }
        }
        g
    }

    pub(super) fn range(&self, lo: DVec2, hi: DVec2) -> (usize, usize, usize, usize) {
        let ix =
            |v: f64, n: usize| ((crate::geom::floor(v / self.size).max(0.0)) as usize).min(n - 1);
        let (a, b) = (lo - self.lo, hi - self.lo);
        (
            ix(a.x, self.nx),
            ix(a.y, self.ny),
            ix(b.x, self.nx),
            ix(b.y, self.ny),
        )
    }

    /// Calls `f` once for each box listed in a bucket meeting `[lo, hi]` that `keep` accepts
    /// (buckets by their bounds), in bucket order; `seen` (one stamp per box) marks those
    /// already met, with `stamp`, which must differ from every earlier query's.
    ///
    /// `region`, when it has 3 or more vertices, is a convex polygon that every bucket `keep`
    /// accepts meets, up to a margin far below [`ROW_PAD_M`]: in each row of buckets only those
    /// meeting the region's part in that row, grown by the pad, are offered to `keep` (the
    /// others it would refuse), so a thin region across a wide box costs its own area, not the
    /// box's.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn query(
        &self,
        lo: DVec2,
        hi: DVec2,
        region: &[DVec2],
        keep: &dyn Fn(DVec2, DVec2) -> bool,
        seen: &mut [u32],
        stamp: u32,
        mut f: impl FnMut(u32),
    ) {
        if self.nx == 0 {
            return;
        }
        let (x0, y0, x1, y1) = self.range(lo, hi);
        for y in y0..=y1 {
            let (xa, xb) = if region.len() >= 3 {
                let band0 = self.lo.y + y as f64 * self.size - ROW_PAD_M;
                let band1 = self.lo.y + (y + 1) as f64 * self.size + ROW_PAD_M;
                match row_extent(region, band0, band1) {
                    Some((a, b)) => {
                        let (a, _, b, _) = self.range(
                            DVec2::new(a - ROW_PAD_M, lo.y),
                            DVec2::new(b + ROW_PAD_M, lo.y),
                        );
                        (a.max(x0), b.min(x1))
                    }
                    None => continue,
                }
            } else {
                (x0, x1)
            };
            for x in xa..=xb {
                let b0 = self.lo + DVec2::new(x as f64, y as f64) * self.size;
                if !keep(b0, b0 + DVec2::splat(self.size)) {
                    continue;
                }
                let k = y * self.nx + x;
                for &i in &self.ids[self.start[k] as usize..self.start[k + 1] as usize] {
                    if seen[i as usize] != stamp {
                        seen[i as usize] = stamp;
                        f(i);
                    }
                }
            }
        }
    }
}

/// How far [`Grid::query`] grows a region's part in a row of buckets, metres: far above the
/// margin of the verifier's half-plane filter and the rounding of the row's edge crossings.
const ROW_PAD_M: f64 = 1.0;

/// The least and greatest x of the convex polygon `p` within the band `y0 <= y <= y1`: over its
/// vertices in the band and its edges' crossings of the band's two lines (float, for
/// [`Grid::query`], which pads it); `None` when the band misses it.
fn row_extent(p: &[DVec2], y0: f64, y1: f64) -> Option<(f64, f64)> {
    let (mut a, mut b) = (f64::INFINITY, f64::NEG_INFINITY);
    let n = p.len();
    for i in 0..n {
        let (u, w) = (p[i], p[(i + 1) % n]);
        if u.y >= y0 && u.y <= y1 {
            (a, b) = (a.min(u.x), b.max(u.x));
        }
        for yl in [y0, y1] {
            if (u.y - yl) * (w.y - yl) < 0.0 {
                let x = u.x + (yl - u.y) * (w.x - u.x) / (w.y - u.y);
                (a, b) = (a.min(x), b.max(x));
            }
        }
    }
    (a <= b).then_some((a, b))
}

/// Blockers indexed for the verifier: their boxes and a bucket grid over them. One index can
/// serve many verifiers over subsets of its blockers ([`Verifier::subset`]).
pub struct BlockerIndex<'a> {
    pub(super) polys: Vec<&'a [DVec2]>,
    pub(super) boxes: Vec<(DVec2, DVec2)>,
    pub(super) grid: Grid,
}

impl<'a> BlockerIndex<'a> {
    /// The index of `blockers` (each convex and counter-clockwise, or a 2-vertex segment).
    pub fn new(blockers: impl IntoIterator<Item = &'a [DVec2]>) -> Self {
        let polys: Vec<&[DVec2]> = blockers.into_iter().collect();
        let boxes: Vec<(DVec2, DVec2)> = polys.iter().map(|b| bbox(b)).collect();
        let grid = Grid::new(&boxes);
        BlockerIndex { polys, boxes, grid }
    }

    pub fn len(&self) -> usize {
        self.polys.len()
    }

    /// The bounding box of blocker `i`.
    pub fn bounds(&self, i: u32) -> (DVec2, DVec2) {
        self.boxes[i as usize]
    }

    pub fn is_empty(&self) -> bool {
        self.polys.is_empty()
    }
}

/// The near blockers of a piece: their ids, outlines and boxes, in the same order.
pub(super) type Near<'c, 'a> = (
    &'c [u32],
    &'c [&'a [DVec2]],
    &'c [(DVec2, DVec2)],
    &'c [u32],
);

impl<'a> Verifier<'a> {
    pub(super) fn index(&self) -> &BlockerIndex<'a> {
        match &self.set {
            Blockers::Own(i) => i,
            Blockers::Subset(i, _) => i,
        }
    }

    pub(super) fn member(&self, i: u32) -> bool {
        match &self.set {
            Blockers::Own(_) => true,
            Blockers::Subset(_, m) => m[i as usize],
        }
    }

    pub(super) fn poly(&self, i: u32) -> &'a [DVec2] {
        self.index().polys[i as usize]
    }

    pub(super) fn bounds(&self, i: u32) -> (DVec2, DVec2) {
        self.index().boxes[i as usize]
    }

    /// The blockers that may block a segment from the cell to `[a, b]`: those meeting the
    /// convex hull of the cell and the segment (a float filter that drops only blockers clear of
    /// it by a margin; every segment from the cell to `[a, b]` lies in the hull, and leaving a
    /// blocker out can only certify less).
    pub(super) fn near(&self, a: DVec2, b: DVec2, out: &mut Vec<u32>) {
        let hull = convex_hull(self.cell.iter().copied().chain([a, b]));
        let (lo, hi) = bbox(&hull);
        let clear = clear_of(&hull);
        out.clear();
        let mut seen = self.seen.borrow_mut();
        let (stamps, stamp) = &mut *seen;
        if stamps.len() != self.index().len() || *stamp == u32::MAX {
            *stamps = vec![0; self.index().len()];
            *stamp = 0;
        }
        *stamp += 1;
        self.index().grid.query(
            lo,
            hi,
            &hull,
            &|bl, bh| !clear(bl, bh),
            stamps,
            *stamp,
            |i| {
                if !self.member(i) {
                    return;
                }
                let (bl, bh) = self.bounds(i);
                if !(bl.x > hi.x || bh.x < lo.x || bl.y > hi.y || bh.y < lo.y || clear(bl, bh)) {
                    out.push(i);
                }
            },
        );
    }

    /// [`Self::near`] of the piece `[j, k]`, from the cache when it covers the piece; otherwise
    /// computed for the piece and [`NEAR_AHEAD_M`] beyond, and cached.
    pub(super) fn near_cached<'c>(
        &self,
        par: &Param,
        j: u64,
        k: u64,
        cache: &'c mut NearCache<'a>,
    ) -> Near<'c, 'a> {
        if !(cache.span.0 <= j && k <= cache.span.1) {
            let end = k.max(j.saturating_add(cache.ahead)).min(END);
            let (e, pe) = par
                .at_or_below(end, k)
                .unwrap_or((k, par.at(k).unwrap_or(par.b)));
            let q = par.at(j).unwrap_or(par.a);
            // The previous stretch's buffers are reused (this runs for every new stretch).
            let mut ids = std::mem::take(&mut cache.ids);
            self.near(q, pe, &mut ids);
            // Nearest the stretch's start first (ties by id: deterministic).
            let dist = |i: u32| {
                let (lo, hi) = self.bounds(i);
                (lo - q).max(q - hi).max(DVec2::ZERO).length_squared()
            };
            let keyed = &mut cache.keyed;
            keyed.clear();
            keyed.extend(ids.iter().map(|&i| (dist(i), i)));
            let by = |a: &(f64, u32), b: &(f64, u32)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
            // The search reads the nearest first and mostly stops among them: only those are
            // put in order, the rest follow in a fixed order (deterministic all the same).
            if keyed.len() > NEAREST_SORTED {
                keyed.select_nth_unstable_by(NEAREST_SORTED, by);
                keyed[..NEAREST_SORTED].sort_unstable_by(by);
            } else {
                keyed.sort_unstable_by(by);
            }
            ids.clear();
            ids.extend(keyed.iter().map(|x| x.1));
            cache.polys.clear();
            cache.polys.extend(ids.iter().map(|&i| self.poly(i)));
            cache.boxes.clear();
            cache.boxes.extend(ids.iter().map(|&i| self.bounds(i)));
            // The stretch's points are `a + t d` for `t` in its span (`Param::at`), and `b` at
            // its end: each coordinate monotone in `t`, so they lie in the box of its two ends
            // (taken in floats, then grown far past their rounding).
            let (t0, t1) = (j as f64 / END as f64, e.max(k) as f64 / END as f64);
            let (u, v) = (par.a + par.d * t0, par.a + par.d * t1);
            let (mut lo, mut hi) = (u.min(v), u.max(v));
            if e.max(k) >= END {
                (lo, hi) = (lo.min(par.b), hi.max(par.b));
            }
            let (lo, hi) = (lo - ALONG_PAD_M, hi + ALONG_PAD_M);
            cache.along.clear();
            cache.along.extend((0..ids.len() as u32).filter(|&k| {
                let (bl, bh) = cache.boxes[k as usize];
                bl.x <= hi.x && bh.x >= lo.x && bl.y <= hi.y && bh.y >= lo.y
            }));
            cache.ids = ids;
            cache.span = (j, e.max(k));
        }
        (&cache.ids, &cache.polys, &cache.boxes, &cache.along)
    }
}

/// The float filter of [`Verifier::near`]: `clear(lo, hi)` is true when the box `[lo, hi]` lies
/// wholly beyond one edge of the convex polygon `hull` (counter-clockwise) by a margin, so holds
/// none of its points (rounding only keeps a box more, or drops one that at most touches it).
/// Always false for fewer than 3 vertices.
fn clear_of(hull: &[DVec2]) -> impl Fn(DVec2, DVec2) -> bool {
    // Each hull edge as an outward half-plane `n . x > c + m`.
    let planes: Vec<(DVec2, f64)> = if hull.len() < 3 {
        Vec::new()
    } else {
        (0..hull.len())
            .map(|i| {
                let (u, v) = (hull[i], hull[(i + 1) % hull.len()]);
                let n = (v - u).perp() * -1.0;
                let m = 1e-9 * (n.length() + 1.0) * (1.0 + u.abs().max_element());
                (n, n.dot(u) + m)
            })
            .collect()
    };
    move |bl: DVec2, bh: DVec2| {
        planes.iter().any(|&(n, c)| {
            let x = if n.x >= 0.0 { bl.x } else { bh.x };
            let y = if n.y >= 0.0 { bl.y } else { bh.y };
            n.x * x + n.y * y > c
        })
    }
}

/// The float filter of [`Verifier::near`] for callers that list blockers themselves:
/// `may_meet(lo, hi)` is false only when the box `[lo, hi]` lies outside the bounding box of the
/// convex hull of `cell` and `[a, b]`, or wholly beyond one of the hull's edges by a margin
/// ([`clear_of`]); every segment from the cell to `[a, b]` lies in that hull.
pub fn sight_filter(cell: &[DVec2], a: DVec2, b: DVec2) -> impl Fn(DVec2, DVec2) -> bool {
    let hull = convex_hull(cell.iter().copied().chain([a, b]));
    let (lo, hi) = bbox(&hull);
    let clear = clear_of(&hull);
    move |bl: DVec2, bh: DVec2| {
        !(bl.x > hi.x || bh.x < lo.x || bl.y > hi.y || bh.y < lo.y || clear(bl, bh))
    }
}

/// Convex hull, counter-clockwise, without collinear points (Andrew's monotone chain with exact
/// orientation tests).
pub(super) fn convex_hull(pts: impl Iterator<Item = DVec2>) -> Vec<DVec2> {
    let mut p: Vec<DVec2> = pts.collect();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let mut h: Vec<DVec2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = h.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while h.len() >= start + 2
                && orient(h[h.len() - 2], h[h.len() - 1], q) != Orientation::Ccw
            {
                h.pop();
            }
            h.push(q);
        }
        h.pop();
    }
    h
}

pub(super) fn bbox(p: &[DVec2]) -> (DVec2, DVec2) {
    p.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), &v| (lo.min(v), hi.max(v)),
    )
}

#[cfg(test)]
mod tests {
    use super::super::oracle::{dyadic_points, rect, scene, v};
    use super::super::tests::slices;
    use super::*;
    use crate::geom::predicates::segment_meets_convex;
    use crate::testutil::Lcg;

    /// `n` boxes with corners in `[0, spread]^2` and sides up to `side`.
    fn random_boxes(g: &mut Lcg, n: usize, spread: f64, side: f64) -> Vec<(DVec2, DVec2)> {
        (0..n)
            .map(|_| {
                let lo = v(g.range(0.0, spread), g.range(0.0, spread));
                (lo, lo + v(g.range(0.0, side), g.range(0.0, side)))
            })
            .collect()
    }

    #[test]
    fn the_grid_lists_each_box_meeting_a_query_once() {
        let mut g = Lcg(23);
        for round in 0..200 {
            let n = 1 + (g.next_u64() % 60) as usize;
            let spread = if round % 2 == 0 { 100.0 } else { 3000.0 };
            let boxes = random_boxes(&mut g, n, spread, 80.0);
            let grid = Grid::new(&boxes);
            let mut seen = vec![0u32; n];
            let lo = v(g.range(-50.0, spread), g.range(-50.0, spread));
            let hi = lo + v(g.range(0.0, 200.0), g.range(0.0, 200.0));
            let mut got = Vec::new();
            grid.query(lo, hi, &[], &|_, _| true, &mut seen, 1, |i| got.push(i));
            let mut sorted = got.clone();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), got.len(), "a box listed twice");
            let meets = |b: &(DVec2, DVec2)| {
                !(b.0.x > hi.x || b.1.x < lo.x || b.0.y > hi.y || b.1.y < lo.y)
            };
            for (i, b) in boxes.iter().enumerate() {
                if meets(b) {
                    assert!(got.contains(&(i as u32)), "round {round}: box {i} missed");
                }
            }
        }
    }

    /// The rows a region offers change nothing: a query with the cell-to-stretch hull lists
    /// the same boxes in the same order as one over its whole bounding box.
    #[test]
    fn a_query_by_rows_of_the_hull_lists_what_the_whole_box_lists() {
        let mut g = Lcg(31);
        let mut listed = 0;
        for round in 0..300 {
            let n = 1 + (g.next_u64() % 200) as usize;
            let spread = if round % 2 == 0 { 300.0 } else { 3000.0 };
            let boxes = random_boxes(&mut g, n, spread, 60.0);
            let grid = Grid::new(&boxes);
            // A cell and a far stretch: a thin hull across a wide box.
            let c = v(g.range(0.0, spread), g.range(0.0, spread));
            let s = g.range(1.0, 100.0);
            let a = v(
                g.range(-200.0, spread + 200.0),
                g.range(-200.0, spread + 200.0),
            );
            let b = a + v(g.range(-60.0, 60.0), g.range(-60.0, 60.0));
            let pts = [c, c + v(s, 0.0), c + v(s, s), c + v(0.0, s), a, b];
            let hull = convex_hull(pts.iter().copied());
            let (lo, hi) = bbox(&hull);
            let clear = clear_of(&hull);
            let mut seen = vec![0u32; n];
            let (mut whole, mut rows) = (Vec::new(), Vec::new());
            grid.query(lo, hi, &[], &|l, h| !clear(l, h), &mut seen, 1, |i| {
                whole.push(i)
            });
            grid.query(lo, hi, &hull, &|l, h| !clear(l, h), &mut seen, 2, |i| {
                rows.push(i)
            });
            assert_eq!(whole, rows, "round {round}");
            listed += whole.len();
        }
        assert!(
            listed > 1000,
            "the queries listed too little to compare: {listed}"
        );
    }

    /// Every blocker that some segment from the cell to the piece meets is near it.
    #[test]
    fn near_keeps_every_blocker_a_segment_from_the_cell_meets() {
        let mut g = Lcg(29);
        let mut kept = 0;
        for _ in 0..60 {
            let (cell, blockers, (a, b)) = scene(&mut g, 20);
            let ver = Verifier::new(&cell, slices(&blockers));
            let mut near = Vec::new();
            ver.near(a, b, &mut near);
            let from = dyadic_points(cell[0], cell[2], 4)
                .into_iter()
                .chain(cell.iter().copied())
                .chain(dyadic_points(cell[1], cell[3], 4));
            let from: Vec<DVec2> = from.collect();
            for (i, blk) in blockers.iter().enumerate() {
                let met = from.iter().any(|&c| {
                    dyadic_points(a, b, 5)
                        .iter()
                        .any(|&q| segment_meets_convex(c, q, blk))
                });
                if met {
                    assert!(near.contains(&(i as u32)), "blocker {i} {blk:?} left out");
                    kept += 1;
                }
            }
        }
        assert!(kept > 100, "{kept}");
        // Far beside the hull: left out.
        let cell = rect(0.0, 0.0, 10.0, 10.0);
        let blockers = vec![rect(100.0, 0.0, 110.0, 10.0), rect(0.0, 20.0, 10.0, 22.0)];
        let ver = Verifier::new(&cell, slices(&blockers));
        let mut near = Vec::new();
        ver.near(v(0.0, 40.0), v(10.0, 40.0), &mut near);
        assert_eq!(near, vec![1]);
    }

    /// A verifier over a subset of a shared index answers as one with an index of its own over
    /// the same blockers (named by their place in the index instead).
    #[test]
    fn a_subset_of_a_shared_index_answers_as_its_own_index() {
        let mut g = Lcg(31);
        for _ in 0..40 {
            let (cell, blockers, (a, b)) = scene(&mut g, 16);
            let index = BlockerIndex::new(slices(&blockers));
            let members: Vec<u32> = (0..blockers.len() as u32)
                .filter(|_| g.next() < 0.6)
                .collect();
            let own: Vec<Vec<DVec2>> = members
                .iter()
                .map(|&i| blockers[i as usize].clone())
                .collect();
            let shared = Verifier::subset(&cell, &index, &members).hidden_parts_by(a, b);
            let alone = Verifier::new(&cell, slices(&own)).hidden_parts_by(a, b);
            let renamed: Vec<_> = alone
                .into_iter()
                .map(|(h, u)| {
                    (
                        h,
                        u.iter().map(|&k| members[k as usize]).collect::<Vec<_>>(),
                    )
                })
                .collect();
            assert_eq!(shared, renamed);
        }
    }

    #[test]
    fn the_near_blockers_of_a_stretch_come_nearest_first() {
        let mut g = Lcg(37);
        for _ in 0..40 {
            let (cell, blockers, (a, b)) = scene(&mut g, 30);
            let ver = Verifier::new(&cell, slices(&blockers));
            let par = Param { a, b, d: b - a };
            let mut cache = NearCache {
                span: (1, 0),
                ahead: END / 8,
                ids: Vec::new(),
                polys: Vec::new(),
                boxes: Vec::new(),
                along: Vec::new(),
                keyed: Vec::new(),
            };
            let (ids, _, boxes, along) = ver.near_cached(&par, 0, END / 16, &mut cache);
            let d = |k: usize| {
                let (lo, hi) = boxes[k];
                (lo - a).max(a - hi).max(DVec2::ZERO).length_squared()
            };
            for k in 1..ids.len().min(NEAREST_SORTED) {
                assert!(d(k - 1) <= d(k));
            }
            // `along` lists every box meeting the stretch's box.
            let e = par.at_or_below(END / 8, END / 16).unwrap().1;
            let (lo, hi) = (a.min(e), a.max(e));
            for (k, &(bl, bh)) in boxes.iter().enumerate() {
                let meets = bl.x <= hi.x && bh.x >= lo.x && bl.y <= hi.y && bh.y >= lo.y;
                if meets {
                    assert!(along.contains(&(k as u32)));
                }
            }
        }
    }

    #[test]
    fn the_hull_holds_every_point_and_turns_left() {
        let mut g = Lcg(41);
        for _ in 0..300 {
            let pts: Vec<DVec2> = (0..3 + g.next_u64() % 20)
                .map(|_| v(g.range(-9.0, 9.0).round(), g.range(-9.0, 9.0).round()))
                .collect();
            let h = convex_hull(pts.iter().copied());
            if h.len() < 3 {
                continue;
            }
            for i in 0..h.len() {
                let (u, w) = (h[i], h[(i + 1) % h.len()]);
                assert_eq!(orient(u, w, h[(i + 2) % h.len()]), Orientation::Ccw);
                assert!(pts.iter().all(|&p| orient(u, w, p) != Orientation::Cw));
            }
        }
    }
}
