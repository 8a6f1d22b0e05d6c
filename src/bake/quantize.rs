//! Quantization: a VO to its 5 stored bytes, conservatively (DESIGN.md section 4.5).
//!
//! Input: a VO segment `a`–`b` of one cell (local frame), its height level, the store's
//! [`Frame`], and a `check` that decides whether a segment is hidden (the bake passes the exact
//! verifier over the blockers that support it by rule 2).
//! Output: a [`QVo`] whose dequantized segment passed `check`, or `None` (counted by the caller).
//! Rule: endpoints must lie on the frame's grid (`quantum` metres, a window of 512 steps around
//! the cell centre), so the segment is first clipped to that window, then each endpoint is moved
//! inward along the segment by `0, q, 2q, 4q, ..` and replaced by the grid points around it that
//! lie on the far side of the VO's line from the cell (where the umbra is); pairs are tried
//! longest first. Heights were already rounded down to a level by the caller.
//! Invariants: the returned VO is exactly what the runtime decodes (the check runs on
//! [`Frame::dequantize`]'s output); at most [`MAX_CHECKS`] checks per VO.

use glam::DVec2;

use crate::runtime::frame::{Frame, QPoint, QVo, QUANT_STEPS};
use crate::runtime::grid::CellId;

/// Most `check` calls spent on one VO.
pub const MAX_CHECKS: usize = 12;

/// Why a VO could not be stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refused {
    /// Nothing of it lies in the cell's quantization window.
    OutsideWindow,
    /// No grid segment near it passed the check.
    NotHidden,
}

/// Quantizes segment `a`–`b` of cell `id` at height `level`; `check(a, b)` decides the dequantized
/// candidates. Returns the stored VO and how many checks it took.
pub fn quantize(
    frame: &Frame,
    id: CellId,
    ground: u8,
    level: u8,
    a: DVec2,
    b: DVec2,
    mut check: impl FnMut(DVec2, DVec2) -> bool,
) -> Result<QVo, Refused> {
    let c = frame
        .cell_centre(id)
        .map(DVec2::from)
        .ok_or(Refused::OutsideWindow)?;
    let q = frame.quantum;
    let (lo, hi) = window(frame, c);
    let (a, b) = clip(a, b, lo, hi).ok_or(Refused::OutsideWindow)?;
    let len = a.distance(b);
    if len < 2.0 * q {
        return Err(Refused::NotHidden);
    }
    let dir = (b - a) / len;
    // The far side of the VO's line, away from the cell centre.
    let mut far = dir.perp();
    if far.dot((a + b) * 0.5 - c) < 0.0 {
        far = -far;
    }
    let index = |p: DVec2| -> (f64, f64) { ((p.x - lo.x) / q, (p.y - lo.y) / q) };
    let around = |p: DVec2, line_pt: DVec2| -> Vec<(u16, u16)> {
        let (fx, fy) = index(p);
        let mut v = Vec::with_capacity(4);
        for kx in [fx.floor(), fx.ceil()] {
            for ky in [fy.floor(), fy.ceil()] {
                if !(0.0..QUANT_STEPS as f64).contains(&kx)
                    || !(0.0..QUANT_STEPS as f64).contains(&ky)
                {
                    continue;
                }
                let g = lo + DVec2::new(kx, ky) * q;
                if (g - line_pt).dot(far) >= 0.0 {
                    let k = (kx as u16, ky as u16);
                    if !v.contains(&k) {
                        v.push(k);
                    }
                }
            }
        }
        v
    };
    let mut checks = 0;
    let mut shift = 0.0;
    while 2.0 * shift + 2.0 * q <= len && checks < MAX_CHECKS {
        let (pa, pb) = (a + dir * shift, b - dir * shift);
        let (ca, cb) = (around(pa, pa), around(pb, pb));
        // (length in grid steps, grid point of a, grid point of b)
        type Pair = (f64, (u16, u16), (u16, u16));
        let mut pairs: Vec<Pair> = Vec::new();
        for &ka in &ca {
            for &kb in &cb {
                if ka == kb {
                    continue;
                }
                let d = (ka.0 as f64 - kb.0 as f64).hypot(ka.1 as f64 - kb.1 as f64);
                pairs.push((d, ka, kb));
            }
        }
        pairs.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
        for (_, ka, kb) in pairs {
            if checks >= MAX_CHECKS {
                break;
            }
            let qvo = QVo {
                a: QPoint::fine(ka.0, ka.1),
                b: QPoint::fine(kb.0, kb.1),
                level,
                deep: false,
            };
            let Some(g) = frame.dequantize(id, ground, &qvo) else {
                continue;
            };
            checks += 1;
            if check(DVec2::from(g.a), DVec2::from(g.b)) {
                return Ok(qvo);
            }
        }
        shift = if shift == 0.0 { q } else { 2.0 * shift };
    }
    Err(Refused::NotHidden)
}

