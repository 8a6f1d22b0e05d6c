//! A seeded procedural city, modelled on the randomly generated urban model of paper 003
//! (Leyvand, Sorkine, Cohen-Or, "Ray Space Factorization for From-Region Visibility", sec. on
//! results): blocks separated by streets, blocks
//! filled with building lots, buildings 9–12 m wide and long, rotated by at most 30°, some of
//! them H- and T-shaped, heights drawn from a skewed storey distribution with a few towers.
//!
//! Input: [`CityParams`] (exact building count, seed).
//! Output: [`generate`] gives the buildings in a fixed fill order; [`write_geojson`] streams
//! them as a GeoJSON FeatureCollection (`id`, `height`, `levels`, `kind` properties).
//! Invariants:
//! - exactly `buildings` buildings; the same `(buildings, seed)` gives bit-identical geometry and
//!   byte-identical GeoJSON (one sequential SplitMix64 stream, no hash maps, no threads, and only
//!   `+ - * / sqrt`, which IEEE 754 rounds exactly, so no libm differences between platforms);
//! - every exterior ring is simple, counter-clockwise, open, with vertices on a millimetre grid
//!   (what the GeoJSON holds, so the file and the returned rings agree exactly);
//! - each building lies inside its own square lot shrunk by [`LOT_MARGIN`], lots do not overlap,
//!   so no two footprints meet (not even touch);
//! - width and length of each building (its bounding box in its own frame) lie in 9–12 m up to
//!   the millimetre rounding, its rotation in ±30°;
//! - coordinates sit near `(500000, 5000000)`, like a projected CRS, to exercise the
//!   large-coordinate path. The GeoJSON therefore carries projected metres, not WGS84.

use std::io::{self, Write};

use glam::DVec2;

/// What to generate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CityParams {
    /// Exact number of buildings.
    pub buildings: usize,
    /// PRNG seed.
    pub seed: u64,
}

/// The footprint shape of a generated building.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BuildingKind {
    /// A rectangle.
    Box,
    /// An H: two wings joined by a middle bar (12 vertices, non-convex).
    H,
    /// A T: a top bar and a centred stem (8 vertices, non-convex).
    T,
}

impl BuildingKind {
    /// The value of the GeoJSON `kind` property.
    pub fn as_str(self) -> &'static str {
        match self {
            BuildingKind::Box => "box",
            BuildingKind::H => "H",
            BuildingKind::T => "T",
        }
    }
}

/// One generated building.
#[derive(Clone, Debug, PartialEq)]
pub struct GenBuilding {
    /// Exterior ring, counter-clockwise, open (no repeated last point), world coordinates on a
    /// millimetre grid.
    pub rings: Vec<DVec2>,
    /// Height above the ground, metres (`levels * STOREY_HEIGHT`).
    pub height: f64,
    /// Number of storeys.
    pub levels: u32,
    pub kind: BuildingKind,
}

/// World position of the south-west corner of the city.
pub const ORIGIN: DVec2 = DVec2::new(500_000.0, 5_000_000.0);
/// Side of a square building lot, metres. A 12 × 12 m footprint rotated by 30° spans
/// `12 (cos 30° + sin 30°) ≈ 16.39 m`, which fits in `LOT - 2 LOT_MARGIN`.
pub const LOT: f64 = 18.0;
/// Minimum distance from a building to its lot boundary, metres (so buildings on neighbouring
/// lots are at least twice this apart).
pub const LOT_MARGIN: f64 = 0.5;
/// Storey height, metres.
pub const STOREY_HEIGHT: f64 = 3.0;
/// Smallest and largest building width/length, metres.
pub const MIN_SIDE: f64 = 9.0;
pub const MAX_SIDE: f64 = 12.0;

const STREET_MIN: f64 = 12.0;
const STREET_MAX: f64 = 25.0;
const AVENUE_MIN: f64 = 30.0;
const AVENUE_MAX: f64 = 40.0;
/// Every this many street gaps (counted from the first), the street is an avenue.
const AVENUE_EVERY: usize = 6;
/// Lots per block along x and y (inclusive ranges).
const BLOCK_LOTS_X: (u32, u32) = (2, 5);
const BLOCK_LOTS_Y: (u32, u32) = (2, 4);
/// Probability that a lot stays empty (a yard, a small square).
const P_VACANT: f64 = 0.04;
/// Probability that a block is a downtown block (taller buildings, more towers).
const P_DOWNTOWN: f64 = 0.08;
const P_H: f64 = 0.12;
const P_T: f64 = 0.12;
const P_TOWER: f64 = 0.008;
const P_TOWER_DOWNTOWN: f64 = 0.15;
/// Relative weights of 1..=12 storeys: skewed, mode at 3.
const LEVEL_WEIGHTS: [u32; 12] = [6, 14, 18, 17, 13, 10, 7, 5, 4, 3, 2, 1];
const TOWER_LEVELS: (u32, u32) = (15, 45);

