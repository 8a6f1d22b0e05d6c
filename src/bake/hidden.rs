//! Sampled from-region visibility: which points around a cell are hidden from it, as a raster.
//!
//! Input: a cell (convex, counter-clockwise rectangle), the blocker edges of one slice (2D
//! segments, each facing outwards from its blocker, from [`EdgeTwins::boundary_edges`]), and a
//! [`MapParams`] (eyes on the cell's boundary, angular bins, pixel size, window).
//! Output: a [`HiddenMap`] ([`HiddenMap::build_slices`]: one per slice, from one pass over the
//! union of the slices' edges, each the map its slice's edges give alone): a square raster
//! around the cell centre whose pixels are marked
//! *visible* when some sampled ray from some eye reaches them before meeting an edge; the others
//! count as hidden.
//! Method: per eye, a polar depth buffer (the distance to the first edge along the central ray
//! of each angular bin, edges taken near to far and skipped when a coarse tile maximum shows them
//! wholly behind what is already there), then every bin's ray marks the pixels it crosses up to
//! that depth. The slices whose march along a ray starts at the same step share it: it walks
//! once into a raster of one byte a pixel, a bit a slice, each bit set while its own slice's
//! march lasts (the same points by the same additions, so the same pixels), and the bytes are
//! split into the slices' bit maps at the end.
//! Invariant: a proposal only, sampled in floating point. Nothing here decides occlusion: a
//! segment lying in hidden pixels is a candidate VO, which the exact verifier alone certifies
//! (`super::certify`). Sampling can miss a narrow view (a gap thinner than a bin, an eye
//! position between samples); the verifier then cuts the candidate there.

use crate::geom::{ceil, floor};
use glam::DVec2;

pub use crate::geom::pseudo_angle;

/// How finely a [`HiddenMap`] samples visibility.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapParams {
    /// Eyes on the cell's boundary: its corners, and this many points on each edge between them.
    pub edge_eyes: usize,
    /// Angular bins of each eye's depth buffer (a multiple of [`TILE`]).
    pub bins: usize,
    /// Side of a pixel, metres.
    pub px: f64,
    /// Half the side of the square raster, metres, around the cell centre.
    pub half: f64,
}

impl Default for MapParams {
    fn default() -> Self {
        MapParams {
            edge_eyes: 3,
            bins: 512,
            px: 4.0,
            half: 1024.0,
        }
    }
}

/// Bins per tile of the coarse maximum used to skip hidden edges.
pub const TILE: usize = 16;

/// The unit direction of pseudo-angle `p`.
fn direction(p: f64) -> DVec2 {
    let (x, y) = if p < 1.0 {
        (1.0 - p, p)
    } else if p < 2.0 {
        (1.0 - p, 2.0 - p)
    } else if p < 3.0 {
        (p - 3.0, 2.0 - p)
    } else {
        (p - 3.0, p - 4.0)
    };
    DVec2::new(x, y).normalize()
}

/// The visible pixels around one cell for one slice.
#[derive(Clone, Debug)]
pub struct HiddenMap {
    /// Lower-left corner of pixel (0, 0).
    pub lo: DVec2,
    pub px: f64,
    /// Pixels per side.
    pub n: usize,
    visible: Vec<u64>,
}

impl HiddenMap {
    /// Whether pixel `(ix, iy)` counts as hidden (outside the raster: no).
    #[inline]
    pub fn hidden_px(&self, ix: i64, iy: i64) -> bool {
        if ix < 0 || iy < 0 || ix >= self.n as i64 || iy >= self.n as i64 {
            return false;
        }
        let k = iy as usize * self.n + ix as usize;
        self.visible[k >> 6] & (1 << (k & 63)) == 0
    }

    /// Whether the pixel at raster position `q` (in pixels from `lo`) counts as hidden.
    #[inline]
    pub fn hidden_at(&self, q: DVec2) -> bool {
        if !(q.x >= 0.0 && q.y >= 0.0) {
            return false;
        }
        // (As in `mark`: `u32` saturates outside the raster like `usize`.)
        let (ix, iy) = (q.x as u32 as usize, q.y as u32 as usize);
        if ix >= self.n || iy >= self.n {
            return false;
        }
        let k = iy * self.n + ix;
        self.visible[k >> 6] & (1 << (k & 63)) == 0
    }