/// The quantization window of the cell centred at `c`: the box of its grid points.
pub fn window(frame: &Frame, c: DVec2) -> (DVec2, DVec2) {
    let half = (QUANT_STEPS / 2) as f64;
    (
        c - DVec2::splat(half * frame.quantum),
        c + DVec2::splat((half - 1.0) * frame.quantum),
    )
}

/// Liang–Barsky clip of segment `a`–`b` to the box `[lo, hi]`; `None` when nothing is left.
pub fn clip(a: DVec2, b: DVec2, lo: DVec2, hi: DVec2) -> Option<(DVec2, DVec2)> {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-d.x, a.x - lo.x),
        (d.x, hi.x - a.x),
        (-d.y, a.y - lo.y),
        (d.y, hi.y - a.y),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 < t1).then(|| (a + d * t0, a + d * t1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runtime::grid::GridDescriptor;

    fn frame() -> Frame {
        Frame {
            origin: [0.0; 3],
            grid: GridDescriptor {
                min_x: 0.0,
                min_y: 0.0,
                cell_size: 100.0,
                nx: 1,
                ny: 1,
            },
            quantum: 2.0,
            eye_lo: 1.5,
            eye_hi: 2.0,
            ground_z0: 0.0,
            ground_step: 0.0,
            h0: 2.0,
            h_ratio: 1.25,
        }
    }

    #[test]
    fn endpoints_land_on_the_grid_beyond_the_line_and_inside_the_segment() {
        let f = frame();
        let (a, b) = (DVec2::new(10.3, 150.7), DVec2::new(90.9, 151.1));
        let q = quantize(&f, 0, 0, 3, a, b, |_, _| true).unwrap();
        let g = f.dequantize(0, 0, &q).unwrap();
        for p in [g.a, g.b] {
            assert_eq!(p[0] % 2.0, 0.0);
            assert_eq!(p[1] % 2.0, 0.0);
            assert!(p[1] >= 150.7, "on the far side of the line: {p:?}");
            assert!(p[0] >= 10.3 - 2.0 && p[0] <= 90.9 + 2.0);
        }
        assert_eq!(q.level, 3);
    }

    #[test]
    fn a_refusing_check_shrinks_then_drops() {
        let f = frame();
        let (a, b) = (DVec2::new(10.0, 150.0), DVec2::new(90.0, 150.0));
        // Accept only segments at least 6 m inside both ends.
        let q = quantize(&f, 0, 0, 1, a, b, |p, r| {
            p.x.min(r.x) >= 16.0 && p.x.max(r.x) <= 84.0
        });
        let g = f.dequantize(0, 0, &q.unwrap()).unwrap();
        assert!(g.a[0].min(g.b[0]) >= 16.0);
        assert_eq!(
            quantize(&f, 0, 0, 1, a, b, |_, _| false),
            Err(Refused::NotHidden)
        );
        // Far outside the window.
        let far = DVec2::new(5000.0, 0.0);
        assert_eq!(
            quantize(&f, 0, 0, 1, far, far + DVec2::X * 10.0, |_, _| true),
            Err(Refused::OutsideWindow)
        );
    }
}
