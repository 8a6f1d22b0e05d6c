//! The frame: what a decoder needs beside a cell's bytes to turn them into geometry.
//!
//! Input: a [`Frame`] (scene origin, grid, quantization and vertical frames, eye heights) and a
//! cell's quantized VOs. Output: each VO as a local segment with its height range [g, h], and the
//! cell's view (rectangle and eye heights) that rule 3 needs.
//! Invariants:
//! - a quantized endpoint is `centre + (k - 256) * quantum * 2^e` with `k` in `0..512` per axis
//!   and `e` in `0..8` ([`QPoint`]; store format 1 has `e = 0` only), where `centre` is the
//!   cell's centre; with a power-of-two quantum and a dyadic grid, every dequantized endpoint is
//!   exact in f64, so the bake's verifier checks exactly the segment the runtime uses;
//! - the VO top of level `k` (`0..32`; format 1: `0..16`) is `e1 + h0 * (h_ratio^k - 1)`, computed by one function
//!   ([`Frame::vo_top`]) that the bake also uses: the bake checks what the runtime will read;
//! - the VO bottom is the cell's ground `g` (or, for a deep VO of format 2.1, `ground_z0`), and
//!   the eyes stand at `g + eye_lo ..= g + rise * ground_step + eye_hi` (the rise of format 2.1;
//!   0 in 2.0).

use crate::runtime::grid::{CellId, GridDescriptor};

/// Mantissa steps per axis of a quantized endpoint: `x` and `y` in `0..QUANT_STEPS`, offset by
/// half (`x - 256`).
pub const QUANT_STEPS: u16 = 512;
/// Exponents of a quantized endpoint: `e` in `0..EXPONENTS` (store format 2; format 1 has `e = 0`
/// only).
pub const EXPONENTS: u8 = 8;
/// Height levels: `0..HEIGHT_LEVELS` (store format 2).
pub const HEIGHT_LEVELS: u8 = 32;
/// Height levels of store format 1: `0..HEIGHT_LEVELS_V1`.
pub const HEIGHT_LEVELS_V1: u8 = 16;
/// At most this many VOs per cell.
pub const MAX_VOS_PER_CELL: usize = 10;

/// Everything a decoder needs beside a cell's bytes (the "grid descriptor" of FORMAT.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// World position of the local origin: `world = local + origin`.
    pub origin: [f64; 3],
    /// The cell grid, in the local frame.
    pub grid: GridDescriptor,
    /// Finest step of the VO endpoint grid, metres (a power of two): an endpoint of exponent `e`
    /// lies on the grid of step `quantum * 2^e` around its cell's centre.
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

/// One quantized VO endpoint: the point `centre + (x - 256, y - 256) * quantum * 2^e` of its
/// cell. Precision follows distance: the step doubles with each exponent, so a far endpoint is
/// held to about the same angle, seen from the cell, as a near one (1/256 to 1/128 of its
/// distance along the larger axis).
///
/// A point is *canonical* when no smaller exponent holds it: `e == 0`, or `x - 256` or
/// `y - 256` lies outside `-128..128`. Every position has exactly one canonical form.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct QPoint {
    pub e: u8,
    pub x: u16,
    pub y: u16,
}

impl QPoint {
    /// A point of exponent 0 (the only form of store format 1).
    pub const fn fine(x: u16, y: u16) -> QPoint {
        QPoint { e: 0, x, y }
    }

    /// Whether every field lies in its range (`e < 8`, `x, y < 512`).
    pub fn in_range(&self) -> bool {
        self.e < EXPONENTS && self.x < QUANT_STEPS && self.y < QUANT_STEPS
    }

    /// Whether no smaller exponent holds the same position.
    pub fn is_canonical(&self) -> bool {
        let half = |v: u16| (128..384).contains(&v);
        self.e == 0 || !(half(self.x) && half(self.y))
    }

    /// The canonical form of the same position (fields in range).
    pub fn canonical(mut self) -> QPoint {
        while !self.is_canonical() {
            // `x - 256` in `-128..128`: twice that on the finer grid.
            self.x = 2 * self.x - 256;
            self.y = 2 * self.y - 256;
            self.e -= 1;
        }
        self
    }

