// @ts-check
/**
 * The frame (FORMAT.md section 4): what a decoder needs beside a cell's bytes, and what the
 * bytes mean as geometry. The port of src/runtime/frame.rs, src/runtime/grid.rs and
 * src/runtime/format/frame.rs.
 *
 * Input: 112 bytes, or a frame's fields. Output: a checked {@link Frame}; cell ids at
 * positions, cell rectangles, eye heights (with a 2.1 cell's rise), VO tops and dequantized
 * VOs (a 2.1 deep VO standing from `ground_z0`).
 * Invariants: every number is computed with the same IEEE operations, in the same order, as
 * the Rust code, so the same bits (JavaScript numbers are binary64, and neither side contracts
 * into fused multiply-adds); the rules F1..F12 are checked in the document's order and the first
 * broken one is named.
 */

import { FormatError } from './errors.js';

/** Length of an encoded frame. */
export const FRAME_LEN = 112;
/** Height levels of a 2.0 VO (`0..32`), and of a 1.0 VO (`0..16`). */
export const HEIGHT_LEVELS = 32;
export const HEIGHT_LEVELS_V1 = 16;
/** At most this many VOs per cell. */
export const MAX_VOS_PER_CELL = 10;
/** Most cells a grid may have (rule F4). */
export const MAX_CELLS = 2 ** 31;

/**
 * `r^k` by binary powering, each step rounded: the bits of Rust's `pow_u8` (FORMAT.md 3.4).
 * @param {number} r
 * @param {number} k an integer in 0..=255
 */
export function powU8(r, k) {
  let acc = 1.0;
  for (;;) {
    if (k & 1) acc *= r;
    k >>>= 1;
    if (k === 0) return acc;
    r *= r;
  }
}

/**
 * `x == 2^k` for an integer `k` in `-10..=10`, read off the bits (rule F5).
 * @param {number} x
 */
function isPowerOfTwoInRange(x) {
  const dv = new DataView(new ArrayBuffer(8));
  dv.setFloat64(0, x, true);
  const lo = dv.getUint32(0, true);
  const hi = dv.getUint32(4, true);
  const sign = hi >>> 31;
  const exp = ((hi >>> 20) & 0x7ff) - 1023;
  const mantissa = (hi & 0xfffff) !== 0 || lo !== 0;
  return sign === 0 && !mantissa && exp >= -10 && exp <= 10;
}

/** One quantized endpoint: `centre + (x - 256, y - 256) * quantum * 2^e` (FORMAT.md 3.2). */
export class QPoint {
  /**
   * @param {number} e exponent, 0..8
   * @param {number} x mantissa, 0..512
   * @param {number} y mantissa, 0..512
   */
  constructor(e, x, y) {
    this.e = e;
    this.x = x;
    this.y = y;
  }

  /** No smaller exponent holds the same position (FORMAT.md 3.3). */
  isCanonical() {
    const half = (/** @type {number} */ v) => v >= 128 && v < 384;
    return this.e === 0 || !(half(this.x) && half(this.y));
  }

  /** The offset from the cell's centre in quanta, exact: `[(x - 256) 2^e, (y - 256) 2^e]`. */
  steps() {
    const s = 2 ** this.e;
    return [(this.x - 256) * s, (this.y - 256) * s];
  }

  /**
   * The offset from the cell's centre, metres (exact for a power-of-two quantum).
   * @param {number} quantum
   */
  offset(quantum) {
    const step = quantum * 2 ** this.e;
    return [(this.x - 256) * step, (this.y - 256) * step];
  }
}

/** One VO as stored: two endpoints, a height level and where its bottom stands. */
export class QVo {
  /**
   * @param {QPoint} a
   * @param {QPoint} b
   * @param {number} level
   * @param {boolean} [deep] format 2.1 (bit 47): the VO stands from the frame's lowest ground
   *   level (`ground_z0`) rather than from its cell's ground (FORMAT.md 3.4); false in 2.0
   */
  constructor(a, b, level, deep = false) {
    this.a = a;
    this.b = b;
    this.level = level;
    this.deep = deep;
  }

  isCanonical() {
    return this.a.isCanonical() && this.b.isCanonical();
  }

  /** Both endpoints at the same position (FORMAT.md 3.5). */
  isDegenerate() {
    const [ax, ay] = this.a.steps();
    const [bx, by] = this.b.steps();
    return ax === bx && ay === by;
  }
}

/**
 * A frame: scene origin, cell grid, VO quantization, vertical frame (FORMAT.md section 4).
 * Field names follow the document.
 */