    /// Raster position (in pixels from `lo`) of the local point `p`.
    #[inline]
    pub fn raster(&self, p: DVec2) -> DVec2 {
        (p - self.lo) / self.px
    }

    /// Whether the pixel holding `p` counts as hidden.
    #[inline]
    pub fn hidden(&self, p: DVec2) -> bool {
        let f = (p - self.lo) / self.px;
        // Truncation is floor for non-negative values (and avoids a libm call).
        if !(f.x >= 0.0 && f.y >= 0.0) {
            return false;
        }
        self.hidden_px(f.x as i64, f.y as i64)
    }

    /// Share of the raster's pixels that count as hidden.
    pub fn hidden_share(&self) -> f64 {
        let vis: u32 = self.visible.iter().map(|w| w.count_ones()).sum();
        1.0 - vis as f64 / (self.n * self.n) as f64
    }

    /// Builds the map of `cell` from the outward-facing `edges` of the slice's blockers.
    pub fn build(cell: &[DVec2; 4], edges: &[(DVec2, DVec2)], p: &MapParams) -> HiddenMap {
        let member = vec![1u8; edges.len()];
        let mut maps = Self::build_slices(cell, edges, &member, 1, p);
        maps.pop().expect("one slice asked, one map built")
    }

    /// The maps of `cell` for `slices` slices at once (at most 8), from the union of their
    /// edges: `edges[i]` is an edge of slice `s` when bit `s` of `member[i]` is set. Each map is
    /// the one [`Self::build`] gives from that slice's edges alone: a bin's depth is the least
    /// hit distance over the slice's edges, whatever their order, and an edge (or a group of
    /// them) is passed over for a slice only when that slice's buffer already lies wholly in
    /// front of its nearest point, where its hits cannot undercut the buffer (but by a rounding
    /// of the two distances, which could differ in the order edges come; no store of the bundled
    /// scenes or of a generated city of 10^5 buildings changed). The work per edge and bin (its
    /// hit distance) is shared by every slice that has the edge, where a map per slice computed
    /// it once per slice. A proposal tool all the same (module header).
    pub fn build_slices(
        cell: &[DVec2; 4],
        edges: &[(DVec2, DVec2)],
        member: &[u8],
        slices: usize,
        p: &MapParams,
    ) -> Vec<HiddenMap> {
        assert!(
            edges.len() == member.len() && slices <= 8,
            "one slice mask per edge, 8 slices"
        );
        let centre = (cell[0] + cell[2]) * 0.5;
        let n = ((2.0 * p.half) / p.px).ceil() as usize;
        let (origin, px) = (centre - DVec2::splat(p.half), p.px);
        let mut maps: Vec<HiddenMap> = (0..slices)
            .map(|_| HiddenMap {
                lo: origin,
                px: p.px,
                n,
                visible: vec![0; (n * n).div_ceil(64)],
            })
            .collect();
        let bins = (p.bins.max(TILE) / TILE * TILE).next_power_of_two();
        let scale = bins as f64 / 4.0;
        let dirs: Vec<DVec2> = (0..bins)
            .map(|k| direction((k as f64 + 0.5) / scale))
            .collect();
        let far = p.half * std::f64::consts::SQRT_2 + p.px;
        let groups = Groups::new(edges, member, centre);
        let mut depth = vec![vec![far; bins]; slices];
        let mut tile = vec![vec![far; bins / TILE]; slices];
        // Every slice's pixels, one byte a pixel, bit `s` for slice `s` (split into the maps at
        // the end).
        let mut raster = vec![0u8; n * n];
        // Eyes on each edge, with the outward normal of that edge (corners: of both edges). A ray
        // into the cell crosses it and leaves through another edge, whose own eyes see beyond
        // it, so only rays leaving the cell are cast.
        let mut eyes: Vec<(DVec2, DVec2, DVec2)> = Vec::new();
        for i in 0..4 {
            let (a, b) = (cell[i], cell[(i + 1) % 4]);
            let out = (b - a).perp() * -1.0;
            let prev = (a - cell[(i + 3) % 4]).perp() * -1.0;
            eyes.push((a, out, prev));
            for k in 1..=p.edge_eyes {
                eyes.push((
                    a + (b - a) * (k as f64 / (p.edge_eyes + 1) as f64),
                    out,
                    out,
                ));
            }
        }
        // Bins whose central ray lies in the counter-clockwise span from pseudo-angle `pa` to
        // `pb` (less than a half-turn), as at most two ranges.
        let spans = |pa: f64, pb: f64| -> [(usize, usize); 2] {
            const NONE: (usize, usize) = (1, 0);
            let first = |a: f64| (ceil(a * scale - 0.5).max(0.0)) as usize;
            let last = |b: f64| {
                let l = floor(b * scale - 0.5);
                (l >= 0.0).then(|| (l as usize).min(bins - 1))
            };
            if pa <= pb {
                match last(pb) {
                    Some(l) => [(first(pa), l), NONE],
                    None => [NONE, NONE],
                }
            } else {
                [(first(pa), bins - 1), last(pb).map_or(NONE, |l| (0, l))]
            }
        };
        let hidden_behind = |tile: &[f64], r: [(usize, usize); 2], dmin: f64| {
            r.iter()
                .filter(|(a, b)| a <= b)
                .all(|&(a, b)| (a / TILE..=b / TILE).all(|t| tile[t] <= dmin))
        };
        // The slices of `mask` whose buffer does not already lie wholly in front of `r` at
        // distance `dmin`.
        let open = |tile: &[Vec<f64>], mask: u8, r: [(usize, usize); 2], dmin: f64| {
            let mut live = 0u8;
            for s in set_bits(mask) {
                if !hidden_behind(&tile[s], r, dmin) {
                    live |= 1 << s;
                }
            }
            live
        };
        for &(e, out1, out2) in &eyes {
            for s in 0..slices {
                depth[s].fill(far);
                tile[s].fill(far);
            }
            let outward = |x: DVec2| (x - e).dot(out1) > 0.0 || (x - e).dot(out2) > 0.0;
            for g in &groups.groups {
                // A whole group behind what is already in a slice's buffer is skipped for it.
                let (lo, hi) = g.bounds;
                let inside = e.x >= lo.x - 1.0
                    && e.x <= hi.x + 1.0
                    && e.y >= lo.y - 1.0
                    && e.y <= hi.y + 1.0;
                let mut live = g.member;
                if !inside {
                    let dmin = (lo - e).max(e - hi).max(DVec2::ZERO).length();
                    if dmin >= far {
                        continue;
                    }
                    let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
                    if !corners.iter().any(|&c| outward(c)) {
                        continue;
                    }
                    let pc = pseudo_angle((lo + hi) * 0.5 - e);
                    let (mut dlo, mut dhi) = (0.0f64, 0.0f64);
                    for c in corners {
                        let mut d = pseudo_angle(c - e) - pc;
                        if d > 2.0 {
                            d -= 4.0;
                        } else if d < -2.0 {
                            d += 4.0;
                        }
                        dlo = dlo.min(d);
                        dhi = dhi.max(d);
                    }
                    let wrap = |x: f64| x.rem_euclid(4.0);
                    if dhi - dlo < 2.0 {
                        live = open(&tile, live, spans(wrap(pc + dlo), wrap(pc + dhi)), dmin);
                        if live == 0 {
                            continue;
                        }
                    }
                }
                for &i in &groups.ids[g.range.0..g.range.1] {
                    let mask = member[i as usize] & live;
                    if mask == 0 {
                        continue;
                    }
                    let (u, v) = edges[i as usize];
                    // Front-facing only: the eye strictly on the outer (right) side.
                    if (v - u).perp_dot(e - u) >= 0.0 || !(outward(u) || outward(v)) {
                        continue;
                    }
                    let dmin = seg_distance(e, u, v);
                    if dmin >= far {
                        continue;
                    }
                    // Seen from e, the edge runs counter-clockwise from v to u.
                    let ranges = spans(pseudo_angle(v - e), pseudo_angle(u - e));
                    let todo = open(&tile, mask, ranges, dmin);
                    if todo == 0 {
                        continue;
                    }
                    let w = v - u;
                    let num = (u - e).perp_dot(w);
                    for (r0, r1) in ranges {
                        if r0 > r1 {
                            continue;
                        }
                        for k in r0..=r1 {
                            let den = dirs[k].perp_dot(w);
                            if den == 0.0 {
                                continue;
                            }
                            let t = num / den;
                            if t >= 0.0 {
                                for s in set_bits(todo) {
                                    if t < depth[s][k] {
                                        depth[s][k] = t;
                                    }
                                }
                            }
                        }
                        for s in set_bits(todo) {
                            for t in r0 / TILE..=r1 / TILE {
                                tile[s][t] = depth[s][t * TILE..(t + 1) * TILE]
                                    .iter()
                                    .fold(0.0f64, |m, &d| m.max(d));
                            }
                        }
                    }
                }
            }
            // March every outward bin's ray up to its depth, marking the pixels it crosses. Rays
            // of a coarser level (more trailing zeros) are spaced less than a pixel apart up to
            // some distance; a finer ray starts there, or where a coarser neighbour stopped.
            // The slices whose march starts at the same step walk the same points (the same
            // start, the same additions), so they walk them once, into one byte a pixel with a
            // bit a slice, each bit set while its own slice's march lasts: the pixels of each
            // map are those of its own march.
            let o = (e - origin) / px;
            let dtheta = std::f64::consts::TAU / bins as f64;
            for k in 0..bins {
                let d = dirs[k];
                if d.dot(out1) < 0.0 && d.dot(out2) < 0.0 {
                    continue;
                }
                let mut first = [0usize; 8];
                let mut steps = [0usize; 8];
                let mut todo = 0u8;
                for (s, depth) in depth.iter().enumerate() {
                    let len = depth[k].min(far);
                    let start = if k == 0 {
                        0.0
                    } else {
                        let tz = k.trailing_zeros();
                        let w = 1usize << tz;
                        let neighbours = depth[k - w].min(depth[(k + w) % bins]);
                        (p.px / ((2 << tz) as f64 * dtheta)).min(neighbours)
                    };
                    if start < len {
                        first[s] = (start / p.px) as usize;
                        steps[s] = (len / p.px) as usize;
                        todo |= 1 << s;
                    }
                    // The pixel holding the end point (the surface itself).
                    if let Some(at) = pixel(o + d * (len / p.px), n) {
                        raster[at] |= 1 << s;
                    }
                }
                while todo != 0 {
                    let f = first[todo.trailing_zeros() as usize];
                    let mut live = 0u8;
                    for s in set_bits(todo) {
                        if first[s] == f {
                            live |= 1 << s;
                        }
                    }
                    todo &= !live;
                    let mut q = o + d * f as f64;
                    let mut i = f;
                    while live != 0 {
                        // March to the nearest end among the live slices, then drop it.
                        let end = set_bits(live).map(|s| steps[s]).min().unwrap_or(0);
                        while i <= end {
                            if let Some(at) = pixel(q, n) {
                                raster[at] |= live;
                            }
                            q += d;
                            i += 1;
                        }
                        for s in set_bits(live) {
                            if steps[s] == end {
                                live &= !(1 << s);
                            }
                        }
                    }
                }
            }
        }
        for (s, map) in maps.iter_mut().enumerate() {
            for (word, bytes) in map.visible.iter_mut().zip(raster.chunks(64)) {
                *word = slice_bits(bytes, s);
            }
        }
        maps
    }
}

