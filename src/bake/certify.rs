//! Certification: a proposed segment at a height level to a stored VO, or nothing.
//!
//! Input: a cell, its eyes and ground, the usable blockers with their rule-2 [`Support`], the
//! store's [`Frame`], and a proposal `a`–`b` at a height level.
//! Output: a [`Certified`] VO: its stored bytes, the dequantized geometry the runtime will
//! read, and the hidden part of the proposal it came from; or `None`.
//! Rule: the blockers that support the proposal by rule 2, with the tighter bounds for its own
//! segment (which hold for each of its sub-segments), go to the exact verifier
//! ([`Verifier::hidden_parts_by`]), which returns the certified hidden pieces of the proposal,
//! each with the blockers its certificates use; the piece is quantized ([`quantize`]),
//! and every quantized candidate is checked again from its dequantized form: rule 2 for the
//! dequantized segment, then either the exact test that it lies in the closed umbra of the
//! certified piece ([`point_in_umbra`] at both ends: every segment from the cell to it then
//! crosses the piece, so the piece's blockers hide it too, and each ray's crossing with them
//! comes at a smaller fraction of its length), or the verifier on the blockers that pass. When
//! rule 2 leaves too few blockers at the proposal's level, lower levels are tried. A stored VO is
//! then raised: to the highest level that every blocker of its certificates supports for this
//! very segment (rule 2's tighter bounds; those blockers alone hide it), then, while a verifier
//! over the blockers that support the next level for this segment certifies it, again to what
//! the blockers of that certificate support.
//! Invariant: what is returned passed rule 2 and the exact verifier in exactly the form the
//! runtime decodes (ARCHITECTURE.md invariant 10).

use glam::DVec2;

use super::far::FarPiece;
use super::quantize::{quantize, Refused};
use super::slice::{d_near, line_lambda, point_segment_distance, Support};
use crate::geom::predicates::point_in_umbra;
use crate::geom::verify::{sight_filter, BlockerIndex, Verifier};
use crate::runtime::frame::{Frame, QVo, VoGeom, HEIGHT_LEVELS};
use crate::runtime::grid::CellId;

/// Height levels tried for one proposal or VO before it is dropped: its own, then each lower one
/// (both generators: [`Certifier::pieces`], [`Certifier::store`], and the growth's gate).
pub const LEVEL_FALLBACKS: usize = 3;

/// One cell's certification context.
pub struct Certifier<'a> {
    pub frame: &'a Frame,
    pub id: CellId,
    /// Where the cell stands: its ground level and rise.
    pub ground: crate::runtime::frame::CellGround,
    pub cell: &'a [DVec2; 4],
    /// Eye heights and ground height: `(e0, e1, g)`.
    pub heights: (f64, f64, f64),
    /// Usable blockers: polygon and rule-2 support.
    pub blockers: Vec<(&'a [DVec2], Support)>,
    /// `blockers`' polygons, indexed once for all the cell's verifiers (which name blockers by
    /// their position in `blockers`).
    pub index: &'a BlockerIndex<'a>,
    /// One verifier per height level and distance band, built when first needed.
    pub verifiers: Vec<std::cell::OnceCell<Verifier<'a>>>,
}

/// A stored VO and where it came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Certified {
    pub q: QVo,
    /// The dequantized VO, as the runtime reads it.
    pub geom: VoGeom,
    /// The certified piece of the proposal that was quantized.
    pub piece: (DVec2, DVec2),
}

/// What certification cost and found, summed over a cell.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CertifyStats {
    /// Proposals sent to the verifier.
    pub tried: usize,
    /// Certified pieces sent to quantization ([`Certifier::store`]).
    pub stores: usize,
    /// Of those, stored in some form.
    pub stored: usize,
    /// Stored only after a lower level or a shorter grid segment replaced the proposal.
    pub shrunk: usize,
    /// Exact verifications run (hidden-part searches and quantized checks).
    pub checks: usize,
    /// Levels a stored VO was raised by after quantization.
    pub raised: usize,
    /// Length proposed and length certified (all its pieces of at least [`MIN_PIECE_M`]), metres.
    pub proposed_m: f64,
    pub certified_m: f64,
}

/// Distance bands for rule 2's perspective bonus: band `k > 0` holds VOs at least
/// `BAND0_M * 2^(k - 1)` metres from the cell, band 0 any VO.
pub const BANDS: usize = 7;
pub const BAND0_M: f64 = 50.0;

/// The least distance of band `k` (0 for band 0).
pub fn band_floor(k: usize) -> f64 {
    if k == 0 {
        0.0
    } else {
        BAND0_M * (1u32 << (k - 1)) as f64
    }
}

