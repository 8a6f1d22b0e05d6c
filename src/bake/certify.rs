//! Certification: a proposed segment at a height level to a stored VO, or nothing.
//!
//! Input: a cell, its eyes and ground, the usable blockers with their rule-2 [`Support`], the
//! store's [`Frame`], and a proposal `a`–`b` at a height level.
//! Output: a [`Certified`] VO: its 5 stored bytes, the dequantized geometry the runtime will
//! read, and the hidden part of the proposal it came from; or `None`.
//! Rule: the blockers that support the VO by rule 2 (for its own `d_near`) go to the exact
//! verifier ([`Verifier::hidden_parts`]), which returns the certified hidden pieces of the
//! proposal; the longest is quantized ([`quantize`]), and every quantized candidate is checked
//! again from its dequantized form: rule 2 for the dequantized segment, then the verifier on the
//! blockers that pass. When rule 2 leaves too few blockers at the proposal's level, lower levels
//! are tried. A stored VO is then raised while rule 2 still holds, first by the band's bound,
//! then by the tighter bound for its own segment.
//! Invariant: what is returned passed rule 2 and the exact verifier in exactly the form the
//! runtime decodes (ARCHITECTURE.md invariant 10).

use glam::DVec2;

use super::quantize::{quantize, Refused};
use super::slice::{d_near, line_lambda, Support};
use crate::geom::verify::Verifier;
use crate::runtime::frame::{Frame, QVo, VoGeom, HEIGHT_LEVELS};
use crate::runtime::grid::CellId;

/// Lower levels tried when a proposal fails at its own.
pub const LEVEL_FALLBACKS: usize = 3;

/// One cell's certification context.
pub struct Certifier<'a> {
    pub frame: &'a Frame,
    pub id: CellId,
    pub ground: u8,
    pub cell: &'a [DVec2; 4],
    /// Eye heights and ground height: `(e0, e1, g)`.
    pub heights: (f64, f64, f64),
    /// Usable blockers: polygon and rule-2 support.
    pub blockers: Vec<(&'a [DVec2], Support)>,
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
    /// Of those, raised by rule 2's tighter bound ([`Support::supports_beside`]).
    pub raised_beside: usize,
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
            Verifier::new(
                self.cell,
                self.blockers
                    .iter()
                    .filter(|(_, s)| s.supports(e0, e1, g, h, dn))
                    .map(|(p, _)| *p),
            )
            // Pieces shorter than MIN_PIECE_M are dropped anyway.
            .with_max_step(0.5 * MIN_PIECE_M)
        })
    }

    /// Whether VO `a`–`b` at `level` is certified hidden over the blockers that support it by
    /// rule 2's tighter bound ([`Support::supports_beside`], with the segment's own distances),
    /// in a verifier of its own. Only blockers meeting the box of the cell and the segment can
    /// meet a segment between them; when the tighter bound admits none beyond the band's
    /// (`band_set`), the band's verifier has already answered and the sweep is skipped.
    fn hidden_beside(&self, level: u8, band: usize, a: DVec2, b: DVec2) -> bool {
        let (e0, e1, g) = self.heights;
        let h = self.frame.vo_top(e1, level);
        let dn = d_near(self.cell, &[a, b]);
        let (lo, hi) = self
            .cell
            .iter()
            .fold((a.min(b), a.max(b)), |(l, u), v| (l.min(*v), u.max(*v)));
        let floor = band_floor(band).max(f64::MIN_POSITIVE);
        let mut new = false;
        let used: Vec<&[DVec2]> = self
            .blockers
            .iter()
            .filter(|(p, _)| {
                let (pl, ph) = p
                    .iter()
                    .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(l, u), v| {
                        (l.min(*v), u.max(*v))
                    });
                pl.x <= hi.x && ph.x >= lo.x && pl.y <= hi.y && ph.y >= lo.y
            })
            .filter(|(p, s)| {
                let line = line_lambda(self.cell, p, a, b);
                let ok = s.supports_beside(e0, e1, g, h, dn, d_near(p, &[a, b]), line);
                new |= ok && !s.supports(e0, e1, g, h, floor);
                ok
            })
            .map(|(p, _)| *p)
            .collect();
        new && Verifier::new(self.cell, used)
            .with_max_step(0.5 * MIN_PIECE_M)
            .is_hidden(a, b)
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
        // Pieces are no nearer the cell than the proposal.
        let band = self.band(a, b, 0.0);
        for level in (1..=level).rev().take(LEVEL_FALLBACKS) {
            stats.checks += 1;
            let mut out: Vec<Piece> = self
                .verifier(level, band)
                .hidden_parts(a, b)
                .into_iter()
                .filter(|p| p.p0.distance(p.p1) >= MIN_PIECE_M)
                .map(|p| Piece {
                    level,
                    a: p.p0,
                    b: p.p1,
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
        let margin = 2.0 * f.quantum;
        let band = self.band(piece.a, piece.b, margin);
        let floor = band_floor(band);
        let in_band = |qa: DVec2, qb: DVec2| d_near(self.cell, &[qa, qb]) >= floor;
        for (n, level) in (1..=piece.level).rev().take(LEVEL_FALLBACKS).enumerate() {
            let mut checks = 0;
            let v = self.verifier(level, band);
            let r = quantize(
                f,
                self.id,
                self.ground,
                level,
                piece.a,
                piece.b,
                |qa, qb| {
                    checks += 1;
                    in_band(qa, qb) && v.is_hidden(qa, qb)
                },
            );
            stats.checks += checks;
            match r {
                Ok(mut q) => {
                    let mut geom = f.dequantize(self.id, self.ground, &q)?;
                    stats.stored += 1;
                    if n > 0 || checks > 1 {
                        stats.shrunk += 1;
                    }
                    let (qa, qb) = (DVec2::from(geom.a), DVec2::from(geom.b));
                    while q.level + 1 < HEIGHT_LEVELS {
                        stats.checks += 1;
                        if !self.verifier(q.level + 1, band).is_hidden(qa, qb) {
                            break;
                        }
                        q.level += 1;
                        geom = f.dequantize(self.id, self.ground, &q)?;
                        stats.raised += 1;
                    }
                    // Then by rule 2's tighter bound, over the blockers that support this very
                    // segment where they stand (a verifier of its own: its blockers hold for
                    // this segment, not for its band).
                    while q.level + 1 < HEIGHT_LEVELS {
                        stats.checks += 1;
                        if !self.hidden_beside(q.level + 1, band, qa, qb) {
                            break;
                        }
                        q.level += 1;
                        geom = f.dequantize(self.id, self.ground, &q)?;
                        stats.raised += 1;
                        stats.raised_beside += 1;
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

/// Shortest certified piece kept as a candidate, metres.
pub const MIN_PIECE_M: f64 = 8.0;

/// A certified hidden piece of a proposal, at a height level.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Piece {
    pub level: u8,
    pub a: DVec2,
    pub b: DVec2,
}
