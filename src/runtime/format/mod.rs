//! The three wire forms of `docs/FORMAT.md` (version 2.0; 1.0 still read): the frame's 112
//! bytes ([`frame`]), the store file ([`store`]) and the cell blob ([`blob`]), with the cell
//! records they share ([`records`]). This module holds what all of them use: the constants, the
//! version table, the error type and the checked reader.
//!
//! Input: untrusted bytes (a store file, a cell blob, a frame), or, to encode, a [`Frame`],
//! [`CellRecord`]s and a [`SceneSection`]. Output: a borrowed [`Store`] that answers per-cell
//! queries, decoded cell records, or the encoded bytes.
//! Invariants:
//! - decoding never panics and never reads outside its input: every read goes through
//!   `get`/`split_*_checked`, every length is computed in `u64` with sizes bounded by the frame
//!   rules (at most 2^31 cells), nothing is indexed by a value read from the input;
//! - decoding never allocates: [`Store::parse`] borrows the bytes (the CRS name too), records
//!   are fixed-size values ([`VoList`] holds at most [`MAX_VOS_PER_CELL`] VOs inline);
//! - one decoder reads both majors: a 1.0 VO (5 bytes) comes out as the [`QVo`] of 2.0 with
//!   exponents 0, so a record is the same value whatever the major of its bytes;
//! - a decoder checks the rules in the order of FORMAT.md section 8 and reports the first
//!   violation, naming the rule and where it is ([`FormatError`]);
//! - the encoders write 2.0 only, and only what the decoder accepts; encoding is canonical: an
//!   accepted 2.0 store re-encodes to the same bytes (minor version and checksum aside), an
//!   accepted 1.0 store to the 2.0 store of the same records with an empty scene section.
//!
//! [`Frame`]: crate::runtime::frame::Frame
//! [`QVo`]: crate::runtime::frame::QVo
//! [`MAX_VOS_PER_CELL`]: crate::runtime::frame::MAX_VOS_PER_CELL

use thiserror::Error;

use crate::runtime::frame::{HEIGHT_LEVELS, HEIGHT_LEVELS_V1, MAX_VOS_PER_CELL};
use crate::runtime::grid::CellId;

pub use crate::runtime::frame::{VO_BYTES, VO_BYTES_V1};

pub mod blob;
pub mod frame;
pub mod records;
pub mod store;

pub use blob::{decode_blob, encode_blob};
pub use frame::{decode_frame, encode_frame, validate_frame};
pub use records::{CellGround, CellRecord, VoList};
pub use store::{encode_store, encode_store_with, OwnedStore, SceneSection, Store};

/// Length of an encoded [`Frame`].
pub const FRAME_LEN: usize = 112;
/// First 8 bytes of a store file: 0x89, "VOCC", CR, LF, 0x1A.
pub const STORE_MAGIC: [u8; 8] = [0x89, b'V', b'O', b'C', b'C', 0x0D, 0x0A, 0x1A];
/// First 4 bytes of a cell blob: "VOCB".
pub const BLOB_MAGIC: [u8; 4] = *b"VOCB";
/// The major version this module writes (it reads [`MAJOR`] and [`MAJOR_V1`]).
pub const MAJOR: u16 = 2;
/// The older major version this module still reads (FORMAT.md section 12).
pub const MAJOR_V1: u16 = 1;
/// The minor version this module writes for a store without deep VOs (it reads every minor of
/// both majors).
pub const MINOR: u16 = 0;
/// The minor version of a store that holds a deep VO (bit 47, FORMAT.md 3.1): 2.1.
pub const MINOR_DEEP: u16 = 1;
/// Length of a store file's header.
pub const HEADER_LEN: usize = 136;
/// Length of the fixed part of a 2.0 store's scene section (`objects`, `scene`, `crs_len`),
/// which starts right after the header; `crs_len` bytes of CRS name follow it.
pub const SCENE_FIXED_LEN: usize = 13;
/// Longest CRS name a 2.0 store holds, bytes.
pub const MAX_CRS_LEN: usize = 255;
/// Length of a blob without a record (an empty or skipped cell).
pub const BLOB_MIN_LEN: usize = 14;
/// Cells per entry of the block table.
pub const CELLS_PER_BLOCK: u32 = 64;
/// Index value of a skipped cell (inside a building).
pub const SKIPPED: u8 = 0xFF;
/// Most cells a grid may have (frame rule F4).
pub const MAX_CELLS: u64 = 1 << 31;

