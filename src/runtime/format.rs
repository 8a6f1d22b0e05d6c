//! The store file, the cell blob and the frame's 112 bytes: decoders and encoders
//! (specification: `docs/FORMAT.md`, version 1.0).
//!
//! Input: untrusted bytes (a store file, a cell blob, a frame), or, to encode, a [`Frame`] and
//! [`CellRecord`]s. Output: a borrowed [`Store`] that answers per-cell queries, decoded cell
//! records, or the encoded bytes.
//! Invariants:
//! - decoding never panics and never reads outside its input: every read goes through
//!   `get`/`split_*_checked`, every length is computed in `u64` with sizes bounded by the frame
//!   rules (at most 2^31 cells), nothing is indexed by a value read from the input;
//! - decoding never allocates: [`Store::parse`] borrows the bytes, records are fixed-size values
//!   ([`VoList`] holds at most [`MAX_VOS_PER_CELL`] VOs inline);
//! - a decoder checks the rules in the order of FORMAT.md section 8 and reports the first
//!   violation, naming the rule and where it is ([`FormatError`]);
//! - the encoder writes only what the decoder accepts, and encoding is canonical: an accepted
//!   store re-encodes to the same bytes (minor version and checksum aside).

use std::fmt;
use std::ops::Deref;

use thiserror::Error;

use crate::runtime::crc::{crc32, Crc32};
use crate::runtime::frame::{Frame, QVo, HEIGHT_LEVELS, MAX_VOS_PER_CELL, QUANT_STEPS};
use crate::runtime::grid::{CellId, GridDescriptor};

/// Length of an encoded [`Frame`].
pub const FRAME_LEN: usize = 112;
/// First 8 bytes of a store file: 0x89, "VOCC", CR, LF, 0x1A.
pub const STORE_MAGIC: [u8; 8] = [0x89, b'V', b'O', b'C', b'C', 0x0D, 0x0A, 0x1A];
/// First 4 bytes of a cell blob: "VOCB".
pub const BLOB_MAGIC: [u8; 4] = *b"VOCB";
/// The major version this module reads and writes.
pub const MAJOR: u16 = 1;
/// The minor version this module writes (it reads every minor of [`MAJOR`]).
pub const MINOR: u16 = 0;
/// Length of a store file's header.
pub const HEADER_LEN: usize = 136;
/// Length of a blob without a record (an empty or skipped cell).
pub const BLOB_MIN_LEN: usize = 14;
/// Cells per entry of the block table.
pub const CELLS_PER_BLOCK: u32 = 64;
/// Index value of a skipped cell (inside a building).
pub const SKIPPED: u8 = 0xFF;
/// Bytes per stored VO.
pub const VO_BYTES: usize = 5;
/// Most cells a grid may have (frame rule F4).
pub const MAX_CELLS: u64 = 1 << 31;

const CRC_OFFSET: usize = 132;
const BLOB_COUNT_OFFSET: u64 = 9;
const BLOB_RECORD_OFFSET: u64 = 10;

/// Why bytes were refused (decoders) or could not be written (encoders). Offsets are in bytes
/// from the start of the store file or blob.
#[derive(Clone, Debug, PartialEq, Eq, Error)]
pub enum FormatError {
    #[error("truncated: {needed} bytes needed, {got} given")]
    Truncated { needed: u64, got: u64 },
    #[error("trailing bytes: {expected} bytes expected, {got} given")]
    TrailingBytes { expected: u64, got: u64 },
    #[error("bad magic number: not a vocc store or blob")]
    BadMagic,
    #[error("unsupported major version {major} (this reader implements {MAJOR})")]
    UnsupportedVersion { major: u16 },
    #[error("unknown flags {flags:#010x} at offset 12 (every bit is reserved in version 1.0)")]
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
    #[error("cell {id} is outside the grid of {cells} cells")]
    CellOutOfGrid { id: CellId, cells: u64 },
    #[error("{got} cell records given for a grid of {expected} cells")]
    CellCount { expected: u64, got: u64 },
    #[error("{count} VOs in one cell; at most {MAX_VOS_PER_CELL}")]
    TooManyVos { count: usize },
    #[error("VO {vo} of cell {cell} has a field out of range (coordinates 0..512, level 0..16)")]
    VoOutOfRange { cell: CellId, vo: u8 },
    #[error("cell {cell} has ground level {ground}, but no ground byte is stored for it")]
    GroundNotStored { cell: CellId, ground: u8 },
    #[error("payload of {len} bytes does not fit the u32 payload_len")]
    PayloadTooLarge { len: u64 },
}

