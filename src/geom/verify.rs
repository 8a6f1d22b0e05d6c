//! The exact hidden-interval verifier (DESIGN.md section 6.1): the final gate for every virtual
//! occluder.
//!
//! Input: a convex cell `C` (counter-clockwise), convex blockers (counter-clockwise polygons, or
//! segments: 2-vertex blockers, walls seen from above), and a segment `s = [a, b]` with f64
//! endpoints. Output: the sub-intervals of `s` hidden from every
//! point of `C`: every closed 2D segment from a point of `C` to a point of such an interval meets
//! some blocker (touching counts).
//!
//! Invariant: an interval is reported only with a proof that is exact for the f64 inputs. It
//! shares no code with the occluder growth except [`super::predicates`].
//!
//! ## The certificate
//! For a point `q`, a *certificate* is a chain of blockers `B_1..B_m`, each with a chord
//! `[l_k, r_k]` between two of its points (vertices, or a vertex of a neighbour lying in it) and
//! a separating line `L_k` between `B_k` and `C`
//! through two input vertices. It holds at `q` when (every test an exact orientation of `q`
//! against two input vertices):
//! - (S) `q` lies strictly on `B_k`'s side of `L_k`, for every k;
//! - (A) `orient(q, l_k, r_k) = Ccw`: `q` sees the chord under a counter-clockwise angle below a
//!   half-turn (the arc `[l_k, r_k]`), for every k;
//! - (O) `orient(q, l_{k+1}, r_k) != Cw` and `orient(q, r_k, r_{k+1}) != Cw`: the direction of
//!   `r_k` lies in the next arc (exact, as that arc is below a half-turn);
//! - (C) every cell vertex `c` has `orient(q, l_1, c) != Cw` and `orient(q, c, r_m) != Cw`.
//!
//! **Lemma 1.** If a certificate holds at `q`, then `q` is hidden. *Proof.* By (O) and induction
//! the arcs cover the counter-clockwise sweep from `l_1` to `r_m`: if they cover the sweep to
//! `r_k`, and `r_k` lies in `[l_{k+1}, r_{k+1}]`, adding that arc extends it to `r_{k+1}`. Let the
//! sweep turn through `σ`. Each cell vertex lies within a half-turn counter-clockwise of `l_1` and
//! within a half-turn clockwise of `r_m` (C); if `σ >= π` the first puts it in the sweep, and if
//! `σ < π` the two together do. `q` is outside `C` (by (S), `C` is on the other closed side of
//! `L_1`), so `C` is seen within the angular hull of its vertices, hence inside the sweep: the
//! direction to any `c` in `C` lies in some arc `k`. By (A) the ray from `q` towards `c` crosses
//! the chord `[l_k, r_k]`, which lies in `B_k`, at a point `x`. By (S) `q` is strictly on
//! `B_k`'s side of `L_k` and `c` on the other closed side, so the ray crosses `L_k` once, at or
//! before `c`, and `x` (on `B_k`'s closed side) comes no later. So `[q, c]` contains `x`. ∎
//!
//! **Segments.** A 2-vertex blocker (a wall) is the closed segment between its vertices: convex,
//! closed, with an empty interior. Lemma 1 uses of `B_k` only that it is convex and closed, that
//! its chord lies in it, and that it lies on one closed side of `L_k`; all hold for a segment,
//! whose only chord is itself (its two ends, in the order `q` sees them) and whose separating
//! lines may be its own line (the segment lies on it, which is on its closed side). Seen edge-on
//! from `q` its two ends are collinear with `q`, (A) fails, and it is simply not a link there.
//! The predicates answer exactly for segments ([`super::predicates`], module header); in
//! particular a point of the segment's line beyond its ends is outside it, so the search's
//! "both ends in one blocker" shortcut below holds for segments too (the piece then lies on
//! the wall, and a segment from `C` to any point of it meets the wall there).
//!
//! **Lemma 2.** Each condition is `f(q) > 0` or `f(q) >= 0` for an affine `f` (the orientation
//! determinant is affine in `q`), so a certificate that holds at both ends of a segment holds at
//! every point of it. ∎
//!
//! ## The search: a sweep along the segment
//! Parameters along `s` are dyadic, `t = j / 2^30`, and a point is used only when `a + t (b - a)`
//! is exactly representable (checked), so it lies exactly on `s` and consecutive pieces tile `s`
//! with no gap. From the current point `q` (first `a`) a certificate is read off at `q` and a
//! probe point a little ahead (the tangent vertices of each blocker near them, then a
//! chain of overlapping chords that covers the cell's angle, greedily (from the arc that covers the
//! cell's first tangent, each time the arc reaching farthest), joining
//! blockers that share a vertex through it), checked exactly at both. Every condition is affine
//! along `s`, so where the certificate stops holding is estimated in floating point from its
//! values at `q` and `b`; the estimate is rounded down to a dyadic point and the certificate is
//! checked exactly there (binary search back towards the probe when rounding made it fail). By
//! Lemma 2 the piece between is hidden; the sweep goes on from its end. A piece whose two ends lie
//! in one blocker lies in it (blockers are convex), and is hidden. Where no certificate is found,
//! the sweep steps on, doubling its step from [`MIN_PIECE_M`], and the skipped part counts as
//! visible: the output can only be smaller than the true hidden set, never larger.
//! **Leaving a blocker.** Where the segment leaves a blocker `X` into the open, the certificate
//! beyond needs `X` as a link, whose (A) fails inside `X`; so a piece `[q, p]` with `q` in `X`
//! is accepted when a certificate holds at its anchor `m` and at `p`, `[q, m]` meets the chord
//! `[l, r]` of `X`'s link, and every condition but that chord's (A) holds at `q`. *Proof.*
//! `orient(x, l, r)` is affine along `[q, m]`, not positive at `q` and positive at `m`, so the
//! segment meets the line of the chord once, at `x*`, which lies in `[l, r]` (they meet) and so
//! in `X`: `[q, x*]` lies in `X`. On `(x*, m]` the chord's (A) holds strictly and every other
//! condition holds at both ends, so the certificate holds there (Lemma 2); and on `[m, p]`.
//! Likewise, a piece from a point of one blocker to a point of another is in their union when it
//! meets a segment between two vertices that both contain (a shared edge of two pieces).
//! The blockers a certificate uses (its links', or the one or two blockers a piece lies in) are
//! reported with the piece ([`Verifier::hidden_by`], [`Verifier::hidden_parts_by`]): every
//! segment from the cell to a point of the piece meets one of them, which is what rule 2 needs
//! of a VO's supporters.
//! Certificates found are kept per verifier (bucketed by position) and tried first at later
//! points nearby; a cached certificate is checked exactly like a new one, so the cache saves
//! searching and decides nothing.
//! Only blockers meeting the convex hull of the cell and the current piece are searched (a
//! spatial grid, then a floating-point filter that drops only blockers clear of the hull; leaving
//! a blocker out can only certify less).

use glam::DVec2;

use super::pseudo_angle;

use super::predicates::{
    common_tangents, orient, point_in_convex, segment_intersection, set_side, tangent_vertices,
    Containment, Orientation, SegmentIntersection, SetSide,
};

/// Least step of the sweep past a point it cannot certify, metres.
pub const MIN_PIECE_M: f64 = 0.01;
/// Longest step of the sweep past points it cannot certify, metres: a hidden part shorter than
/// this between visible ones may be missed (never claimed).
pub const MAX_STEP_M: f64 = 0.5;
/// Parameters along a verified segment are multiples of `2^-PARAM_BITS`.
pub const PARAM_BITS: u32 = 30;
/// The sweep's first probe ahead of its current point, metres (halved down to [`MIN_PIECE_M`]
/// when no certificate holds that far).
pub const PROBE_M: f64 = 0.01;