    /// The offset from the cell's centre in units of the frame's quantum, exact.
    pub fn steps(&self) -> (i64, i64) {
        (
            (self.x as i64 - 256) << self.e,
            (self.y as i64 - 256) << self.e,
        )
    }

    /// The offset from the cell's centre, metres: exact in f64 for a power-of-two `quantum`.
    pub fn offset(&self, quantum: f64) -> [f64; 2] {
        let step = quantum * (1u32 << self.e) as f64;
        [
            (self.x as f64 - 256.0) * step,
            (self.y as f64 - 256.0) * step,
        ]
    }
}

/// One VO as stored: two endpoints, a height level and where its bottom stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct QVo {
    pub a: QPoint,
    pub b: QPoint,
    pub level: u8,
    /// Store format 2.1 (bit 47): the VO stands from the frame's lowest ground level
    /// (`ground_z0`) rather than from its cell's ground, so that it may hide what lies below the
    /// cell (downhill). Its supporters reach that low (rule 2; ARCHITECTURE.md, "Terrain").
    pub deep: bool,
}

/// Bytes of a VO in store format 2.
pub const VO_BYTES: usize = 6;
/// Bytes of a VO in store format 1.
pub const VO_BYTES_V1: usize = 5;

impl QVo {
    /// The 6 stored bytes of format 2: a 48-bit little-endian word with endpoint `a` in bits
    /// 0..21 (`e` 0..3, `x` 3..12, `y` 12..21), endpoint `b` in 21..42 (same layout), the level
    /// in 42..47, and bit 47 the deep flag (2.1; clear in 2.0). Fields must be in range.
    pub fn to_bytes(&self) -> [u8; VO_BYTES] {
        let p = |q: &QPoint| -> u64 {
            (q.e as u64 & 0x7) | (q.x as u64 & 0x1ff) << 3 | (q.y as u64 & 0x1ff) << 12
        };
        let w: u64 = p(&self.a)
            | p(&self.b) << 21
            | (self.level as u64 & 0x1f) << 42
            | (self.deep as u64) << 47;
        let b = w.to_le_bytes();
        [b[0], b[1], b[2], b[3], b[4], b[5]]
    }

    /// Inverse of [`QVo::to_bytes`] for every 6-byte value.
    pub fn from_bytes(b: [u8; VO_BYTES]) -> QVo {
        let w = u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], 0, 0]);
        let p = |v: u64| QPoint {
            e: (v & 0x7) as u8,
            x: (v >> 3 & 0x1ff) as u16,
            y: (v >> 12 & 0x1ff) as u16,
        };
        QVo {
            a: p(w),
            b: p(w >> 21),
            level: (w >> 42 & 0x1f) as u8,
            deep: w >> 47 & 1 == 1,
        }
    }

    /// Bit 47 of a format-2 VO: the deep flag of format 2.1, which a 2.0 decoder rejects.
    pub fn reserved_bit(b: [u8; VO_BYTES]) -> bool {
        b[5] & 0x80 != 0
    }

    /// The 5 stored bytes of format 1: a 40-bit little-endian word with `a.x` in bits 0..9,
    /// `a.y` in 9..18, `b.x` in 18..27, `b.y` in 27..36 and the level in 36..40. Only for a VO
    /// that format 1 can hold ([`QVo::fits_v1`]).
    pub fn to_bytes_v1(&self) -> [u8; VO_BYTES_V1] {
        let w: u64 = (self.a.x as u64 & 0x1ff)
            | (self.a.y as u64 & 0x1ff) << 9
            | (self.b.x as u64 & 0x1ff) << 18
            | (self.b.y as u64 & 0x1ff) << 27
            | (self.level as u64 & 0xf) << 36;
        let b = w.to_le_bytes();
        [b[0], b[1], b[2], b[3], b[4]]
    }

    /// Inverse of [`QVo::to_bytes_v1`]; every 5-byte value decodes (both exponents 0).
    pub fn from_bytes_v1(b: [u8; VO_BYTES_V1]) -> QVo {
        let w = u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], 0, 0, 0]);
        QVo {
            a: QPoint::fine((w & 0x1ff) as u16, (w >> 9 & 0x1ff) as u16),
            b: QPoint::fine((w >> 18 & 0x1ff) as u16, (w >> 27 & 0x1ff) as u16),
            level: (w >> 36 & 0xf) as u8,
            deep: false,
        }
    }

    /// Whether store format 1 can hold this VO: exponents 0, level below 16.
    pub fn fits_v1(&self) -> bool {
        self.a.e == 0 && self.b.e == 0 && self.level < HEIGHT_LEVELS_V1 && !self.deep
    }

    /// Whether every field lies in its range (format 2).
    pub fn in_range(&self) -> bool {
        self.a.in_range() && self.b.in_range() && self.level < HEIGHT_LEVELS
    }

    /// Whether both endpoints are canonical ([`QPoint::is_canonical`]).
    pub fn is_canonical(&self) -> bool {
        self.a.is_canonical() && self.b.is_canonical()
    }

    /// Both endpoints at the same position: a zero-length VO, which a decoder rejects.
    pub fn is_degenerate(&self) -> bool {
        self.a.steps() == self.b.steps()
    }
}

