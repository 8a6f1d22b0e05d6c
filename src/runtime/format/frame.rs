//! The frame's 112 bytes (FORMAT.md section 4) and its rules F1..F12 (section 4.1).
//!
//! Input: a [`Frame`], or exactly 112 untrusted bytes. Output: the bytes, or the checked frame.
//! Invariants: the rules are checked in the document's order and the first broken one is
//! named (`BadFrame`); [`encode_frame`] writes any frame as it is, and the decoders and store
//! encoders call [`validate_frame`]. Rule F12 (the highest VO top is finite) takes the highest
//! level of a major: 31 for 2.0, 15 for the frame inside a 1.0 store. A frame on its own (the
//! 112 bytes of [`decode_frame`], the frame given beside a blob, the encoders' frame) follows
//! the 2.0 rule, which every frame it accepts passes at level 15 too.

use super::{FormatError, Reader, Version, FRAME_LEN, MAX_CELLS};
use crate::runtime::frame::Frame;
use crate::runtime::grid::GridDescriptor;

/// Checks the frame rules F1..F12 of FORMAT.md section 4.1, in order, as version 2.0 states
/// them (F12 at level 31): the rule of a frame on its own and of every frame an encoder writes.
pub fn validate_frame(f: &Frame) -> Result<(), FormatError> {
    validate_frame_of(f, Version::V2)
}

/// The frame rules with F12 at the highest level of `version` (a 1.0 store: 15).
pub(crate) fn validate_frame_of(f: &Frame, version: Version) -> Result<(), FormatError> {
    let g = &f.grid;
    let floats = [
        f.origin[0],
        f.origin[1],
        f.origin[2],
        g.min_x,
        g.min_y,
        g.cell_size,
        f.quantum,
        f.eye_lo,
        f.eye_hi,
        f.ground_z0,
        f.ground_step,
        f.h0,
        f.h_ratio,
    ];
    let rule = |ok: bool, what: &'static str| {
        if ok {
            Ok(())
        } else {
            Err(FormatError::BadFrame(what))
        }
    };
    rule(
        floats.iter().all(|x| x.is_finite()),
        "F1: every float must be finite",
    )?;
    rule(g.cell_size > 0.0, "F2: cell_size must be > 0")?;
    rule(g.nx >= 1 && g.ny >= 1, "F3: nx and ny must be >= 1")?;
    rule(g.cell_count() <= MAX_CELLS, "F4: nx * ny must be <= 2^31")?;
    rule(
        is_power_of_two_in_range(f.quantum),
        "F5: quantum must be a power of two in [2^-10, 2^10]",
    )?;
    rule(f.eye_lo >= 0.0, "F6: eye_lo must be >= 0")?;
    rule(f.eye_lo <= f.eye_hi, "F7: eye_lo must be <= eye_hi")?;
    rule(f.ground_step >= 0.0, "F8: ground_step must be >= 0")?;
    rule(f.h0 > 0.0, "F9: h0 must be > 0")?;
    rule(f.h_ratio >= 1.0, "F10: h_ratio must be >= 1")?;
    let far_x = g.min_x + g.nx as f64 * g.cell_size;
    let far_y = g.min_y + g.ny as f64 * g.cell_size;
    rule(
        far_x.is_finite() && far_y.is_finite(),
        "F11: the grid's far corner must be finite",
    )?;
    let top = f.vo_top(f.ground_z(u8::MAX) + f.eye_hi, version.top_level());
    rule(top.is_finite(), "F12: the highest VO top must be finite")?;
    Ok(())
}

/// `x == 2^k` for an integer `k` in `-10..=10`.
fn is_power_of_two_in_range(x: f64) -> bool {
    let bits = x.to_bits();
    let sign = bits >> 63;
    let exp = ((bits >> 52) & 0x7ff) as i64 - 1023;
    let mantissa = bits & ((1u64 << 52) - 1);
    sign == 0 && mantissa == 0 && (-10..=10).contains(&exp)
}

pub(super) fn push_frame(out: &mut Vec<u8>, f: &Frame) {
    let g = &f.grid;
    for x in [
        f.origin[0],
        f.origin[1],
        f.origin[2],
        g.min_x,
        g.min_y,
        g.cell_size,
    ] {
        out.extend_from_slice(&x.to_le_bytes());
    }
    out.extend_from_slice(&g.nx.to_le_bytes());
    out.extend_from_slice(&g.ny.to_le_bytes());
    for x in [
        f.quantum,
        f.eye_lo,
        f.eye_hi,
        f.ground_z0,
        f.ground_step,
        f.h0,
        f.h_ratio,
    ] {
        out.extend_from_slice(&x.to_le_bytes());
    }
}

/// The frame's 112 bytes (FORMAT.md section 4). Writes any frame as it is; [`decode_frame`]
/// and the store encoders check the rules.
pub fn encode_frame(f: &Frame) -> [u8; FRAME_LEN] {
    let mut v = Vec::with_capacity(FRAME_LEN);
    push_frame(&mut v, f);
    let mut out = [0u8; FRAME_LEN];
    out.copy_from_slice(&v);
    out
}

/// Decodes and checks a frame from exactly 112 bytes.
pub fn decode_frame(bytes: &[u8]) -> Result<Frame, FormatError> {
    let got = bytes.len() as u64;
    if bytes.len() > FRAME_LEN {
        return Err(FormatError::TrailingBytes {
            expected: FRAME_LEN as u64,
            got,
        });
    }
    let short = FormatError::Truncated {
        needed: FRAME_LEN as u64,
        got,
    };
    let f = read_frame(&mut Reader::new(bytes)).ok_or(short)?;
    validate_frame(&f)?;
    Ok(f)
}

pub(super) fn read_frame(r: &mut Reader<'_>) -> Option<Frame> {
    let origin = [r.f64()?, r.f64()?, r.f64()?];
    let (min_x, min_y, cell_size) = (r.f64()?, r.f64()?, r.f64()?);
    let (nx, ny) = (r.u32()?, r.u32()?);
    Some(Frame {
        origin,
        grid: GridDescriptor {
            min_x,
            min_y,
            cell_size,
            nx,
            ny,
        },
        quantum: r.f64()?,
        eye_lo: r.f64()?,
        eye_hi: r.f64()?,
        ground_z0: r.f64()?,
        ground_step: r.f64()?,
        h0: r.f64()?,
        h_ratio: r.f64()?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_of_two_rule() {
        for k in -10..=10 {
            assert!(is_power_of_two_in_range(2f64.powi(k)), "2^{k}");
        }
        for x in [
            0.0,
            -0.5,
            0.75,
            3.0,
            2f64.powi(-11),
            2048.0,
            f64::NAN,
            f64::INFINITY,
        ] {
            assert!(!is_power_of_two_in_range(x), "{x}");
        }
    }
}