const END: u64 = 1 << PARAM_BITS;

/// A hidden sub-interval of the verified segment: parameters along `a -> b` and the exact
/// endpoints (each lies exactly on the segment).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hidden {
    pub t0: f64,
    pub t1: f64,
    pub p0: DVec2,
    pub p1: DVec2,
}

/// A line through two input points, and the strict side on which its blocker lies.
#[derive(Clone, Copy, Debug)]
struct SepLine {
    a: DVec2,
    b: DVec2,
    side: Orientation,
}

impl SepLine {
    fn holds(&self, q: DVec2) -> bool {
        orient(self.a, self.b, q) == self.side
    }
}

/// One link of a certificate: a chord `[l, r]` of blocker `poly` (an index into the blockers
/// near the segment) and its separating line.
#[derive(Clone, Copy, Debug)]
struct Link {
    l: DVec2,
    r: DVec2,
    sep: SepLine,
    poly: usize,
}

/// One condition of a certificate at `q`: `orient(q, u, v)` is `Ccw` (strict) or not `Cw`.
#[derive(Clone, Copy, Debug)]
struct Cond {
    u: DVec2,
    v: DVec2,
    strict: bool,
}

impl Cond {
    fn holds(&self, q: DVec2) -> bool {
        match orient(q, self.u, self.v) {
            Orientation::Ccw => true,
            Orientation::Collinear => !self.strict,
            Orientation::Cw => false,
        }
    }

    /// `orient(q, u, v)` in floating point, an affine function of `q`.
    fn value(&self, q: DVec2) -> f64 {
        (self.u - q).perp_dot(self.v - q)
    }
}

/// The conditions (S), (A), (O) and (C) of a chain (module header).
fn conditions(links: &[Link], cell: &[DVec2]) -> Vec<Cond> {
    let mut c = Vec::with_capacity(3 * links.len() + 2 * cell.len());
    for k in links {
        let (u, v) = match k.sep.side {
            Orientation::Ccw => (k.sep.a, k.sep.b),
            _ => (k.sep.b, k.sep.a),
        };
        c.push(Cond { u, v, strict: true });
        c.push(Cond {
            u: k.l,
            v: k.r,
            strict: true,
        });
    }
    for p in links.windows(2) {
        c.push(Cond {
            u: p[1].l,
            v: p[0].r,
            strict: false,
        });
        c.push(Cond {
            u: p[0].r,
            v: p[1].r,
            strict: false,
        });
    }
    if let (Some(first), Some(last)) = (links.first(), links.last()) {
        for &v in cell {
            c.push(Cond {
                u: first.l,
                v,
                strict: false,
            });
            c.push(Cond {
                u: v,
                v: last.r,
                strict: false,
            });
        }
    }
    c
}

/// The blockers near one stretch of the swept segment, `span` in parameters.
struct NearCache<'a> {
    span: (u64, u64),
    /// How far past a requested piece a new stretch reaches, in parameter steps.
    ahead: u64,
    ids: Vec<u32>,
    /// The blockers of `ids`, in the same order, and their boxes.
    polys: Vec<&'a [DVec2]>,
    boxes: Vec<(DVec2, DVec2)>,
    /// The positions in `ids` of the blockers whose boxes meet the box of the stretch (grown
    /// by [`ALONG_PAD_M`]), ascending: only these can hold a point of the stretch.
    along: Vec<u32>,
    /// Scratch: `ids` keyed by distance, while they are put in order.
    keyed: Vec<(f64, u32)>,
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
struct Grid {
    lo: DVec2,
    size: f64,
    nx: usize,
    ny: usize,
    start: Vec<u32>,
    ids: Vec<u32>,
}

impl Grid {
    const SIZE_M: f64 = 32.0;

