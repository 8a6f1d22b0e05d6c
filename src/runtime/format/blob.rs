//! The cell blob (FORMAT.md section 6): one cell's record, self-contained, decoded with only
//! the frame beside it.
//!
//! Input: a [`Frame`] and a blob's untrusted bytes (major 2 or 1), or a cell id and its
//! [`CellRecord`]. Output: the cell id and record, or the blob's bytes (2.0).
//! Invariants: [`decode_blob`] checks the rules of section 8.3 in order and allocates nothing;
//! the blob's major says how its VOs decode (6 bytes, or 5 for 1.0), and the frame beside it
//! follows the frame rules of a frame on its own (2.0); [`encode_blob`] writes 2.0, and only
//! what it accepts.

use super::frame::validate_frame;
use super::records::{check_record, count_of, push_record, read_record, record_size, CellRecord};
use super::{
    exact_length, FormatError, Reader, Version, BLOB_COUNT_OFFSET, BLOB_MAGIC, BLOB_MIN_LEN,
    BLOB_RECORD_OFFSET, MAJOR, SKIPPED,
};
use crate::runtime::crc::crc32;
use crate::runtime::frame::Frame;
use crate::runtime::grid::CellId;

/// Encodes the 2.0 blob of cell `id` (FORMAT.md section 6).
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

/// Decodes and checks a cell blob of major 2 or 1 (FORMAT.md section 8.3, in order) against
/// `frame`.
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
    let major = r.u8().ok_or(short.clone())? as u16;
    let version = Version::of(major).ok_or(FormatError::UnsupportedVersion { major })?;
    let id = r.u32().ok_or(short.clone())?;
    let value = r.u8().ok_or(short)?;
    let ground_byte = frame.per_cell_ground();
    let n = count_of(value, version, ground_byte).ok_or(FormatError::BadIndexByte {
        cell: id,
        value,
        offset: BLOB_COUNT_OFFSET,
    })?;
    let size = record_size(n, ground_byte, version);
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
    let rec = read_record(id, n, ground_byte, version, record, BLOB_RECORD_OFFSET)?;
    Ok((id, rec))
}

#[cfg(test)]
mod tests {
    use super::super::store::encode_store;
    use super::super::test_util::{frame, q};
    use super::super::{BLOB_MIN_LEN, HEADER_LEN};
    use super::*;

    #[test]
    fn flat_ground_has_no_ground_byte() {
        let f = frame(0.0, 2, 1);
        let rec = CellRecord::new(0, &[q(1, 2, 3, 4, 5)]).unwrap();
        let bytes = encode_store(&f, &[rec, CellRecord::EMPTY]).unwrap();
        assert_eq!(bytes.len(), HEADER_LEN + 13 + 2 + 4 + 6);
        let blob = encode_blob(&f, 0, &rec).unwrap();
        assert_eq!(blob.len(), BLOB_MIN_LEN + 6);
        assert_eq!(decode_blob(&f, &blob).unwrap(), (0, rec));
        let high = CellRecord::new(3, &[q(1, 2, 3, 4, 5)]).unwrap();
        assert_eq!(
            encode_blob(&f, 0, &high),
            Err(FormatError::GroundNotStored { cell: 0, ground: 3 })
        );
    }
}
