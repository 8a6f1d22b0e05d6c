//! The store file (FORMAT.md section 5): header, scene section (2.0), index, block table,
//! payload.
//!
//! Input: untrusted bytes of a whole store file (major 2 or 1), or a [`Frame`], one
//! [`CellRecord`] per cell and a [`SceneSection`]. Output: a borrowed [`Store`] that answers
//! per-cell queries, an [`OwnedStore`] that keeps its bytes and lends a [`Store`] without
//! checking them again, or the file's bytes (2.0).
//! Invariants: [`Store::parse`] checks the rules of section 8.1 in order, once, in
//! O(cells + VOs), allocating nothing; [`Store::cell`] then reads at most 63 index bytes and
//! one record; [`encode_store_with`] writes only what `parse` accepts, canonically, in 2.0.

use super::frame::{push_frame, read_frame, validate_frame, validate_frame_of};
use super::records::{check_record, count_of, push_record, read_record, record_size, CellRecord};
use super::{
    exact_length, u32_at, FormatError, Reader, Version, CELLS_PER_BLOCK, CRC_OFFSET, FRAME_LEN,
    HEADER_LEN, MAJOR, MAX_CRS_LEN, MINOR, MINOR_DEEP, SCENE_FIXED_LEN, SKIPPED, STORE_MAGIC,
};
use crate::runtime::crc::{crc32, Crc32};
use crate::runtime::frame::Frame;
use crate::runtime::grid::CellId;

/// The scene section of a 2.0 store (FORMAT.md section 5.2): what the store was baked from.
/// Engines need none of it; it lets a tool check a store against its scene. A 1.0 store reads
/// as [`SceneSection::NONE`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SceneSection<'a> {
    /// How many objects the store was baked for; 0: not recorded.
    pub objects: u32,
    /// A fingerprint of the scene it was baked from, opaque; 0: not recorded.
    pub scene: u64,
    /// The name of the scene's coordinate reference system (e.g. `EPSG:3946`), at most 255
    /// bytes of UTF-8; empty: unknown.
    pub crs: &'a str,
}

impl SceneSection<'_> {
    /// Nothing recorded: no object count, no fingerprint, no CRS.
    pub const NONE: SceneSection<'static> = SceneSection {
        objects: 0,
        scene: 0,
        crs: "",
    };
}

impl Default for SceneSection<'_> {
    fn default() -> Self {
        SceneSection::NONE
    }
}

/// A parsed store file (2.0 or 1.0). Borrows the bytes; every check is done once by
/// [`Store::parse`], and each [`Store::cell`] reads at most 63 index bytes and one record,
/// allocating nothing.
#[derive(Clone, Copy, Debug)]
pub struct Store<'a> {
    frame: Frame,
    version: Version,
    minor: u16,
    cells: u32,
    ground_byte: bool,
    section: SceneSection<'a>,
    index: &'a [u8],
    blocks: &'a [u8],
    payload: &'a [u8],
    index_offset: u64,
    payload_offset: u64,
}

fn blocks_of(cells: u64) -> u64 {
    cells.div_ceil(CELLS_PER_BLOCK as u64)
}

/// The bytes of a 2.0 store that no cell's record holds: header, scene section with a CRS name
/// of `crs_len` bytes, and block table (FORMAT.md sections 5.1, 5.2, 5.4). The index (1 byte a
/// cell) and the payload come on top.
pub fn fixed_len(cells: u64, crs_len: usize) -> u64 {
    (HEADER_LEN + SCENE_FIXED_LEN + crs_len) as u64 + 4 * blocks_of(cells)
}

impl<'a> Store<'a> {
    /// Checks a whole store file of major 2 or 1 (FORMAT.md section 8.1, in order) in
    /// O(cells + VOs) and borrows it.
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
        let version = Version::of(major).ok_or(FormatError::UnsupportedVersion { major })?;
        let minor = r.u16().ok_or(short.clone())?;
        let flags = r.u32().ok_or(short.clone())?;
        if flags != 0 {
            return Err(FormatError::UnknownFlags { flags });
        }
        let frame = read_frame(&mut Reader::new(
            &r.take::<FRAME_LEN>().ok_or(short.clone())?,
        ))
        .ok_or(short.clone())?;
        validate_frame_of(&frame, version)?;
        let payload_len = r.u32().ok_or(short.clone())?;
        let stored = r.u32().ok_or(short.clone())?;