    fn new(boxes: &[(DVec2, DVec2)]) -> Grid {
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

    fn range(&self, lo: DVec2, hi: DVec2) -> (usize, usize, usize, usize) {
        let ix = |v: f64, n: usize| ((super::floor(v / self.size).max(0.0)) as usize).min(n - 1);
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
    fn query(
        &self,
        lo: DVec2,
        hi: DVec2,
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
            for x in x0..=x1 {
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

/// Blockers indexed for the verifier: their boxes and a bucket grid over them. One index can
/// serve many verifiers over subsets of its blockers ([`Verifier::subset`]).
pub struct BlockerIndex<'a> {
    polys: Vec<&'a [DVec2]>,
    boxes: Vec<(DVec2, DVec2)>,
    grid: Grid,
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

/// A verifier's blockers: an index of its own, or a subset of a shared one.
enum Blockers<'a> {
    Own(BlockerIndex<'a>),
    Subset(&'a BlockerIndex<'a>, Vec<bool>),
}

/// The verifier for one cell and one set of blockers.
pub struct Verifier<'a> {
    cell: &'a [DVec2],
    set: Blockers<'a>,
    /// Certificates found so far, tried first where they were found (module header).
    cache: std::cell::RefCell<CertCache>,
    /// Longest step past points the sweep cannot certify, metres ([`MAX_STEP_M`]).
    max_step_m: f64,
    /// Least step past a point it cannot certify, and the precision to which the end of a
    /// hidden part is sought, metres ([`MIN_PIECE_M`]).
    min_step_m: f64,
    /// Scratch of [`Self::near`]: a stamp per blocker of the index, and the last stamp used.
    seen: std::cell::RefCell<(Vec<u32>, u32)>,
    /// Scratch of [`Self::extend`]: the conditions of the certificate at hand.
    conds: std::cell::RefCell<Vec<Cond>>,
    /// Scratch buffers of [`Self::chain`], kept between its calls (hundreds of thousands per
    /// cell) so that they are not allocated each time; each call clears what it uses.
    scratch: std::cell::RefCell<ChainScratch>,
}

/// A cheap hasher for the certificate cache's bucket keys (pairs of small integers from the
/// verifier's own coordinates; no untrusted keys reach it, so no need for a keyed hash).
#[derive(Default)]
struct KeyHasher(u64);

impl std::hash::Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_i64(&mut self, x: i64) {
        self.write_u64(x as u64);
    }
}

type BuildKeyHasher = std::hash::BuildHasherDefault<KeyHasher>;

/// A cached certificate: where its conditions lie in [`CertCache::conds`], and the blockers its
/// chords lie in (shared, not copied, when it is used again).
type Cert = (u32, u32, std::rc::Rc<[u32]>);
/// The near blockers of a piece: their ids, outlines and boxes, in the same order.
type Near<'c, 'a> = (
    &'c [u32],
    &'c [&'a [DVec2]],
    &'c [(DVec2, DVec2)],
    &'c [u32],
);

/// Certificates (their conditions) by where they held: each is listed in the buckets of the
/// bounding box of the piece it certified, grown by [`CACHE_REACH_M`].
#[derive(Default)]
struct CertCache {
    /// Each certificate's conditions (a range of `conds`) and the blockers (verifier indices)
    /// its chords lie in.
    certs: Vec<Cert>,
    /// The conditions of all the certificates, one after another: one buffer, not an
    /// allocation per certificate.
    conds: Vec<Cond>,
    /// Per bucket, its newest entry in `listed`.
    buckets: std::collections::HashMap<(i64, i64), u32, BuildKeyHasher>,
    /// The buckets' lists, all in one: a certificate, and the entry listed before it in the
    /// same bucket ([`NO_ENTRY`]: none). One buffer, not a vector per bucket.
    listed: Vec<(u32, u32)>,
}

/// The end of a bucket's list in [`CertCache::listed`].
const NO_ENTRY: u32 = u32::MAX;

/// A new certificate is first sought among this many blockers nearest the point.
pub const NEAREST_FIRST: usize = 12;
/// Cached certificates tried per point, newest first.
pub const CACHE_TRIES: usize = 16;
/// A cached certificate reaching less far than this is not enough: a new one is sought too,
/// metres.
pub const CACHE_ENOUGH_M: f64 = 2.0;

/// How far along `[q, b]` (as a share of it) every condition of a certificate stays true,
/// estimated in floating point from their affine values at both ends.
fn reach(conds: &[Cond], q: DVec2, b: DVec2) -> f64 {
    let mut t = 1.0f64;
    for c in conds {
        let (f0, f1) = (c.value(q), c.value(b));
        // A strict condition fails where f reaches 0, a non-strict one where it goes below
        // (one that is 0 all along, as a join through a shared vertex, never fails).
        let fails = if c.strict { f1 <= 0.0 } else { f1 < 0.0 };
        if fails {
            t = if f0 > 0.0 { t.min(f0 / (f0 - f1)) } else { 0.0 };
        }
    }
    t
}

/// Side of a bucket of the certificate cache, metres.
pub const CACHE_BUCKET_M: f64 = 8.0;
/// A cached certificate is tried within this distance of the piece it certified, metres.
pub const CACHE_REACH_M: f64 = 4.0;

impl CertCache {
    fn key(p: DVec2) -> (i64, i64) {
        (
            super::floor(p.x / CACHE_BUCKET_M) as i64,
            super::floor(p.y / CACHE_BUCKET_M) as i64,
        )
    }

    /// Caches the certificate of conditions `conds` and blockers `used`, which held from `p0`
    /// to `p1`.
    fn add(&mut self, conds: &[Cond], used: std::rc::Rc<[u32]>, p0: DVec2, p1: DVec2) {
        let id = self.certs.len() as u32;
        let start = self.conds.len() as u32;
        self.conds.extend_from_slice(conds);
        self.certs.push((start, self.conds.len() as u32, used));
        let r = DVec2::splat(CACHE_REACH_M);
        let (lo, hi) = (Self::key(p0.min(p1) - r), Self::key(p0.max(p1) + r));
        // Long pieces are listed along their length only (at most 64 buckets).
        let n = ((hi.0 - lo.0 + 1) * (hi.1 - lo.1 + 1)) as usize;
        if n <= 64 {
            for x in lo.0..=hi.0 {
                for y in lo.1..=hi.1 {
                    self.list((x, y), id);
                }
            }
        } else {
            let steps = (p0.distance(p1) / CACHE_BUCKET_M).ceil().max(1.0) as usize;
            for k in 0..=steps.min(64) {
                let q = p0 + (p1 - p0) * (k as f64 / steps.min(64) as f64);
                self.list(Self::key(q), id);
            }
        }
    }

    /// Lists certificate `id` in bucket `key`, newest, unless it is the newest there already.
    fn list(&mut self, key: (i64, i64), id: u32) {
        let at = self.listed.len() as u32;
        let head = self.buckets.entry(key).or_insert(NO_ENTRY);
        if *head != NO_ENTRY && self.listed[*head as usize].0 == id {
            return;
        }
        self.listed.push((id, *head));
        *head = at;
    }

    /// The conditions of certificate `id`.
    fn conds_of(&self, id: u32) -> &[Cond] {
        let (s, e, _) = self.certs[id as usize];
        &self.conds[s as usize..e as usize]
    }

    /// Of the newest [`CACHE_TRIES`] certificates listed where `q` is, one that holds at `q`
    /// and `p` and reaches furthest towards `b` ([`reach`]), with that reach, if any.
    fn find(&self, q: DVec2, p: DVec2, b: DVec2) -> Option<(u32, f64)> {
        let mut at = *self.buckets.get(&Self::key(q))?;
        std::iter::from_fn(|| {
            let &(id, prev) = self.listed.get(at as usize)?;
            at = prev;
            Some(id)
        })
        .take(CACHE_TRIES)
        .filter(|&i| {
            let c = self.conds_of(i);
            [q, p].iter().all(|&x| c.iter().all(|k| k.holds(x)))
        })
        .map(|i| (i, reach(self.conds_of(i), q, b)))
        .max_by(|x, y| x.1.total_cmp(&y.1))
    }
}

/// Parameters `j / 2^PARAM_BITS` along one segment, turned into exact points of it.
struct Param {
    a: DVec2,
    b: DVec2,
    d: DVec2,
}

impl Param {
    /// The point at parameter `j`, when `a + (j / 2^PARAM_BITS) (b - a)` is exact.
    fn at(&self, j: u64) -> Option<DVec2> {
        if j == 0 {
            return Some(self.a);
        }
        if j >= END {
            return Some(self.b);
        }
        let t = j as f64 / END as f64;
        let exact = |a: f64, d: f64| -> Option<f64> {
            let u = d * t;
            // The product is exact when its fused error is zero, the sum by TwoSum.
            if d.mul_add(t, -u) != 0.0 {
                return None;
            }
            let s = a + u;
            let bb = s - a;
            let err = (a - (s - bb)) + (u - bb);
            (err == 0.0 && s.is_finite()).then_some(s)
        };
        Some(DVec2::new(
            exact(self.a.x, self.d.x)?,
            exact(self.a.y, self.d.y)?,
        ))
    }

    /// The exact point at `j` or, failing that, at the nearest coarser parameter in `(lo, j]`
    /// (fewer low bits); `None` when there is none.
    fn at_or_below(&self, j: u64, lo: u64) -> Option<(u64, DVec2)> {
        let mut k = j;
        let mut bit = 0;
        while k > lo {
            if let Some(p) = self.at(k) {
                return Some((k, p));
            }
            bit += 1;
            if bit > PARAM_BITS {
                return None;
            }
            k = (j >> bit) << bit;
        }
        None
    }
}

impl<'a> Verifier<'a> {
    /// `cell`: convex, counter-clockwise, non-degenerate. Every blocker: the same, or a segment
    /// (exactly 2 distinct vertices). Blockers are named by their position in `blockers`.
    pub fn new(cell: &'a [DVec2], blockers: impl IntoIterator<Item = &'a [DVec2]>) -> Self {
        Self::with_set(cell, Blockers::Own(BlockerIndex::new(blockers)))
    }

    /// A verifier over the blockers `members` of `index` (named by their position in it).
    pub fn subset(cell: &'a [DVec2], index: &'a BlockerIndex<'a>, members: &[u32]) -> Self {
        let mut m = vec![false; index.len()];
        for &i in members {
            if let Some(x) = m.get_mut(i as usize) {
                *x = true;
            }
        }
        Self::with_set(cell, Blockers::Subset(index, m))
    }

    fn with_set(cell: &'a [DVec2], set: Blockers<'a>) -> Self {
        Verifier {
            cell,
            set,
            cache: Default::default(),
            max_step_m: MAX_STEP_M,
            min_step_m: MIN_PIECE_M,
            seen: Default::default(),
            conds: Default::default(),
            scratch: Default::default(),
        }
    }

    fn index(&self) -> &BlockerIndex<'a> {
        match &self.set {
            Blockers::Own(i) => i,
            Blockers::Subset(i, _) => i,
        }
    }

    fn member(&self, i: u32) -> bool {
        match &self.set {
            Blockers::Own(_) => true,
            Blockers::Subset(_, m) => m[i as usize],
        }
    }

    fn poly(&self, i: u32) -> &'a [DVec2] {
        self.index().polys[i as usize]
    }