/// The band of a VO whose least distance from the cell is `dn`.
pub fn band_of(dn: f64) -> usize {
    (0..BANDS).rev().find(|&k| band_floor(k) <= dn).unwrap_or(0)
}

/// The highest level `l` in `1..HEIGHT_LEVELS` with `ok(l)`, or `None`, where `vo_tops` are the
/// levels' VO tops and `ok` is rule 2 for one blocker. When the tops rise with the level
/// (`rising`), support falls as they rise (rule 2's bound on a ray's height grows with the VO
/// top), so the level is found by bisection (5 tests, not 31), then tested once more itself: the
/// level returned is always one that supports. `estimate` is given only where that fall is exact
/// in floating point too (eyes above 0, so every bound on a ray's height is positive: each
/// operation of the bound is then monotone): the answer is then the one `l` with `ok(l)` (or
/// `l = 0`) and not `ok(l + 1)`, so the level the estimated top points to ([`Support::
/// top_beside_estimate`]) is taken when it passes those two tests (2 tests for most blockers,
/// the bisection's own answer), else the bisection runs. Tops that do not rise: every level from
/// the highest. Tested against the plain scan.
///
/// [`Support::top_beside_estimate`]: super::slice::Support::top_beside_estimate
fn highest_level(
    vo_tops: &[f64],
    rising: bool,
    estimate: Option<f64>,
    ok: impl Fn(u8) -> bool,
) -> Option<u8> {
    if !rising {
        return (1..HEIGHT_LEVELS).rev().find(|&l| ok(l));
    }
    if let Some(estimate) = estimate.filter(|h| !h.is_nan()) {
        let l = vo_tops[1..].partition_point(|&t| t <= estimate) as u8;
        if (l == 0 || ok(l)) && (l + 1 >= HEIGHT_LEVELS || !ok(l + 1)) {
            return (l > 0).then_some(l);
        }
    }
    let (mut lo, mut hi) = (1u8, HEIGHT_LEVELS);
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if ok(mid) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    let l = lo - 1;
    if l == 0 {
        return None;
    }
    if ok(l) {
        return Some(l);
    }
    (1..HEIGHT_LEVELS).rev().find(|&l| ok(l))
}