        // 2.0: the scene section's fixed part, which says how long the section is.
        let (objects, scene, crs_len) = match version {
            Version::V1 => (0, 0, 0u8),
            Version::V2 => {
                let needed = (HEADER_LEN + SCENE_FIXED_LEN) as u64;
                let mut s = Reader::new(body);
                let short = FormatError::Truncated { needed, got };
                (
                    s.u32().ok_or(short.clone())?,
                    s.u64().ok_or(short.clone())?,
                    s.u8().ok_or(short)?,
                )
            }
        };
        let section_len = match version {
            Version::V1 => 0,
            Version::V2 => (SCENE_FIXED_LEN + crs_len as usize) as u64,
        };

        // At most 2^31 cells (rule F4): none of these sums can overflow a u64.
        let cells = frame.grid.cell_count();
        let blocks = blocks_of(cells);
        let index_offset = HEADER_LEN as u64 + section_len;
        let payload_offset = index_offset + cells + 4 * blocks;
        let expected = payload_offset + payload_len as u64;
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
        let n_section = usize::try_from(section_len).map_err(|_| too_short.clone())?;
        let n_index = usize::try_from(cells).map_err(|_| too_short.clone())?;
        let n_blocks = usize::try_from(4 * blocks).map_err(|_| too_short.clone())?;
        let (section, rest) = body.split_at_checked(n_section).ok_or(too_short.clone())?;
        let (index, rest) = rest.split_at_checked(n_index).ok_or(too_short.clone())?;
        let (table, payload) = rest.split_at_checked(n_blocks).ok_or(too_short.clone())?;