    fn bounds(&self, i: u32) -> (DVec2, DVec2) {
        self.index().boxes[i as usize]
    }

    /// This verifier, stepping at most `m` metres past points it cannot certify (it may then
    /// miss hidden parts shorter than `m` between visible ones: it certifies less, never more).
    pub fn with_max_step(mut self, m: f64) -> Self {
        self.max_step_m = m.max(self.min_step_m);
        self
    }

    /// This verifier, stepping at least `m` metres past a point it cannot certify and seeking
    /// where a hidden part begins to within `m` (default [`MIN_PIECE_M`]): it may then report a
    /// hidden part up to `m` shorter at its start than a finer search would, which certifies
    /// less, never more, for far fewer searches at the edges of visible gaps.
    pub fn with_min_step(mut self, m: f64) -> Self {
        self.min_step_m = m.max(MIN_PIECE_M);
        self.max_step_m = self.max_step_m.max(self.min_step_m);
        self
    }

    /// The blockers that may block a segment from the cell to `[a, b]`: those meeting the
    /// convex hull of the cell and the segment (a float filter that drops only blockers clear of
    /// it by a margin; every segment from the cell to `[a, b]` lies in the hull, and leaving a
    /// blocker out can only certify less).
    fn near(&self, a: DVec2, b: DVec2, out: &mut Vec<u32>) {
        let hull = convex_hull(self.cell.iter().copied().chain([a, b]));
        let (lo, hi) = bbox(&hull);
        // Each hull edge as an outward half-plane `n . x > c + m`: a box wholly beyond one,
        // by the margin, holds no point of the hull (rounding of this float test only keeps
        // a blocker more, or drops one that at most touches the hull).
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
        let clear = |bl: DVec2, bh: DVec2| {
            planes.iter().any(|&(n, c)| {
                let x = if n.x >= 0.0 { bl.x } else { bh.x };
                let y = if n.y >= 0.0 { bl.y } else { bh.y };
                n.x * x + n.y * y > c
            })
        };
        out.clear();
        let mut seen = self.seen.borrow_mut();
        let (stamps, stamp) = &mut *seen;
        if stamps.len() != self.index().len() || *stamp == u32::MAX {
            *stamps = vec![0; self.index().len()];
            *stamp = 0;
        }
        *stamp += 1;
        self.index()
            .grid
            .query(lo, hi, &|bl, bh| !clear(bl, bh), stamps, *stamp, |i| {
                if !self.member(i) {
                    return;
                }
                let (bl, bh) = self.bounds(i);
                if !(bl.x > hi.x || bh.x < lo.x || bl.y > hi.y || bh.y < lo.y || clear(bl, bh)) {
                    out.push(i);
                }
            });
    }

    /// [`Self::near`] of the piece `[j, k]`, from the cache when it covers the piece; otherwise
    /// computed for the piece and [`NEAR_AHEAD_M`] beyond, and cached.
    fn near_cached<'c>(
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

    /// The certified hidden sub-intervals of `[a, b]`, in order, merged where they touch.
    pub fn hidden_parts(&self, a: DVec2, b: DVec2) -> Vec<Hidden> {
        self.sweep(a, b, false)
            .into_iter()
            .map(|(h, _)| h)
            .collect()
    }

    /// [`Self::hidden_parts`], each with the blockers its certificates use (indices into this
    /// verifier's blockers, ascending; see [`Self::hidden_by`]).
    pub fn hidden_parts_by(&self, a: DVec2, b: DVec2) -> Vec<(Hidden, Vec<u32>)> {
        self.sweep(a, b, false)
    }

    /// True when the whole closed segment `[a, b]` is certified hidden: the same sweep as
    /// [`Self::hidden_parts`], stopping at the first point it cannot certify.
    pub fn is_hidden(&self, a: DVec2, b: DVec2) -> bool {
        self.hidden_by(a, b).is_some()
    }

    /// When the whole closed segment `[a, b]` is certified hidden ([`Self::is_hidden`]), the
    /// blockers its certificates use (indices into this verifier's blockers, ascending): every
    /// segment from the cell to a point of `[a, b]` meets one of them (Lemma 1 and the pieces
    /// inside blockers, module header), so a VO on `[a, b]` is hidden by them alone.
    pub fn hidden_by(&self, a: DVec2, b: DVec2) -> Option<Vec<u32>> {
        let mut parts = self.sweep(a, b, true);
        match parts[..] {
            [(h, _)] if h.p0 == a && h.p1 == b => parts.pop().map(|(_, used)| used),
            _ => None,
        }
    }

    /// The certified pieces, each with the blockers its certificates use.
    fn sweep(&self, a: DVec2, b: DVec2, stop_at_gap: bool) -> Vec<(Hidden, Vec<u32>)> {
        let mut out: Vec<(Hidden, Vec<u32>)> = Vec::new();
        let len = a.distance(b);
        if !(len > 0.0 && len.is_finite()) {
            return out;
        }
        let par = Param { a, b, d: b - a };
        let steps = |m: f64| ((m / len * END as f64) as u64).clamp(1, END);
        let (min_step, probe) = (steps(self.min_step_m), steps(PROBE_M));
        let max_step = steps(self.max_step_m);
        let mut j = 0u64;
        let mut gap = min_step;
        let mut cache = NearCache {
            span: (1, 0),
            ahead: steps(NEAR_AHEAD_M),
            ids: Vec::new(),
            polys: Vec::new(),
            boxes: Vec::new(),
            along: Vec::new(),
            keyed: Vec::new(),
        };
        // The last point that could not be certified, after which the sweep stepped on.
        let mut failed: Option<u64> = None;
        while j < END {
            let Some(mut q) = par.at(j) else { break };
            let mut found = self.piece_from(&par, (j, q), probe, &mut cache);
            // Stepping on doubles the step, so the first certified point may lie far past the
            // start of the hidden part: bisect back towards the last failure, down to the
            // least step.
            if let (true, Some(mut lo)) = (found.is_some(), failed) {
                while j - lo > min_step {
                    let Some((mid, qm)) = par.at_or_below(lo + (j - lo) / 2, lo) else {
                        break;
                    };
                    match self.piece_from(&par, (mid, qm), probe, &mut cache) {
                        Some(r) => (j, q, found) = (mid, qm, Some(r)),
                        None => lo = mid,
                    }
                }
            }
            failed = None;
            match found {
                Some((e, pe, used)) => {
                    match out.last_mut() {
                        Some((h, all)) if h.p1 == q => {
                            h.t1 = e as f64 / END as f64;
                            h.p1 = pe;
                            all.extend_from_slice(&used);
                        }
                        _ => out.push((
                            Hidden {
                                t0: j as f64 / END as f64,
                                t1: e as f64 / END as f64,
                                p0: q,
                                p1: pe,
                            },
                            used.to_vec(),
                        )),
                    }
                    j = e;
                    gap = min_step;
                }
                None => {
                    if stop_at_gap {
                        break;
                    }
                    // The last probe ahead of `b` is tried too, however long the step.
                    let last = END.saturating_sub(probe);
                    if j >= last {
                        break;
                    }
                    // The next exact point at least a step on (far from the origin, exact
                    // points of a long segment can be sparse: step further until one is found).
                    let mut step = gap;
                    let next = loop {
                        let target = j.saturating_add(step).min(last);
                        if let Some((k, _)) = par.at_or_below(target, j) {
                            break Some(k);
                        }
                        if target == last {
                            break None;
                        }
                        step = step.saturating_mul(2);
                    };
                    let Some(k) = next else { break };
                    failed = Some(j);
                    j = k;
                    gap = gap.saturating_mul(2).min(max_step);
                }
            }
        }
        for (_, used) in &mut out {
            used.sort_unstable();
            used.dedup();
        }
        out
    }