impl<'a> Certifier<'a> {
    /// The verifier of a level and a distance band: over the blockers that support, by rule 2,
    /// a VO of that level's top whose least distance from the cell is at least the band's floor
    /// (for band 0, wherever it stands: the ratio at its cap of 1, `t >= h`). Rule 2's bound
    /// only falls as the VO's distance grows, so these blockers support every VO of the band,
    /// and one verifier, with the certificates it caches, serves all of them.
    fn verifier(&self, level: u8, band: usize) -> &Verifier<'a> {
        self.verifiers[level as usize * BANDS + band].get_or_init(|| {
            let (e0, e1, g) = self.heights;
            let h = self.frame.vo_top(e1, level);
            let dn = band_floor(band).max(f64::MIN_POSITIVE);
            let ids: Vec<u32> = (0..self.blockers.len() as u32)
                .filter(|&i| self.blockers[i as usize].1.supports(e0, e1, g, h, dn))
                .collect();
            self.verifier_over(&ids)
        })
    }

    /// A verifier over the blockers `ids` (indices into `blockers`).
    fn verifier_over(&self, ids: &[u32]) -> Verifier<'a> {
        Verifier::subset(self.cell, self.index, ids)
            // Pieces shorter than MIN_PIECE_M are dropped anyway: the sweep may step that far
            // past points it cannot certify.
            .with_max_step(MIN_PIECE_M)
            .with_min_step(MIN_STEP_M)
    }

    /// The blockers that may meet a segment from the cell to `a`–`b`: those whose box meets the
    /// convex hull of both ([`sight_filter`], the verifier's own filter; the others meet no such
    /// segment), as (index into `blockers`, polygon, support), ascending by index. The hull
    /// leaves out most of the box of a far, slanting proposal: 0.93 of Tokyo centre's bake CPU
    /// against the box of both, stores byte for byte the same.
    fn near_segment(
        &self,
        a: DVec2,
        b: DVec2,
    ) -> impl Iterator<Item = (u32, &'a [DVec2], Support)> + '_ {
        let may_meet = sight_filter(self.cell, a, b);
        (0u32..)
            .zip(&self.blockers)
            .filter(move |&(i, _)| {
                let (pl, ph) = self.index.bounds(i);
                may_meet(pl, ph)
            })
            .map(|(i, &(p, s))| (i, p, s))
    }

    /// For each blocker that may meet a segment from the cell to `a`–`b` (`near_segment`), the
    /// highest level at which it supports a VO on `a`–`b` by rule 2 with the
    /// tighter bounds for that segment ([`Support::supports_beside`]), when it supports one.
    /// As `(index into blockers, level)`, ascending by index (the verifiers built from it list
    /// their blockers in a fixed order).
    fn levels_beside(&self, a: DVec2, b: DVec2) -> Vec<(u32, u8)> {
        let (e0, e1, g) = self.heights;
        let dn = d_near(self.cell, &[a, b]);
        // The VO tops of the levels, once, and whether they rise with the level (any frame with
        // `h_ratio >= 1`: `highest_level` then bisects).
        let vo_tops: Vec<f64> = (0..HEIGHT_LEVELS)
            .map(|l| self.frame.vo_top(e1, l))
            .collect();
        let rising = vo_tops.windows(2).all(|w| w[0] <= w[1]);
        let mut out = Vec::new();
        for (i, p, s) in self.near_segment(a, b) {
            let line = line_lambda(self.cell, p, a, b);
            let top_at = |dbs: f64| {
                highest_level(
                    &vo_tops,
                    rising,
                    (e1 > 0.0).then(|| s.top_beside_estimate(e0, e1, g, dn, dbs, line)),
                    |l| s.supports_beside(e0, e1, g, vo_tops[l as usize], dn, dbs, line),
                )
            };
            // The level falls as the distance between blocker and segment does (rule 2's
            // bound grows), and that distance, `d_near`, lies between 0 and one of the
            // vertex-to-segment distances it takes the least of: when the levels at both ends
            // agree, it is not needed (3n such distances).
            let far = top_at(
                p.first()
                    .map_or(f64::INFINITY, |&v| point_segment_distance(v, a, b)),
            );
            let top = if far.is_none() || top_at(0.0) == far {
                far
            } else {
                top_at(d_near(p, &[a, b]))
            };
            if let Some(l) = top {
                out.push((i, l));
            }
        }
        out
    }

    /// The blockers that support a VO of `level` on the segment `a`–`b` by rule 2 with the
    /// tighter bounds for that segment ([`Support::supports_beside`]), ascending indices into
    /// `blockers`: those whose box meets the box of the cell and the segment (the others meet
    /// no segment from the cell to it). They support every sub-segment as well: a sub-segment
    /// lies no nearer the cell, no nearer a blocker, and on the same line, so each bound only
    /// falls for it. The cheap tests come first: the ratio at its cap of 1 (a blocker as tall as
    /// the VO supports it wherever it stands), then the bound with an upper estimate of
    /// `dist(B, s)` (its first vertex's distance), which refuses when even that fails, then the
    /// bound with 0, which admits when that passes, and only then the exact least distance.
    fn supporters_beside(&self, level: u8, a: DVec2, b: DVec2) -> Vec<u32> {
        let (e0, e1, g) = self.heights;
        let h = self.frame.vo_top(e1, level);
        let dn = d_near(self.cell, &[a, b]);
        let mut out = Vec::new();
        for (i, p, s) in self.near_segment(a, b) {
            if s.supports_anywhere(e0, e1, g, h) {
                out.push(i);
                continue;
            }
            let line = line_lambda(self.cell, p, a, b);
            let beside = |d_bs: f64| s.supports_beside(e0, e1, g, h, dn, d_bs, line);
            let d_hi = p
                .first()
                .map_or(f64::INFINITY, |&v| point_segment_distance(v, a, b));
            if beside(d_hi) && (beside(0.0) || beside(d_near(p, &[a, b]))) {
                out.push(i);
            }
        }
        out
    }

    /// The band a segment belongs to, and the check that it does (rounding-safe: the band is
    /// taken from its distance less a margin, then its distance is checked against the floor).
    fn band(&self, a: DVec2, b: DVec2, margin: f64) -> usize {
        band_of((d_near(self.cell, &[a, b]) - margin).max(0.0))
    }

    /// The certified hidden pieces of proposal `a`–`b` at `level` (or, when none, at up to
    /// [`LEVEL_FALLBACKS`] - 1 lower levels), at least [`MIN_PIECE_M`] long, longest first.
    pub fn pieces(&self, level: u8, a: DVec2, b: DVec2, stats: &mut CertifyStats) -> Vec<Piece> {
        stats.tried += 1;
        stats.proposed_m += a.distance(b);
        for level in (1..=level).rev().take(LEVEL_FALLBACKS) {
            stats.checks += 1;
            // Over the proposal's own supporters: rule 2's tighter bounds for its segment hold
            // for each of its pieces (`supporters_beside`).
            let ids = self.supporters_beside(level, a, b);
            let mut out: Vec<Piece> = self
                .verifier_over(&ids)
                .hidden_parts_by(a, b)
                .into_iter()
                .filter(|(p, _)| p.p0.distance(p.p1) >= MIN_PIECE_M)
                .map(|(p, used)| Piece {
                    level,
                    a: p.p0,
                    b: p.p1,
                    used,
                })
                .collect();
            if !out.is_empty() {
                out.sort_by(|x, y| y.a.distance(y.b).total_cmp(&x.a.distance(x.b)));
                stats.certified_m += out.iter().map(|p| p.a.distance(p.b)).sum::<f64>();
                return out;
            }
        }
        Vec::new()
    }

    /// A certified piece quantized to its stored form, re-checked from the dequantized bytes
    /// (rule 2 for that segment through its band, then the exact verifier); lower levels when
    /// that fails. A stored VO is then raised level by level while the verifier of the higher
    /// level (whose blockers support it by rule 2) still certifies its dequantized segment.
    pub fn store(&self, piece: &Piece, stats: &mut CertifyStats) -> Option<Certified> {
        let f = self.frame;
        stats.stores += 1;
        // Quantization moves an end by at most a grid diagonal.
        let margin = 2.0
            * super::quantize::step_at(f, self.id, piece.a)
                .max(super::quantize::step_at(f, self.id, piece.b));
        let band = self.band(piece.a, piece.b, margin);
        let floor = band_floor(band);
        let in_band = |qa: DVec2, qb: DVec2| d_near(self.cell, &[qa, qb]) >= floor;
        for (n, level) in (1..=piece.level).rev().take(LEVEL_FALLBACKS).enumerate() {
            let mut checks = 0;
            let v = self.verifier(level, band);
            // The blockers that certified the last quantized candidate checked: the one kept.
            let mut used: Vec<u32> = Vec::new();
            let r = quantize(
                f,
                self.id,
                self.ground.level,
                level,
                piece.a,
                piece.b,
                |qa, qb| {
                    checks += 1;
                    if !in_band(qa, qb) {
                        return false;
                    }
                    // Behind the certified piece: hidden by the piece's blockers (module
                    // header), no sweep needed.
                    if !piece.used.is_empty()
                        && [qa, qb]
                            .iter()
                            .all(|&x| point_in_umbra(self.cell, piece.a, piece.b, x))
                    {
                        used = piece.used.clone();
                        return true;
                    }
                    match v.hidden_by(qa, qb) {
                        Some(u) => {
                            used = u;
                            true
                        }
                        None => false,
                    }
                },
            );
            stats.checks += checks;
            match r {
                Ok(mut q) => {
                    // Certified for a bottom below the cell's ground (`ground_z0`, a deep cell,
                    // bake/terrain.rs): stored as a deep VO, which stands from there.
                    q.deep = self.heights.2 < f.ground_z(self.ground.level);
                    let mut geom = f.dequantize(self.id, self.ground, &q)?;
                    stats.stored += 1;
                    if n > 0 || checks > 1 {
                        stats.shrunk += 1;
                    }
                    let (qa, qb) = (DVec2::from(geom.a), DVec2::from(geom.b));
                    let start = q.level;
                    q.level = self.raise(q.level, qa, qb, &used, stats);
                    if q.level > start {
                        stats.raised += (q.level - start) as usize;
                        geom = f.dequantize(self.id, self.ground, &q)?;
                    }
                    return Some(Certified {
                        q,
                        geom,
                        piece: (piece.a, piece.b),
                    });
                }
                Err(Refused::OutsideWindow) => return None,
                Err(Refused::NotHidden) => {}
            }
        }
        None
    }
}

