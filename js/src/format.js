// @ts-check
/**
 * The store file and the cell blob (FORMAT.md sections 5, 6, 8 and 12): the port of
 * src/runtime/format/{mod,records,store,blob}.rs.
 *
 * Input: untrusted bytes (a `Uint8Array`) of a store file or a blob, majors 2 (with its minor
 * 2.1) and 1. Output: a {@link Store} that answers per-cell queries, or a blob's cell id and
 * record.
 * Invariants:
 * - the rules of FORMAT.md section 8 are checked in the document's order and the first broken
 *   one is thrown as a {@link FormatError} with the Rust error's kind, fields and message;
 * - nothing is read outside the input, and nothing is allocated in proportion to a length
 *   field (only to the input's own size);
 * - one decoder reads both majors: a 1.0 VO (5 bytes) comes out as the 2.0 VO with exponents 0;
 * - 2.1 (FORMAT.md 13) is read as Rust reads it: index and count values `11..=20` (a 2.0 store
 *   or blob with ground bytes only) announce `value - 10` VOs after a ground byte and a rise
 *   byte (checked by S22/B14, `BadRise`), and bit 47 of a VO is its deep flag.
 *
 * Extending it (a minor version giving meaning to a reserved value, FORMAT.md 2.4): a store
 * flag is a bit of {@link KNOWN_FLAGS} and a field of {@link Store}; an index value of the
 * reserved range `21..=254` is a case of `countOf` (whether it is valid), `split` (how many VOs
 * it announces and what the record holds besides) and `recordSize` (how many payload bytes its
 * record takes), the only places that read index values, with the record's new bytes read in
 * `readRecord` (as 2.1's rise byte is); new VO bytes belong to the
 * version's entry of {@link VERSIONS} (`voBytes`, `decodeVo`). Every length, offset and check
 * below goes through these, so nothing else changes.
 */

import { crc32, crcUpdate } from './crc.js';
import { FormatError } from './errors.js';
import {
  FRAME_LEN, HEIGHT_LEVELS, HEIGHT_LEVELS_V1, MAX_VOS_PER_CELL, QPoint, QVo, readFrame, validateFrame,
} from './frame.js';

/** First 8 bytes of a store file: 0x89, "VOCC", CR, LF, 0x1A. */
export const STORE_MAGIC = [0x89, 0x56, 0x4f, 0x43, 0x43, 0x0d, 0x0a, 0x1a];
/** First 4 bytes of a cell blob: "VOCB". */
export const BLOB_MAGIC = [0x56, 0x4f, 0x43, 0x42];
export const HEADER_LEN = 136;
/** The fixed part of a 2.0 store's scene section (`objects`, `scene`, `crs_len`). */
export const SCENE_FIXED_LEN = 13;
export const BLOB_MIN_LEN = 14;
export const CELLS_PER_BLOCK = 64;
/** Index value of a skipped cell. */
export const SKIPPED = 0xff;
/** The store flag bits this reader knows: none (every bit is reserved in 1.0 and 2.0). */
export const KNOWN_FLAGS = 0;
const CRC_OFFSET = 132;
const BLOB_COUNT_OFFSET = 9;
const BLOB_RECORD_OFFSET = 10;

/** Index values `RISE_BASE + n` (`n` in `1..=10`) announce `n` VOs after a ground byte and a
 * rise byte (format 2.1). */
export const RISE_BASE = 10;

/**
 * A 2.0 VO from its 6 bytes at `at` (FORMAT.md 3.1); every value decodes, bit 47 being the
 * deep flag of 2.1.
 * @param {Uint8Array} b
 * @param {number} at
 */
function decodeVoV2(b, at) {
  const lo = b[at] | (b[at + 1] << 8) | (b[at + 2] << 16); // bits 0..24
  const hi = b[at + 3] | (b[at + 4] << 8) | (b[at + 5] << 16); // bits 24..48
  const a = lo & 0x1fffff;
  const bb = (lo >>> 21) | ((hi & 0x3ffff) << 3);
  const p = (/** @type {number} */ v) => new QPoint(v & 7, (v >>> 3) & 0x1ff, (v >>> 12) & 0x1ff);
  return new QVo(p(a), p(bb), (hi >>> 18) & 0x1f, (hi & 0x800000) !== 0);
}