/// Bit `s` of each of up to 64 bytes, as the bits of a word (byte `j` to bit `j`).
#[inline]
fn slice_bits(bytes: &[u8], s: usize) -> u64 {
    if let Ok(chunk) = <&[u8; 64]>::try_from(bytes) {
        // Eight bytes at a time: bit `s` of each byte down to bit 0, then the multiply sends
        // bit 0 of byte `i` to bit `56 + i` (the products of other bytes land elsewhere and
        // carry nothing into the top byte).
        let mut w = 0u64;
        for (i, b) in chunk.chunks_exact(8).enumerate() {
            let x =
                (u64::from_le_bytes(b.try_into().unwrap_or([0; 8])) >> s) & 0x0101_0101_0101_0101;
            w |= (x.wrapping_mul(0x0102_0408_1020_4080) >> 56) << (8 * i);
        }
        w
    } else {
        bytes
            .iter()
            .enumerate()
            .fold(0u64, |w, (j, &b)| w | (((b >> s) & 1) as u64) << j)
    }
}

/// The index of the pixel at raster position `q` (in pixels) on an `n` by `n` raster, row-major,
/// if it lies on it. (Positions are truncated to `u32`, which saturates beyond the raster just
/// as `usize` would: the same pixels, for a cheaper conversion in the map's innermost loops.)
#[inline]
fn pixel(q: DVec2, n: usize) -> Option<usize> {
    if q.x >= 0.0 && q.y >= 0.0 {
        let (ix, iy) = (q.x as u32 as usize, q.y as u32 as usize);
        if ix < n && iy < n {
            return Some(iy * n + ix);
        }
    }
    None
}

