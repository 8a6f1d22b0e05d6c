//! The exact hidden-interval verifier (docs/DESIGN.md section 6.1): the final gate for every virtual
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
//! with no gap. Such points are dense only when `a` and `b` have few significant bits: callers put
//! ends on the VO grid (2^-10 m, ARCHITECTURE.md invariant 8); with full-mantissa ends the first
//! exact point after `a` may lie halfway along, and the sweep certifies little. From the current
//! point `q` (first `a`) a certificate is read off at `q` and a probe point a little ahead (the
//! tangent vertices of each blocker near them, then a chain of overlapping chords that covers the
//! cell's angle, greedily (from the arc that covers the cell's first tangent, each time the arc
//! reaching farthest), joining blockers that share a vertex through it), checked exactly at both.
//! Every condition is affine along `s`, so where the certificate stops holding is estimated in
//! floating point from its values at `q` and `b`; the estimate is rounded down to a dyadic point
//! and the certificate is checked exactly there (binary search back towards the probe when rounding
//! made it fail). By Lemma 2 the piece between is hidden; the sweep goes on from its end. A piece
//! whose two ends lie in one blocker lies in it (blockers are convex), and is hidden. Where no
//! certificate is found, the sweep steps on, doubling its step from [`MIN_PIECE_M`], and the
//! skipped part counts as visible: the output can only be smaller than the true hidden set, never
//! larger.
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
//!
//! ## Files
//! - [`certificate`]: a certificate's links and its conditions (S), (A), (O), (C), how far along
//!   a segment they hold, the separating line of a link; nothing here searches.
//! - [`index`]: the blockers indexed once per cell ([`BlockerIndex`], a bucket grid over their
//!   boxes) and the blockers near one stretch of a swept segment.
//! - [`cache`]: certificates found, by where they held, tried first at later points nearby.
//! - [`chain`]: the search for a certificate at a point: chords read nearest blocker first, the
//!   cover of the cell's angle by them, checked exactly.
//! - [`sweep`]: the sweep along the segment: exact dyadic points, pieces certified one after
//!   another, pieces inside blockers, the gaps stepped over.

mod cache;
mod certificate;
mod chain;
mod index;
#[cfg(test)]
mod oracle;
mod sweep;

use glam::DVec2;

pub use cache::{CACHE_BUCKET_M, CACHE_ENOUGH_M, CACHE_REACH_M, CACHE_TRIES};
pub use certificate::exact_midpoint;
pub use chain::NEAREST_FIRST;
pub use index::{sight_filter, BlockerIndex};
pub use index::{ALONG_PAD_M, NEAREST_SORTED, NEAR_AHEAD_M};

use cache::CertCache;
use certificate::Cond;
use chain::ChainScratch;

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
}

#[cfg(test)]
mod tests {
    use super::oracle::{brute_hidden, dyadic_points, rect, scene, v};
    use super::*;
    use crate::testutil::Lcg;

    pub(super) fn slices(b: &[Vec<DVec2>]) -> impl Iterator<Item = &[DVec2]> {
        b.iter().map(|x| x.as_slice())
    }

    #[test]
    fn a_certificate_is_refused_when_a_blocker_it_needs_is_removed() {
        // Two walls staggered in depth, overlapping in x: together they hide a segment far
        // behind, which neither hides alone.
        let cell = rect(0.0, 0.0, 10.0, 10.0);
        let left = rect(-20.0, 20.0, 6.0, 22.0);
        let right = rect(4.0, 24.0, 30.0, 26.0);
        let both = vec![left.clone(), right.clone()];
        let (a, b) = (v(-10.0, 60.0), v(20.0, 60.0));
        let ver = Verifier::new(&cell, slices(&both));
        assert_eq!(ver.hidden_by(a, b), Some(vec![0, 1]));
        for q in dyadic_points(a, b, 6) {
            assert!(brute_hidden(&cell, &both, q, 400));
        }
        for alone in [&left, &right] {
            let one = vec![alone.clone()];
            assert_eq!(Verifier::new(&cell, slices(&one)).hidden_by(a, b), None);
            assert!(dyadic_points(a, b, 6)
                .iter()
                .any(|&q| !brute_hidden(&cell, &one, q, 400)));
        }
        // The same through one shared index: a subset that leaves either out refuses.
        let index = BlockerIndex::new(slices(&both));
        assert_eq!(Verifier::subset(&cell, &index, &[0]).hidden_by(a, b), None);
        assert_eq!(Verifier::subset(&cell, &index, &[1]).hidden_by(a, b), None);
        let ver = Verifier::subset(&cell, &index, &[0, 1]);
        assert_eq!(ver.hidden_by(a, b), Some(vec![0, 1]));
    }

    /// Rule 2 needs of a VO's supporters that they alone hide it: every piece is hidden, for
    /// the oracle, by the blockers reported with it.
    #[test]
    fn certified_pieces_are_hidden_by_the_blockers_reported_with_them() {
        let mut g = Lcg(7);
        let mut pieces = 0;
        for _ in 0..80 {
            let (cell, blockers, (a, b)) = scene(&mut g, 14);
            let ver = Verifier::new(&cell, slices(&blockers));
            let parts = ver.hidden_parts_by(a, b);
            // In order, apart, within the segment, on it.
            for w in parts.windows(2) {
                assert!(w[0].0.t1 < w[1].0.t0, "{parts:?}");
            }
            for (h, used) in &parts {
                assert!(0.0 <= h.t0 && h.t0 < h.t1 && h.t1 <= 1.0, "{h:?}");
                assert!(h.p0.distance(a + (b - a) * h.t0) < 1e-9, "{h:?}");
                assert!(used.windows(2).all(|w| w[0] < w[1]), "{used:?}");
                let only: Vec<Vec<DVec2>> =
                    used.iter().map(|&i| blockers[i as usize].clone()).collect();
                for q in dyadic_points(h.p0, h.p1, 3) {
                    assert!(brute_hidden(&cell, &only, q, 300), "{q:?} of {h:?}");
                }
                pieces += 1;
            }
            // The whole segment is certified exactly when the sweep finds one piece covering it.
            let whole = matches!(parts[..], [(h, _)] if h.p0 == a && h.p1 == b);
            assert_eq!(ver.is_hidden(a, b), whole);
        }
        assert!(pieces > 20, "only {pieces} pieces: the scenes test little");
    }
}