/**
 * A 1.0 VO from its 5 bytes at `at` (FORMAT.md 12.3): exponents 0; every value decodes.
 * @param {Uint8Array} b
 * @param {number} at
 */
function decodeVoV1(b, at) {
  const lo = (b[at] | (b[at + 1] << 8) | (b[at + 2] << 16) | (b[at + 3] << 24)) >>> 0;
  const b4 = b[at + 4];
  return new QVo(
    new QPoint(0, lo & 0x1ff, (lo >>> 9) & 0x1ff),
    new QPoint(0, (lo >>> 18) & 0x1ff, ((lo >>> 27) | (b4 << 5)) & 0x1ff),
    (b4 >>> 4) & 0xf,
  );
}

/**
 * @typedef {object} Version
 * @property {number} major
 * @property {number} voBytes bytes per stored VO
 * @property {number} topLevel the highest height level (frame rule F12 checks its top)
 * @property {boolean} sceneSection whether a scene section follows the header
 * @property {(b: Uint8Array, at: number) => QVo} decodeVo every value decodes (a 2.0 VO's bit
 *   47 is the deep flag of 2.1)
 * @property {boolean} rise whether index values `11..=20` (2.1, with ground bytes) are read
 */

/** The majors this reader implements, and what differs between them. @type {Record<number, Version>} */
export const VERSIONS = {
  1: { major: 1, voBytes: 5, topLevel: HEIGHT_LEVELS_V1 - 1, sceneSection: false, decodeVo: decodeVoV1, rise: false },
  2: { major: 2, voBytes: 6, topLevel: HEIGHT_LEVELS - 1, sceneSection: true, decodeVo: decodeVoV2, rise: true },
};

/**
 * The record of one cell: skipped (inside a building), or a ground level, a rise (format 2.1:
 * the cell's top eye stands `rise` ground steps higher; 0 in 2.0 and 1.0, and for a skipped or
 * empty cell) and at most 10 VOs, most effective first. Give the whole record to
 * `Frame#cellView` and `Frame#dequantize`, which read both `ground` and `rise`.
 * @typedef {{skipped: boolean, ground: number, rise: number, vos: QVo[]}} CellRecord
 */

/** @type {CellRecord} */
const SKIPPED_RECORD = Object.freeze({ skipped: true, ground: 0, rise: 0, vos: /** @type {QVo[]} */ ([]) });
/** @type {CellRecord} */
const EMPTY_RECORD = Object.freeze({ skipped: false, ground: 0, rise: 0, vos: /** @type {QVo[]} */ ([]) });

/**
 * The record a valid index value announces, as the value itself (`0` for none, `1..=10` VOs,
 * and in 2.1, with a ground byte, `11..=20`: `value - 10` VOs after a rise byte), or -1 for a
 * value the store or blob cannot hold (Rust's `count_of`).
 * @param {number} value
 * @param {Version} v
 * @param {boolean} groundByte
 */
function countOf(value, v, groundByte) {
  if (value === SKIPPED) return 0;
  if (value <= MAX_VOS_PER_CELL) return value;
  if (v.rise && groundByte && value > RISE_BASE && value - RISE_BASE <= MAX_VOS_PER_CELL) return value;
  return -1;
}

/**
 * VOs and whether a rise byte is stored, for a value {@link countOf} gave.
 * @param {number} c
 */
function split(c) {
  return c > RISE_BASE ? { n: c - RISE_BASE, rise: true } : { n: c, rise: false };
}

/**
 * Payload bytes of a cell whose {@link countOf} is `c`.
 * @param {number} c
 * @param {boolean} groundByte
 * @param {Version} v
 */
function recordSize(c, groundByte, v) {
  const { n, rise } = split(c);
  return n === 0 ? 0 : n * v.voBytes + (groundByte ? 1 : 0) + (rise ? 1 : 0);
}