/// Edges in square groups (by the cell of a grid their first end lies in), groups ordered by
/// distance from the cell centre, with their bounds.
struct Groups {
    groups: Vec<Group>,
    ids: Vec<u32>,
}

struct Group {
    bounds: (DVec2, DVec2),
    range: (usize, usize),
    /// The slices its edges belong to (bits, as in [`HiddenMap::build_slices`]).
    member: u8,
}

impl Groups {
    const SIZE_M: f64 = 32.0;

    fn new(edges: &[(DVec2, DVec2)], member: &[u8], centre: DVec2) -> Groups {
        let key = |p: DVec2| {
            let k = ((p - centre) / Self::SIZE_M).map(floor);
            (k.x as i64, k.y as i64)
        };
        let mut keyed: Vec<((i64, i64), u32)> = edges
            .iter()
            .enumerate()
            .map(|(i, e)| (key(e.0), i as u32))
            .collect();
        sort_keyed(&mut keyed);
        let mut groups: Vec<Group> = Vec::new();
        let mut ids: Vec<u32> = Vec::with_capacity(keyed.len());
        let mut i = 0;
        while i < keyed.len() {
            let k = keyed[i].0;
            let start = ids.len();
            let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
            let mut m = 0u8;
            while i < keyed.len() && keyed[i].0 == k {
                let (u, v) = edges[keyed[i].1 as usize];
                lo = lo.min(u).min(v);
                hi = hi.max(u).max(v);
                m |= member[keyed[i].1 as usize];
                ids.push(keyed[i].1);
                i += 1;
            }
            groups.push(Group {
                bounds: (lo, hi),
                range: (start, ids.len()),
                member: m,
            });
        }
        groups.sort_by(|a, b| {
            let da = ((a.bounds.0 + a.bounds.1) * 0.5).distance_squared(centre);
            let db = ((b.bounds.0 + b.bounds.1) * 0.5).distance_squared(centre);
            da.total_cmp(&db)
        });
        Groups { groups, ids }
    }
}