// ---------------------------------------------------------------------------------------------
// Records

const NO_VO: QVo = QVo {
    x1: 0,
    y1: 0,
    x2: 0,
    y2: 0,
    level: 0,
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
    /// whose ground is not stored) and its VOs, most effective first.
    Vos { ground: u8, vos: VoList },
}

impl CellRecord {
    /// A cell without VOs.
    pub const EMPTY: CellRecord = CellRecord::Vos {
        ground: 0,
        vos: VoList::new(),
    };

    /// The record of `vos` on ground level `ground`.
    pub fn new(ground: u8, vos: &[QVo]) -> Result<CellRecord, FormatError> {
        Ok(CellRecord::Vos {
            ground,
            vos: VoList::from_slice(vos)?,
        })
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
            CellRecord::Vos { vos, .. } => vos.len() as u8,
        }
    }
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
    fn f64(&mut self) -> Option<f64> {
        self.take().map(f64::from_le_bytes)
    }
}

fn u32_at(bytes: &[u8], at: u64) -> Option<u32> {
    let at = usize::try_from(at).ok()?;
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes(b.try_into().ok()?))
}

/// VOs a valid index value announces (`None` for a reserved value).
fn count_of(value: u8) -> Option<u8> {
    match value {
        SKIPPED => Some(0),
        v if v as usize <= MAX_VOS_PER_CELL => Some(v),
        _ => None,
    }
}

/// Payload bytes of a cell with `n` VOs.
fn record_size(n: u8, ground_byte: bool) -> u64 {
    if n == 0 {
        0
    } else {
        n as u64 * VO_BYTES as u64 + ground_byte as u64
    }
}

/// Decodes one record of `n >= 1` VOs from exactly its bytes; `offset` is where `bytes` starts
/// in the file or blob (for errors).
fn read_record(
    cell: CellId,
    n: u8,
    ground_byte: bool,
    bytes: &[u8],
    offset: u64,
) -> Result<CellRecord, FormatError> {
    let short = || FormatError::Truncated {
        needed: offset + record_size(n, ground_byte),
        got: offset + bytes.len() as u64,
    };
    let mut r = Reader::new(bytes);
    let ground = if ground_byte {
        r.u8().ok_or_else(short)?
    } else {
        0
    };
    let mut vos = VoList::new();
    for k in 0..n {
        let q = QVo::from_bytes(r.take::<VO_BYTES>().ok_or_else(short)?);
        if q.is_degenerate() {
            return Err(FormatError::DegenerateVo {
                cell,
                vo: k,
                offset: offset + ground_byte as u64 + k as u64 * VO_BYTES as u64,
            });
        }
        vos.push(q)?;
    }
    Ok(CellRecord::Vos { ground, vos })
}

// ---------------------------------------------------------------------------------------------
// Frame

