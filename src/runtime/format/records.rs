//! Cell records, the unit the store's payload and the blob share (FORMAT.md sections 5.3 and
//! 5.5): one cell's ground level and at most 10 VOs, or "skipped".
//!
//! Input: a record's bytes, its index value and the major of its store or blob (decoding), or a
//! [`CellRecord`] (encoding, 2.0). Output: the record, its size, its bytes.
//! Invariants: a record is a fixed-size value ([`VoList`] holds its VOs inline, no heap), the
//! same whatever the major of its bytes (a 1.0 VO has exponents 0); `record_size` is the one
//! place that says how many payload bytes a count takes; decoding rejects, VO by VO, a reserved
//! bit set (2.0), a non-canonical endpoint (2.0) and a degenerate VO, in that order; encoding
//! also a field out of range or an unstored ground level.

use std::fmt;
use std::ops::Deref;

use super::{FormatError, Reader, Version, SKIPPED, VO_BYTES, VO_BYTES_V1};
pub use crate::runtime::frame::CellGround;
use crate::runtime::frame::{QPoint, QVo, MAX_VOS_PER_CELL};
use crate::runtime::grid::CellId;

const NO_VO: QVo = QVo {
    a: QPoint::fine(0, 0),
    b: QPoint::fine(0, 0),
    level: 0,
    deep: false,
};

/// At most [`MAX_VOS_PER_CELL`] VOs, inline (no heap). Dereferences to `&[QVo]`.
#[derive(Clone, Copy)]
pub struct VoList {
    vos: [QVo; MAX_VOS_PER_CELL],
    len: u8,
}

impl VoList {
    /// The empty list.
    pub const fn new() -> VoList {
        VoList {
            vos: [NO_VO; MAX_VOS_PER_CELL],
            len: 0,
        }
    }

    /// The list of `vos`, or [`FormatError::TooManyVos`] past [`MAX_VOS_PER_CELL`].
    pub fn from_slice(vos: &[QVo]) -> Result<VoList, FormatError> {
        let mut l = VoList::new();
        for &q in vos {
            l.push(q)
                .map_err(|_| FormatError::TooManyVos { count: vos.len() })?;
        }
        Ok(l)
    }

    /// Appends `q`, or refuses when the list is full.
    pub fn push(&mut self, q: QVo) -> Result<(), FormatError> {
        let slot = self
            .vos
            .get_mut(self.len as usize)
            .ok_or(FormatError::TooManyVos {
                count: self.len as usize + 1,
            })?;
        *slot = q;
        self.len += 1;
        Ok(())
    }

    pub fn as_slice(&self) -> &[QVo] {
        self.vos.get(..self.len as usize).unwrap_or(&[])
    }
}

impl Default for VoList {
    fn default() -> Self {
        VoList::new()
    }
}

impl Deref for VoList {
    type Target = [QVo];
    fn deref(&self) -> &[QVo] {
        self.as_slice()
    }
}

impl PartialEq for VoList {
    fn eq(&self, other: &Self) -> bool {
        self.as_slice() == other.as_slice()
    }
}

impl Eq for VoList {}

impl fmt::Debug for VoList {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.as_slice()).finish()
    }
}

/// One cell's stored content.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellRecord {
    /// The cell lies inside a building: no VOs, no ground (index value 255).
    Skipped,
    /// The cell's ground level (0 when the frame's ground is flat, and for a cell without VOs,
    /// whose ground is not stored), its rise (format 2.1: the cell's top eye stands `rise`
    /// ground steps higher, a camera on a slope; 0 in 2.0) and its VOs, most effective first.
    Vos { ground: u8, rise: u8, vos: VoList },
}

/// Index values `RISE_BASE + n` (`n` in `1..=10`) announce `n` VOs after a ground byte and a
/// rise byte (format 2.1).
pub const RISE_BASE: u8 = 10;

impl CellRecord {
    /// A cell without VOs.
    pub const EMPTY: CellRecord = CellRecord::Vos {
        ground: 0,
        rise: 0,
        vos: VoList::new(),
    };

    /// The record of `vos` on ground level `ground`.
    pub fn new(ground: u8, vos: &[QVo]) -> Result<CellRecord, FormatError> {
        Ok(CellRecord::Vos {
            ground,
            rise: 0,
            vos: VoList::from_slice(vos)?,
        })
    }