export class Frame {
  /**
   * @param {{origin: number[], minX: number, minY: number, cellSize: number, nx: number,
   *   ny: number, quantum: number, eyeLo: number, eyeHi: number, groundZ0: number,
   *   groundStep: number, h0: number, hRatio: number}} f
   */
  constructor(f) {
    /** World position of the local origin: `world = local + origin`. @type {number[]} */
    this.origin = [f.origin[0], f.origin[1], f.origin[2]];
    this.minX = f.minX;
    this.minY = f.minY;
    this.cellSize = f.cellSize;
    this.nx = f.nx;
    this.ny = f.ny;
    this.quantum = f.quantum;
    this.eyeLo = f.eyeLo;
    this.eyeHi = f.eyeHi;
    this.groundZ0 = f.groundZ0;
    this.groundStep = f.groundStep;
    this.h0 = f.h0;
    this.hRatio = f.hRatio;
  }

  /** Number of cells, `nx * ny`. */
  cellCount() {
    return this.nx * this.ny;
  }

  /** Whether cells carry a ground byte (`ground_step != 0`). */
  perCellGround() {
    return this.groundStep !== 0;
  }

  /**
   * Local height of ground level `level`.
   * @param {number} level
   */
  groundZ(level) {
    return this.groundZ0 + level * this.groundStep;
  }

  /**
   * The top eye of a cell standing on `stand`: `ground_z(level) + rise * ground_step +
   * eye_hi`, in that order (FORMAT.md 3.4; Rust's `Frame::top_eye`).
   * @param {Stand} stand
   */
  topEye(stand) {
    const s = standOf(stand);
    return this.groundZ(s.level) + s.rise * this.groundStep + this.eyeHi;
  }

  /**
   * VO top of level `level` for a cell whose top eye is at `e1` (FORMAT.md 3.4).
   * @param {number} e1
   * @param {number} level
   */
  voTop(e1, level) {
    return e1 + this.h0 * (powU8(this.hRatio, level) - 1.0);
  }

  /**
   * The cell holding local position `(x, y)`, or `null` outside the grid (and for NaN).
   * @param {number} x
   * @param {number} y
   * @returns {number | null}
   */
  cellAt(x, y) {
    const fx = (x - this.minX) / this.cellSize;
    const fy = (y - this.minY) / this.cellSize;
    const inside = fx >= 0.0 && fy >= 0.0 && fx < this.nx && fy < this.ny;
    if (!inside) return null;
    return Math.trunc(fy) * this.nx + Math.trunc(fx);
  }

  /**
   * The cell holding world position `(x, y)`, or `null`.
   * @param {number} x
   * @param {number} y
   */
  cellAtWorld(x, y) {
    return this.cellAt(x - this.origin[0], y - this.origin[1]);
  }

  /**
   * Local rectangle `[x0, y0, x1, y1]` of a cell, or `null` outside the grid.
   * @param {number} id
   * @returns {number[] | null}
   */
  cellRect(id) {
    if (this.nx === 0 || !(id >= 0 && id < this.cellCount()) || !Number.isInteger(id)) return null;
    const i = id % this.nx;
    const j = Math.floor(id / this.nx);
    const x0 = this.minX + i * this.cellSize;
    const y0 = this.minY + j * this.cellSize;
    return [x0, y0, x0 + this.cellSize, y0 + this.cellSize];
  }

  /**
   * Centre of a cell, local frame.
   * @param {number} id
   */
  cellCentre(id) {
    const r = this.cellRect(id);
    if (!r) return null;
    return [r[0] + 0.5 * this.cellSize, r[1] + 0.5 * this.cellSize];
  }

  /**
   * The cell as rule 3 sees it: rectangle and eye heights, for a cell standing on `stand` (its
   * record, or a bare ground level with no rise): eyes from `g + eye_lo` to the top eye
   * `g + rise * ground_step + eye_hi` (FORMAT.md 3.4). Pass the record: a 2.1 cell's rise
   * raises its top eye, and leaving it out would cull with eyes lower than the cameras'.
   * @param {number} id
   * @param {Stand} stand
   * @returns {CellView | null}
   */
  cellView(id, stand) {
    const rect = this.cellRect(id);
    if (!rect) return null;
    const g = this.groundZ(standOf(stand).level);
    return { rect, e0: g + this.eyeLo, e1: this.topEye(stand) };
  }

  /**
   * The geometry of a stored VO of cell `id` standing on `stand` (its record, or a bare ground
   * level): segment `a`–`b` (local) standing from the cell's ground `g`, or from `ground_z0`
   * for a deep VO (2.1), to the top `h` of its level above the cell's top eye.
   * @param {number} id
   * @param {Stand} stand
   * @param {QVo} q
   * @returns {VoGeom | null}
   */
  dequantize(id, stand, q) {
    const c = this.cellCentre(id);
    if (!c) return null;
    const g = this.groundZ(standOf(stand).level);
    const oa = q.a.offset(this.quantum);
    const ob = q.b.offset(this.quantum);
    return {
      a: [c[0] + oa[0], c[1] + oa[1]],
      b: [c[0] + ob[0], c[1] + ob[1]],
      g: q.deep ? this.groundZ0 : g,
      h: this.voTop(this.topEye(stand), q.level),
    };
  }
}

