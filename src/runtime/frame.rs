//! The frame: what a decoder needs beside a cell's bytes to turn them into geometry.
//!
//! Input: a [`Frame`] (scene origin, grid, quantization and vertical frames, eye heights) and a
//! cell's quantized VOs. Output: each VO as a local segment with its height range [g, h], and the
//! cell's view (rectangle and eye heights) that rule 3 needs.
//! Invariants:
//! - a quantized endpoint is `centre + (k - 256) * quantum` with `k` in `0..512`, where `centre`
//!   is the cell's centre; with a power-of-two quantum and a dyadic grid, every dequantized
//!   endpoint is exact in f64, so the bake's verifier checks exactly the segment the runtime uses;
//! - the VO top of level `k` is `e1 + h0 * (h_ratio^k - 1)`, computed by one function
//!   ([`Frame::vo_top`]) that the bake also uses: the bake checks what the runtime will read;
//! - the VO bottom `g` is the cell's ground, and the eyes stand at `g + eye_lo ..= g + eye_hi`.

use crate::runtime::grid::{CellId, GridDescriptor};

/// Quantized coordinates per axis: endpoints use `k` in `0..QUANT_STEPS`.
pub const QUANT_STEPS: u16 = 512;
/// Height levels: `0..HEIGHT_LEVELS`.
pub const HEIGHT_LEVELS: u8 = 16;
/// At most this many VOs per cell.
pub const MAX_VOS_PER_CELL: usize = 10;

/// Everything a decoder needs beside a cell's bytes (the "grid descriptor" of FORMAT.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// World position of the local origin: `world = local + origin`.
    pub origin: [f64; 3],
    /// The cell grid, in the local frame.
    pub grid: GridDescriptor,
    /// Step of the VO endpoint grid, metres (a power of two).
    pub quantum: f64,
    /// Eye heights above the cell's ground, metres: `0 <= eye_lo <= eye_hi`.
    pub eye_lo: f64,
    pub eye_hi: f64,
    /// Local height of ground level 0, metres.
    pub ground_z0: f64,
    /// Step between ground levels, metres; 0 when every cell stands at `ground_z0` (then the
    /// store holds no ground byte per cell).
    pub ground_step: f64,
    /// VO top of level k: `e1 + h0 * (h_ratio^k - 1)`.
    pub h0: f64,
    pub h_ratio: f64,
}

/// One VO as stored: endpoint grid coordinates and a height level.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct QVo {
    pub x1: u16,
    pub y1: u16,
    pub x2: u16,
    pub y2: u16,
    pub level: u8,
}

impl QVo {
    /// The 5 stored bytes: a 40-bit little-endian word with `x1` in bits 0..9, `y1` in 9..18,
    /// `x2` in 18..27, `y2` in 27..36 and the level in 36..40. Fields must be in range.
    pub fn to_bytes(&self) -> [u8; 5] {
        let w: u64 = (self.x1 as u64 & 0x1ff)
            | (self.y1 as u64 & 0x1ff) << 9
            | (self.x2 as u64 & 0x1ff) << 18
            | (self.y2 as u64 & 0x1ff) << 27
            | (self.level as u64 & 0xf) << 36;
        let b = w.to_le_bytes();
        [b[0], b[1], b[2], b[3], b[4]]
    }

    /// Inverse of [`QVo::to_bytes`]; every 5-byte value decodes.
    pub fn from_bytes(b: [u8; 5]) -> QVo {
        let w = u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], 0, 0, 0]);
        QVo {
            x1: (w & 0x1ff) as u16,
            y1: (w >> 9 & 0x1ff) as u16,
            x2: (w >> 18 & 0x1ff) as u16,
            y2: (w >> 27 & 0x1ff) as u16,
            level: (w >> 36 & 0xf) as u8,
        }
    }

    /// Both endpoints the same grid point: a zero-length VO, which a decoder rejects.
    pub fn is_degenerate(&self) -> bool {
        self.x1 == self.x2 && self.y1 == self.y2
    }
}

/// A VO in the local frame: segment `a`–`b`, standing from `g` to `h`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoGeom {
    pub a: [f64; 2],
    pub b: [f64; 2],
    pub g: f64,
    pub h: f64,
}