/// Sorts `keyed` ascending, as `sort_unstable` would (the ids are distinct, so the order is
/// total and any sort gives the same result). The keys of one map span a few thousand grid
/// squares around the cell, so a counting sort over them (ids placed in ascending order within
/// a square) replaces a comparison sort of tens of thousands of edges per slice; a wider span
/// falls back to the comparison sort.
fn sort_keyed(keyed: &mut Vec<((i64, i64), u32)>) {
    let ids_ascending = keyed.windows(2).all(|w| w[0].1 < w[1].1);
    let Some(((x0, y0), (x1, y1))) = keyed.iter().fold(None, |r, &((x, y), _)| {
        Some(match r {
            None => ((x, y), (x, y)),
            Some(((a, b), (c, d))) => ((x.min(a), y.min(b)), (x.max(c), y.max(d))),
        })
    }) else {
        return;
    };
    let (nx, ny) = (x1.abs_diff(x0) + 1, y1.abs_diff(y0) + 1);
    if !ids_ascending || nx.saturating_mul(ny) > 4 * keyed.len() as u64 + 1024 {
        keyed.sort_unstable();
        return;
    }
    // Squares in (x, y) order: the key's own lexicographic order.
    let slot = |(x, y): (i64, i64)| (x.abs_diff(x0) * ny + y.abs_diff(y0)) as usize;
    let mut start = vec![0u32; (nx * ny) as usize + 1];
    for &(k, _) in keyed.iter() {
        start[slot(k) + 1] += 1;
    }
    for s in 1..start.len() {
        start[s] += start[s - 1];
    }
    let mut out = vec![((0i64, 0i64), 0u32); keyed.len()];
    for &(k, i) in keyed.iter() {
        let s = &mut start[slot(k)];
        out[*s as usize] = (k, i);
        *s += 1;
    }
    *keyed = out;
}

/// Least distance from `p` to the segment `[a, b]`.
fn seg_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let l2 = d.length_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(d) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + d * t)
}