/// SplitMix64 (Steele, Lea, Flood 2014): tiny, fast, and fully specified.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)` with 53 random bits.
    fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// Uniform integer in `lo..=hi` (multiply-shift; the bias is below 2^-32).
    fn range_u32(&mut self, lo: u32, hi: u32) -> u32 {
        let span = (hi - lo + 1) as u64;
        lo + (((self.next_u64() >> 32) * span) >> 32) as u32
    }

    fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }
}

fn street_width(rng: &mut SplitMix64, gap: usize) -> f64 {
    if gap % AVENUE_EVERY == AVENUE_EVERY / 2 {
        rng.range(AVENUE_MIN, AVENUE_MAX)
    } else {
        rng.range(STREET_MIN, STREET_MAX)
    }
}

fn draw_levels(rng: &mut SplitMix64, downtown: bool) -> u32 {
    let p_tower = if downtown { P_TOWER_DOWNTOWN } else { P_TOWER };
    if rng.chance(p_tower) {
        return rng.range_u32(TOWER_LEVELS.0, TOWER_LEVELS.1);
    }
    let total: u32 = LEVEL_WEIGHTS.iter().sum();
    let mut k = rng.range_u32(0, total - 1);
    let mut levels = 1;
    for (i, &w) in LEVEL_WEIGHTS.iter().enumerate() {
        if k < w {
            levels = i as u32 + 1;
            break;
        }
        k -= w;
    }
    if downtown {
        levels += rng.range_u32(2, 6);
    }
    levels
}