        // S17: the CRS name is UTF-8.
        let crs_bytes = section.get(SCENE_FIXED_LEN..).unwrap_or(&[]);
        let crs = core::str::from_utf8(crs_bytes).map_err(|e| FormatError::CrsNotUtf8 {
            offset: (HEADER_LEN + SCENE_FIXED_LEN + e.valid_up_to()) as u64,
        })?;
        let store = Store {
            frame,
            version,
            minor,
            cells: cells as u32,
            ground_byte: frame.per_cell_ground(),
            section: SceneSection {
                objects,
                scene,
                crs,
            },
            index,
            blocks: table,
            payload,
            index_offset,
            payload_offset,
        };
        store.check_index()?;
        store.check_offsets(payload_len)?;
        store.check_vos()?;
        Ok(store)
    }

    /// Where the parts a [`Store`] borrows lie in its bytes, with what `parse` read: what an
    /// [`OwnedStore`] keeps beside the bytes.
    fn layout(&self) -> Layout {
        Layout {
            frame: self.frame,
            version: self.version,
            minor: self.minor,
            cells: self.cells,
            ground_byte: self.ground_byte,
            objects: self.section.objects,
            scene: self.section.scene,
            crs_len: self.section.crs.len(),
            index_offset: self.index_offset,
            payload_offset: self.payload_offset,
        }
    }

    /// The store `parse` accepted in `bytes` with layout `l`, without checking it again. Never
    /// panics: a part outside `bytes` (which an accepted store's layout cannot give) reads empty.
    fn view(bytes: &'a [u8], l: &Layout) -> Store<'a> {
        let at = |a: u64, b: u64| -> &'a [u8] {
            usize::try_from(a)
                .ok()
                .zip(usize::try_from(b).ok())
                .and_then(|(a, b)| bytes.get(a..b))
                .unwrap_or(&[])
        };
        let crs_start = (HEADER_LEN + SCENE_FIXED_LEN) as u64;
        let crs = core::str::from_utf8(at(crs_start, crs_start + l.crs_len as u64)).unwrap_or("");
        let index_end = l.index_offset + l.cells as u64;
        Store {
            frame: l.frame,
            version: l.version,
            minor: l.minor,
            cells: l.cells,
            ground_byte: l.ground_byte,
            section: SceneSection {
                objects: l.objects,
                scene: l.scene,
                crs,
            },
            index: at(l.index_offset, index_end),
            blocks: at(index_end, l.payload_offset),
            payload: at(l.payload_offset, bytes.len() as u64),
            index_offset: l.index_offset,
            payload_offset: l.payload_offset,
        }
    }

    /// S10: every index value is a count or [`SKIPPED`].
    fn check_index(&self) -> Result<(), FormatError> {
        for (i, &value) in self.index.iter().enumerate() {
            if count_of(value, self.version, self.ground_byte).is_none() {
                return Err(FormatError::BadIndexByte {
                    cell: i as CellId,
                    value,
                    offset: self.index_offset + i as u64,
                });
            }
        }
        Ok(())
    }

    /// Payload bytes of a cell with index value `value` (valid).
    fn size_of(&self, value: u8) -> u64 {
        record_size(
            count_of(value, self.version, self.ground_byte).unwrap_or(0),
            self.ground_byte,
            self.version,
        )
    }

    /// Where the block table would end had it all its bytes (for a truncation error that
    /// cannot happen after the length check).
    fn table_short(&self) -> FormatError {
        FormatError::Truncated {
            needed: self.payload_offset,
            got: self.index_offset + self.index.len() as u64 + self.blocks.len() as u64,
        }
    }

    /// S11 and S12: the block table and `payload_len` agree with the counts.
    fn check_offsets(&self, payload_len: u32) -> Result<(), FormatError> {
        let mut off: u64 = 0;
        for (i, &value) in self.index.iter().enumerate() {
            if i as u64 % CELLS_PER_BLOCK as u64 == 0 {
                let block = (i as u64 / CELLS_PER_BLOCK as u64) as u32;
                let stored =
                    u32_at(self.blocks, block as u64 * 4).ok_or_else(|| self.table_short())?;
                if stored as u64 != off {
                    return Err(FormatError::BlockOffset {
                        block,
                        stored,
                        expected: off,
                    });
                }
            }
            off += self.size_of(value);
        }
        if off != payload_len as u64 {
            return Err(FormatError::PayloadLength {
                stored: payload_len,
                expected: off,
            });
        }
        Ok(())
    }

    /// S18, S19 and S13, VO by VO in file order: no reserved bit, canonical endpoints, no
    /// degenerate VO.
    fn check_vos(&self) -> Result<(), FormatError> {
        let mut off: u64 = 0;
        for (i, &value) in self.index.iter().enumerate() {
            let n = count_of(value, self.version, self.ground_byte).unwrap_or(0);
            if n > 0 {
                self.record_at(i as CellId, n, off)?;
            }
            off += self.size_of(value);
        }
        Ok(())
    }

    /// The record of `n >= 1` VOs of `cell` at payload offset `off`.
    fn record_at(&self, cell: CellId, n: u8, off: u64) -> Result<CellRecord, FormatError> {
        let size = record_size(n, self.ground_byte, self.version);
        let file_off = self.payload_offset + off;
        let bytes = usize::try_from(off)
            .ok()
            .and_then(|s| self.payload.get(s..s.checked_add(size as usize)?))
            .ok_or(FormatError::Truncated {
                needed: file_off + size,
                got: self.payload_offset + self.payload.len() as u64,
            })?;
        read_record(cell, n, self.ground_byte, self.version, bytes, file_off)
    }

    /// The frame stored in the header.
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// `(major, minor)` of the file.
    pub fn version(&self) -> (u16, u16) {
        (self.version.major(), self.minor)
    }

    /// The file's major version: 2, or 1 for a store written before 2.0.
    pub fn major(&self) -> u16 {
        self.version.major()
    }

    /// Bytes per stored VO in this file: 6 (2.0) or 5 (1.0).
    pub fn vo_bytes(&self) -> usize {
        self.version.vo_bytes()
    }

    /// The scene section ([`SceneSection::NONE`] for a 1.0 store).
    pub fn scene_section(&self) -> SceneSection<'a> {
        self.section
    }

    /// How many objects the store was baked for; 0: not recorded (always for 1.0).
    pub fn objects(&self) -> u32 {
        self.section.objects
    }

    /// The fingerprint of the scene the store was baked from; 0: not recorded (always for 1.0).
    pub fn scene(&self) -> u64 {
        self.section.scene
    }

    /// The name of the scene's coordinate reference system; empty: unknown (always for 1.0).
    pub fn crs(&self) -> &'a str {
        self.section.crs
    }

    /// Number of cells, `nx * ny`.
    pub fn cell_count(&self) -> u32 {
        self.cells
    }

    /// Bytes of cell `id` in the file: its index byte and its payload record (0 outside the
    /// grid).
    pub fn cell_bytes(&self, id: CellId) -> u64 {
        self.index
            .get(id as usize)
            .map_or(0, |&v| 1 + self.size_of(v))
    }

    /// The record of cell `id`: reads at most 63 index bytes and the record.
    pub fn cell(&self, id: CellId) -> Result<CellRecord, FormatError> {
        let out = FormatError::CellOutOfGrid {
            id,
            cells: self.cells as u64,
        };
        let value = *self.index.get(id as usize).ok_or(out)?;
        let n =
            count_of(value, self.version, self.ground_byte).ok_or(FormatError::BadIndexByte {
                cell: id,
                value,
                offset: self.index_offset + id as u64,
            })?;
        if value == SKIPPED {
            return Ok(CellRecord::Skipped);
        }
        if n == 0 {
            return Ok(CellRecord::EMPTY);
        }
        let block = id / CELLS_PER_BLOCK;
        let start = (block * CELLS_PER_BLOCK) as usize;
        let mut off =
            u32_at(self.blocks, block as u64 * 4).ok_or_else(|| self.table_short())? as u64;
        for &v in self.index.get(start..id as usize).unwrap_or(&[]) {
            off += self.size_of(v);
        }
        self.record_at(id, n, off)
    }

    /// The cell holding local position `(x, y)`, or `None` outside the grid (and for NaN).
    pub fn cell_at(&self, x_local: f64, y_local: f64) -> Option<CellId> {
        self.frame.grid.cell_at(x_local, y_local)
    }
}