/**
 * Where a cell stands: a bare ground level (rise 0), or anything with the `ground` level and
 * `rise` of a cell record (format 2.1; 0 in 2.0), such as the record itself.
 * @typedef {number | {ground: number, rise?: number}} Stand
 */

/**
 * `stand` as a level and a rise.
 * @param {Stand} stand
 * @returns {{level: number, rise: number}}
 */
export function standOf(stand) {
  if (typeof stand === 'number') return { level: stand, rise: 0 };
  return { level: stand.ground, rise: stand.rise ?? 0 };
}

/**
 * @typedef {{rect: number[], e0: number, e1: number}} CellView
 * @typedef {{a: number[], b: number[], g: number, h: number}} VoGeom
 */

/**
 * The frame rules F1..F12 of FORMAT.md 4.1, in order, with F12 at level `topLevel` (31 for a
 * frame on its own and a 2.0 store, 15 in a 1.0 store's header). Throws `BadFrame`.
 * @param {Frame} f
 * @param {number} [topLevel]
 */
export function validateFrame(f, topLevel = HEIGHT_LEVELS - 1) {
  const floats = [
    f.origin[0], f.origin[1], f.origin[2], f.minX, f.minY, f.cellSize,
    f.quantum, f.eyeLo, f.eyeHi, f.groundZ0, f.groundStep, f.h0, f.hRatio,
  ];
  /** @param {boolean} ok @param {string} rule */
  const rule = (ok, rule) => {
    if (!ok) throw new FormatError('BadFrame', { rule });
  };
  rule(floats.every(Number.isFinite), 'F1: every float must be finite');
  rule(f.cellSize > 0.0, 'F2: cell_size must be > 0');
  rule(f.nx >= 1 && f.ny >= 1, 'F3: nx and ny must be >= 1');
  rule(f.nx * f.ny <= MAX_CELLS, 'F4: nx * ny must be <= 2^31');
  rule(isPowerOfTwoInRange(f.quantum), 'F5: quantum must be a power of two in [2^-10, 2^10]');
  rule(f.eyeLo >= 0.0, 'F6: eye_lo must be >= 0');
  rule(f.eyeLo <= f.eyeHi, 'F7: eye_lo must be <= eye_hi');
  rule(f.groundStep >= 0.0, 'F8: ground_step must be >= 0');
  rule(f.h0 > 0.0, 'F9: h0 must be > 0');
  rule(f.hRatio >= 1.0, 'F10: h_ratio must be >= 1');
  const farX = f.minX + f.nx * f.cellSize;
  const farY = f.minY + f.ny * f.cellSize;
  rule(Number.isFinite(farX) && Number.isFinite(farY), "F11: the grid's far corner must be finite");
  const top = f.voTop(f.groundZ(255) + f.eyeHi, topLevel);
  rule(Number.isFinite(top), 'F12: the highest VO top must be finite');
}

/**
 * Reads the 112 bytes at `at` as a frame (no checks).
 * @param {DataView} dv
 * @param {number} at
 */
export function readFrame(dv, at) {
  const f64 = (/** @type {number} */ o) => dv.getFloat64(at + o, true);
  return new Frame({
    origin: [f64(0), f64(8), f64(16)],
    minX: f64(24),
    minY: f64(32),
    cellSize: f64(40),
    nx: dv.getUint32(at + 48, true),
    ny: dv.getUint32(at + 52, true),
    quantum: f64(56),
    eyeLo: f64(64),
    eyeHi: f64(72),
    groundZ0: f64(80),
    groundStep: f64(88),
    h0: f64(96),
    hRatio: f64(104),
  });
}

/**
 * The frame's 112 bytes (writes any frame as it is).
 * @param {Frame} f
 */
export function encodeFrame(f) {
  const out = new Uint8Array(FRAME_LEN);
  const dv = new DataView(out.buffer);
  const put = (/** @type {number} */ o, /** @type {number} */ v) => dv.setFloat64(o, v, true);
  put(0, f.origin[0]);
  put(8, f.origin[1]);
  put(16, f.origin[2]);
  put(24, f.minX);
  put(32, f.minY);
  put(40, f.cellSize);
  dv.setUint32(48, f.nx, true);
  dv.setUint32(52, f.ny, true);
  put(56, f.quantum);
  put(64, f.eyeLo);
  put(72, f.eyeHi);
  put(80, f.groundZ0);
  put(88, f.groundStep);
  put(96, f.h0);
  put(104, f.hRatio);
  return out;
}

/**
 * Decodes and checks a frame from exactly 112 bytes (FORMAT.md 8.2: R1, R2, R3).
 * @param {Uint8Array} bytes
 */
export function decodeFrame(bytes) {
  if (bytes.length > FRAME_LEN) {
    throw new FormatError('TrailingBytes', { expected: FRAME_LEN, got: bytes.length });
  }
  if (bytes.length < FRAME_LEN) {
    throw new FormatError('Truncated', { needed: FRAME_LEN, got: bytes.length });
  }
  const f = readFrame(new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength), 0);
  validateFrame(f);
  return f;
}