/// For every edge of every polygon of one blocker list (3 or more vertices; walls have no
/// entry), the polygons of the list that hold its reverse: the edge is inside a set of these
/// blockers exactly when one of them is in the set. Built once per bake, so that a cell's
/// slices take their [`EdgeTwins::boundary_edges`] by lookups, not by sorting every edge.
pub struct EdgeTwins {
    /// Per blocker, the index of its first edge in `twin_start` (one past the last: the next
    /// blocker's).
    first_edge: Vec<u32>,
    /// Per edge, where its twins start in `twins` (one past the last: the next edge's).
    twin_start: Vec<u32>,
    twins: Vec<u32>,
}

impl EdgeTwins {
    pub fn new<P: AsRef<[DVec2]>>(polys: &[P]) -> EdgeTwins {
        let key = |u: DVec2, v: DVec2| (u.x.to_bits(), u.y.to_bits(), v.x.to_bits(), v.y.to_bits());
        fn edges(p: &[DVec2]) -> impl Iterator<Item = (DVec2, DVec2)> + '_ {
            let n = if p.len() >= 3 { p.len() } else { 0 };
            (0..n).map(move |i| (p[i], p[(i + 1) % n]))
        }
        // Every edge as (its key, its polygon), sorted; and every edge's reverse as (that key,
        // the edge's index), sorted: one merge of the two finds each edge's twins, a run of
        // `keys` (the same polygons in the same order a search of `keys` per edge would find,
        // without a random access into a list of millions per edge).
        let mut keys: Vec<((u64, u64, u64, u64), u32)> = Vec::new();
        let mut reversed: Vec<((u64, u64, u64, u64), u32)> = Vec::new();
        let mut first_edge = Vec::with_capacity(polys.len() + 1);
        for (i, p) in polys.iter().enumerate() {
            first_edge.push(reversed.len() as u32);
            for (u, v) in edges(p.as_ref()) {
                keys.push((key(u, v), i as u32));
                reversed.push((key(v, u), reversed.len() as u32));
            }
        }
        first_edge.push(reversed.len() as u32);
        keys.sort_unstable();
        reversed.sort_unstable();
        // Per edge, the run of `keys` holding its reverse.
        let mut run = vec![(0u32, 0u32); reversed.len()];
        let mut at = 0usize;
        for &(k, e) in &reversed {
            while at < keys.len() && keys[at].0 < k {
                at += 1;
            }
            let end = at + keys[at..].iter().take_while(|x| x.0 == k).count();
            run[e as usize] = (at as u32, end as u32);
        }
        let mut twin_start = Vec::with_capacity(run.len() + 1);
        twin_start.push(0u32);
        let mut twins = Vec::new();
        for &(s, e) in &run {
            twins.extend(keys[s as usize..e as usize].iter().map(|x| x.1));
            twin_start.push(twins.len() as u32);
        }
        EdgeTwins {
            first_edge,
            twin_start,
            twins,
        }
    }

    /// The outward-facing boundary edges of the blockers `ids` (ascending indices into `polys`,
    /// the list this was built from): every edge of every convex polygon, counter-clockwise,
    /// except an edge whose reverse is an edge of another polygon of the set (the inside of a
    /// footprint split into pieces). A 2-vertex blocker (a wall) gives both directions, always:
    /// a wall is thin, so its two faces cancel nothing (not even each other). Edges come in the
    /// order of `ids`, the walls' last.
    pub fn boundary_edges<P: AsRef<[DVec2]>>(
        &self,
        polys: &[P],
        ids: &[u32],
    ) -> Vec<(DVec2, DVec2)> {
        let mut out: Vec<(DVec2, DVec2)> = Vec::new();
        let mut walls: Vec<(DVec2, DVec2)> = Vec::new();
        self.each_boundary_edge(polys, ids, |key, u, v| {
            if key & WALL_EDGE == 0 {
                out.push((u, v));
            } else {
                walls.push((u, v));
            }
        });
        out.extend(walls);
        out
    }

    /// The boundary edges of several slices' blockers (`slices[s]`: ascending ids, as for
    /// [`Self::boundary_edges`]; at most 8 slices), each edge once, with the slices that have
    /// it as bits (bit `s`: slice `s`), ordered by blocker and edge: the input of
    /// [`HiddenMap::build_slices`].
    pub fn slice_edges<P: AsRef<[DVec2]>>(
        &self,
        polys: &[P],
        slices: &[Vec<u32>],
    ) -> (Vec<(DVec2, DVec2)>, Vec<u8>) {
        assert!(slices.len() <= 8, "at most 8 slices");
        // The union of the slices' blockers, ascending, each with the slices it is in (merged
        // slice by slice: each list is ascending).
        let mut union: Vec<(u32, u8)> = Vec::new();
        for (s, ids) in slices.iter().enumerate() {
            debug_assert!(ids.windows(2).all(|w| w[0] < w[1]));
            let bit = 1u8 << s;
            let mut merged = Vec::with_capacity(union.len() + ids.len());
            let (mut u, mut v) = (union.iter().peekable(), ids.iter().peekable());
            loop {
                let next = match (u.peek(), v.peek()) {
                    (Some(&&(i, m)), Some(&&j)) if i == j => {
                        u.next();
                        v.next();
                        (i, m | bit)
                    }
                    (Some(&&(i, m)), Some(&&j)) if i < j => {
                        u.next();
                        (i, m)
                    }
                    (_, Some(&&j)) => {
                        v.next();
                        (j, bit)
                    }
                    (Some(&&x), None) => {
                        u.next();
                        x
                    }
                    (None, None) => break,
                };
                merged.push(next);
            }
            union = merged;
        }
        let slices_of = |t: u32| {
            union
                .binary_search_by_key(&t, |x| x.0)
                .map_or(0, |j| union[j].1)
        };
        // An edge of a blocker is a boundary edge of each of its slices that holds none of its
        // twins ([`Self::each_boundary_edge`]); a wall's two directions are boundary edges of
        // all its slices. Blockers ascending, edges in order: the order of their keys.
        let mut edges: Vec<(DVec2, DVec2)> = Vec::new();
        let mut member: Vec<u8> = Vec::new();
        for &(i, m) in &union {
            let p = polys[i as usize].as_ref();
            match p.len() {
                0 | 1 => {}
                2 => {
                    edges.extend([(p[0], p[1]), (p[1], p[0])]);
                    member.extend([m, m]);
                }
                n => {
                    for k in 0..n {
                        let inside = self
                            .twins_of(i, k)
                            .iter()
                            .fold(0u8, |acc, &t| acc | slices_of(t));
                        if m & !inside != 0 {
                            edges.push((p[k], p[(k + 1) % n]));
                            member.push(m & !inside);
                        }
                    }
                }
            }
        }
        (edges, member)
    }

    /// The blockers holding the reverse of edge `k` of blocker `i` (a polygon).
    fn twins_of(&self, i: u32, k: usize) -> &[u32] {
        let e = self.first_edge[i as usize] as usize + k;
        &self.twins[self.twin_start[e] as usize..self.twin_start[e + 1] as usize]
    }

    /// [`Self::boundary_edges`], each edge given to `f` with a key that names it among all the
    /// edges of `polys` (blocker index in the high 32 bits, edge index in the low ones; a
    /// wall's two directions 0 and 1, with [`WALL_EDGE`] set), in the order of `ids`.
    pub fn each_boundary_edge<P: AsRef<[DVec2]>>(
        &self,
        polys: &[P],
        ids: &[u32],
        mut f: impl FnMut(u64, DVec2, DVec2),
    ) {
        debug_assert!(ids.windows(2).all(|w| w[0] < w[1]));
        for &i in ids {
            let p = polys[i as usize].as_ref();
            let key = (i as u64) << 32;
            match p.len() {
                0 | 1 => {}
                2 => {
                    f(key | WALL_EDGE, p[0], p[1]);
                    f(key | WALL_EDGE | 1, p[1], p[0]);
                }
                n => {
                    for k in 0..n {
                        let inside = self
                            .twins_of(i, k)
                            .iter()
                            .any(|t| ids.binary_search(t).is_ok());
                        if !inside {
                            f(key | k as u64, p[k], p[(k + 1) % n]);
                        }
                    }
                }
            }
        }
    }
}

/// The indices of the set bits of `m`, lowest first (the slices of a mask,
/// [`HiddenMap::build_slices`]).
#[inline(always)]
fn set_bits(mut m: u8) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        let s = (m != 0).then(|| m.trailing_zeros() as usize)?;
        m &= m - 1;
        Some(s)
    })
}

/// The bit of an edge key ([`EdgeTwins::each_boundary_edge`]) that marks a wall's direction.
pub const WALL_EDGE: u64 = 1 << 31;

#[cfg(test)]
mod tests;