/// Checks the frame rules F1..F12 of FORMAT.md section 4.1, in order.
pub fn validate_frame(f: &Frame) -> Result<(), FormatError> {
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
    let top = f.vo_top(f.ground_z(u8::MAX) + f.eye_hi, HEIGHT_LEVELS - 1);
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

fn push_frame(out: &mut Vec<u8>, f: &Frame) {
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

fn read_frame(r: &mut Reader<'_>) -> Option<Frame> {
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

// ---------------------------------------------------------------------------------------------
// Store

/// A parsed store file. Borrows the bytes; every check is done once by [`Store::parse`], and
/// each [`Store::cell`] reads at most 63 index bytes and one record, allocating nothing.
#[derive(Clone, Copy, Debug)]
pub struct Store<'a> {
    frame: Frame,
    minor: u16,
    cells: u32,
    ground_byte: bool,
    index: &'a [u8],
    blocks: &'a [u8],
    payload: &'a [u8],
    payload_offset: u64,
}

fn blocks_of(cells: u64) -> u64 {
    cells.div_ceil(CELLS_PER_BLOCK as u64)
}

impl<'a> Store<'a> {
    /// Checks a whole store file (FORMAT.md section 8.1, in order) in O(cells + VOs) and
    /// borrows it.
    pub fn parse(bytes: &'a [u8]) -> Result<Store<'a>, FormatError> {
        let got = bytes.len() as u64;
        let (header, body) =
            bytes
                .split_first_chunk::<HEADER_LEN>()
                .ok_or(FormatError::Truncated {
                    needed: HEADER_LEN as u64,
                    got,
                })?;
        // The header is 136 bytes, so these reads cannot fail; `?` keeps them checked anyway.
        let short = FormatError::Truncated {
            needed: HEADER_LEN as u64,
            got,
        };
        let mut r = Reader::new(header);
        if r.take::<8>().ok_or(short.clone())? != STORE_MAGIC {
            return Err(FormatError::BadMagic);
        }
        let major = r.u16().ok_or(short.clone())?;
        if major != MAJOR {
            return Err(FormatError::UnsupportedVersion { major });
        }
        let minor = r.u16().ok_or(short.clone())?;
        let flags = r.u32().ok_or(short.clone())?;
        if flags != 0 {
            return Err(FormatError::UnknownFlags { flags });
        }
        let frame = decode_frame(&r.take::<FRAME_LEN>().ok_or(short.clone())?)?;
        let payload_len = r.u32().ok_or(short.clone())?;
        let stored = r.u32().ok_or(short.clone())?;

        // At most 2^31 cells (rule F4): none of these sums can overflow a u64.
        let cells = frame.grid.cell_count();
        let blocks = blocks_of(cells);
        let expected = HEADER_LEN as u64 + cells + 4 * blocks + payload_len as u64;
        exact_length(expected, got)?;

        let mut crc = Crc32::new();
        crc.update(header.first_chunk::<CRC_OFFSET>().ok_or(short.clone())?);
        crc.update(&[0; 4]);
        crc.update(body);
        let computed = crc.finish();
        if computed != stored {
            return Err(FormatError::Checksum { stored, computed });
        }

        // The length matched, so these splits succeed; a failure would be reported as
        // truncation, never a panic.
        let too_short = FormatError::Truncated {
            needed: expected,
            got,
        };
        let n_index = usize::try_from(cells).map_err(|_| too_short.clone())?;
        let n_blocks = usize::try_from(4 * blocks).map_err(|_| too_short.clone())?;
        let (index, rest) = body.split_at_checked(n_index).ok_or(too_short.clone())?;
        let (table, payload) = rest.split_at_checked(n_blocks).ok_or(too_short)?;
        let store = Store {
            frame,
            minor,
            cells: cells as u32,
            ground_byte: frame.per_cell_ground(),
            index,
            blocks: table,
            payload,
            payload_offset: HEADER_LEN as u64 + cells + 4 * blocks,
        };
        store.check_index()?;
        store.check_offsets(payload_len)?;
        store.check_vos()?;
        Ok(store)
    }

    /// S10: every index value is a count or [`SKIPPED`].
    fn check_index(&self) -> Result<(), FormatError> {
        for (i, &value) in self.index.iter().enumerate() {
            if count_of(value).is_none() {
                return Err(FormatError::BadIndexByte {
                    cell: i as CellId,
                    value,
                    offset: HEADER_LEN as u64 + i as u64,
                });
            }
        }
        Ok(())
    }

    /// S11 and S12: the block table and `payload_len` agree with the counts.
    fn check_offsets(&self, payload_len: u32) -> Result<(), FormatError> {
        let mut off: u64 = 0;
        for (i, &value) in self.index.iter().enumerate() {
            if i as u64 % CELLS_PER_BLOCK as u64 == 0 {
                let block = (i as u64 / CELLS_PER_BLOCK as u64) as u32;
                let stored =
                    u32_at(self.blocks, block as u64 * 4).ok_or(FormatError::Truncated {
                        needed: self.payload_offset,
                        got: HEADER_LEN as u64 + self.index.len() as u64 + self.blocks.len() as u64,
                    })?;
                if stored as u64 != off {
                    return Err(FormatError::BlockOffset {
                        block,
                        stored,
                        expected: off,
                    });
                }
            }
            off += record_size(count_of(value).unwrap_or(0), self.ground_byte);
        }
        if off != payload_len as u64 {
            return Err(FormatError::PayloadLength {
                stored: payload_len,
                expected: off,
            });
        }
        Ok(())
    }

    /// S13: no degenerate VO.
    fn check_vos(&self) -> Result<(), FormatError> {
        let mut off: u64 = 0;
        for (i, &value) in self.index.iter().enumerate() {
            let n = count_of(value).unwrap_or(0);
            if n > 0 {
                self.record_at(i as CellId, n, off)?;
            }
            off += record_size(n, self.ground_byte);
        }
        Ok(())
    }

    /// The record of `n >= 1` VOs of `cell` at payload offset `off`.
    fn record_at(&self, cell: CellId, n: u8, off: u64) -> Result<CellRecord, FormatError> {
        let size = record_size(n, self.ground_byte);
        let file_off = self.payload_offset + off;
        let bytes = usize::try_from(off)
            .ok()
            .and_then(|s| self.payload.get(s..s.checked_add(size as usize)?))
            .ok_or(FormatError::Truncated {
                needed: file_off + size,
                got: self.payload_offset + self.payload.len() as u64,
            })?;
        read_record(cell, n, self.ground_byte, bytes, file_off)
    }

    /// The frame stored in the header.
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// `(major, minor)` of the file.
    pub fn version(&self) -> (u16, u16) {
        (MAJOR, self.minor)
    }

    /// Number of cells, `nx * ny`.
    pub fn cell_count(&self) -> u32 {
        self.cells
    }

    /// The record of cell `id`: reads at most 63 index bytes and the record.
    pub fn cell(&self, id: CellId) -> Result<CellRecord, FormatError> {
        let out = FormatError::CellOutOfGrid {
            id,
            cells: self.cells as u64,
        };
        let value = *self.index.get(id as usize).ok_or(out)?;
        let n = count_of(value).ok_or(FormatError::BadIndexByte {
            cell: id,
            value,
            offset: HEADER_LEN as u64 + id as u64,
        })?;
        if value == SKIPPED {
            return Ok(CellRecord::Skipped);
        }
        if n == 0 {
            return Ok(CellRecord::EMPTY);
        }
        let block = id / CELLS_PER_BLOCK;
        let start = (block * CELLS_PER_BLOCK) as usize;
        let mut off = u32_at(self.blocks, block as u64 * 4).ok_or(FormatError::Truncated {
            needed: self.payload_offset,
            got: HEADER_LEN as u64 + self.index.len() as u64 + self.blocks.len() as u64,
        })? as u64;
        for &v in self.index.get(start..id as usize).unwrap_or(&[]) {
            off += record_size(count_of(v).unwrap_or(0), self.ground_byte);
        }
        self.record_at(id, n, off)
    }

    /// The cell holding local position `(x, y)`, or `None` outside the grid (and for NaN).
    pub fn cell_at(&self, x_local: f64, y_local: f64) -> Option<CellId> {
        self.frame.grid.cell_at(x_local, y_local)
    }
}

/// Checks one record for encoding and returns its payload size. `offset` is where the record
/// will start (for errors).
fn check_record(
    cell: CellId,
    rec: &CellRecord,
    ground_byte: bool,
    offset: u64,
) -> Result<u64, FormatError> {
    let CellRecord::Vos { ground, vos } = rec else {
        return Ok(0);
    };
    if *ground != 0 && (vos.is_empty() || !ground_byte) {
        return Err(FormatError::GroundNotStored {
            cell,
            ground: *ground,
        });
    }
    for (k, q) in vos.iter().enumerate() {
        let k8 = k as u8;
        if [q.x1, q.y1, q.x2, q.y2].iter().any(|&c| c >= QUANT_STEPS) || q.level >= HEIGHT_LEVELS {
            return Err(FormatError::VoOutOfRange { cell, vo: k8 });
        }
        if q.is_degenerate() {
            return Err(FormatError::DegenerateVo {
                cell,
                vo: k8,
                offset: offset + ground_byte as u64 + (k * VO_BYTES) as u64,
            });
        }
    }
    Ok(record_size(vos.len() as u8, ground_byte))
}

fn push_record(out: &mut Vec<u8>, rec: &CellRecord, ground_byte: bool) {
    if let CellRecord::Vos { ground, vos } = rec {
        if !vos.is_empty() {
            if ground_byte {
                out.push(*ground);
            }
            for q in vos.iter() {
                out.extend_from_slice(&q.to_bytes());
            }
        }
    }
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

/// Encodes a store file: `cells[i]` is the record of cell `i` (`cells.len() == nx * ny`).
pub fn encode_store(frame: &Frame, cells: &[CellRecord]) -> Result<Vec<u8>, FormatError> {
    validate_frame(frame)?;
    let n = frame.grid.cell_count();
    if cells.len() as u64 != n {
        return Err(FormatError::CellCount {
            expected: n,
            got: cells.len() as u64,
        });
    }
    let ground_byte = frame.per_cell_ground();
    let blocks = blocks_of(n);
    let payload_offset = HEADER_LEN as u64 + n + 4 * blocks;
    let mut table = Vec::with_capacity(blocks as usize);
    let mut payload_len: u64 = 0;
    for (i, rec) in cells.iter().enumerate() {
        if i as u64 % CELLS_PER_BLOCK as u64 == 0 {
            table.push(payload_len);
        }
        payload_len += check_record(i as CellId, rec, ground_byte, payload_offset + payload_len)?;
    }
    let payload_len32 = u32::try_from(payload_len)
        .map_err(|_| FormatError::PayloadTooLarge { len: payload_len })?;

    let mut out = Vec::with_capacity((payload_offset + payload_len) as usize);
    out.extend_from_slice(&STORE_MAGIC);
    out.extend_from_slice(&MAJOR.to_le_bytes());
    out.extend_from_slice(&MINOR.to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    push_frame(&mut out, frame);
    out.extend_from_slice(&payload_len32.to_le_bytes());
    out.extend_from_slice(&[0; 4]);
    out.extend(cells.iter().map(|r| r.index_byte()));
    for off in table {
        // Each entry is at most payload_len, which fits a u32.
        out.extend_from_slice(&(off as u32).to_le_bytes());
    }
    for rec in cells {
        push_record(&mut out, rec, ground_byte);
    }
    let crc = crc32(&out);
    out[CRC_OFFSET..CRC_OFFSET + 4].copy_from_slice(&crc.to_le_bytes());
    Ok(out)
}

// ---------------------------------------------------------------------------------------------
// Blob

/// Encodes the blob of cell `id` (FORMAT.md section 6).
pub fn encode_blob(frame: &Frame, id: CellId, rec: &CellRecord) -> Result<Vec<u8>, FormatError> {
    validate_frame(frame)?;
    let cells = frame.grid.cell_count();
    if id as u64 >= cells {
        return Err(FormatError::CellOutOfGrid { id, cells });
    }
    let ground_byte = frame.per_cell_ground();
    let size = check_record(id, rec, ground_byte, BLOB_RECORD_OFFSET)?;
    let mut out = Vec::with_capacity(BLOB_MIN_LEN + size as usize);
    out.extend_from_slice(&BLOB_MAGIC);
    out.push(MAJOR as u8);
    out.extend_from_slice(&id.to_le_bytes());
    out.push(rec.index_byte());
    push_record(&mut out, rec, ground_byte);
    let crc = crc32(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    Ok(out)
}

/// Decodes and checks a cell blob (FORMAT.md section 8.3, in order) against `frame`.
pub fn decode_blob(frame: &Frame, bytes: &[u8]) -> Result<(CellId, CellRecord), FormatError> {
    validate_frame(frame)?;
    let got = bytes.len() as u64;
    let short = FormatError::Truncated {
        needed: BLOB_MIN_LEN as u64,
        got,
    };
    if bytes.len() < BLOB_MIN_LEN {
        return Err(short);
    }
    let mut r = Reader::new(bytes);
    if r.take::<4>().ok_or(short.clone())? != BLOB_MAGIC {
        return Err(FormatError::BadMagic);
    }
    let major = r.u8().ok_or(short.clone())?;
    if major as u16 != MAJOR {
        return Err(FormatError::UnsupportedVersion {
            major: major as u16,
        });
    }
    let id = r.u32().ok_or(short.clone())?;
    let value = r.u8().ok_or(short)?;
    let n = count_of(value).ok_or(FormatError::BadIndexByte {
        cell: id,
        value,
        offset: BLOB_COUNT_OFFSET,
    })?;
    let ground_byte = frame.per_cell_ground();
    let size = record_size(n, ground_byte);
    let expected = BLOB_MIN_LEN as u64 + size;
    exact_length(expected, got)?;
    let (body, tail) = bytes
        .split_last_chunk::<4>()
        .ok_or(FormatError::Truncated {
            needed: expected,
            got,
        })?;
    let stored = u32::from_le_bytes(*tail);
    let computed = crc32(body);
    if stored != computed {
        return Err(FormatError::Checksum { stored, computed });
    }
    let cells = frame.grid.cell_count();
    if id as u64 >= cells {
        return Err(FormatError::CellOutOfGrid { id, cells });
    }
    if value == SKIPPED {
        return Ok((id, CellRecord::Skipped));
    }
    if n == 0 {
        return Ok((id, CellRecord::EMPTY));
    }
    let record = body.get(BLOB_RECORD_OFFSET as usize..).unwrap_or(&[]);
    let rec = read_record(id, n, ground_byte, record, BLOB_RECORD_OFFSET)?;
    Ok((id, rec))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(ground_step: f64, nx: u32, ny: u32) -> Frame {
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

    fn q(x1: u16, y1: u16, x2: u16, y2: u16, level: u8) -> QVo {
        QVo {
            x1,
            y1,
            x2,
            y2,
            level,
        }
    }

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

    #[test]
    fn block_table_lets_cell_find_records_past_64_cells() {
        let f = frame(0.25, 13, 11); // 143 cells, 3 blocks
        let cells: Vec<CellRecord> = (0..143u16)
            .map(|i| match i % 7 {
                0 => CellRecord::Skipped,
                1 => CellRecord::EMPTY,
                k => CellRecord::new(
                    i as u8,
                    &(0..k)
                        .map(|j| q(i, j, i + 1, 300, (j % 16) as u8))
                        .collect::<Vec<_>>(),
                )
                .unwrap(),
            })
            .collect();
        let bytes = encode_store(&f, &cells).unwrap();
        let s = Store::parse(&bytes).unwrap();
        assert_eq!(s.cell_count(), 143);
        for (i, rec) in cells.iter().enumerate() {
            assert_eq!(s.cell(i as u32).unwrap(), *rec, "cell {i}");
        }
        assert_eq!(
            s.cell(143),
            Err(FormatError::CellOutOfGrid {
                id: 143,
                cells: 143
            })
        );
    }

    #[test]
    fn flat_ground_has_no_ground_byte() {
        let f = frame(0.0, 2, 1);
        let rec = CellRecord::new(0, &[q(1, 2, 3, 4, 5)]).unwrap();
        let bytes = encode_store(&f, &[rec, CellRecord::EMPTY]).unwrap();
        assert_eq!(bytes.len(), HEADER_LEN + 2 + 4 + 5);
        let blob = encode_blob(&f, 0, &rec).unwrap();
        assert_eq!(blob.len(), BLOB_MIN_LEN + 5);
        assert_eq!(decode_blob(&f, &blob).unwrap(), (0, rec));
        let high = CellRecord::new(3, &[q(1, 2, 3, 4, 5)]).unwrap();
        assert_eq!(
            encode_blob(&f, 0, &high),
            Err(FormatError::GroundNotStored { cell: 0, ground: 3 })
        );
    }
}