    /// The longest certified piece `[j, e]` the sweep finds from the point `q` at parameter
    /// `j`: its end parameter and point, and the blockers its certificate uses.
    fn piece_from(
        &self,
        par: &Param,
        (j, q): (u64, DVec2),
        probe: u64,
        cache: &mut NearCache<'a>,
    ) -> Option<(u64, DVec2, std::rc::Rc<[u32]>)> {
        // The probe point: the next exact point at least `probe` on (further when exact points
        // are sparse, far from the origin).
        let mut step = probe.max(1);
        let (k, p) = loop {
            let target = j.saturating_add(step).min(END);
            if let Some(x) = par.at_or_below(target, j) {
                break x;
            }
            if target == END {
                return None;
            }
            step = step.saturating_mul(2);
        };
        self.extend(par, (j, q), (k, p), cache)
    }

    /// Given the piece `[q, p]` (parameters `j < k`), a certificate for it, extended as far
    /// along the segment as it holds: the end parameter and point.
    fn extend(
        &self,
        par: &Param,
        (j, q): (u64, DVec2),
        (k, p): (u64, DVec2),
        cache: &mut NearCache<'a>,
    ) -> Option<(u64, DVec2, std::rc::Rc<[u32]>)> {
        // A certificate found before that holds here (it proves the piece as well as a new one).
        let remaining = q.distance(par.b);
        let cached = self.cache.borrow().find(q, p, par.b);
        // A cached certificate that reaches only a little way: a new one may reach further.
        let cached = cached.filter(|(_, t)| t * remaining >= CACHE_ENOUGH_M);
        // The certificate's conditions: a cached one's copied into a buffer reused from call to
        // call, a new one's as found.
        let mut conds_buf = self.conds.borrow_mut();
        conds_buf.clear();
        let (used, fresh): (std::rc::Rc<[u32]>, bool) = match cached {
            Some((id, _)) => {
                let c = self.cache.borrow();
                conds_buf.extend_from_slice(c.conds_of(id));
                (c.certs[id as usize].2.clone(), false)
            }
            None => {
                let (ids, near, boxes, along) = self.near_cached(par, j, k, cache);
                // Inside one blocker: the piece up to where the segment leaves it.
                let inside = |b: &[DVec2], x| point_in_convex(b, x) != Containment::Outside;
                // The blockers holding q, and (when there are any) those holding p, in the
                // stretch's order (its boxes and polygons lie in that order too).
                let holding = |x: DVec2| -> Vec<u32> {
                    let mut out = Vec::new();
                    for &k in along {
                        let k = k as usize;
                        let (lo, hi) = boxes[k];
                        let in_box = lo.x <= x.x && x.x <= hi.x && lo.y <= x.y && x.y <= hi.y;
                        if in_box && inside(near[k], x) {
                            out.push(ids[k]);
                        }
                    }
                    out
                };
                let at_q = holding(q);
                let at_p = if at_q.is_empty() {
                    Vec::new()
                } else {
                    holding(p)
                };
                if let Some(&i) = at_q.iter().find(|i| at_p.contains(i)) {
                    let blk = self.poly(i);
                    if blk.len() < 3 {
                        let exit = exit_param(blk, par, j);
                        let (e, pe) = self.furthest(par, k, p, exit, &|x| inside(blk, x));
                        return Some((e, pe, [i].into()));
                    }
                    // A polygon is a certificate by itself: on no edge's outer side.
                    let n = blk.len();
                    let conds = (0..n)
                        .map(|e| Cond {
                            u: blk[e],
                            v: blk[(e + 1) % n],
                            strict: false,
                        })
                        .collect::<Vec<Cond>>();
                    *conds_buf = conds;
                    ([i].into(), true)
                } else if let Some((i, j)) = self.across_two(&at_q, &at_p, q, p) {
                    // From one blocker into one it meets: the piece is covered, and the sweep
                    // goes on from p (inside the second).
                    return Some((k, p, [i.min(j), i.max(j)].into()));
                } else {
                    // Leaving a blocker, the chords are read from `p`, beyond its edge.
                    let leaving = !at_q.is_empty();
                    let anchor = if leaving {
                        p
                    } else {
                        exact_midpoint(q, p).unwrap_or(q)
                    };
                    let pts = [anchor, q, p];
                    let valid = |links: &[Link]| {
                        let conds = conditions(links, self.cell);
                        let holds = |x: DVec2| conds.iter().all(|c| c.holds(x));
                        if !(holds(anchor) && holds(p)) {
                            return None;
                        }
                        if holds(q) {
                            return Some(conds);
                        }
                        // Leaving a blocker: `q` inside a link's blocker, `[q, anchor]`
                        // crossing that link's chord, every other condition holding at `q`
                        // (module header, "Leaving a blocker").
                        let bridge = links.iter().find(|k| {
                            inside(near[k.poly], q)
                                && segment_intersection(q, anchor, k.l, k.r)
                                    != SegmentIntersection::Disjoint
                        })?;
                        conds
                            .iter()
                            .all(|c| (c.strict && c.u == bridge.l && c.v == bridge.r) || c.holds(q))
                            .then_some(conds)
                    };
                    // Chords read at the anchor first; near an umbra boundary, from all three
                    // points.
                    let with_used = |links: &[Link]| {
                        let c = valid(links)?;
                        let mut used: Vec<u32> = links.iter().map(|k| ids[k.poly]).collect();
                        used.sort_unstable();
                        used.dedup();
                        Some((c, used))
                    };
                    let search = |near: &[&[DVec2]]| -> Option<(Vec<Cond>, Vec<u32>)> {
                        let first = self.chain(near, boxes, &pts, false)?;
                        match with_used(&first) {
                            Some(c) => Some(c),
                            None => with_used(&self.chain(near, boxes, &pts, true)?),
                        }
                    };
                    // The blockers nearest the point first (the stretch's order, by distance
                    // from its start): they subtend the widest angles, and a few of them often
                    // cover the cell.
                    let (conds, used) = search(near)?;
                    *conds_buf = conds;
                    (used.into(), true)
                }
            }
        };
        // Where the first condition stops holding, estimated from its affine values at q and b.
        let conds: &[Cond] = &conds_buf;
        let t = reach(conds, q, par.b);
        let est = j + ((END - j) as f64 * t) as u64;
        let (e, pe) = self.furthest(par, k, p, est, &|x| conds.iter().all(|c| c.holds(x)));
        if fresh {
            self.cache.borrow_mut().add(conds, used.clone(), q, pe);
        }
        Some((e, pe, used))
    }

