//! Quantization: a VO to its 5 stored bytes, conservatively (docs/DESIGN.md section 4.5).
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

use crate::runtime::frame::{Frame, QPoint, QVo, EXPONENTS};
use crate::runtime::grid::CellId;

/// The least an end moves inward when the snapped segment fails, metres: the verifier finds
/// where a hidden part ends to within 0.5 m (`certify::MIN_STEP_M`).
pub const MIN_SHIFT_M: f64 = 1.0;

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

/// The exponent of the grid an endpoint at offset `d` from its cell's centre snaps to: the
/// least whose mantissas reach it with a step to spare (`|d| <= 255 * step` per axis), or the
/// largest.
pub fn exponent(frame: &Frame, d: DVec2) -> u8 {
    let m = d.x.abs().max(d.y.abs());
    (0..EXPONENTS)
        .find(|&e| m <= 255.0 * step(frame, e))
        .unwrap_or(EXPONENTS - 1)
}

/// The grid step of exponent `e`, metres.
pub fn step(frame: &Frame, e: u8) -> f64 {
    frame.quantum * (1u32 << e) as f64
}

/// The grid step an endpoint at `p` snaps to in cell `id`, metres.
pub fn step_at(frame: &Frame, id: CellId, p: DVec2) -> f64 {
    let c = frame.cell_centre(id).map(DVec2::from).unwrap_or(p);
    step(frame, exponent(frame, p - c))
}

/// Quantizes segment `a`–`b` of cell `id` at height `level`; `check(a, b)` decides the dequantized
/// candidates. Returns the stored VO.
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
    let (lo, hi) = window(frame, c);
    let (a, b) = clip(a, b, lo, hi).ok_or(Refused::OutsideWindow)?;
    let len = a.distance(b);
    let (sa, sb) = (step_at(frame, id, a), step_at(frame, id, b));
    if len < sa + sb {
        return Err(Refused::NotHidden);
    }
    // Ends move inward by whole steps, at least [`MIN_SHIFT_M`].
    let (ua, ub) = (sa.max(MIN_SHIFT_M), sb.max(MIN_SHIFT_M));
    let dir = (b - a) / len;
    // The far side of the VO's line, away from the cell centre.
    let mut far = dir.perp();
    if far.dot((a + b) * 0.5 - c) < 0.0 {
        far = -far;
    }
    // The grid points around `p` (on its own exponent's grid, each in canonical form) that lie
    // on the far side of the line through `p`.
    let around = |p: DVec2| -> Vec<QPoint> {
        let d = p - c;
        let e = exponent(frame, d);
        let s = step(frame, e);
        let (fx, fy) = (d.x / s, d.y / s);
        let mut v: Vec<QPoint> = Vec::with_capacity(4);
        for kx in [crate::geom::floor(fx), crate::geom::ceil(fx)] {
            for ky in [crate::geom::floor(fy), crate::geom::ceil(fy)] {
                if !(-256.0..256.0).contains(&kx) || !(-256.0..256.0).contains(&ky) {
                    continue;
                }
                let g = c + DVec2::new(kx, ky) * s;
                if (g - p).dot(far) >= 0.0 {
                    let k = QPoint {
                        e,
                        x: (kx + 256.0) as u16,
                        y: (ky + 256.0) as u16,
                    }
                    .canonical();
                    if !v.contains(&k) {
                        v.push(k);
                    }
                }
            }
        }
        v
    };
    let mut checks = 0;
    // Ends moved inward by 0, 1, 2, 4, .. of their own steps.
    let mut k = 0.0;
    while k * (ua + ub) + sa + sb <= len && checks < MAX_CHECKS {
        let (pa, pb) = (a + dir * (k * ua), b - dir * (k * ub));
        let (ca, cb) = (around(pa), around(pb));
        // (length, endpoint a, endpoint b)
        let mut pairs: Vec<(f64, QPoint, QPoint)> = Vec::new();
        for &ka in &ca {
            for &kb in &cb {
                if ka.steps() == kb.steps() {
                    continue;
                }
                let (da, db) = (ka.steps(), kb.steps());
                let d = ((da.0 - db.0) as f64).hypot((da.1 - db.1) as f64);
                pairs.push((d, ka, kb));
            }
        }
        pairs.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
        for (_, ka, kb) in pairs {
            if checks >= MAX_CHECKS {
                break;
            }
            let qvo = QVo {
                a: ka,
                b: kb,
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
        k = if k == 0.0 { 1.0 } else { 2.0 * k };
    }
    Err(Refused::NotHidden)
}

/// The quantization window of the cell centred at `c`: the box the grid of the largest exponent
/// covers.
pub fn window(frame: &Frame, c: DVec2) -> (DVec2, DVec2) {
    let s = step(frame, EXPONENTS - 1);
    (c - DVec2::splat(256.0 * s), c + DVec2::splat(255.0 * s))
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
    fn precision_follows_distance() {
        let f = Frame {
            quantum: 0.25,
            ..frame()
        };
        // Cell 0 is centred at (50, 50). A segment across the line y = 50 + d, for d from 60 m
        // to 8 km: its stored ends lie on the grid of their own exponent, canonical, no further
        // from where they were than a grid diagonal, and that grid's step is 1/256 to 1/128 of
        // the end's distance (along the larger axis), or the finest.
        for d in [60.0, 130.0, 700.0, 2_500.0, 8_000.0] {
            // Long enough for a few grid steps at that distance.
            let half = 30.2f64.max(0.25 * d);
            let (a, b) = (
                DVec2::new(50.3 - half, 50.0 + d),
                DVec2::new(50.7 + half, 50.0 + d),
            );
            let q = quantize(&f, 0, 0, 3, a, b, |_, _| true).unwrap();
            let g = f.dequantize(0, 0, &q).unwrap();
            for (p, want) in [(q.a, a), (q.b, b)] {
                assert!(p.is_canonical() && p.in_range(), "{d}: {p:?}");
                let step = 0.25 * (1u32 << p.e) as f64;
                let off = want - DVec2::new(50.0, 50.0);
                let m = off.x.abs().max(off.y.abs());
                assert!(
                    step == 0.25 || (step * 128.0 <= m && m <= step * 256.0),
                    "{d}: {p:?}"
                );
                let got = if p == q.a { g.a } else { g.b };
                assert!(DVec2::from(got).distance(want) <= step * 2f64.sqrt() + 1e-9);
                // On the far side of the line, away from the cell.
                assert!(got[1] >= 50.0 + d, "{d}: {got:?}");
            }
        }
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
        // Far outside the window (256 * 2^7 steps of 2 m: 65.5 km).
        let far = DVec2::new(70_000.0, 0.0);
        assert_eq!(
            quantize(&f, 0, 0, 1, far, far + DVec2::X * 10.0, |_, _| true),
            Err(Refused::OutsideWindow)
        );
    }
}