    /// The same record with its top eye `rise` ground steps higher (format 2.1).
    pub fn with_rise(self, rise: u8) -> CellRecord {
        match self {
            CellRecord::Vos { ground, vos, .. } => CellRecord::Vos { ground, rise, vos },
            s => s,
        }
    }

    /// The rise (0 for a skipped cell, and in 2.0).
    pub fn rise(&self) -> u8 {
        match self {
            CellRecord::Skipped => 0,
            CellRecord::Vos { rise, .. } => *rise,
        }
    }

    /// Where the cell stands: its ground level and rise.
    pub fn stand(&self) -> CellGround {
        CellGround {
            level: self.ground(),
            rise: self.rise(),
        }
    }

    /// The VOs (none for a skipped cell).
    pub fn vos(&self) -> &[QVo] {
        match self {
            CellRecord::Skipped => &[],
            CellRecord::Vos { vos, .. } => vos.as_slice(),
        }
    }

    /// The ground level (0 for a skipped cell).
    pub fn ground(&self) -> u8 {
        match self {
            CellRecord::Skipped => 0,
            CellRecord::Vos { ground, .. } => *ground,
        }
    }

    /// The cell's index value: its VO count, or [`SKIPPED`].
    pub fn index_byte(&self) -> u8 {
        match self {
            CellRecord::Skipped => SKIPPED,
            CellRecord::Vos { vos, rise, .. } if *rise > 0 && !vos.is_empty() => {
                RISE_BASE + vos.len() as u8
            }
            CellRecord::Vos { vos, .. } => vos.len() as u8,
        }
    }

    /// The bytes the record takes in a 2.x store: its index byte, and its payload record
    /// (section 5.5: a ground byte when `ground_byte`, a rise byte, 6 bytes per VO) when it
    /// has VOs.
    pub fn stored_len(&self, ground_byte: bool) -> u64 {
        match self {
            CellRecord::Skipped => 1,
            CellRecord::Vos { .. } => 1 + record_size(self.index_byte(), ground_byte, Version::V2),
        }
    }
}

/// The record a valid index value announces, as the value itself (`0` for none, `1..=10` VOs,
/// and in 2.1, with a ground byte, `11..=20`: `value - 10` VOs after a rise byte); `None` for a
/// value the store or blob cannot hold.
pub(super) fn count_of(value: u8, version: Version, ground_byte: bool) -> Option<u8> {
    match value {
        SKIPPED => Some(0),
        v if v as usize <= MAX_VOS_PER_CELL => Some(v),
        v if version == Version::V2
            && ground_byte
            && v > RISE_BASE
            && (v - RISE_BASE) as usize <= MAX_VOS_PER_CELL =>
        {
            Some(v)
        }
        _ => None,
    }
}

/// VOs and whether a rise byte is stored, for a value [`count_of`] gave.
fn split(v: u8) -> (u8, bool) {
    if v > RISE_BASE {
        (v - RISE_BASE, true)
    } else {
        (v, false)
    }
}

/// Payload bytes of a cell whose [`count_of`] is `v` in a store or blob of `version`.
pub(super) fn record_size(v: u8, ground_byte: bool, version: Version) -> u64 {
    let (n, rise) = split(v);
    if n == 0 {
        0
    } else {
        n as u64 * version.vo_bytes() as u64 + ground_byte as u64 + rise as u64
    }
}