    /// The two blockers whose union holds `[q, p]`, if any: `q` in one of `at_q`, `p` in another
    /// of `at_p` (the blockers holding each), and the
    /// segment crosses a segment `[u, v]` between two vertices that both blockers contain (the
    /// shared edge of two pieces of one footprint, or where two blockers overlap). *Proof.* The
    /// crossing `x` lies in `[u, v]`, which lies in both blockers (convex, closed); so `[q, x]`
    /// lies in the first and `[x, p]` in the second, and every point of `[q, p]` is in a
    /// blocker, hence hidden (touching counts). All tests are exact.
    fn across_two(&self, at_q: &[u32], at_p: &[u32], q: DVec2, p: DVec2) -> Option<(u32, u32)> {
        let inside = |b: &[DVec2], x| point_in_convex(b, x) != Containment::Outside;
        for &i in at_q {
            for &j in at_p {
                if i == j {
                    continue;
                }
                let (bi, bj) = (self.poly(i), self.poly(j));
                let both: Vec<DVec2> = bi
                    .iter()
                    .chain(bj)
                    .copied()
                    .filter(|&v| inside(bi, v) && inside(bj, v))
                    .collect();
                for (n, &u) in both.iter().enumerate() {
                    for &v in &both[n..] {
                        if segment_intersection(q, p, u, v) != SegmentIntersection::Disjoint {
                            return Some((i, j));
                        }
                    }
                }
            }
        }
        None
    }

    /// The largest exact parameter in `[k, est]` whose point passes `ok`, by checking `est` and
    /// then searching back towards `k` (whose point `p` passed).
    fn furthest(
        &self,
        par: &Param,
        k: u64,
        p: DVec2,
        est: u64,
        ok: &dyn Fn(DVec2) -> bool,
    ) -> (u64, DVec2) {
        let (mut good, mut gp) = (k, p);
        let mut bad = est.min(END) + 1;
        if est > k {
            if let Some((e, pe)) = par.at_or_below(est.min(END), k) {
                if ok(pe) {
                    return (e, pe);
                }
                bad = e;
            }
        }
        // Binary search between a passing and a failing parameter.
        while bad > good + 1 {
            let mid = good + (bad - good) / 2;
            match par.at_or_below(mid, good) {
                Some((m, pm)) if ok(pm) => {
                    good = m;
                    gp = pm;
                }
                Some((m, _)) => bad = m,
                None => break,
            }
        }
        (good, gp)
    }

    /// A chain of blocker chords whose conditions (S), (A), (O) and (C) hold at every point of
    /// `pts`: the chords seen from `pts[0]` are read nearest blocker first until their
    /// floating-point spans cover the cell's angle, then [`Self::cover`] picks a chain among
    /// them and checks every condition exactly. Floating point only chooses what is tried.
    fn chain(
        &self,
        near: &[&[DVec2]],
        boxes: &[(DVec2, DVec2)],
        pts: &[DVec2; 3],
        multi: bool,
    ) -> Option<Vec<Link>> {
        use Orientation::*;
        let q = pts[0];
        let (cl, cr) = guess_tangents(q, self.cell)?;
        let (cl, cr) = (self.cell[cl], self.cell[cr]);
        // Directions from q as pseudo-angles unwrapped about the cell's middle direction: the
        // cell spans [ucl, ucr]. Only to decide when enough blockers have been read (the cover
        // is then sought and checked exactly).
        let mid = pseudo_angle((cl + cr) * 0.5 - q);
        let u = |x: DVec2| {
            let d = pseudo_angle(x - q) - mid;
            if d > 2.0 {
                d - 4.0
            } else if d < -2.0 {
                d + 4.0
            } else {
                d
            }
        };
        let (ucl, ucr) = (u(cl), u(cr));
        // Whether the spans read so far cover the cell's angle ([`Sweep`]).
        let mut scratch = self.scratch.borrow_mut();
        let ChainScratch {
            seps,
            arcs,
            usable,
            beyond,
        } = &mut *scratch;
        let mut sweep = Sweep::new(ucl, ucr, beyond);
        seps.clear();
        seps.resize(near.len(), None);
        arcs.clear();
        let mut next = 8usize;
        for (poly, b) in near.iter().enumerate() {
            if let Some((l, r)) = guess_tangents(q, b) {
                // Only arcs that meet the cell's angle from q can be links (a cheap filter
                // before the separating line; the conditions decide).
                if guess(q, cl, b[r]) != Cw && guess(q, b[l], cr) != Cw {
                    sweep.add(u(b[l]).max(ucl), u(b[r]).min(ucr));
                    // Chords from the extreme vertices seen from each test point: near an
                    // umbra boundary, nearly collinear vertices trade places within
                    // millimetres.
                    // (At most one per test point, in a fixed array: this runs for every
                    // blocker read.)
                    let (mut ls, mut nl) = ([b[l]; 3], 1);
                    let (mut rs, mut nr) = ([b[r]; 3], 1);
                    for &p in &pts[1..(if multi { 3 } else { 1 })] {
                        if let Some((l, r)) = guess_tangents(p, b) {
                            if !ls[..nl].contains(&b[l]) {
                                ls[nl] = b[l];
                                nl += 1;
                            }
                            if !rs[..nr].contains(&b[r]) {
                                rs[nr] = b[r];
                                nr += 1;
                            }
                        }
                    }
                    for &l in &ls[..nl] {
                        for &r in &rs[..nr] {
                            // Where the piece leaves this blocker, its chord is not seen
                            // from the start inside it ("Leaving a blocker").
                            let seen = |x: DVec2| {
                                guess(x, l, r) == Ccw
                                    || (x == pts[1]
                                        && point_in_convex(b, x) != Containment::Outside)
                            };
                            if pts.iter().all(|&x| seen(x)) {
                                // The separating line comes later, only for arcs the cover
                                // picks.
                                let sep = SepLine {
                                    a: l,
                                    b: r,
                                    side: Ccw,
                                };
                                arcs.push(Link { l, r, sep, poly });
                            }
                        }
                    }
                }
            }
            // Blockers come nearest first: the cover is sought once the arcs read so far seem
            // to cover the cell's angle, and again after each doubling. Not after the last
            // blocker when they still seem not to: the cover reads the same arcs from `q`, so
            // it could succeed there only where the two floating-point readings disagree at a
            // rounding-sized gap, and trying cost 5% of the bake's instructions for nothing
            // (the stores of every bundled scene and of a generated city came out the same).
            // Skipping a search can only certify less, never more.
            let last = poly + 1 == near.len();
            if poly + 1 >= next || last {
                next *= 2;
                if sweep.covers() && !arcs.is_empty() {
                    if let Some(path) = self.cover(near, boxes, pts, arcs, seps, usable) {
                        return Some(path);
                    }
                }
            }
        }
        None
    }

