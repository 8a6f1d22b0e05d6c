//! The store file (FORMAT.md section 5): header, index, block table, payload.
//!
//! Input: untrusted bytes of a whole store file, or a [`Frame`] and one [`CellRecord`] per
//! cell. Output: a borrowed [`Store`] that answers per-cell queries, or the file's bytes.
//! Invariants: [`Store::parse`] checks rules S1..S16 of section 8.1 in order, once, in
//! O(cells + VOs), allocating nothing; [`Store::cell`] then reads at most 63 index bytes and
//! one record; [`encode_store`] writes only what `parse` accepts, canonically.

use super::frame::{decode_frame, push_frame, validate_frame};
use super::records::{check_record, count_of, push_record, read_record, record_size, CellRecord};
use super::{
    exact_length, u32_at, FormatError, Reader, CELLS_PER_BLOCK, CRC_OFFSET, FRAME_LEN, HEADER_LEN,
    MAJOR, MINOR, SKIPPED, STORE_MAGIC,
};
use crate::runtime::crc::{crc32, Crc32};
use crate::runtime::frame::Frame;
use crate::runtime::grid::CellId;

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
}