/// Rounds to the nearest millimetre (the grid the GeoJSON is written on).
#[inline]
fn mm(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

/// The local footprint, centred on the origin of its `w × l` bounding box, counter-clockwise.
fn local_shape(rng: &mut SplitMix64, kind: BuildingKind, w: f64, l: f64) -> Vec<DVec2> {
    let (hw, hl) = (0.5 * w, 0.5 * l);
    let p = DVec2::new;
    match kind {
        BuildingKind::Box => vec![p(-hw, -hl), p(hw, -hl), p(hw, hl), p(-hw, hl)],
        BuildingKind::H => {
            // Two wings of width `a` along y, joined by a bar of height `b` centred in y.
            let a = w * rng.range(0.28, 0.36);
            let hb = 0.5 * l * rng.range(0.28, 0.4);
            vec![
                p(-hw, -hl),
                p(-hw + a, -hl),
                p(-hw + a, -hb),
                p(hw - a, -hb),
                p(hw - a, -hl),
                p(hw, -hl),
                p(hw, hl),
                p(hw - a, hl),
                p(hw - a, hb),
                p(-hw + a, hb),
                p(-hw + a, hl),
                p(-hw, hl),
            ]
        }
        BuildingKind::T => {
            // A bar of height `b` along the top, a stem of width `2 hs` centred in x.
            let b = l * rng.range(0.3, 0.4);
            let hs = 0.5 * w * rng.range(0.3, 0.45);
            vec![
                p(-hs, -hl),
                p(hs, -hl),
                p(hs, hl - b),
                p(hw, hl - b),
                p(hw, hl),
                p(-hw, hl),
                p(-hw, hl - b),
                p(-hs, hl - b),
            ]
        }
    }
}

/// One building on the lot whose south-west corner is `lot_min`.
fn building(rng: &mut SplitMix64, lot_min: DVec2, downtown: bool) -> GenBuilding {
    let kind = {
        let u = rng.unit();
        if u < P_H {
            BuildingKind::H
        } else if u < P_H + P_T {
            BuildingKind::T
        } else {
            BuildingKind::Box
        }
    };
    let w = rng.range(MIN_SIDE, MAX_SIDE);
    let l = rng.range(MIN_SIDE, MAX_SIDE);
    // Rotation by its half-angle tangent t: cos = (1 - t²)/(1 + t²), sin = 2t/(1 + t²), exact
    // up to IEEE rounding on every platform. |t| ≤ tan 15° = 2 - √3 gives |angle| ≤ 30°.
    let tmax = 2.0 - 3f64.sqrt();
    let t = rng.range(-tmax, tmax);
    let (c, s) = ((1.0 - t * t) / (1.0 + t * t), 2.0 * t / (1.0 + t * t));
    let local = local_shape(rng, kind, w, l);
    // Half extents of the rotated bounding box, then the slack left in the lot.
    let hx = 0.5 * (w * c.abs() + l * s.abs());
    let hy = 0.5 * (w * s.abs() + l * c.abs());
    let (sx, sy) = (0.5 * LOT - LOT_MARGIN - hx, 0.5 * LOT - LOT_MARGIN - hy);
    debug_assert!(
        sx >= 0.0 && sy >= 0.0,
        "LOT too small for the largest rotated footprint"
    );
    let (sx, sy) = (sx.max(0.0), sy.max(0.0));
    let centre =
        lot_min + DVec2::splat(0.5 * LOT) + DVec2::new(rng.range(-sx, sx), rng.range(-sy, sy));
    let rings = local
        .iter()
        .map(|q| {
            let r = DVec2::new(c * q.x - s * q.y, s * q.x + c * q.y) + centre;
            DVec2::new(mm(r.x), mm(r.y))
        })
        .collect();
    let levels = draw_levels(rng, downtown);
    GenBuilding {
        rings,
        height: levels as f64 * STOREY_HEIGHT,
        levels,
        kind,
    }
}

/// Generates exactly `p.buildings` buildings.
///
/// Layout: a grid of blocks, `cols` block columns chosen so the city comes out near-square in
/// metres; every block column has its own lot count and every street gap its own width. Block
/// rows are made south to north until `N` buildings exist; within a row, blocks go west to east
/// and, in each block, lots go row by row. The last block row is usually only partly filled.
pub fn generate(p: &CityParams) -> Vec<GenBuilding> {
    let n = p.buildings;
    let mut out = Vec::with_capacity(n);
    if n == 0 {
        return out;
    }
    // A fixed salt, so that seed 0 does not start the stream at state 0.
    let mut rng = SplitMix64(p.seed ^ 0x7663_6f63_6369_7479);
    // Expected block size, for a near-square city: cols * bw ≈ rows * bh, cols * rows * k ≈ N.
    let mean_street = (STREET_MIN + STREET_MAX) / 2.0;
    let mean_lx = (BLOCK_LOTS_X.0 + BLOCK_LOTS_X.1) as f64 / 2.0;
    let mean_ly = (BLOCK_LOTS_Y.0 + BLOCK_LOTS_Y.1) as f64 / 2.0;
    let (bw, bh) = (mean_lx * LOT + mean_street, mean_ly * LOT + mean_street);
    let per_block = mean_lx * mean_ly * (1.0 - P_VACANT);
    let cols = ((n as f64 * bh / (bw * per_block)).sqrt().ceil() as usize).max(1);

    // Block columns: lot counts and west edges.
    let mut col_lots = Vec::with_capacity(cols);
    let mut col_x = Vec::with_capacity(cols);
    let mut x = 0.0;
    for i in 0..cols {
        if i > 0 {
            x += street_width(&mut rng, i - 1);
        }
        let k = rng.range_u32(BLOCK_LOTS_X.0, BLOCK_LOTS_X.1);
        col_lots.push(k);
        col_x.push(x);
        x += k as f64 * LOT;
    }

    let mut y = 0.0;
    let mut row = 0usize;
    'rows: loop {
        if row > 0 {
            y += street_width(&mut rng, row - 1);
        }
        let ly = rng.range_u32(BLOCK_LOTS_Y.0, BLOCK_LOTS_Y.1);
        for (&lx, &bx) in col_lots.iter().zip(&col_x) {
            let downtown = rng.chance(P_DOWNTOWN);
            for j in 0..ly {
                for i in 0..lx {
                    if rng.chance(P_VACANT) {
                        continue;
                    }
                    let lot_min = ORIGIN + DVec2::new(bx + i as f64 * LOT, y + j as f64 * LOT);
                    out.push(building(&mut rng, lot_min, downtown));
                    if out.len() == n {
                        break 'rows;
                    }
                }
            }
        }
        y += ly as f64 * LOT;
        row += 1;
    }
    out
}