/// A cell as rule 3 sees it: its rectangle `[x0, y0, x1, y1]` and eye heights, local frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellView {
    pub rect: [f64; 4],
    pub e0: f64,
    pub e1: f64,
}

impl Frame {
    /// Local height of ground level `level`.
    pub fn ground_z(&self, level: u8) -> f64 {
        self.ground_z0 + level as f64 * self.ground_step
    }

    /// Whether cells carry a ground byte.
    pub fn per_cell_ground(&self) -> bool {
        self.ground_step != 0.0
    }

    /// Centre of a cell, local frame.
    pub fn cell_centre(&self, id: CellId) -> Option<[f64; 2]> {
        let r = self.grid.cell_rect(id)?;
        Some([
            r[0] + 0.5 * self.grid.cell_size,
            r[1] + 0.5 * self.grid.cell_size,
        ])
    }

    /// The view of a cell standing on ground level `ground`.
    pub fn cell_view(&self, id: CellId, ground: u8) -> Option<CellView> {
        let rect = self.grid.cell_rect(id)?;
        let g = self.ground_z(ground);
        Some(CellView {
            rect,
            e0: g + self.eye_lo,
            e1: g + self.eye_hi,
        })
    }

    /// VO top of level `level` for a cell whose top eye is at `e1`.
    pub fn vo_top(&self, e1: f64, level: u8) -> f64 {
        e1 + self.h0 * (pow_u8(self.h_ratio, level) - 1.0)
    }

    /// Local coordinate of grid index `k` along an axis whose cell centre is `c`.
    pub fn coord(&self, c: f64, k: u16) -> f64 {
        c + (k as f64 - (QUANT_STEPS / 2) as f64) * self.quantum
    }

    /// The geometry of a stored VO of cell `id` standing on ground level `ground`.
    pub fn dequantize(&self, id: CellId, ground: u8, q: &QVo) -> Option<VoGeom> {
        let c = self.cell_centre(id)?;
        let g = self.ground_z(ground);
        Some(VoGeom {
            a: [self.coord(c[0], q.x1), self.coord(c[1], q.y1)],
            b: [self.coord(c[0], q.x2), self.coord(c[1], q.y2)],
            g,
            h: self.vo_top(g + self.eye_hi, q.level),
        })
    }
}

/// `r^k` by binary powering in plain IEEE operations: the bits `powi` gives when it runs
/// (compiler-rt's `__powidf2`, the same steps), in every build. `powi` itself may be folded
/// at compile time with another rounding where inlining makes `k` a constant, so a
/// whole-program build gave other VO tops, and other stores.
fn pow_u8(mut r: f64, mut k: u8) -> f64 {
    let mut acc = 1.0;
    loop {
        if k & 1 == 1 {
            acc *= r;
        }
        k >>= 1;
        if k == 0 {
            return acc;
        }
        r *= r;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn qvo_bytes_round_trip_and_pin_the_bit_layout() {
        let q = QVo {
            x1: 1,
            y1: 2,
            x2: 3,
            y2: 511,
            level: 15,
        };
        // 1 | 2<<9 | 3<<18 | 511<<27 | 15<<36
        assert_eq!(q.to_bytes(), [0x01, 0x04, 0x0c, 0xf8, 0xff]);
        assert_eq!(QVo::from_bytes(q.to_bytes()), q);
        for b in [[0u8; 5], [0xff; 5], [0x12, 0x34, 0x56, 0x78, 0x9a]] {
            assert_eq!(QVo::from_bytes(b).to_bytes(), b);
        }
    }

    #[test]
    fn vo_tops_power_as_powi_does_when_it_runs() {
        // `black_box` keeps `powi` from being folded here: this is the run-time `__powidf2`.
        for r in [1.0f64, 1.0625, 1.1, 1.25, 1.3333333333333333, 2.0, 0.9] {
            for k in 0..=u8::MAX {
                let want = std::hint::black_box(r).powi(std::hint::black_box(k as i32));
                assert_eq!(pow_u8(r, k).to_bits(), want.to_bits(), "{r}^{k}");
            }
        }
    }
}