impl Certifier<'_> {
    /// The highest level, from `level` up, at which the segment `a`–`b`, hidden by the blockers
    /// `used` (indices into [`Self::blockers`]) at `level`, is certified: first the highest that
    /// every blocker of `used` supports for this very segment by rule 2's tighter bounds (those
    /// blockers alone hide it, so rule 2 holds over them there); then, while a verifier over the
    /// blockers that support the next level for this very segment certifies it, the highest
    /// level the blockers of that certificate support.
    pub fn raise(
        &self,
        level: u8,
        a: DVec2,
        b: DVec2,
        used: &[u32],
        stats: &mut CertifyStats,
    ) -> u8 {
        let tops = self.levels_beside(a, b);
        let top_of = |used: &[u32]| {
            used.iter()
                .map(|&i| {
                    tops.binary_search_by_key(&i, |t| t.0)
                        .map_or(0, |k| tops[k].1)
                })
                .min()
                .unwrap_or(0)
        };
        let mut level = level.max(top_of(used));
        while level + 1 < HEIGHT_LEVELS {
            let next = level + 1;
            let ids: Vec<u32> = tops
                .iter()
                .filter(|&&(_, l)| l >= next)
                .map(|&(i, _)| i)
                .collect();
            stats.checks += 1;
            let v = Verifier::subset(self.cell, self.index, &ids).with_max_step(MIN_PIECE_M);
            match v.hidden_by(a, b) {
                Some(u) => level = next.max(top_of(&u)),
                None => break,
            }
        }
        level
    }

    /// The highest level of this cell whose VO top stands no higher than the far piece's
    /// (at least 1: above the eyes), or `None` when even level 1 is taller.
    /// `None` too for a cell whose VOs stand lower than the piece (a deep cell's).
    pub fn far_level(&self, p: &FarPiece) -> Option<u8> {
        let (_, e1, g) = self.heights;
        if g < p.bottom {
            return None;
        }
        (1..HEIGHT_LEVELS)
            .rev()
            .find(|&l| self.frame.vo_top(e1, l) <= p.top)
    }

    /// A far piece (certified hidden from the cell's whole block, with its eyes, bottom and top,
    /// [`super::far`]) quantized for this cell: at [`Self::far_level`] (a top no higher than the
    /// piece's, above the cell's eyes, on the cell's ground, which is no lower than the block's:
    /// a part of the certified quad), and each quantized candidate kept only when both its ends
    /// lie in the closed umbra of the piece seen from the cell (exact). The piece is hidden from
    /// every eye of the block, so from the cell's; every segment from the cell to a point of its
    /// umbra crosses the piece; and a ray crosses the piece's blockers at a smaller fraction of
    /// its length than on its way to the piece, so rule 2 still holds (module header). No raise:
    /// the piece's blockers may lie beyond the cell's own.
    pub fn store_far(&self, p: &FarPiece, stats: &mut CertifyStats) -> Option<Certified> {
        let f = self.frame;
        stats.stores += 1;
        let level = self.far_level(p)?;
        let mut checks = 0;
        let r = quantize(f, self.id, self.ground.level, level, p.a, p.b, |qa, qb| {
            checks += 1;
            point_in_umbra(self.cell, p.a, p.b, qa) && point_in_umbra(self.cell, p.a, p.b, qb)
        });
        stats.checks += checks;
        let q = r.ok()?;
        stats.stored += 1;
        if checks > 1 {
            stats.shrunk += 1;
        }
        Some(Certified {
            q,
            geom: f.dequantize(self.id, self.ground, &q)?,
            piece: (p.a, p.b),
        })
    }
}