/// What an [`OwnedStore`] keeps of a parsed store besides its bytes.
#[derive(Clone, Copy, Debug)]
struct Layout {
    frame: Frame,
    version: Version,
    minor: u16,
    cells: u32,
    ground_byte: bool,
    objects: u32,
    scene: u64,
    crs_len: usize,
    index_offset: u64,
    payload_offset: u64,
}

/// A parsed store that owns its bytes (a `Vec<u8>`, `Box<[u8]>`, `Arc<[u8]>`, or any
/// `B: AsRef<[u8]>` that gives the same bytes each time it is asked, as those do): for a binding
/// or an engine that keeps a store in a struct of its own. [`OwnedStore::parse`] checks the
/// bytes once, as [`Store::parse`]; [`OwnedStore::store`] then lends a [`Store`] over them
/// without checking them again (O(1)).
///
/// ```
/// use vocc::runtime::{encode_store, CellRecord, Frame, GridDescriptor, OwnedStore};
/// # fn main() -> Result<(), vocc::runtime::FormatError> {
/// # let frame = Frame {
/// #     origin: [0.0; 3],
/// #     grid: GridDescriptor { min_x: 0.0, min_y: 0.0, cell_size: 100.0, nx: 2, ny: 1 },
/// #     quantum: 0.5, eye_lo: 1.5, eye_hi: 2.0, ground_z0: 0.0, ground_step: 0.0,
/// #     h0: 4.0, h_ratio: 1.25,
/// # };
/// let bytes: Vec<u8> = encode_store(&frame, &[CellRecord::EMPTY, CellRecord::Skipped])?;
/// let owned = OwnedStore::parse(bytes)?; // no borrow: it can live in any struct
/// assert_eq!(owned.store().cell_count(), 2);
/// assert_eq!(owned.store().cell(1)?, CellRecord::Skipped);
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Debug)]
pub struct OwnedStore<B = Vec<u8>> {
    bytes: B,
    layout: Layout,
}

impl<B: AsRef<[u8]>> OwnedStore<B> {
    /// Checks a whole store file as [`Store::parse`] does and keeps its bytes.
    pub fn parse(bytes: B) -> Result<OwnedStore<B>, FormatError> {
        let layout = Store::parse(bytes.as_ref())?.layout();
        Ok(OwnedStore { bytes, layout })
    }