    /// A cover of the cell's angle by `arcs` (module header), greedy first, breadth-first when
    /// the greedy gets stuck, with their separating lines (`seps`, per blocker, found when first
    /// needed).
    fn cover(
        &self,
        near: &[&[DVec2]],
        boxes: &[(DVec2, DVec2)],
        pts: &[DVec2; 3],
        arcs: &mut [Link],
        seps: &mut [Option<Option<SepLine>>],
        usable: &mut Vec<bool>,
    ) -> Option<Vec<Link>> {
        use Orientation::*;
        let q = pts[0];
        // (Each test below is spelled out over `pts`, not passed as a `dyn Fn`: they run for
        // every pair of arcs the search weighs, and inline this way.)
        let mut sep_of = |poly: usize| -> Option<SepLine> {
            *seps[poly].get_or_insert_with(|| separating_line(near[poly], self.cell, pts))
        };
        let starts = |k: &Link| {
            pts.iter()
                .all(|&p| self.cell.iter().all(|&c| guess(p, k.l, c) != Cw))
        };
        let ends = |k: &Link| {
            pts.iter()
                .all(|&p| self.cell.iter().all(|&c| guess(p, c, k.r) != Cw))
        };
        let overlaps = |a: &Link, b: &Link| {
            pts.iter()
                .all(|&p| guess(p, b.l, a.r) != Cw && guess(p, a.r, b.r) != Cw)
        };
        // Blockers that share a point `v` (a common vertex, or a vertex of one inside the
        // other) join through it: the chords `[a.l, v]` and `[v, b.r]` lie in their blockers
        // (convexity), are valid by (A), and make (O) hold trivially. Adjacent convex pieces of one footprint, and
        // buildings that share a wall, meet like this; across the line of a shared edge the
        // extreme vertices swap, and only such a join certifies both sides at once.
        // Blockers whose boxes are apart share no point: a cheap test, kept apart so that it
        // inlines where most pairs end.
        let boxes_meet = |a: &Link, b: &Link| {
            let ((al, ah), (bl, bh)) = (boxes[a.poly], boxes[b.poly]);
            !(al.x > bh.x || bl.x > ah.x || al.y > bh.y || bl.y > ah.y)
        };
        let shared = |a: &Link, b: &Link| -> Option<DVec2> {
            if !boxes_meet(a, b) {
                return None;
            }
            let (pa, pb) = (near[a.poly], near[b.poly]);
            let in_both = |v: &DVec2| {
                point_in_convex(pa, *v) != Containment::Outside
                    && point_in_convex(pb, *v) != Containment::Outside
            };
            pa.iter().chain(pb.iter()).copied().find(|v| {
                in_both(v)
                    && pts
                        .iter()
                        .all(|&p| orient(p, a.l, *v) == Ccw && orient(p, *v, b.r) == Ccw)
            })
        };
        let joins =
            |a: &Link, b: &Link| overlaps(a, b) || (boxes_meet(a, b) && shared(a, b).is_some());
        // Greedy cover, as for intervals on a line: from the start arc reaching furthest
        // counter-clockwise (seen from the anchor), repeatedly the joining arc that reaches
        // furthest, while it advances.
        let further = |x: &Link, y: &Link| guess(q, y.r, x.r) == Ccw;
        usable.clear();
        usable.resize(arcs.len(), true);
        let mut path: Vec<Link> = Vec::with_capacity(8);
        let greedy = loop {
            let prev = path.last().copied();
            let mut best: Option<usize> = None;
            for (j, b) in arcs.iter().enumerate() {
                if !usable[j] || best.is_some_and(|k| !further(b, &arcs[k])) {
                    continue;
                }
                let ok = match &prev {
                    None => starts(b),
                    Some(c) => further(b, c) && joins(c, b),
                };
                if ok {
                    best = Some(j);
                }
            }
            let Some(k) = best else {
                break false;
            };
            match sep_of(arcs[k].poly) {
                Some(sep) => {
                    arcs[k].sep = sep;
                    path.push(arcs[k]);
                    if ends(&arcs[k]) {
                        break true;
                    }
                    if path.len() > arcs.len() {
                        break false;
                    }
                }
                None => usable[k] = false,
            }
        };
        if !greedy {
            // The greedy can take an arc that joins nothing further (joins through a shared
            // point do not order like intervals): a breadth-first search over the same arcs
            // finds a chain whenever their joins (as the floating-point guesses see them) hold
            // one, so adding blockers to the set cannot hide a chain from it.
            let n = arcs.len();
            let mut from = vec![usize::MAX; n];
            let mut seen = vec![false; n];
            let mut queue = std::collections::VecDeque::new();
            for j in 0..n {
                if starts(&arcs[j]) {
                    if let Some(sep) = sep_of(arcs[j].poly) {
                        arcs[j].sep = sep;
                        seen[j] = true;
                        queue.push_back(j);
                    }
                }
            }
            let mut end = None;
            while let Some(k) = queue.pop_front() {
                if ends(&arcs[k]) {
                    end = Some(k);
                    break;
                }
                for j in 0..n {
                    if seen[j] || !further(&arcs[j], &arcs[k]) || !joins(&arcs[k], &arcs[j]) {
                        continue;
                    }
                    if let Some(sep) = sep_of(arcs[j].poly) {
                        arcs[j].sep = sep;
                        seen[j] = true;
                        from[j] = k;
                        queue.push_back(j);
                    }
                }
            }
            let mut k = end?;
            path.clear();
            loop {
                path.push(arcs[k]);
                if from[k] == usize::MAX {
                    break;
                }
                k = from[k];
            }
            path.reverse();
        }
        {
            {
                for k in 0..path.len() - 1 {
                    if !overlaps(&path[k], &path[k + 1]) {
                        if let Some(v) = shared(&path[k], &path[k + 1]) {
                            path[k].r = v;
                            path[k + 1].l = v;
                        }
                    }
                }
            }
        }
        Some(path)
    }
}

/// The buffers [`Verifier::chain`] reuses between calls: the separating lines found per blocker,
/// the arcs read, the cover's usable flags and the sweep's spans beyond its reach.
#[derive(Default)]
struct ChainScratch {
    seps: Vec<Option<Option<SepLine>>>,
    arcs: Vec<Link>,
    usable: Vec<bool>,
    beyond: Vec<(f64, f64)>,
}

/// The sweep of the chain search's angular spans (floating point, to decide when enough
/// blockers have been read): the spans sorted by their starts and swept from `from`, each span
/// that starts at or before the reach so far extending it, the answer true as soon as the reach
/// is at least `to` and false at the first gap. When `from < to` that is whether the least point
/// from `from` on that no span starting at or before it passes is at least `to`, whatever order
/// the spans come in, so it is kept up to date as spans are read, with no sort: `reach`, and
/// the spans that start beyond it, taken in when the reach passes their start. (When
/// `from >= to`, the sorted sweep answers at its first span: true when there is none or when
/// one starts at or before `from`.)
struct Sweep<'s> {
    from: f64,
    to: f64,
    reach: f64,
    /// Some span read so far starts at or before `from`.
    at_from: bool,
    /// No span read so far.
    empty: bool,
    beyond: &'s mut Vec<(f64, f64)>,
}

impl<'s> Sweep<'s> {
    /// The sweep from `from` to `to`, with `beyond` as its buffer (cleared).
    fn new(from: f64, to: f64, beyond: &'s mut Vec<(f64, f64)>) -> Self {
        beyond.clear();
        Sweep {
            from,
            to,
            reach: from,
            at_from: false,
            empty: true,
            beyond,
        }
    }

    /// Whether the spans read so far cover `[from, to]` (the sorted sweep's answer).
    fn covers(&self) -> bool {
        if self.from < self.to {
            self.reach >= self.to
        } else {
            self.empty || self.at_from
        }
    }

    /// Adds the span `[a, b]`.
    fn add(&mut self, a: f64, b: f64) {
        self.empty = false;
        self.at_from |= !(a > self.from);
        if a > self.reach {
            self.beyond.push((a, b));
            return;
        }
        if !(b > self.reach) {
            return;
        }
        self.reach = b;
        loop {
            let before = self.reach;
            let reach = &mut self.reach;
            self.beyond.retain(|&(a, b)| {
                if a > *reach {
                    return true;
                }
                if b > *reach {
                    *reach = b;
                }
                false
            });
            if !(self.reach > before) {
                break;
            }
        }
    }
}