/// Shortest certified piece kept as a candidate, metres.
pub const MIN_PIECE_M: f64 = 8.0;
/// Where a certified piece begins after a visible gap is sought to within this, metres: far
/// below the 4 m grid the stored ends snap to at 100 m cells.
pub const MIN_STEP_M: f64 = 0.5;

/// A certified hidden piece of a proposal, at a height level, with the blockers (indices into
/// [`Certifier::blockers`]) whose certificates hide it.
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    pub level: u8,
    pub a: DVec2,
    pub b: DVec2,
    pub used: Vec<u32>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::cell::CellSetup;
    use crate::bake::long::certifier;
    use crate::bake::params::BakeParams;
    use crate::bake::plan::Plan;
    use crate::geom::predicates::segment_meets_convex;
    use crate::testutil::squares;

    /// `highest_level` by the estimate (rule 2's, or any other), by bisection and by the plain
    /// scan of every level give the same level for rule 2 over random blockers, eyes, distances
    /// and frames (300,000 draws of a fixed generator), and rule 2's estimate alone decides most
    /// of them (so the fast path is taken, not only correct).
    #[test]
    fn highest_level_by_the_estimate_is_the_scans() {
        let mut next = crate::testutil::uniform(7);
        let (mut by_estimate, mut supported, n) = (0usize, 0usize, 300_000);
        for _ in 0..n {
            let e0 = next(0.5, 80.0);
            let e1 = e0 + next(0.0, 3.0);
            let g = e0 - next(0.0, 2.0);
            let s = Support {
                base: next(-5.0, 1.2) * e0,
                top: e1 + next(-20.0, 250.0),
                d_far: next(1.0, 3000.0),
            };
            let (h0, ratio) = (next(0.5, 12.0), next(1.0, 1.35));
            let frame_tops: Vec<f64> = (0..HEIGHT_LEVELS)
                .map(|l| e1 + h0 * ((0..l).fold(1.0, |p, _| p * ratio) - 1.0))
                .collect();
            let (dn, dbs) = (next(-10.0, 3000.0), next(-1.0, 3000.0));
            let line = next(-0.1, 1.2);
            let ok = |l: u8| s.supports_beside(e0, e1, g, frame_tops[l as usize], dn, dbs, line);
            let scan = (1..HEIGHT_LEVELS).rev().find(|&l| ok(l));
            let estimate = s.top_beside_estimate(e0, e1, g, dn, dbs, line);
            // Decided by the estimate: its level and the next tested, no bisection.
            let tests = std::cell::Cell::new(0);
            let counted = |l: u8| {
                tests.set(tests.get() + 1);
                ok(l)
            };
            assert_eq!(
                highest_level(&frame_tops, true, Some(estimate), counted),
                scan
            );
            by_estimate += usize::from(tests.get() <= 2);
            // Whatever the estimate, the answer is the scan's: a wrong one only costs tests.
            let wrong = next(e1 - 50.0, e1 + 400.0);
            for guess in [wrong, f64::NEG_INFINITY, f64::INFINITY, f64::NAN] {
                assert_eq!(highest_level(&frame_tops, true, Some(guess), ok), scan);
            }
            assert_eq!(highest_level(&frame_tops, true, None, ok), scan);
            assert_eq!(highest_level(&frame_tops, false, None, ok), scan);
            supported += usize::from(scan.is_some());
        }
        // Both answers drawn often: some level supported (82%), none.
        assert!(
            supported > n / 2 && supported < n * 9 / 10,
            "{supported} of {n}"
        );
        assert!(by_estimate > n * 99 / 100, "{by_estimate} of {n}");
    }

    /// A row of 30 m squares, 60 m tall, from x = 100 to 400 at y = 160, with the squares of
    /// `gaps` (their place in the row) left out, a low block behind it, and a tower 150 m tall
    /// far off (the height levels reach the tallest building); the cell is `[200, 300) x [0, 100)`.
    fn street(gaps: &[usize]) -> crate::scene::Scene {
        let mut items: Vec<([f64; 3], f64, f64)> = (0..10)
            .filter(|k| !gaps.contains(k))
            .map(|k| ([100.0 + 30.0 * k as f64, 160.0, 30.0], 0.0, 60.0))
            .collect();
        items.push(([240.0, 400.0, 20.0], 0.0, 10.0));
        items.push(([1400.0, 1400.0, 10.0], 0.0, 150.0));
        // A hut at the corner: the grid starts at (0, 0).
        items.push(([0.0, 0.0, 2.0], 0.0, 3.0));
        squares(&items)
    }

    /// Runs `f` with the certifier of the cell holding `(250, 50)`.
    fn with_certifier(scene: &crate::scene::Scene, f: impl FnOnce(&Certifier)) {
        let plan = Plan::new(scene, BakeParams::default()).unwrap();
        let id = plan.frame.grid.cell_at(250.0, 50.0).unwrap();
        let setup = CellSetup::new(&plan, id).ok().unwrap();
        let index = BlockerIndex::new(
            setup
                .near
                .iter()
                .map(|&i| plan.set.polys[i as usize].as_slice()),
        );
        f(&certifier(&plan, &setup, &index));
    }

    /// `near_segment` keeps every blocker that a segment from the cell to the proposal meets
    /// (sampled: 5 x 5 points of the cell to 41 points of the proposal), and leaves out blockers
    /// whose boxes meet the box of the cell and the proposal but lie outside their hull.
    #[test]
    fn near_segment_keeps_every_blocker_a_sight_line_meets_and_leaves_the_hulls_outside() {
        // 20 m squares every 60 m over [0, 1800) x [0, 1800), 30 m tall.
        let items: Vec<([f64; 3], f64, f64)> = (0..900)
            .map(|k| {
                let (i, j) = ((k % 30) as f64, (k / 30) as f64);
                ([60.0 * i, 60.0 * j, 20.0], 0.0, 30.0)
            })
            .collect();
        with_certifier(&squares(&items), |c| {
            let mut left_out = 0;
            for (a, b) in [
                (DVec2::new(700.0, 300.0), DVec2::new(1000.0, 1100.0)),
                (DVec2::new(30.0, 900.0), DVec2::new(500.0, 1150.0)),
                (DVec2::new(1100.0, 10.0), DVec2::new(1150.0, 800.0)),
            ] {
                let near: Vec<u32> = c.near_segment(a, b).map(|(i, _, _)| i).collect();
                assert!(near.windows(2).all(|w| w[0] < w[1]));
                let (lo, hi) = c
                    .cell
                    .iter()
                    .fold((a.min(b), a.max(b)), |(l, u), v| (l.min(*v), u.max(*v)));
                let (c0, c1) = (c.cell[0].min(c.cell[2]), c.cell[0].max(c.cell[2]));
                for (i, &(poly, _)) in c.blockers.iter().enumerate() {
                    let i = i as u32;
                    let seen = (0..5).any(|u| {
                        (0..5).any(|v| {
                            let p = c0 + (c1 - c0) * DVec2::new(u as f64, v as f64) / 4.0;
                            (0..=40).any(|t| {
                                let x = a.lerp(b, t as f64 / 40.0);
                                segment_meets_convex(p, x, poly)
                            })
                        })
                    });
                    assert!(!seen || near.contains(&i), "blocker {i} left out");
                    let (pl, ph) = c.index.bounds(i);
                    let in_box = pl.x <= hi.x && ph.x >= lo.x && pl.y <= hi.y && ph.y >= lo.y;
                    left_out += usize::from(in_box && !near.contains(&i));
                }
            }
            assert!(left_out > 50, "the hull left out {left_out}");
        });
    }

    /// The highest level whose VO top stands no higher than `top`.
    fn level_under(c: &Certifier, top: f64) -> u8 {
        let e1 = c.heights.1;
        (1..HEIGHT_LEVELS)
            .rev()
            .find(|&l| c.frame.vo_top(e1, l) <= top)
            .unwrap()
    }

    /// The 3D oracle: the segment from an eye `(p, e)` to a point `(x, z)` passes through the
    /// prism of one of the blockers (clipped in 2D, its height checked over the clipped part).
    fn blocked(p: DVec2, e: f64, x: DVec2, z: f64, blockers: &[(&[DVec2], Support)]) -> bool {
        blockers.iter().any(|(poly, s)| {
            let d = x - p;
            let (mut t0, mut t1) = (0.0f64, 1.0f64);
            let n = poly.len();
            for i in 0..n {
                let (u, w) = (poly[i], poly[(i + 1) % n]);
                let (f0, fd) = ((w - u).perp_dot(p - u), (w - u).perp_dot(d));
                if fd == 0.0 {
                    if f0 < 0.0 {
                        return false;
                    }
                } else if fd > 0.0 {
                    t0 = t0.max(-f0 / fd);
                } else {
                    t1 = t1.min(-f0 / fd);
                }
            }
            let (h0, h1) = (e + t0 * (z - e), e + t1 * (z - e));
            t0 <= t1 && h0.min(h1) <= s.top && h0.max(h1) >= s.base
        })
    }

    /// Every sampled ray from an eye of the cell to the quad standing on `a`–`b` from `g` to
    /// `h` is blocked by `blockers`.
    fn assert_quad_hidden(c: &Certifier, a: DVec2, b: DVec2, g: f64, h: f64, blockers: &[u32]) {
        let (e0, e1, _) = c.heights;
        let bl: Vec<(&[DVec2], Support)> =
            blockers.iter().map(|&i| c.blockers[i as usize]).collect();
        let (lo, hi) = (c.cell[0], c.cell[2]);
        for i in 0..=4 {
            for j in 0..=4 {
                let p = lo
                    + (hi - lo) * DVec2::new(i as f64, j as f64) * (0.999 / 4.0)
                    + (hi - lo) * 0.0005;
                for e in [e0 + 1e-6, (e0 + e1) / 2.0, e1 - 1e-6] {
                    for k in 0..=16 {
                        let x = a + (b - a) * (k as f64 / 16.0);
                        for z in [g + 1e-6, (g + h) / 2.0, h - 1e-6] {
                            assert!(blocked(p, e, x, z, &bl), "{p} {e} -> {x} {z}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_proposal_behind_a_row_is_certified_stored_and_hidden_in_3d() {
        with_certifier(&street(&[]), |c| {
            let level = level_under(c, 50.0);
            let (a, b) = (DVec2::new(150.0, 250.0), DVec2::new(350.0, 250.0));
            let mut stats = CertifyStats::default();
            let pieces = c.pieces(level, a, b, &mut stats);
            // The whole proposal, at its own level, hidden by the row alone.
            assert_eq!(pieces.len(), 1, "{pieces:?}");
            let p = &pieces[0];
            assert_eq!((p.level, p.a, p.b), (level, a, b));
            let (e0, e1, g) = c.heights;
            for &i in &p.used {
                let s = c.blockers[i as usize].1;
                assert!(s.top == 60.0 && s.supports(e0, e1, g, c.frame.vo_top(e1, level), 150.0));
            }
            assert_quad_hidden(c, p.a, p.b, g, c.frame.vo_top(e1, level), &p.used);
            // Stored: what the runtime reads back is hidden too, by the cell's blockers.
            let s = c.store(p, &mut stats).unwrap();
            assert!(s.q.level >= level, "raised, never lowered: {:?}", s.q);
            assert!(s.geom.h >= e1 && s.geom.g <= e0);
            let all: Vec<u32> = (0..c.blockers.len() as u32).collect();
            let (ga, gb) = (DVec2::from(s.geom.a), DVec2::from(s.geom.b));
            assert_quad_hidden(c, ga, gb, s.geom.g, s.geom.h, &all);
            assert_eq!((stats.tried, stats.stores, stats.stored), (1, 1, 1));
        });
    }

    /// With squares of the row removed, no certified piece reaches into what the gap shows,
    /// and too low a row certifies nothing at a level above it.
    #[test]
    fn a_certificate_is_refused_where_its_blocker_is_removed() {
        let (a, b) = (DVec2::new(150.0, 250.0), DVec2::new(350.0, 250.0));
        with_certifier(&street(&[4, 5]), |c| {
            let level = level_under(c, 50.0);
            let pieces = c.pieces(level, a, b, &mut CertifyStats::default());
            let polys: Vec<&[DVec2]> = c.blockers.iter().map(|b| b.0).collect();
            let total: f64 = pieces.iter().map(|p| p.a.distance(p.b)).sum();
            assert!(total < 0.9 * a.distance(b), "{pieces:?}");
            for p in &pieces {
                for k in 0..=32 {
                    let x = p.a + (p.b - p.a) * (k as f64 / 32.0);
                    // Every segment from the cell's corners and middle to x meets the row.
                    for i in 0..=8 {
                        let s = c.cell[0] + (c.cell[2] - c.cell[0]) * (i as f64 / 8.0);
                        let t = c.cell[1] + (c.cell[3] - c.cell[1]) * (i as f64 / 8.0);
                        for q in [s, t] {
                            assert!(polys.iter().any(|b| segment_meets_convex(q, x, b)), "{x}");
                        }
                    }
                }
            }
        });
        // The whole row, but VOs above what its blockers support on this segment (at the
        // proposal's level and every fallback): rule 2 with the tighter bounds for the segment,
        // which the row at 60 m supports up to about 78 m (the line's bound: the row stands 60
        // m in front of the proposal's line, which lies 250 m from the cell's far side).
        with_certifier(&street(&[]), |c| {
            let e1 = c.heights.1;
            let supported = c.levels_beside(a, b).iter().map(|&(_, l)| l).max().unwrap();
            let top = c.frame.vo_top(e1, supported);
            assert!(top > 61.0 && top < 80.0, "{top}");
            let above = supported + 1;
            let level = above + LEVEL_FALLBACKS as u8 - 1;
            assert!(
                level < HEIGHT_LEVELS,
                "the levels reach {}",
                c.frame.vo_top(e1, 31)
            );
            assert!(c
                .pieces(level, a, b, &mut CertifyStats::default())
                .is_empty());
            // At the highest level they support, taller than the row itself: certified (the
            // band's bound, the ratio at its cap of 1 this far out, would refuse it).
            let (e0, g) = (c.heights.0, c.heights.2);
            let row: Vec<&Support> = c
                .blockers
                .iter()
                .map(|(_, s)| s)
                .filter(|s| s.top == 60.0)
                .collect();
            assert_eq!(row.len(), 10);
            assert!(row.iter().all(|s| !s.supports(e0, e1, g, top, 150.0)));
            assert!(!c
                .pieces(supported, a, b, &mut CertifyStats::default())
                .is_empty());
        });
    }

    #[test]
    fn bands_grow_with_distance() {
        assert_eq!(band_of(0.0), 0);
        assert_eq!(band_of(BAND0_M - 1.0), 0);
        assert_eq!(band_of(BAND0_M), 1);
        for k in 1..BANDS {
            assert_eq!(band_of(band_floor(k)), k);
            assert!(band_floor(k) > band_floor(k - 1));
        }
        assert_eq!(band_of(1e9), BANDS - 1);
    }
}