/// Appends `v` in millimetres as a decimal with exactly three fraction digits.
fn push_mm(buf: &mut Vec<u8>, v: f64) {
    let m = (v * 1000.0).round() as i64;
    if m < 0 {
        buf.push(b'-');
    }
    let m = m.unsigned_abs();
    push_u64(buf, m / 1000);
    let f = m % 1000;
    let digit = |d: u64| b'0' + d as u8;
    buf.extend_from_slice(&[b'.', digit(f / 100), digit(f / 10 % 10), digit(f % 10)]);
}

fn push_u64(buf: &mut Vec<u8>, mut v: u64) {
    let mut tmp = [0u8; 20];
    let mut i = tmp.len();
    loop {
        i -= 1;
        tmp[i] = b'0' + (v % 10) as u8;
        v /= 10;
        if v == 0 {
            break;
        }
    }
    buf.extend_from_slice(&tmp[i..]);
}

/// Writes the buildings as a GeoJSON FeatureCollection, one Feature per line: properties
/// `id` (`"b<index>"`), `height` (m), `levels`, `kind` (`"box"`, `"H"`, `"T"`); a `Polygon`
/// whose single ring is closed and counter-clockwise. Numbers have three decimals (mm).
///
/// The text is formatted by hand into a 64 KiB buffer and handed to `w` in large chunks, so
/// `w` need not be buffered.
pub fn write_geojson<W: Write>(mut w: W, buildings: &[GenBuilding]) -> io::Result<()> {
    const CHUNK: usize = 1 << 16;
    let mut buf: Vec<u8> = Vec::with_capacity(CHUNK + 4096);
    buf.extend_from_slice(b"{\"type\":\"FeatureCollection\",\"features\":[\n");
    for (i, b) in buildings.iter().enumerate() {
        if i > 0 {
            buf.extend_from_slice(b",\n");
        }
        buf.extend_from_slice(b"{\"type\":\"Feature\",\"properties\":{\"id\":\"b");
        push_u64(&mut buf, i as u64);
        buf.extend_from_slice(b"\",\"height\":");
        push_mm(&mut buf, b.height);
        buf.extend_from_slice(b",\"levels\":");
        push_u64(&mut buf, b.levels as u64);
        buf.extend_from_slice(b",\"kind\":\"");
        buf.extend_from_slice(b.kind.as_str().as_bytes());
        buf.extend_from_slice(b"\"},\"geometry\":{\"type\":\"Polygon\",\"coordinates\":[[");
        let ring = b.rings.iter().chain(b.rings.first());
        for (k, q) in ring.enumerate() {
            if k > 0 {
                buf.push(b',');
            }
            buf.push(b'[');
            push_mm(&mut buf, q.x);
            buf.push(b',');
            push_mm(&mut buf, q.y);
            buf.push(b']');
        }
        buf.extend_from_slice(b"]]}}");
        if buf.len() >= CHUNK {
            w.write_all(&buf)?;
            buf.clear();
        }
    }
    buf.extend_from_slice(b"\n]}\n");
    w.write_all(&buf)?;
    w.flush()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::predicates::{
        orient, point_in_ring, ring_orientation, segment_intersection, Containment, Orientation,
        SegmentIntersection,
    };

    fn city(n: usize, seed: u64) -> Vec<GenBuilding> {
        generate(&CityParams { buildings: n, seed })
    }

    fn geojson(b: &[GenBuilding]) -> Vec<u8> {
        let mut out = Vec::new();
        write_geojson(&mut out, b).unwrap();
        out
    }

    fn edges(r: &[DVec2]) -> impl Iterator<Item = (DVec2, DVec2)> + '_ {
        (0..r.len()).map(move |i| (r[i], r[(i + 1) % r.len()]))
    }

    fn bbox(r: &[DVec2]) -> (DVec2, DVec2) {
        r.iter()
            .fold((r[0], r[0]), |(lo, hi), &p| (lo.min(p), hi.max(p)))
    }

    #[test]
    fn deterministic_bytes() {
        let a = geojson(&city(3000, 42));
        let b = geojson(&city(3000, 42));
        assert_eq!(a, b);
        let c = geojson(&city(3000, 43));
        assert_ne!(a, c);
    }

    #[test]
    fn exact_count() {
        for n in [0, 1, 2, 7, 1000, 1234] {
            assert_eq!(city(n, 7).len(), n, "n = {n}");
        }
        // A prefix property is not promised, but the first building of a city depends only on
        // the seed and the column layout; check a few seeds all give exact counts.
        for seed in 0..20 {
            assert_eq!(city(57, seed).len(), 57);
        }
    }

    #[test]
    fn box_sizes_and_rotation() {
        let tol = 0.005; // mm rounding of both end points, and then some
        let max_angle = 30f64.to_radians() + 1e-3;
        let mut boxes = 0;
        for b in city(5000, 11).iter() {
            let r = &b.rings;
            match b.kind {
                BuildingKind::Box => {
                    boxes += 1;
                    assert_eq!(r.len(), 4);
                    let (u, v) = (r[1] - r[0], r[2] - r[1]);
                    let (w, l) = (u.length(), v.length());
                    assert!((MIN_SIDE - tol..=MAX_SIDE + tol).contains(&w), "width {w}");
                    assert!((MIN_SIDE - tol..=MAX_SIDE + tol).contains(&l), "length {l}");
                    // Opposite sides equal, corners right angles (up to the mm grid).
                    assert!((u + (r[3] - r[2])).length() < 2.0 * tol);
                    assert!(u.dot(v).abs() / (w * l) < 1e-3);
                    let angle = u.y.atan2(u.x);
                    assert!(angle.abs() <= max_angle, "angle {}", angle.to_degrees());
                }
                BuildingKind::H | BuildingKind::T => {
                    // Own frame: first edge is along local +x; extents along it and across it.
                    let d = (r[1] - r[0]).normalize();
                    let n = d.perp();
                    let ext = |a: DVec2| {
                        let ps: Vec<f64> = r.iter().map(|&p| (p - r[0]).dot(a)).collect();
                        ps.iter().cloned().fold(f64::MIN, f64::max)
                            - ps.iter().cloned().fold(f64::MAX, f64::min)
                    };
                    assert!(d.y.atan2(d.x).abs() <= max_angle);
                    for e in [ext(d), ext(n)] {
                        assert!((MIN_SIDE - tol..=MAX_SIDE + tol).contains(&e), "extent {e}");
                    }
                }
            }
            assert_eq!(b.height, b.levels as f64 * STOREY_HEIGHT);
            assert!(b.levels >= 1);
        }
        assert!(boxes > 3000);
    }

    /// Simple: non-adjacent edges are disjoint, adjacent edges meet only at their shared vertex
    /// (no collinear fold-back), and the ring is counter-clockwise.
    fn assert_simple_ccw(r: &[DVec2]) {
        let n = r.len();
        for i in 0..n {
            let (a, b, c) = (r[i], r[(i + 1) % n], r[(i + 2) % n]);
            assert_ne!(
                orient(a, b, c),
                Orientation::Collinear,
                "collinear corner in {r:?}"
            );
            for j in i + 2..n {
                if i == 0 && j == n - 1 {
                    continue;
                }
                let (c, d) = (r[j], r[(j + 1) % n]);
                assert_eq!(
                    segment_intersection(a, b, c, d),
                    SegmentIntersection::Disjoint,
                    "edges {i} and {j} meet in {r:?}"
                );
            }
        }
        assert_eq!(ring_orientation(r), Orientation::Ccw);
    }

    #[test]
    fn rings_simple_ccw_and_shapes_nonconvex() {
        let mut seen = [0usize; 3];
        for b in city(4000, 5).iter() {
            assert_simple_ccw(&b.rings);
            let r = &b.rings;
            let n = r.len();
            let reflex = (0..n)
                .filter(|&i| orient(r[i], r[(i + 1) % n], r[(i + 2) % n]) == Orientation::Cw)
                .count();
            match b.kind {
                BuildingKind::Box => {
                    seen[0] += 1;
                    assert_eq!(reflex, 0);
                }
                BuildingKind::H => {
                    seen[1] += 1;
                    assert_eq!((n, reflex), (12, 4));
                }
                BuildingKind::T => {
                    seen[2] += 1;
                    assert_eq!((n, reflex), (8, 2));
                }
            }
        }
        assert!(seen.iter().all(|&k| k > 100), "{seen:?}");
    }

    #[test]
    fn no_overlaps() {
        let bs = city(2000, 99);
        // Grid buckets by bounding box; a pair is tested when it shares a bucket.
        let cell = 25.0;
        let key = |p: DVec2| ((p.x / cell).floor() as i64, (p.y / cell).floor() as i64);
        let mut buckets: std::collections::BTreeMap<(i64, i64), Vec<usize>> = Default::default();
        for (i, b) in bs.iter().enumerate() {
            let (lo, hi) = bbox(&b.rings);
            let (k0, k1) = (key(lo), key(hi));
            for x in k0.0..=k1.0 {
                for y in k0.1..=k1.1 {
                    buckets.entry((x, y)).or_default().push(i);
                }
            }
        }
        let mut pairs = std::collections::BTreeSet::new();
        for ids in buckets.values() {
            for (k, &i) in ids.iter().enumerate() {
                for &j in &ids[k + 1..] {
                    pairs.insert((i.min(j), i.max(j)));
                }
            }
        }
        assert!(
            pairs.len() > 2000,
            "too few neighbour pairs: {}",
            pairs.len()
        );
        for &(i, j) in &pairs {
            let (p, q) = (&bs[i].rings, &bs[j].rings);
            for (a, b) in edges(p) {
                for (c, d) in edges(q) {
                    assert_eq!(
                        segment_intersection(a, b, c, d),
                        SegmentIntersection::Disjoint,
                        "buildings {i} and {j} meet"
                    );
                }
            }
            // No crossing edges: either disjoint or one inside the other; rule out the latter.
            assert_eq!(point_in_ring(q, p[0]), Containment::Outside, "{i} in {j}");
            assert_eq!(point_in_ring(p, q[0]), Containment::Outside, "{j} in {i}");
        }
    }

    #[test]
    fn large_coordinates_and_height_distribution() {
        let bs = city(20_000, 3);
        let (lo, _) = bs.iter().fold((bs[0].rings[0], bs[0].rings[0]), |acc, b| {
            let (l, h) = bbox(&b.rings);
            (acc.0.min(l), acc.1.max(h))
        });
        assert!(lo.x >= ORIGIN.x && lo.y >= ORIGIN.y);
        let hi = bs
            .iter()
            .flat_map(|b| b.rings.iter())
            .fold(lo, |a, &p| a.max(p));
        let (w, h) = (hi.x - lo.x, hi.y - lo.y);
        assert!(w / h > 0.7 && w / h < 1.4, "not near-square: {w} x {h}");
        let towers = bs.iter().filter(|b| b.levels >= TOWER_LEVELS.0).count();
        let low = bs.iter().filter(|b| b.levels <= 5).count();
        assert!(towers > 20 && towers < 2000, "towers {towers}");
        assert!(low > bs.len() / 2, "low {low}");
    }

    #[test]
    fn geojson_parses() {
        let bs = city(1000, 8);
        let text = geojson(&bs);
        let v: serde_json::Value = serde_json::from_slice(&text).unwrap();
        assert_eq!(v["type"], "FeatureCollection");
        let fs = v["features"].as_array().unwrap();
        assert_eq!(fs.len(), bs.len());
        for (i, (f, b)) in fs.iter().zip(&bs).enumerate() {
            assert_eq!(f["type"], "Feature");
            let pr = &f["properties"];
            assert_eq!(pr["id"], format!("b{i}"));
            assert_eq!(pr["height"].as_f64().unwrap(), b.height);
            assert_eq!(pr["levels"].as_u64().unwrap(), b.levels as u64);
            assert_eq!(pr["kind"], b.kind.as_str());
            assert_eq!(f["geometry"]["type"], "Polygon");
            let rings = f["geometry"]["coordinates"].as_array().unwrap();
            assert_eq!(rings.len(), 1);
            let ring: Vec<DVec2> = rings[0]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| DVec2::new(p[0].as_f64().unwrap(), p[1].as_f64().unwrap()))
                .collect();
            assert_eq!(ring.len(), b.rings.len() + 1);
            assert_eq!(ring.first(), ring.last());
            // The file holds exactly the generated (mm-grid) coordinates.
            assert_eq!(&ring[..b.rings.len()], &b.rings[..]);
            assert_eq!(ring_orientation(&ring[..b.rings.len()]), Orientation::Ccw);
        }
    }

    #[test]
    fn mm_formatting() {
        let mut s = Vec::new();
        for v in [
            0.0,
            1.0004,
            0.999,
            -2.5,
            0.07,
            500_123.456_7,
            5_000_000.001,
            12.0,
        ] {
            push_mm(&mut s, v);
            s.push(b' ');
        }
        assert_eq!(
            String::from_utf8(s).unwrap(),
            "0.000 1.000 0.999 -2.500 0.070 500123.457 5000000.001 12.000 "
        );
    }
}