/// Decodes one record whose [`count_of`] is `v` (at least one VO) of `version` from exactly its
/// bytes; `offset` is where `bytes` starts in the file or blob (for errors).
pub(super) fn read_record(
    cell: CellId,
    v: u8,
    ground_byte: bool,
    version: Version,
    bytes: &[u8],
    offset: u64,
) -> Result<CellRecord, FormatError> {
    let short = || FormatError::Truncated {
        needed: offset + record_size(v, ground_byte, version),
        got: offset + bytes.len() as u64,
    };
    let (n, has_rise) = split(v);
    let mut r = Reader::new(bytes);
    let ground = if ground_byte {
        r.u8().ok_or_else(short)?
    } else {
        0
    };
    let rise = if has_rise {
        r.u8().ok_or_else(short)?
    } else {
        0
    };
    // S22/B14 (2.1): a rise byte of 0, or a top eye above ground level 255.
    if has_rise && (rise == 0 || ground as u16 + rise as u16 > 255) {
        return Err(FormatError::BadRise {
            cell,
            ground,
            rise,
            offset: offset + 1,
        });
    }
    let mut vos = VoList::new();
    for k in 0..n {
        let at =
            offset + ground_byte as u64 + has_rise as u64 + k as u64 * version.vo_bytes() as u64;
        let q = match version {
            Version::V1 => QVo::from_bytes_v1(r.take::<VO_BYTES_V1>().ok_or_else(short)?),
            Version::V2 => {
                // Bit 47 is the deep flag of 2.1 (FORMAT.md 3.1), read by this decoder.
                QVo::from_bytes(r.take::<VO_BYTES>().ok_or_else(short)?)
            }
        };
        check_vo(cell, k, &q, at)?;
        vos.push(q)?;
    }
    Ok(CellRecord::Vos { ground, rise, vos })
}

/// The checks both a decoder and the encoder make of a VO whose fields are in range: its
/// endpoints canonical (S19/B12; always so in 1.0, whose exponents are 0), then not degenerate
/// (S13/B9). `offset` is where its bytes start.
fn check_vo(cell: CellId, vo: u8, q: &QVo, offset: u64) -> Result<(), FormatError> {
    if !q.is_canonical() {
        return Err(FormatError::NonCanonicalVo {
            cell,
            vo,
            offset,
            endpoint: if q.a.is_canonical() { 'b' } else { 'a' },
        });
    }
    if q.is_degenerate() {
        return Err(FormatError::DegenerateVo { cell, vo, offset });
    }
    Ok(())
}

/// Checks one record for encoding (2.0) and returns its payload size. `offset` is where the
/// record will start (for errors).
pub(super) fn check_record(
    cell: CellId,
    rec: &CellRecord,
    ground_byte: bool,
    offset: u64,
) -> Result<u64, FormatError> {
    let CellRecord::Vos { ground, rise, vos } = rec else {
        return Ok(0);
    };
    if (*ground != 0 || *rise != 0) && (vos.is_empty() || !ground_byte) {
        return Err(FormatError::GroundNotStored {
            cell,
            ground: *ground,
        });
    }
    if *ground as u16 + *rise as u16 > 255 {
        return Err(FormatError::BadRise {
            cell,
            ground: *ground,
            rise: *rise,
            offset: offset + 1,
        });
    }
    let has_rise = *rise > 0;
    for (k, q) in vos.iter().enumerate() {
        let k8 = k as u8;
        if !q.in_range() {
            return Err(FormatError::VoOutOfRange { cell, vo: k8 });
        }
        check_vo(
            cell,
            k8,
            q,
            offset + ground_byte as u64 + has_rise as u64 + (k * VO_BYTES) as u64,
        )?;
    }
    Ok(record_size(rec.index_byte(), ground_byte, Version::V2))
}

/// Appends a record checked by [`check_record`], in 2.0 (6-byte VOs).
pub(super) fn push_record(out: &mut Vec<u8>, rec: &CellRecord, ground_byte: bool) {
    if let CellRecord::Vos { ground, rise, vos } = rec {
        if !vos.is_empty() {
            if ground_byte {
                out.push(*ground);
            }
            if *rise > 0 {
                out.push(*rise);
            }
            for q in vos.iter() {
                out.extend_from_slice(&q.to_bytes());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::q;
    use super::*;

    #[test]
    fn vo_list_holds_at_most_ten() {
        let v = q(1, 2, 3, 4, 5);
        let mut l = VoList::new();
        for _ in 0..MAX_VOS_PER_CELL {
            l.push(v).unwrap();
        }
        assert_eq!(l.len(), 10);
        assert_eq!(l.push(v), Err(FormatError::TooManyVos { count: 11 }));
        assert_eq!(
            VoList::from_slice(&[v; 11]),
            Err(FormatError::TooManyVos { count: 11 })
        );
        // Equality looks at the VOs only.
        let mut a = VoList::from_slice(&[v, v]).unwrap();
        let b = VoList::from_slice(&[v]).unwrap();
        assert_ne!(a, b);
        a.len = 1;
        assert_eq!(a, b);
    }
}