/**
 * Decodes one record whose {@link countOf} is `c` (at least one VO), whose bytes start at `at`
 * of `bytes` (an offset of the file or blob, for errors too); the caller has checked that they
 * are all there. Checks, in order: the rise (S22/B14, 2.1), then VO by VO a non-canonical
 * endpoint (S19/B12) and a degenerate VO (S13/B9).
 * @param {number} cell
 * @param {number} c
 * @param {boolean} groundByte
 * @param {Version} v
 * @param {Uint8Array} bytes
 * @param {number} at
 * @returns {CellRecord}
 */
function readRecord(cell, c, groundByte, v, bytes, at) {
  const { n, rise: hasRise } = split(c);
  const ground = groundByte ? bytes[at] : 0;
  // A rise byte is only announced with a ground byte (countOf), so it follows it, at `at + 1`.
  const rise = hasRise ? bytes[at + 1] : 0;
  // S22/B14 (2.1): a rise byte of 0, or a top eye above ground level 255.
  if (hasRise && (rise === 0 || ground + rise > 255)) {
    throw new FormatError('BadRise', { cell, ground, rise, offset: at + 1 });
  }
  const head = (groundByte ? 1 : 0) + (hasRise ? 1 : 0);
  const vos = [];
  for (let k = 0; k < n; k++) {
    const offset = at + head + k * v.voBytes;
    const q = v.decodeVo(bytes, offset);
    if (!q.isCanonical()) {
      const endpoint = q.a.isCanonical() ? 'b' : 'a';
      throw new FormatError('NonCanonicalVo', { cell, vo: k, offset, endpoint });
    }
    if (q.isDegenerate()) throw new FormatError('DegenerateVo', { cell, vo: k, offset });
    vos.push(q);
  }
  return { skipped: false, ground, rise, vos };
}

/**
 * `got` bytes where exactly `expected` are needed.
 * @param {number} expected
 * @param {number} got
 */
function exactLength(expected, got) {
  if (got < expected) throw new FormatError('Truncated', { needed: expected, got });
  if (got > expected) throw new FormatError('TrailingBytes', { expected, got });
}

/**
 * The length of the longest prefix of `b[start..end)` that is valid UTF-8 (Rust's
 * `Utf8Error::valid_up_to`: well-formed sequences of Unicode's table 3-7).
 * @param {Uint8Array} b
 * @param {number} start
 * @param {number} end
 */
function utf8ValidUpTo(b, start, end) {
  let i = start;
  while (i < end) {
    const c = b[i];
    let n = 0;
    let lo = 0x80;
    let hi = 0xbf;
    if (c < 0x80) n = 0;
    else if (c >= 0xc2 && c <= 0xdf) n = 1;
    else if (c >= 0xe0 && c <= 0xef) {
      n = 2;
      if (c === 0xe0) lo = 0xa0;
      if (c === 0xed) hi = 0x9f;
    } else if (c >= 0xf0 && c <= 0xf4) {
      n = 3;
      if (c === 0xf0) lo = 0x90;
      if (c === 0xf4) hi = 0x8f;
    } else return i - start;
    for (let k = 1; k <= n; k++) {
      const t = i + k;
      if (t >= end) return i - start;
      const min = k === 1 ? lo : 0x80;
      const max = k === 1 ? hi : 0xbf;
      if (b[t] < min || b[t] > max) return i - start;
    }
    i += n + 1;
  }
  return end - start;
}

/**
 * A parsed store file (2.0 or 1.0). Every rule is checked once by {@link Store.parse}; each
 * {@link Store#cell} then reads at most 63 index bytes and one record.
 */
export class Store {
  /**
   * Checks a whole store file of major 2 or 1 (FORMAT.md section 8.1, in order). The store
   * keeps a reference to `bytes` (not a copy).
   * @param {Uint8Array} bytes
   * @returns {Store}
   */
  static parse(bytes) {
    return new Store(bytes);
  }

