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
//! are tried.
//! Invariant: what is returned passed rule 2 and the exact verifier in exactly the form the
//! runtime decodes (ARCHITECTURE.md invariant 10).

use glam::DVec2;

use super::quantize::{quantize, Refused};
use super::slice::{d_near, Support};
use crate::geom::verify::Verifier;
use crate::runtime::frame::{Frame, QVo, VoGeom};
use crate::runtime::grid::CellId;

/// Lower levels tried when a proposal fails at its own.
pub const LEVEL_FALLBACKS: usize = 3;

/// One cell's certification context.
pub struct Certifier<'a> {
    pub frame: &'a Frame,
    pub id: CellId,
    pub ground: u8,
    pub cell: [DVec2; 4],
    /// Eye heights and ground height: `(e0, e1, g)`.
    pub heights: (f64, f64, f64),
    /// Usable blockers: polygon and rule-2 support.
    pub blockers: Vec<(&'a [DVec2], Support)>,
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
    /// Of those, certified and stored in some form.
    pub stored: usize,
    /// Stored only after a lower level or a shorter grid segment replaced the proposal.
    pub shrunk: usize,
    /// Exact verifications run (hidden-part searches and quantized checks).
    pub checks: usize,
    /// Length proposed and length certified (the longest certified piece), metres.
    pub proposed_m: f64,
    pub certified_m: f64,
}

impl<'a> Certifier<'a> {
    /// The verifier over the blockers that support a VO of top `h` on segment `a`–`b`.
    fn verifier(&self, h: f64, a: DVec2, b: DVec2) -> Verifier<'_> {
        let (e0, e1, g) = self.heights;
        let dn = d_near(&self.cell, &[a, b]);
        Verifier::new(
            &self.cell,
            self.blockers
                .iter()
                .filter(|(_, s)| s.supports(e0, e1, g, h, dn))
                .map(|(p, _)| *p),
        )
    }

    /// Certifies proposal `a`–`b` at `level` (or a lower one), quantized.
    pub fn certify(
        &self,
        level: u8,
        a: DVec2,
        b: DVec2,
        stats: &mut CertifyStats,
    ) -> Option<Certified> {
        let f = self.frame;
        let (_, e1, _) = self.heights;
        stats.tried += 1;
        stats.proposed_m += a.distance(b);
        let mut first = true;
        for level in (1..=level).rev().take(LEVEL_FALLBACKS) {
            let h = f.vo_top(e1, level);
            stats.checks += 1;
            let t = std::time::Instant::now();
            let parts = self.verifier(h, a, b).hidden_parts(a, b);
            if std::env::var("VOCC_DEBUG").is_ok() {
                let tot: f64 = parts.iter().map(|p| p.p0.distance(p.p1)).sum();
                let best = parts.iter().map(|p| p.p0.distance(p.p1)).fold(0.0, f64::max);
                eprintln!(
                    "certify level {level} len {:.1} parts {} total {:.1} best {:.1} in {:.2} ms; a {a} b {b}",
                    a.distance(b),
                    parts.len(),
                    tot,
                    best,
                    t.elapsed().as_secs_f64() * 1e3
                );
                if parts.is_empty() {
                    let (e0, e1, g) = self.heights;
                    let dn = d_near(&self.cell, &[a, b]);
                    let used: Vec<&[DVec2]> = self
                        .blockers
                        .iter()
                        .filter(|(_, s)| s.supports(e0, e1, g, h, dn))
                        .map(|(p, _)| *p)
                        .collect();
                    let mut vis = Vec::new();
                    for k in 0..=100 {
                        let q = a + (b - a) * (k as f64 / 100.0);
                        // rays from 400 boundary points
                        let mut seen = false;
                        for j in 0..400 {
                            let t = j as f64 / 100.0;
                            let (i, f) = (t.floor() as usize, t.fract());
                            let c = self.cell[i] + (self.cell[(i + 1) % 4] - self.cell[i]) * f;
                            if !used.iter().any(|p| crate::geom::predicates::segment_meets_convex(c, q, p)) {
                                seen = true;
                                break;
                            }
                        }
                        vis.push(if seen { 'V' } else { '.' });
                    }
                    eprintln!("   brute: {}", vis.iter().collect::<String>());
                }
            }
            let Some(best) = parts
                .iter()
                .max_by(|x, y| x.p0.distance(x.p1).total_cmp(&y.p0.distance(y.p1)))
            else {
                first = false;
                continue;
            };
            let (p0, p1) = (best.p0, best.p1);
            let mut checks = 0;
            let r = quantize(f, self.id, self.ground, level, p0, p1, |qa, qb| {
                checks += 1;
                self.verifier(h, qa, qb).is_hidden(qa, qb)
            });
            stats.checks += checks;
            match r {
                Ok(q) => {
                    let geom = f.dequantize(self.id, self.ground, &q)?;
                    stats.stored += 1;
                    stats.certified_m += p0.distance(p1);
                    if !first || checks > 1 || parts.len() > 1 || (p0, p1) != (a, b) {
                        stats.shrunk += 1;
                    }
                    return Some(Certified {
                        q,
                        geom,
                        piece: (p0, p1),
                    });
                }
                Err(Refused::OutsideWindow) => return None,
                Err(Refused::NotHidden) => first = false,
            }
        }
        None
    }
}