/// Where a cell stands: its ground level and rise (`CellRecord::Vos`), what
/// [`crate::runtime::Frame::cell_view`] and [`crate::runtime::Frame::dequantize`] need. A bare
/// level converts to it with rise 0.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct CellGround {
    pub level: u8,
    pub rise: u8,
}

impl From<u8> for CellGround {
    fn from(level: u8) -> CellGround {
        CellGround { level, rise: 0 }
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

    /// The view of a cell standing on `ground` (a level, or a level and a rise): its eyes
    /// from `g + eye_lo` to `g + rise * ground_step + eye_hi`, `g` the level's height.
    pub fn cell_view(&self, id: CellId, ground: impl Into<CellGround>) -> Option<CellView> {
        let s = ground.into();
        let rect = self.grid.cell_rect(id)?;
        let g = self.ground_z(s.level);
        Some(CellView {
            rect,
            e0: g + self.eye_lo,
            e1: self.top_eye(s),
        })
    }

    /// The top eye of a cell standing on `s`: `ground_z(level) + rise * ground_step + eye_hi`.
    pub fn top_eye(&self, s: CellGround) -> f64 {
        self.ground_z(s.level) + s.rise as f64 * self.ground_step + self.eye_hi
    }

    /// VO top of level `level` for a cell whose top eye is at `e1`.
    pub fn vo_top(&self, e1: f64, level: u8) -> f64 {
        e1 + self.h0 * (pow_u8(self.h_ratio, level) - 1.0)
    }

    /// The geometry of a stored VO of cell `id` standing on `ground` (a level, or a level and a
    /// rise): from the cell's ground, or from `ground_z0` for a deep VO (format 2.1), to the top
    /// of its level above the cell's top eye.
    pub fn dequantize(&self, id: CellId, ground: impl Into<CellGround>, q: &QVo) -> Option<VoGeom> {
        let s = ground.into();
        let c = self.cell_centre(id)?;
        let g = self.ground_z(s.level);
        Some(VoGeom {
            a: add(c, q.a.offset(self.quantum)),
            b: add(c, q.b.offset(self.quantum)),
            g: if q.deep { self.ground_z0 } else { g },
            h: self.vo_top(self.top_eye(s), q.level),
        })
    }
}

fn add(c: [f64; 2], d: [f64; 2]) -> [f64; 2] {
    [c[0] + d[0], c[1] + d[1]]
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
            a: QPoint { e: 1, x: 2, y: 3 },
            b: QPoint { e: 7, x: 511, y: 4 },
            level: 31,
            deep: false,
        };
        // 1 | 2<<3 | 3<<12 | (7 | 511<<3 | 4<<12)<<21 | 31<<42
        let w: u64 = 1 | 2 << 3 | 3 << 12 | (7 | 511 << 3 | 4 << 12) << 21 | 31 << 42;
        assert_eq!(q.to_bytes()[..], w.to_le_bytes()[..6]);
        assert_eq!(q.to_bytes(), [0x11, 0x30, 0xe0, 0xff, 0x09, 0x7c]);
        assert_eq!(QVo::from_bytes(q.to_bytes()), q);
        assert!(!QVo::reserved_bit(q.to_bytes()));
        for b in [
            [0u8; 6],
            [0xff, 0xff, 0xff, 0xff, 0xff, 0x7f],
            [0x12, 0x34, 0x56, 0x78, 0x9a, 0x3c],
        ] {
            assert_eq!(QVo::from_bytes(b).to_bytes(), b);
        }
        assert!(QVo::reserved_bit([0, 0, 0, 0, 0, 0x80]));
        let deep = QVo { deep: true, ..q };
        assert_eq!(deep.to_bytes(), [0x11, 0x30, 0xe0, 0xff, 0x09, 0xfc]);
        assert_eq!(QVo::from_bytes(deep.to_bytes()), deep);
    }

    #[test]
    fn qvo_v1_bytes_round_trip_and_pin_the_bit_layout() {
        let q = QVo {
            a: QPoint::fine(1, 2),
            b: QPoint::fine(3, 511),
            level: 15,
            deep: false,
        };
        // 1 | 2<<9 | 3<<18 | 511<<27 | 15<<36
        assert_eq!(q.to_bytes_v1(), [0x01, 0x04, 0x0c, 0xf8, 0xff]);
        assert_eq!(QVo::from_bytes_v1(q.to_bytes_v1()), q);
        for b in [[0u8; 5], [0xff; 5], [0x12, 0x34, 0x56, 0x78, 0x9a]] {
            assert_eq!(QVo::from_bytes_v1(b).to_bytes_v1(), b);
            assert!(QVo::from_bytes_v1(b).fits_v1());
        }
    }

    #[test]
    fn every_position_has_one_canonical_point() {
        // Every point of exponents 0..3 over a coarse lattice of mantissas: its canonical form
        // holds the same position, and two canonical points are equal exactly when their
        // positions are.
        let mut seen = std::collections::HashMap::new();
        for e in 0..3u8 {
            for x in (0..512u16).step_by(7) {
                for y in (0..512u16).step_by(11) {
                    let p = QPoint { e, x, y };
                    let c = p.canonical();
                    assert!(c.in_range() && c.is_canonical());
                    assert_eq!(c.steps(), p.steps());
                    assert_eq!(c.offset(0.25), p.offset(0.25));
                    if let Some(old) = seen.insert(p.steps(), c) {
                        assert_eq!(old, c);
                    }
                }
            }
        }
        assert!(!QPoint {
            e: 1,
            x: 128,
            y: 383
        }
        .is_canonical());
        assert!(QPoint {
            e: 1,
            x: 127,
            y: 256
        }
        .is_canonical());
        assert!(QPoint {
            e: 1,
            x: 256,
            y: 384
        }
        .is_canonical());
        // (-56, 44) steps of 4: (-112, 88) of 2, both under 128, so (-224, 176) of 1.
        let p = |e, x, y| QPoint { e, x, y };
        assert_eq!(p(2, 200, 300).canonical(), p(0, 32, 432));
        // (-76, 44) of 4: (-152, 88) of 2, which is canonical.
        assert_eq!(p(2, 180, 300).canonical(), p(1, 104, 344));
    }

    #[test]
    fn endpoints_dequantize_exactly_at_every_exponent() {
        let f = Frame {
            origin: [0.0; 3],
            grid: GridDescriptor {
                min_x: 0.0,
                min_y: 0.0,
                cell_size: 100.0,
                nx: 3,
                ny: 3,
            },
            quantum: 0.25,
            eye_lo: 1.5,
            eye_hi: 2.0,
            ground_z0: 0.0,
            ground_step: 0.0,
            h0: 2.0,
            h_ratio: 1.25,
        };
        // Cell 4 is the centre one, centred at (150, 150).
        let q = QVo {
            a: QPoint { e: 0, x: 0, y: 511 },
            b: QPoint { e: 7, x: 511, y: 0 },
            level: 0,
            deep: false,
        };
        let g = f.dequantize(4, 0, &q).unwrap();
        assert_eq!(g.a, [150.0 - 64.0, 150.0 + 63.75]);
        assert_eq!(g.b, [150.0 + 255.0 * 32.0, 150.0 - 256.0 * 32.0]);
        assert_eq!(g.h, 2.0);
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