  /** @param {Uint8Array} bytes */
  constructor(bytes) {
    const got = bytes.length;
    if (got < HEADER_LEN) throw new FormatError('Truncated', { needed: HEADER_LEN, got });
    const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    for (let i = 0; i < 8; i++) if (bytes[i] !== STORE_MAGIC[i]) throw new FormatError('BadMagic');
    const major = dv.getUint16(8, true);
    const version = VERSIONS[major];
    if (!version) throw new FormatError('UnsupportedVersion', { major });
    const minor = dv.getUint16(10, true);
    const flags = dv.getUint32(12, true);
    if ((flags & ~KNOWN_FLAGS) !== 0) throw new FormatError('UnknownFlags', { flags });
    const frame = readFrame(dv, 16);
    validateFrame(frame, version.topLevel);
    const payloadLen = dv.getUint32(128, true);
    const stored = dv.getUint32(CRC_OFFSET, true);

    let objects = 0;
    let scene = 0n;
    let crsLen = 0;
    if (version.sceneSection) {
      const needed = HEADER_LEN + SCENE_FIXED_LEN;
      if (got < needed) throw new FormatError('Truncated', { needed, got });
      objects = dv.getUint32(HEADER_LEN, true);
      scene = dv.getBigUint64(HEADER_LEN + 4, true);
      crsLen = bytes[HEADER_LEN + 12];
    }
    const sectionLen = version.sceneSection ? SCENE_FIXED_LEN + crsLen : 0;
    const cells = frame.cellCount();
    const blocks = Math.ceil(cells / CELLS_PER_BLOCK);
    const indexOffset = HEADER_LEN + sectionLen;
    const tableOffset = indexOffset + cells;
    const payloadOffset = tableOffset + 4 * blocks;
    exactLength(payloadOffset + payloadLen, got);

    let c = crcUpdate(0xffffffff, bytes, 0, CRC_OFFSET);
    c = crcUpdate(c, new Uint8Array(4));
    const computed = (crcUpdate(c, bytes, HEADER_LEN) ^ 0xffffffff) >>> 0;
    if (computed !== stored) throw new FormatError('Checksum', { stored, computed });

    // S17: the CRS name is UTF-8.
    const crsStart = HEADER_LEN + SCENE_FIXED_LEN;
    let crs = '';
    if (version.sceneSection) {
      const valid = utf8ValidUpTo(bytes, crsStart, crsStart + crsLen);
      if (valid < crsLen) throw new FormatError('CrsNotUtf8', { offset: crsStart + valid });
      crs = new TextDecoder().decode(bytes.subarray(crsStart, crsStart + crsLen));
    }

    /** The file's bytes. */
    this.bytes = bytes;
    /** The frame stored in the header. */
    this.frame = frame;
    this.version = version;
    /** `major` (2, or 1 for a store written before 2.0) and `minor` of the file. */
    this.major = major;
    this.minor = minor;
    /** The scene section: objects baked for, fingerprint (a `bigint`), CRS; 0, 0n, '' in 1.0. */
    this.objects = objects;
    this.scene = scene;
    this.crs = crs;
    this.cellCount = cells;
    this.groundByte = frame.perCellGround();
    this.indexOffset = indexOffset;
    this.tableOffset = tableOffset;
    this.payloadOffset = payloadOffset;
    this.dv = dv;

    // S10: every index value is a count or skipped (or, in 2.1 with ground bytes, a count with
    // a rise).
    for (let i = 0; i < cells; i++) {
      const value = bytes[indexOffset + i];
      if (countOf(value, version, this.groundByte) < 0) {
        throw new FormatError('BadIndexByte', { cell: i, value, offset: indexOffset + i });
      }
    }
    // S11, S12: the block table and payload_len agree with the counts.
    let off = 0;
    for (let i = 0; i < cells; i++) {
      if (i % CELLS_PER_BLOCK === 0) {
        const block = i / CELLS_PER_BLOCK;
        const st = dv.getUint32(tableOffset + 4 * block, true);
        if (st !== off) throw new FormatError('BlockOffset', { block, stored: st, expected: off });
      }
      off += this.sizeOf(bytes[indexOffset + i]);
    }
    if (off !== payloadLen) {
      throw new FormatError('PayloadLength', { stored: payloadLen, expected: off });
    }
    // S22 (2.1), then S19 and S13 VO by VO (S18: bit 47 is read as the deep flag), in file
    // order.
    off = 0;
    for (let i = 0; i < cells; i++) {
      const value = bytes[indexOffset + i];
      const c = countOf(value, version, this.groundByte);
      if (c > 0) readRecord(i, c, this.groundByte, version, bytes, payloadOffset + off);
      off += this.sizeOf(value);
    }
  }