    /// The store, borrowed from the bytes kept (no check is made again).
    pub fn store(&self) -> Store<'_> {
        Store::view(self.bytes.as_ref(), &self.layout)
    }

    /// The store file's bytes.
    pub fn bytes(&self) -> &[u8] {
        self.bytes.as_ref()
    }

    /// Gives the bytes back.
    pub fn into_bytes(self) -> B {
        self.bytes
    }
}

/// Encodes a 2.0 store file with an empty scene section ([`SceneSection::NONE`]): `cells[i]` is
/// the record of cell `i` (`cells.len() == nx * ny`).
pub fn encode_store(frame: &Frame, cells: &[CellRecord]) -> Result<Vec<u8>, FormatError> {
    encode_store_with(frame, cells, &SceneSection::NONE)
}

/// Encodes a 2.0 store file with its scene section: `cells[i]` is the record of cell `i`
/// (`cells.len() == nx * ny`). Refuses (in this order) a frame that breaks a rule of 4.1, a CRS
/// name over 255 bytes, another number of records than cells, and a record a decoder would
/// refuse.
pub fn encode_store_with(
    frame: &Frame,
    cells: &[CellRecord],
    scene: &SceneSection<'_>,
) -> Result<Vec<u8>, FormatError> {
    validate_frame(frame)?;
    let crs = scene.crs.as_bytes();
    let crs_len = u8::try_from(crs.len())
        .ok()
        .filter(|&n| n as usize <= MAX_CRS_LEN)
        .ok_or(FormatError::CrsTooLong { len: crs.len() })?;
    let n = frame.grid.cell_count();
    if cells.len() as u64 != n {
        return Err(FormatError::CellCount {
            expected: n,
            got: cells.len() as u64,
        });
    }
    let ground_byte = frame.per_cell_ground();
    let blocks = blocks_of(n);
    let payload_offset = fixed_len(n, crs.len()) + n;
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
    // The lowest minor whose additions the file uses (FORMAT.md 2.4): 2.1 with a deep VO.
    let deep = cells
        .iter()
        .any(|r| r.rise() > 0 || r.vos().iter().any(|q| q.deep));
    out.extend_from_slice(&if deep { MINOR_DEEP } else { MINOR }.to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    push_frame(&mut out, frame);
    out.extend_from_slice(&payload_len32.to_le_bytes());
    out.extend_from_slice(&[0; 4]);
    out.extend_from_slice(&scene.objects.to_le_bytes());
    out.extend_from_slice(&scene.scene.to_le_bytes());
    out.push(crs_len);
    out.extend_from_slice(crs);
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

#[cfg(test)]
mod tests {
    use super::super::test_util::{frame, q};
    use super::*;

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

    /// An owned store answers as the borrowed one: every cell, the section, the byte counts.
    #[test]
    fn owned_store_lends_the_store_it_parsed() {
        let f = frame(0.25, 13, 11);
        let cells: Vec<CellRecord> = (0..143u16)
            .map(|i| match i % 5 {
                0 => CellRecord::Skipped,
                1 => CellRecord::EMPTY,
                k => CellRecord::new(i as u8, &[q(i, k, i + 1, 300, 3)]).unwrap(),
            })
            .collect();
        let section = SceneSection {
            objects: 2576,
            scene: 0x0123_4567_89ab_cdef,
            crs: "EPSG:3946",
        };
        let bytes = encode_store_with(&f, &cells, &section).unwrap();
        let borrowed = Store::parse(&bytes).unwrap();
        let owned = OwnedStore::parse(bytes.clone().into_boxed_slice()).unwrap();
        let s = owned.store();
        assert_eq!(s.scene_section(), section);
        assert_eq!(s.version(), borrowed.version());
        assert_eq!(s.frame(), borrowed.frame());
        for id in 0..144 {
            assert_eq!(s.cell(id), borrowed.cell(id), "cell {id}");
            assert_eq!(s.cell_bytes(id), borrowed.cell_bytes(id), "cell {id}");
        }
        assert_eq!(owned.bytes(), &bytes[..]);
        assert_eq!(&*owned.into_bytes(), &bytes[..]);
        let mut bad = bytes;
        bad[140] ^= 1;
        assert!(matches!(
            OwnedStore::parse(bad),
            Err(FormatError::Checksum { .. })
        ));
    }
}