const CRC_OFFSET: usize = 132;
const BLOB_COUNT_OFFSET: u64 = 9;
const BLOB_RECORD_OFFSET: u64 = 10;

/// The majors a decoder reads, and what differs between them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Version {
    /// 1.0: 5-byte VOs (exponents 0, levels 0..16), no scene section.
    V1,
    /// 2.0: 6-byte VOs (exponents 0..8, levels 0..32), a scene section after the header.
    V2,
}

impl Version {
    /// The version of a major, or `None` for a major this module does not read.
    pub(crate) fn of(major: u16) -> Option<Version> {
        match major {
            MAJOR_V1 => Some(Version::V1),
            MAJOR => Some(Version::V2),
            _ => None,
        }
    }

    pub(crate) fn major(self) -> u16 {
        match self {
            Version::V1 => MAJOR_V1,
            Version::V2 => MAJOR,
        }
    }

    /// Bytes per stored VO.
    pub(crate) fn vo_bytes(self) -> usize {
        match self {
            Version::V1 => VO_BYTES_V1,
            Version::V2 => VO_BYTES,
        }
    }

    /// The highest height level a VO of this major can hold (frame rule F12 checks its top).
    pub(crate) fn top_level(self) -> u8 {
        match self {
            Version::V1 => HEIGHT_LEVELS_V1 - 1,
            Version::V2 => HEIGHT_LEVELS - 1,
        }
    }
}

/// Why bytes were refused (decoders) or could not be written (encoders). Offsets are in bytes
/// from the start of the store file or blob.
#[derive(Clone, Debug, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum FormatError {
    #[error("truncated: {needed} bytes needed, {got} given")]
    Truncated { needed: u64, got: u64 },
    #[error("trailing bytes: {expected} bytes expected, {got} given")]
    TrailingBytes { expected: u64, got: u64 },
    #[error("bad magic number: not a vocc store or blob")]
    BadMagic,
    #[error("unsupported major version {major} (this reader implements {MAJOR_V1} and {MAJOR})")]
    UnsupportedVersion { major: u16 },
    #[error(
        "unknown flags {flags:#010x} at offset 12 (every bit is reserved in versions 1.0 and 2.0)"
    )]
    UnknownFlags { flags: u32 },
    #[error("bad frame: rule {0}")]
    BadFrame(&'static str),
    #[error("checksum mismatch: stored {stored:#010x}, computed {computed:#010x}")]
    Checksum { stored: u32, computed: u32 },
    #[error("bad count {value} for cell {cell} at offset {offset} (0..=10 VOs or 255 skipped)")]
    BadIndexByte {
        cell: CellId,
        value: u8,
        offset: u64,
    },
    #[error("block table entry {block} is {stored}, the counts before it give {expected}")]
    BlockOffset {
        block: u32,
        stored: u32,
        expected: u64,
    },
    #[error("payload_len is {stored}, the counts give {expected}")]
    PayloadLength { stored: u32, expected: u64 },
    #[error("VO {vo} of cell {cell} at offset {offset} is degenerate (one grid point)")]
    DegenerateVo { cell: CellId, vo: u8, offset: u64 },
    /// Rule S18 (store) / B11 (blob): bit 47 of a 2.0 VO is reserved.
    #[error("VO {vo} of cell {cell} at offset {offset} sets the reserved bit 47")]
    ReservedVoBit { cell: CellId, vo: u8, offset: u64 },
    /// Rule S19 (store) / B12 (blob): an endpoint (`'a'` or `'b'`) that a smaller exponent
    /// holds; every position has one encoding.
    #[error("VO {vo} of cell {cell} at offset {offset}: endpoint {endpoint} is not canonical (a smaller exponent holds it)")]
    NonCanonicalVo {
        cell: CellId,
        vo: u8,
        offset: u64,
        endpoint: char,
    },
    /// Rule S17: the scene section's CRS name is not UTF-8; `offset` is the first byte that is
    /// not part of a valid sequence.
    #[error("the CRS name is not UTF-8 (at offset {offset})")]
    CrsNotUtf8 { offset: u64 },
    #[error("cell {id} is outside the grid of {cells} cells")]
    CellOutOfGrid { id: CellId, cells: u64 },
    #[error("{got} cell records given for a grid of {expected} cells")]
    CellCount { expected: u64, got: u64 },
    #[error("{count} VOs in one cell; at most {MAX_VOS_PER_CELL}")]
    TooManyVos { count: usize },
    #[error("VO {vo} of cell {cell} has a field out of range (exponents 0..8, coordinates 0..512, level 0..32)")]
    VoOutOfRange { cell: CellId, vo: u8 },
    #[error("a CRS name of {len} bytes; at most {MAX_CRS_LEN}")]
    CrsTooLong { len: usize },
    #[error("cell {cell} has ground level {ground}, but no ground byte is stored for it")]
    GroundNotStored { cell: CellId, ground: u8 },
    #[error("payload of {len} bytes does not fit the u32 payload_len")]
    PayloadTooLarge { len: u64 },
    /// 2.1: a cell's rise byte (at `offset`) is 0, or puts its top eye above ground level 255.
    #[error("cell {cell}'s rise {rise} at offset {offset} is 0 or takes its ground level {ground} past 255")]
    BadRise {
        cell: CellId,
        ground: u8,
        rise: u8,
        offset: u64,
    },
}