  /**
   * Payload bytes of a cell with index value `value` (valid).
   * @param {number} value
   */
  sizeOf(value) {
    return recordSize(Math.max(countOf(value, this.version, this.groundByte), 0), this.groundByte, this.version);
  }

  /** Bytes per stored VO in this file: 6 (2.0) or 5 (1.0). */
  get voBytes() {
    return this.version.voBytes;
  }

  /**
   * Bytes of cell `id` in the file: its index byte and its record (0 outside the grid).
   * @param {number} id
   */
  cellBytes(id) {
    if (!(id >= 0 && id < this.cellCount)) return 0;
    return 1 + this.sizeOf(this.bytes[this.indexOffset + id]);
  }

  /**
   * The record of cell `id`: reads at most 63 index bytes and the record.
   * @param {number} id
   * @returns {CellRecord}
   */
  cell(id) {
    if (!(Number.isInteger(id) && id >= 0 && id < this.cellCount)) {
      throw new FormatError('CellOutOfGrid', { id, cells: this.cellCount });
    }
    const value = this.bytes[this.indexOffset + id];
    if (value === SKIPPED) return SKIPPED_RECORD;
    const c = countOf(value, this.version, this.groundByte);
    if (c === 0) return EMPTY_RECORD;
    const block = Math.floor(id / CELLS_PER_BLOCK);
    let off = this.dv.getUint32(this.tableOffset + 4 * block, true);
    for (let i = block * CELLS_PER_BLOCK; i < id; i++) off += this.sizeOf(this.bytes[this.indexOffset + i]);
    return readRecord(id, c, this.groundByte, this.version, this.bytes, this.payloadOffset + off);
  }

  /**
   * The cell holding local position `(x, y)`, or `null` outside the grid.
   * @param {number} x
   * @param {number} y
   */
  cellAt(x, y) {
    return this.frame.cellAt(x, y);
  }
}

/**
 * Decodes and checks a cell blob of major 2 or 1 (FORMAT.md section 8.3, in order) against
 * `frame` (which follows the rules of a frame on its own, F12 at level 31).
 * @param {import('./frame.js').Frame} frame
 * @param {Uint8Array} bytes
 * @returns {{id: number, record: CellRecord}}
 */
export function decodeBlob(frame, bytes) {
  validateFrame(frame);
  const got = bytes.length;
  if (got < BLOB_MIN_LEN) throw new FormatError('Truncated', { needed: BLOB_MIN_LEN, got });
  for (let i = 0; i < 4; i++) if (bytes[i] !== BLOB_MAGIC[i]) throw new FormatError('BadMagic');
  const major = bytes[4];
  const version = VERSIONS[major];
  if (!version) throw new FormatError('UnsupportedVersion', { major });
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const id = dv.getUint32(5, true);
  const value = bytes[BLOB_COUNT_OFFSET];
  const groundByte = frame.perCellGround();
  const c = countOf(value, version, groundByte);
  if (c < 0) throw new FormatError('BadIndexByte', { cell: id, value, offset: BLOB_COUNT_OFFSET });
  exactLength(BLOB_MIN_LEN + recordSize(c, groundByte, version), got);
  const stored = dv.getUint32(got - 4, true);
  const computed = crc32(bytes, 0, got - 4);
  if (stored !== computed) throw new FormatError('Checksum', { stored, computed });
  const cells = frame.cellCount();
  if (id >= cells) throw new FormatError('CellOutOfGrid', { id, cells });
  if (value === SKIPPED) return { id, record: SKIPPED_RECORD };
  if (c === 0) return { id, record: EMPTY_RECORD };
  return { id, record: readRecord(id, c, groundByte, version, bytes, BLOB_RECORD_OFFSET) };
}

export { FRAME_LEN };