/// A line through two input vertices with the blocker `b` on one closed side and the cell on the
/// other, having every point of `qs` strictly on `b`'s side. Candidates: the cell's edges, the
/// blocker's edges and the two crossing common tangents.
fn separating_line(b: &[DVec2], cell: &[DVec2], qs: &[DVec2]) -> Option<SepLine> {
    let ok = |s: SepLine| qs.iter().all(|&q| s.holds(q));
    // An edge of one polygon (counter-clockwise, so itself on the left) with the other wholly
    // on the right: the blocker's side is right of a cell edge, left of a blocker edge.
    fn edges<'a>(
        poly: &'a [DVec2],
        other: &'a [DVec2],
        side: Orientation,
    ) -> impl Iterator<Item = SepLine> + 'a {
        let n = poly.len();
        (0..n).filter_map(move |i| {
            let (u, v) = (poly[i], poly[(i + 1) % n]);
            (set_side(u, v, other) == SetSide::Right).then_some(SepLine { a: u, b: v, side })
        })
    }
    if let Some(s) = edges(cell, b, Orientation::Cw)
        .chain(edges(b, cell, Orientation::Ccw))
        .find(|&s| ok(s))
    {
        return Some(s);
    }
    let t = common_tangents(cell, b);
    // cross_left: cell on the left, blocker on the right; cross_right: the reverse.
    let cands = [
        t.cross_left.map(|t| (t, Orientation::Cw)),
        t.cross_right.map(|t| (t, Orientation::Ccw)),
    ];
    for (t, side) in cands.into_iter().flatten() {
        let s = SepLine {
            a: cell[t.i],
            b: b[t.j],
            side,
        };
        if ok(s) {
            return Some(s);
        }
    }
    None
}

/// Orientation in plain floating point. The search uses it only to choose candidates (tangent
/// vertices, which arcs join, which reaches furthest); every condition of a certificate is then
/// checked with the exact [`orient`], so a wrong guess can only lose a certificate.
#[inline]
fn guess(a: DVec2, b: DVec2, c: DVec2) -> Orientation {
    sign((b - a).perp_dot(c - a))
}

/// The orientation a floating-point determinant `d` stands for (NaN: collinear).
#[inline]
fn sign(d: f64) -> Orientation {
    if d > 0.0 {
        Orientation::Ccw
    } else if d < 0.0 {
        Orientation::Cw
    } else {
        Orientation::Collinear
    }
}

/// [`tangent_vertices`] with [`guess`]: the extreme vertices of `poly` seen from `q`, or `None`
/// when `q` seems to be inside or on it.
///
/// This runs for every blocker the search reads, so it computes each `poly[i] - q` once:
/// `guess(q, poly[l], poly[i])` is `(poly[l] - q).perp_dot(poly[i] - q)`, the same operations
/// on the same values, so the same bits and the same answers.
fn guess_tangents(q: DVec2, poly: &[DVec2]) -> Option<(usize, usize)> {
    let n = poly.len();
    if n >= 3 {
        // Inside or on: no edge has q strictly on its outer (right) side.
        let mut prev = poly[n - 1];
        let mut outside = false;
        for &v in poly {
            if guess(prev, v, q) == Orientation::Cw {
                outside = true;
                break;
            }
            prev = v;
        }
        if !outside {
            return None;
        }
    }
    if n == 2 && guess(poly[0], poly[1], q) == Orientation::Collinear {
        return tangent_vertices(q, poly);
    }
    let Some(&first) = poly.first() else {
        return Some((0, 0));
    };
    let d0 = first - q;
    let (mut l, mut r) = (0, 0);
    let (mut dl, mut dr) = (d0, d0);
    for (i, &v) in poly.iter().enumerate().skip(1) {
        let di = v - q;
        match sign(dl.perp_dot(di)) {
            Orientation::Cw => (l, dl) = (i, di),
            Orientation::Collinear if di.length_squared() < dl.length_squared() => {
                (l, dl) = (i, di)
            }
            _ => {}
        }
        match sign(dr.perp_dot(di)) {
            Orientation::Ccw => (r, dr) = (i, di),
            Orientation::Collinear if di.length_squared() < dr.length_squared() => {
                (r, dr) = (i, di)
            }
            _ => {}
        }
    }
    Some((l, r))
}

/// The midpoint of `[p, q]` when it is exactly representable (so lies exactly on the segment).
pub fn exact_midpoint(p: DVec2, q: DVec2) -> Option<DVec2> {
    fn exact_sum(a: f64, b: f64) -> Option<f64> {
        // Knuth's TwoSum: the rounding error of a + b, which must be zero.
        let s = a + b;
        let bb = s - a;
        let err = (a - (s - bb)) + (b - bb);
        (err == 0.0 && s.is_finite()).then_some(s)
    }
    let (sx, sy) = (exact_sum(p.x, q.x)?, exact_sum(p.y, q.y)?);
    let m = DVec2::new(sx * 0.5, sy * 0.5);
    // Halving is exact unless it underflows.
    (m.x * 2.0 == sx && m.y * 2.0 == sy && m != p && m != q).then_some(m)
}

/// The parameter (along `par`, from `j`) where the segment leaves the convex `blk`, estimated
/// in floating point (the caller checks the point it gets exactly).
fn exit_param(blk: &[DVec2], par: &Param, j: u64) -> u64 {
    let t0 = j as f64 / END as f64;
    let mut t1 = 1.0f64;
    let n = blk.len();
    for i in 0..n {
        let (u, v) = (blk[i], blk[(i + 1) % n]);
        let w = v - u;
        // Inside is left of u -> v: w x (x - u) >= 0 along x = a + t d.
        let f0 = w.perp_dot(par.a - u);
        let fd = w.perp_dot(par.d);
        if fd < 0.0 {
            t1 = t1.min(-f0 / fd);
        }
    }
    let t = t1.max(t0);
    ((t * END as f64) as u64).min(END)
}

/// Convex hull, counter-clockwise, without collinear points (Andrew's monotone chain with exact
/// orientation tests).
fn convex_hull(pts: impl Iterator<Item = DVec2>) -> Vec<DVec2> {
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

fn bbox(p: &[DVec2]) -> (DVec2, DVec2) {
    p.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), &v| (lo.min(v), hi.max(v)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sweep as first written: sort the spans by start, sweep from `from`.
    fn sorted_reaches(spans: &[(f64, f64)], from: f64, to: f64) -> bool {
        let mut s = spans.to_vec();
        s.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut reach = from;
        for &(a, b) in &s {
            if a > reach {
                return false;
            }
            reach = reach.max(b);
            if reach >= to {
                return true;
            }
        }
        reach >= to
    }

    #[test]
    fn the_incremental_span_sweep_answers_as_the_sorted_one() {
        let mut g = crate::testutil::Lcg(11);
        let mut next = move || ((g.next_u64() >> 33) % 64) as f64 / 16.0 - 1.0;
        for _ in 0..20000 {
            let (from, to) = (next(), next());
            let n = (next() * 8.0 + 8.0) as usize;
            // Some spans empty or reversed, many sharing ends (coarse values).
            let spans: Vec<(f64, f64)> = (0..n).map(|_| (next(), next())).collect();
            let mut buffer = vec![(9.0, 9.0)];
            let mut sweep = Sweep::new(from, to, &mut buffer);
            assert_eq!(sweep.covers(), sorted_reaches(&[], from, to));
            for (k, &(a, b)) in spans.iter().enumerate() {
                sweep.add(a, b);
                assert_eq!(
                    sweep.covers(),
                    sorted_reaches(&spans[..=k], from, to),
                    "{spans:?} from {from} to {to}, after {k}"
                );
            }
        }
    }
}