// ---------------------------------------------------------------------------------------------
// Reading helpers: every read is checked.

struct Reader<'a> {
    rest: &'a [u8],
}

impl<'a> Reader<'a> {
    fn new(bytes: &'a [u8]) -> Reader<'a> {
        Reader { rest: bytes }
    }
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let (h, t) = self.rest.split_first_chunk::<N>()?;
        self.rest = t;
        Some(*h)
    }
    fn u8(&mut self) -> Option<u8> {
        self.take::<1>().map(|b| b[0])
    }
    fn u16(&mut self) -> Option<u16> {
        self.take().map(u16::from_le_bytes)
    }
    fn u32(&mut self) -> Option<u32> {
        self.take().map(u32::from_le_bytes)
    }
    fn u64(&mut self) -> Option<u64> {
        self.take().map(u64::from_le_bytes)
    }
    fn f64(&mut self) -> Option<f64> {
        self.take().map(f64::from_le_bytes)
    }
}

fn u32_at(bytes: &[u8], at: u64) -> Option<u32> {
    let at = usize::try_from(at).ok()?;
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes(b.try_into().ok()?))
}

/// `got` bytes where exactly `expected` are needed: too few is `Truncated`, too many
/// `TrailingBytes`.
fn exact_length(expected: u64, got: u64) -> Result<(), FormatError> {
    if got < expected {
        return Err(FormatError::Truncated {
            needed: expected,
            got,
        });
    }
    if got > expected {
        return Err(FormatError::TrailingBytes { expected, got });
    }
    Ok(())
}

#[cfg(test)]
mod test_util {
    use crate::runtime::frame::{Frame, QPoint, QVo};
    use crate::runtime::grid::GridDescriptor;

    pub(super) fn frame(ground_step: f64, nx: u32, ny: u32) -> Frame {
        Frame {
            origin: [843000.0, 6518000.0, 0.0],
            grid: GridDescriptor {
                min_x: 0.0,
                min_y: 0.0,
                cell_size: 100.0,
                nx,
                ny,
            },
            quantum: 0.5,
            eye_lo: 1.5,
            eye_hi: 2.0,
            ground_z0: 160.0,
            ground_step,
            h0: 4.0,
            h_ratio: 1.25,
        }
    }

    pub(super) fn q(x1: u16, y1: u16, x2: u16, y2: u16, level: u8) -> QVo {
        QVo {
            a: QPoint::fine(x1, y1),
            b: QPoint::fine(x2, y2),
            level,
            deep: false,
        }
    }
}
