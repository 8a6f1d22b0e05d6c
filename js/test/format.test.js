// @ts-check
// The JavaScript decoders against docs/FORMAT.md, as tests/format.rs checks the Rust ones: the
// worked examples of every version (2.0, 1.0 and 2.1) byte for byte, and one test per row of the
// "accepted?" tables (8.1 store, 8.2 frame, 8.3 blob), on both majors where the row applies to
// both, with the same error kind, fields and message as the Rust decoder (corpus.test.js also
// runs the 2.1 rows' inputs through the Rust decoder itself).

import { test } from 'node:test';
import assert from 'node:assert/strict';

import {
  Store, decodeBlob, decodeFrame, encodeFrame, crc32, Frame, QPoint, QVo, FormatError, hypot,
} from '../src/index.js';
import {
  docHex, docFrame, encodeStore, encodeBlob, fixStoreCrc, fixBlobCrc, throwsFormat, frameRule, voBytes, u32,
} from './helpers.js';

const p = (/** @type {number} */ e, /** @type {number} */ x, /** @type {number} */ y) => ({ e, x, y });
/** A VO as a decoded record holds it (`deep` false unless given). */
const v = (/** @type {{e: number, x: number, y: number}} */ a, /** @type {{e: number, x: number, y: number}} */ b, /** @type {number} */ level, deep = false) => ({ a, b, level, deep });
const q = (/** @type {number[]} */ [x1, y1, x2, y2, level]) => v(p(0, x1, y1), p(0, x2, y2), level);
/** A record as the decoders give it (rise 0 unless given). */
const rec = (/** @type {number} */ ground, /** @type {any[]} */ vos, rise = 0) => ({ skipped: false, ground, rise, vos });
/** @param {any} r */
const plain = (r) => JSON.parse(JSON.stringify(r));

const SKIPPED_CELL = { skipped: true, ground: 0, rise: 0, vos: [] };
const EMPTY_CELL = rec(0, []);
const DOC_CELLS = [
  rec(4, [q([196, 376, 336, 376, 5]), v(p(3, 194, 406), p(3, 344, 406), 20), v(p(0, 376, 346), p(2, 286, 456), 16)]),
  SKIPPED_CELL,
  EMPTY_CELL,
];
const DOC_CELLS_V1 = [rec(4, [q([196, 376, 336, 376, 5]), q([376, 176, 376, 346, 3])]), SKIPPED_CELL, EMPTY_CELL];
/** Section 13 (2.1): cell 0 with a rise of 6, its near wall and the far wall made deep. */
const DOC_CELLS_21 = [rec(4, [q([196, 376, 336, 376, 5]), v(p(3, 194, 406), p(3, 344, 406), 20, true)], 6), SKIPPED_CELL, EMPTY_CELL];

/** The 2.0 store of 9.1 and the 1.0 store of 12, with where their parts lie. */
function docs() {
  return [
    { major: 2, bytes: docHex('store'), cells: DOC_CELLS, index: 0x9e, table: 0xa1, ground: 0xa5, vo0: 0xa6, voBytes: 6, payloadLen: 19, crc: 0xe7004571 },
    { major: 1, bytes: docHex('store-1.0'), cells: DOC_CELLS_V1, index: 0x88, table: 0x8b, ground: 0x8f, vo0: 0x90, voBytes: 5, payloadLen: 11, crc: 0x82b0c79a },
  ];
}
/** @param {{vo0: number, voBytes: number}} d @param {number} k */
const voAt = (d, k) => d.vo0 + k * d.voBytes;
/** @param {{bytes: Uint8Array, vo0: number, voBytes: number}} d @param {number} k @param {number[]} vo */
function withVo(d, k, vo) {
  const s = d.bytes.slice();
  s.set(vo, voAt(d, k));
  fixStoreCrc(s);
  return s;
}
/** @param {Uint8Array} b @param {number} at @param {number[]} v */
const patched = (b, at, v, fix = true) => {
  const s = b.slice();
  s.set(v, at);
  if (fix) fixStoreCrc(s);
  return s;
};

test('doc store example decodes as FORMAT.md 9.1 says', () => {
  const bytes = docHex('store');
  assert.equal(bytes.length, 184);
  const s = Store.parse(bytes);
  assert.deepEqual([s.major, s.minor, s.voBytes], [2, 0, 6]);
  assert.deepEqual([s.objects, s.scene, s.crs, s.cellCount], [2576, 0x9e3779b97f4a7c15n, 'EPSG:2154', 3]);
  assert.deepEqual({ ...s.frame }, { ...docFrame() });
  for (let i = 0; i < 3; i++) assert.deepEqual(plain(s.cell(i)), DOC_CELLS[i]);
  assert.deepEqual([0, 1, 2, 3].map((i) => s.cellBytes(i)), [20, 1, 1, 0]);
  assert.equal(s.cellAt(150, 99), 1);
  assert.equal(s.cellAt(300, 0), null);
  assert.deepEqual(bytes.subarray(16, 128), encodeFrame(docFrame()));
  // The writer of the tests gives the same bytes (it pins the VO layout).
  assert.deepEqual(encodeStore(docFrame(), DOC_CELLS, { objects: 2576, scene: 0x9e3779b97f4a7c15n, crs: 'EPSG:2154' }), bytes);
  throwsFormat(() => s.cell(3), 'CellOutOfGrid', { id: 3, cells: 3 });
});

test('doc worked VO decoding matches the frame (FORMAT.md 3, 9.1, 7)', () => {
  const f = docFrame();
  const s = Store.parse(docHex('store'));
  const [near, far, north] = s.cell(0).vos;
  assert.deepEqual(f.dequantize(0, 4, near), { a: [20, 110], b: [90, 110], g: 162, h: 172.20703125 });
  assert.deepEqual(f.dequantize(0, 4, far), { a: [-198, 650], b: [402, 650], g: 162, h: 506.9446951953614 });
  assert.deepEqual(f.dequantize(0, 4, north), { a: [110, 95], b: [110, 450], g: 162, h: 302.10854715202004 });
  assert.deepEqual(far.a.offset(0.5), [-248, 600]);
  assert.equal(new QPoint(3, 200, 300).isCanonical(), false);
  assert.deepEqual(new QPoint(1, 32, 432).steps(), new QPoint(3, 200, 300).steps());
  assert.ok(new QPoint(3, 194, 406).isCanonical() && new QPoint(2, 286, 456).isCanonical());
  assert.ok(!new QPoint(3, 256, 256).isCanonical() && new QPoint(0, 256, 256).isCanonical());
  assert.equal(crc32(new TextEncoder().encode('123456789')), 0xcbf43926);
});

test('doc blob examples decode (FORMAT.md 9.2 and 12)', () => {
  const f = docFrame();
  const b0 = docHex('blob-cell0');
  assert.equal(b0.length, 33);
  assert.deepEqual(plain(decodeBlob(f, b0)), { id: 0, record: DOC_CELLS[0] });
  assert.deepEqual(plain(decodeBlob(f, docHex('blob-cell1'))), { id: 1, record: DOC_CELLS[1] });
  assert.deepEqual(encodeBlob(f, 0, DOC_CELLS[0]), b0);
  assert.deepEqual(b0.subarray(10, 29), docHex('store').subarray(0xa5, 0xb8));
  const v0 = docHex('blob-1.0-cell0');
  assert.equal(v0.length, 25);
  assert.deepEqual(plain(decodeBlob(f, v0)), { id: 0, record: DOC_CELLS_V1[0] });
  assert.deepEqual(encodeBlob(f, 0, DOC_CELLS_V1[0], 1), v0);
  assert.deepEqual(plain(decodeBlob(f, docHex('blob-1.0-cell1'))), { id: 1, record: DOC_CELLS_V1[1] });
});

test('S21: the 1.0 example is read as 2.0 records with exponents 0', () => {
  const bytes = docHex('store-1.0');
  assert.equal(bytes.length, 154);
  assert.deepEqual(encodeStore(docFrame(), DOC_CELLS_V1, { major: 1 }), bytes);
  const s = Store.parse(bytes);
  assert.deepEqual([s.major, s.minor, s.voBytes, s.objects, s.scene, s.crs], [1, 0, 5, 0, 0n, '']);
  for (let i = 0; i < 3; i++) assert.deepEqual(plain(s.cell(i)), DOC_CELLS_V1[i]);
  assert.deepEqual([s.cellBytes(0), s.cellBytes(1)], [12, 1]);
  const [a, b] = s.cell(0).vos;
  assert.deepEqual(s.frame.dequantize(0, 4, a), { a: [20, 110], b: [90, 110], g: 162, h: 172.20703125 });
  assert.deepEqual(s.frame.dequantize(0, 4, b), { a: [110, 10], b: [110, 95], g: 162, h: 167.8125 });
  assert.deepEqual(voBytes(a, 1), [0xc4, 0xf0, 0x42, 0xc5, 0x5b]);
  assert.deepEqual(voBytes(a, 2), [0x20, 0x86, 0x17, 0x50, 0xf1, 0x16]);
});

// Section 8.2: the frame alone.

test('R1, R2: a frame is exactly 112 bytes', () => {
  const b = encodeFrame(docFrame());
  assert.deepEqual({ ...decodeFrame(b) }, { ...docFrame() });
  throwsFormat(() => decodeFrame(b.subarray(0, 111)), 'Truncated', { needed: 112, got: 111 });
  throwsFormat(() => decodeFrame(new Uint8Array(0)), 'Truncated', { needed: 112, got: 0 });
  const long = new Uint8Array(113);
  long.set(b);
  const e = throwsFormat(() => decodeFrame(long), 'TrailingBytes', { expected: 112, got: 113 });
  assert.equal(e.message, 'trailing bytes: 112 bytes expected, 113 given');
});

/** @type {[string, (f: Frame) => void][]} */
const FRAME_CASES = [
  ['F1', (f) => { f.origin[0] = NaN; }],
  ['F1', (f) => { f.origin[2] = Infinity; }],
  ['F1', (f) => { f.minY = -Infinity; }],
  ['F1', (f) => { f.hRatio = NaN; }],
  ['F1', (f) => { f.groundStep = Infinity; }],
  ['F2', (f) => { f.cellSize = 0; }],
  ['F2', (f) => { f.cellSize = -100; }],
  ['F3', (f) => { f.nx = 0; }],
  ['F3', (f) => { f.ny = 0; }],
  ['F4', (f) => { f.nx = 1 << 16; f.ny = (1 << 15) + 1; }],
  ['F4', (f) => { f.nx = 0xffffffff; f.ny = 0xffffffff; }],
  ['F5', (f) => { f.quantum = 0.3; }],
  ['F5', (f) => { f.quantum = 2048; }],
  ['F5', (f) => { f.quantum = 1 / 2048; }],
  ['F5', (f) => { f.quantum = -0.5; }],
  ['F5', (f) => { f.quantum = 0; }],
  ['F6', (f) => { f.eyeLo = -0.1; }],
  ['F7', (f) => { f.eyeLo = 2.5; }],
  ['F8', (f) => { f.groundStep = -0.5; }],
  ['F9', (f) => { f.h0 = 0; }],
  ['F9', (f) => { f.h0 = -1; }],
  ['F10', (f) => { f.hRatio = 0.99; }],
  ['F11', (f) => { f.cellSize = 1e306; f.nx = 1000; }],
  ['F12', (f) => { f.groundStep = 1e307; }],
  ['F12', (f) => { f.hRatio = 1e30; }],
];

test('R3, S6, B0: frame rules F1 to F12, in order, in a frame alone, a store of each major and beside a blob', () => {
  for (const [rule, mutate] of FRAME_CASES) {
    const f = docFrame();
    mutate(f);
    const bytes = encodeFrame(f);
    assert.equal(frameRule(() => decodeFrame(bytes)), rule, JSON.stringify(f));
    for (const d of docs()) {
      assert.equal(frameRule(() => Store.parse(patched(d.bytes, 16, [...bytes]))), rule, `${d.major}.0`);
    }
    assert.equal(frameRule(() => decodeBlob(f, docHex('blob-cell0'))), rule);
  }
  // The limits themselves are accepted: 2^31 cells, quantum 2^-10 and 2^10.
  const f = docFrame();
  f.nx = 1 << 16;
  f.ny = 1 << 15;
  f.quantum = 1 / 1024;
  decodeFrame(encodeFrame(f));
  f.quantum = 1024;
  decodeFrame(encodeFrame(f));
  // The message is Rust's.
  const bad = docFrame();
  bad.cellSize = 0;
  assert.equal(throwsFormat(() => decodeFrame(encodeFrame(bad)), 'BadFrame').message, 'bad frame: rule F2: cell_size must be > 0');
});

test('F12 takes the highest level of the major (31; 15 in a 1.0 store)', () => {
  const f = docFrame();
  f.h0 = 1e306;
  assert.ok(Number.isFinite(f.voTop(f.groundZ(255) + f.eyeHi, 15)));
  assert.ok(!Number.isFinite(f.voTop(f.groundZ(255) + f.eyeHi, 31)));
  assert.deepEqual(plain(Store.parse(encodeStore(f, DOC_CELLS_V1, { major: 1 })).cell(0)), DOC_CELLS_V1[0]);
  assert.equal(frameRule(() => decodeFrame(encodeFrame(f))), 'F12');
  assert.equal(frameRule(() => decodeBlob(f, docHex('blob-1.0-cell0'))), 'F12');
  assert.equal(frameRule(() => Store.parse(encodeStore(f, DOC_CELLS))), 'F12');
});

test('R4: edge values are accepted', () => {
  const f = docFrame();
  Object.assign(f, { eyeLo: 0, eyeHi: 2, hRatio: 1, minX: -5000, minY: -7.5, groundZ0: -30 });
  assert.deepEqual({ ...decodeFrame(encodeFrame(f)) }, { ...f });
});

// Section 8.1: the store.

test('S1: shorter than the header', () => {
  for (const d of docs()) {
    for (const n of [0, 1, 8, 135]) throwsFormat(() => Store.parse(d.bytes.subarray(0, n)), 'Truncated', { needed: 136, got: n });
  }
});

test('S2: bad magic', () => {
  for (const d of docs()) {
    throwsFormat(() => Store.parse(patched(d.bytes, 0, [0x88], false)), 'BadMagic');
    throwsFormat(() => Store.parse(patched(d.bytes, 0, [0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a], false)), 'BadMagic');
    throwsFormat(() => decodeBlob(docFrame(), d.bytes), 'BadMagic');
  }
  for (const name of ['blob-cell0', 'blob-1.0-cell0']) {
    const blob = new Uint8Array(200);
    blob.set(docHex(name));
    const e = throwsFormat(() => Store.parse(blob), 'BadMagic');
    assert.equal(e.message, 'bad magic number: not a vocc store or blob');
  }
});

test('S3: unknown major', () => {
  for (const d of docs()) {
    for (const major of [0, 3, 0x0102, 0xffff]) {
      throwsFormat(() => Store.parse(patched(d.bytes, 8, [major & 0xff, major >> 8])), 'UnsupportedVersion', { major });
    }
  }
  assert.equal(new FormatError('UnsupportedVersion', { major: 3 }).message, 'unsupported major version 3 (this reader implements 1 and 2)');
});

test('S4: any minor is accepted', () => {
  for (const d of docs()) {
    const s = Store.parse(patched(d.bytes, 10, [7, 0]));
    assert.deepEqual([s.major, s.minor], [d.major, 7]);
    assert.deepEqual(plain(s.cell(0)), d.cells[0]);
  }
});

test('S5: nonzero flags', () => {
  for (const d of docs()) {
    for (const flags of [1, 0x80000000]) {
      const e = throwsFormat(() => Store.parse(patched(d.bytes, 12, u32(flags))), 'UnknownFlags', { flags });
      if (flags === 1) assert.equal(e.message, 'unknown flags 0x00000001 at offset 12 (every bit is reserved in versions 1.0 and 2.0)');
    }
  }
});

test('S6: a bad frame in the header, checked before the checksum', () => {
  for (const d of docs()) {
    const neg = new Uint8Array(new Float64Array([-100]).buffer);
    assert.equal(frameRule(() => Store.parse(patched(d.bytes, 56, [...neg]))), 'F2');
    assert.equal(frameRule(() => Store.parse(patched(d.bytes, 64, [0, 0, 0, 0], false))), 'F3');
  }
});

test('S7: shorter than its length fields say', () => {
  for (const d of docs()) {
    const n = d.bytes.length;
    throwsFormat(() => Store.parse(d.bytes.subarray(0, n - 1)), 'Truncated', { needed: n, got: n - 1 });
    throwsFormat(() => Store.parse(patched(d.bytes, 128, u32(0xffffffff))), 'Truncated', { needed: d.ground + 0xffffffff, got: n });
    const big = patched(d.bytes, 64, [...u32(1 << 16), ...u32(1 << 15)], false);
    const cells = 2 ** 31;
    throwsFormat(() => Store.parse(big), 'Truncated', { needed: d.index + cells + 4 * (cells / 64) + d.payloadLen, got: n });
  }
  const s = docHex('store');
  for (const n of [136, 140, 148]) throwsFormat(() => Store.parse(s.subarray(0, n)), 'Truncated', { needed: 149, got: n });
  throwsFormat(() => Store.parse(s.subarray(0, 150)), 'Truncated', { needed: 184, got: 150 });
  throwsFormat(() => Store.parse(patched(s, 0x94, [255])), 'Truncated', { needed: 184 + 246, got: 184 });
});

test('S8: trailing bytes', () => {
  for (const d of docs()) {
    const s = new Uint8Array(d.bytes.length + 1);
    s.set(d.bytes);
    throwsFormat(() => Store.parse(s), 'TrailingBytes', { expected: d.bytes.length, got: d.bytes.length + 1 });
  }
  throwsFormat(() => Store.parse(patched(docHex('store'), 0x94, [8])), 'TrailingBytes', { expected: 183, got: 184 });
});

test('S9: checksum mismatch, over every part', () => {
  for (const d of docs()) {
    const s = d.bytes.slice();
    s[d.vo0] ^= 1;
    const e = throwsFormat(() => Store.parse(s), 'Checksum');
    assert.equal(e.fields.stored, d.crc);
    assert.notEqual(e.fields.computed, d.crc);
    assert.match(e.message, /^checksum mismatch: stored 0x[0-9a-f]{8}, computed 0x[0-9a-f]{8}$/);
    const places = [20, 100, d.index + 1, d.table, d.ground];
    if (d.major === 2) places.push(0x88, 0x8c, 0x93, 0x95, 0x9d);
    for (const at of places) {
      const t = d.bytes.slice();
      t[at] ^= 0x40;
      throwsFormat(() => Store.parse(t), 'Checksum');
    }
  }
});

test('S10: reserved index values (11..=20 only in 1.0 and without ground bytes, 2.1)', () => {
  for (const d of docs()) {
    // 11..=20 announce a rise byte in 2.1 (section 13): reserved in 1.0 only.
    const values = d.major === 1 ? [11, 12, 20, 21, 0x80, 254] : [21, 0x80, 254];
    for (const value of values) {
      const e = throwsFormat(() => Store.parse(patched(d.bytes, d.index + 1, [value])), 'BadIndexByte', { cell: 1, value, offset: d.index + 1 });
      if (value === 21 && d.major === 2) assert.equal(e.message, `bad count 21 for cell 1 at offset ${d.index + 1} (0..=10 VOs or 255 skipped)`);
    }
  }
  // In a 2.0 store with ground bytes, 11..=20 are counts with a rise byte: cell 1 at 11 takes a
  // record of 6 + 2 bytes, which payload_len does not hold (S12 comes next).
  const d = docs()[0];
  for (const value of [11, 20]) {
    const size = 6 * (value - 10) + 2;
    throwsFormat(() => Store.parse(patched(d.bytes, d.index + 1, [value])), 'PayloadLength', { stored: 19, expected: 19 + size });
  }
  // Without ground bytes (flat ground), 11..=20 are refused in 2.0 too.
  const flat = docFrame();
  flat.groundStep = 0;
  const s = encodeStore(flat, [rec(0, [q([196, 376, 336, 376, 5])], 6), {}, {}]);
  assert.equal(s[149], 11);
  throwsFormat(() => Store.parse(s), 'BadIndexByte', { cell: 0, value: 11, offset: 149 });
});

test('S11: a block table inconsistent with the counts', () => {
  for (const d of docs()) {
    throwsFormat(() => Store.parse(patched(d.bytes, d.table, [1])), 'BlockOffset', { block: 0, stored: 1, expected: 0 });
    const f = docFrame();
    f.nx = 100;
    const cells = Array.from({ length: 100 }, () => ({}));
    cells[3] = d.cells[0];
    cells[70] = d.cells[0];
    const good = encodeStore(f, cells, { major: d.major });
    const table = 136 + (d.major === 2 ? 13 : 0) + 100;
    assert.deepEqual([...good.subarray(table, table + 8)], [0, 0, 0, 0, d.payloadLen, 0, 0, 0]);
    throwsFormat(() => Store.parse(patched(good, table + 4, [d.payloadLen + 5])), 'BlockOffset', { block: 1, stored: d.payloadLen + 5, expected: d.payloadLen });
    const s = Store.parse(good);
    assert.deepEqual(plain(s.cell(70)), d.cells[0]);
  }
});

test('S12: payload_len inconsistent with the counts', () => {
  for (const d of docs()) {
    const record = (/** @type {number} */ n) => 1 + n * d.voBytes;
    throwsFormat(() => Store.parse(patched(d.bytes, d.index, [1])), 'PayloadLength', { stored: d.payloadLen, expected: record(1) });
    throwsFormat(() => Store.parse(patched(d.bytes, d.index + 2, [1])), 'PayloadLength', { stored: d.payloadLen, expected: d.payloadLen + record(1) });
  }
});

test('S13: a degenerate VO', () => {
  for (const d of docs()) {
    const deg = voBytes(q([300, 20, 300, 20, 9]), d.major);
    throwsFormat(() => Store.parse(withVo(d, 1, deg)), 'DegenerateVo', { cell: 0, vo: 1, offset: voAt(d, 1) });
    throwsFormat(() => Store.parse(withVo(d, 0, new Array(d.voBytes).fill(0))), 'DegenerateVo', { cell: 0, vo: 0, offset: voAt(d, 0) });
  }
  const far = voBytes({ a: p(5, 0, 511), b: p(5, 0, 511), level: 31 }, 2);
  const e = throwsFormat(() => Store.parse(withVo(docs()[0], 2, far)), 'DegenerateVo', { cell: 0, vo: 2, offset: 0xb2 });
  assert.equal(e.message, 'VO 2 of cell 0 at offset 178 is degenerate (one grid point)');
});

test('S14, S15, S16, S20: accepted edge cases', () => {
  const f = docFrame();
  const cells = [{}, { skipped: true }, {}];
  for (const [major, len] of [[2, 136 + 13 + 3 + 4], [1, 136 + 3 + 4]]) {
    const s = encodeStore(f, cells, { major });
    assert.equal(s.length, len);
    const st = Store.parse(s);
    assert.deepEqual(plain(st.cell(1)), DOC_CELLS[1]);
  }
  for (const d of docs()) assert.equal(Store.parse(patched(d.bytes, d.ground, [255])).cell(0).ground, 255);
  const flat = docFrame();
  flat.groundStep = -0;
  const flatCells = [{ vos: [q([196, 376, 336, 376, 5])] }, {}, { skipped: true }];
  for (const [major, len] of [[2, 136 + 13 + 3 + 4 + 6], [1, 136 + 3 + 4 + 5]]) {
    const s = encodeStore(flat, flatCells, { major });
    assert.equal(s.length, len);
    const st = Store.parse(s);
    assert.ok(Object.is(st.frame.groundStep, -0));
    assert.deepEqual(plain(st.cell(0)), rec(0, flatCells[0].vos ?? []));
  }
  // S20: every exponent and level, any objects and scene, a CRS of 255 bytes of UTF-8.
  const vos = [v(p(7, 0, 511), p(0, 1, 2), 31), v(p(1, 127, 256), p(6, 511, 0), 0)];
  const st = Store.parse(encodeStore(f, [{ ground: 9, vos }, {}, {}], { objects: 0xffffffff, scene: 0xffffffffffffffffn, crs: 'é'.repeat(127) + 'x' }));
  assert.deepEqual(plain(st.cell(0)), rec(9, vos));
  assert.deepEqual([st.objects, st.scene, st.crs.length], [0xffffffff, 0xffffffffffffffffn, 128]);
});

test('S17: a CRS name that is not UTF-8', () => {
  throwsFormat(() => Store.parse(patched(docHex('store'), 0x97, [0xff])), 'CrsNotUtf8', { offset: 0x97 });
  throwsFormat(() => Store.parse(patched(docHex('store'), 0x9d, [0xc3])), 'CrsNotUtf8', { offset: 0x9d });
  const s = patched(docHex('store'), 0x97, [0xff], false);
  throwsFormat(() => Store.parse(s), 'Checksum');
  s[0x9f] = 11;
  fixStoreCrc(s);
  const e = throwsFormat(() => Store.parse(s), 'CrsNotUtf8', { offset: 0x97 });
  assert.equal(e.message, 'the CRS name is not UTF-8 (at offset 151)');
  // Overlong forms, surrogates and code points past U+10FFFF are not UTF-8 either.
  for (const bad of [[0xc0, 0x80], [0xe0, 0x80, 0x80], [0xed, 0xa0, 0x80], [0xf4, 0x90, 0x80, 0x80], [0xf8]]) {
    const crs = 'EP' + 'x'.repeat(7 - bad.length);
    const b = encodeStore(docFrame(), DOC_CELLS, { crs: crs + 'x'.repeat(bad.length) });
    b.set(bad, 149 + crs.length);
    fixStoreCrc(b);
    throwsFormat(() => Store.parse(b), 'CrsNotUtf8', { offset: 149 + crs.length });
  }
});

test('S18: bit 47 of a VO is read as the deep flag (2.1)', () => {
  // Bit 47 was reserved in 2.0; 2.1 reads it as the deep flag (FORMAT.md 3.1): the VO stands
  // from ground_z0. The same bytes otherwise, and any minor (here the 2.0 example's 0).
  const d = docs()[0];
  const s = d.bytes.slice();
  s[voAt(d, 1) + 5] |= 0x80;
  fixStoreCrc(s);
  const st = Store.parse(s);
  assert.equal(st.minor, 0);
  const r = st.cell(0);
  assert.deepEqual(r.vos.map((x) => x.deep), [false, true, false]);
  assert.deepEqual(plain(r.vos[1]), { ...DOC_CELLS[0].vos[1], deep: true });
  const g = /** @type {import('../src/frame.js').VoGeom} */ (st.frame.dequantize(0, r, r.vos[1]));
  assert.equal(g.g, 160); // ground_z0, not the cell's 162
  assert.equal(g.h, 506.9446951953614);
  assert.equal(/** @type {import('../src/frame.js').VoGeom} */ (st.frame.dequantize(0, r, r.vos[0])).g, 162);
  // Re-encoded by the tests' writer: the same bytes with minor 1, read back the same.
  const again = encodeStore(docFrame(), [plain(r), DOC_CELLS[1], DOC_CELLS[2]], { objects: 2576, scene: 0x9e3779b97f4a7c15n, crs: 'EPSG:2154' });
  assert.deepEqual([...again.subarray(8, 12)], [2, 0, 1, 0]);
  assert.deepEqual(plain(Store.parse(again).cell(0)), plain(r));
  // An all-ones VO is deep, canonical and degenerate (both ends (7, 511, 511)).
  throwsFormat(() => Store.parse(withVo(d, 0, new Array(6).fill(0xff))), 'DegenerateVo', { cell: 0, vo: 0, offset: 0xa6 });
  // A deep VO that is not canonical is refused as such (S19 after S18).
  const nc = voBytes({ a: p(1, 226, 316), b: p(0, 336, 376), level: 5, deep: true }, 2);
  assert.equal(nc[5] & 0x80, 0x80);
  throwsFormat(() => Store.parse(withVo(d, 0, nc)), 'NonCanonicalVo', { cell: 0, vo: 0, offset: 0xa6, endpoint: 'a' });
  // The 2.0 reader's refusal keeps Rust's message (this reader never throws it).
  assert.equal(new FormatError('ReservedVoBit', { cell: 0, vo: 1, offset: 172 }).message, 'VO 1 of cell 0 at offset 172 sets the reserved bit 47');
});

// Section 13: version 2.1.

test('doc 2.1 store example decodes as FORMAT.md 13 says', () => {
  const bytes = docHex('store-2.1');
  assert.equal(bytes.length, 179);
  const s = Store.parse(bytes);
  assert.deepEqual([s.major, s.minor, s.voBytes], [2, 1, 6]);
  assert.deepEqual([s.objects, s.scene, s.crs, s.cellCount], [2576, 0x9e3779b97f4a7c15n, 'EPSG:2154', 3]);
  assert.deepEqual({ ...s.frame }, { ...docFrame() });
  for (let i = 0; i < 3; i++) assert.deepEqual(plain(s.cell(i)), DOC_CELLS_21[i]);
  // Cell 0: its index byte and a record of ground, rise and two VOs.
  assert.deepEqual([0, 1, 2].map((i) => s.cellBytes(i)), [1 + 14, 1, 1]);
  assert.equal(bytes[0x9e], 12);
  // The writer of the tests gives the same bytes, minor 1 included (it pins the layout).
  assert.deepEqual(encodeStore(docFrame(), DOC_CELLS_21, { objects: 2576, scene: 0x9e3779b97f4a7c15n, crs: 'EPSG:2154' }), bytes);
  // The same records without the rise and the deep bit are a 2.0 file.
  const plain20 = [rec(4, DOC_CELLS_21[0].vos.map((x) => ({ ...x, deep: false }))), SKIPPED_CELL, EMPTY_CELL];
  assert.deepEqual([...encodeStore(docFrame(), plain20).subarray(8, 12)], [2, 0, 0, 0]);
});

test('doc 2.1 worked figures: the rise raises the eyes and the tops, the deep VO stands from ground_z0', () => {
  const f = docFrame();
  const s = Store.parse(docHex('store-2.1'));
  const r = s.cell(0);
  assert.deepEqual([r.ground, r.rise], [4, 6]);
  const view = /** @type {import('../src/frame.js').CellView} */ (f.cellView(0, r));
  assert.deepEqual([view.e0, view.e1], [163.5, 167]);
  assert.equal(f.topEye(r), 167);
  assert.deepEqual(f.dequantize(0, r, r.vos[0]), { a: [20, 110], b: [90, 110], g: 162, h: 175.20703125 });
  assert.deepEqual(f.dequantize(0, r, r.vos[1]), { a: [-198, 650], b: [402, 650], g: 160, h: 509.9446951953614 });
  // A bare level has no rise: the 2.0 figures (section 9.1).
  const bare = /** @type {import('../src/frame.js').CellView} */ (f.cellView(0, 4));
  assert.deepEqual([bare.e0, bare.e1], [163.5, 164]);
  assert.equal(/** @type {import('../src/frame.js').VoGeom} */ (f.dequantize(0, 4, r.vos[0])).h, 172.20703125);
});

test('doc 2.1 blob example decodes as FORMAT.md 13 says', () => {
  const f = docFrame();
  const b = docHex('blob-2.1-cell0');
  assert.equal(b.length, 28);
  assert.deepEqual(plain(decodeBlob(f, b)), { id: 0, record: DOC_CELLS_21[0] });
  assert.deepEqual(encodeBlob(f, 0, DOC_CELLS_21[0]), b);
  // The blob's count and record are the store's index byte and record.
  assert.equal(b[9], docHex('store-2.1')[0x9e]);
  assert.deepEqual(b.subarray(10, 24), docHex('store-2.1').subarray(0xa5, 0xb3));
  assert.equal(crc32(b, 0, 24), 0x33326b41);
});

test('S22: a rise of 0, or a ground level plus rise over 255 (BadRise)', () => {
  const good = docHex('store-2.1');
  // Rise 0 at offset 0xa6, and ground 4 + rise 252 > 255.
  for (const rise of [0, 252]) {
    const e = throwsFormat(() => Store.parse(patched(good, 0xa6, [rise])), 'BadRise', { cell: 0, ground: 4, rise, offset: 0xa6 });
    if (rise === 252) assert.equal(e.message, "cell 0's rise 252 at offset 166 is 0 or takes its ground level 4 past 255");
  }
  // The edges are accepted: 4 + 251 = 255, and rise 1.
  for (const rise of [251, 1]) assert.equal(Store.parse(patched(good, 0xa6, [rise])).cell(0).rise, rise);
  // Ground 255 leaves no rise at all.
  throwsFormat(() => Store.parse(patched(good, 0xa5, [255])), 'BadRise', { cell: 0, ground: 255, rise: 6, offset: 0xa6 });
  // Checked before the record's VOs (rise 0 and a degenerate VO 0: BadRise) ...
  const both = patched(good, 0xa6, [0, 0, 0, 0, 0, 0, 0]);
  throwsFormat(() => Store.parse(both), 'BadRise', { cell: 0, ground: 4, rise: 0, offset: 0xa6 });
  // ... and in file order: a bad VO of an earlier cell comes first, a bad rise of an earlier
  // cell before a bad VO of a later one.
  const f = docFrame();
  const degenerate = rec(4, [q([9, 9, 9, 9, 1])]);
  const order = encodeStore(f, [degenerate, { ground: 3, rise: 7, vos: [q([196, 376, 336, 376, 5])] }, {}]);
  order[149 + 3 + 4 + 1 + 6 + 1] = 0; // cell 1's rise byte
  fixStoreCrc(order);
  throwsFormat(() => Store.parse(order), 'DegenerateVo', { cell: 0, vo: 0, offset: 149 + 3 + 4 + 1 });
  const order2 = encodeStore(f, [{ ground: 3, rise: 7, vos: [q([196, 376, 336, 376, 5])] }, degenerate, {}]);
  order2[149 + 3 + 4 + 1] = 0; // cell 0's rise byte
  fixStoreCrc(order2);
  throwsFormat(() => Store.parse(order2), 'BadRise', { cell: 0, ground: 3, rise: 0, offset: 149 + 3 + 4 + 1 });
  // A cell on ground 4 with a rise of 6 after a cell with a rise: the block table and the
  // lookup count the rise bytes (cells 70 and 3 on a grid of 100, two blocks).
  const big = docFrame();
  big.nx = 100;
  const cells = Array.from({ length: 100 }, () => EMPTY_CELL);
  cells[3] = DOC_CELLS_21[0];
  cells[70] = DOC_CELLS_21[0];
  const st = Store.parse(encodeStore(big, cells));
  assert.equal(st.minor, 1);
  assert.deepEqual(plain(st.cell(70)), DOC_CELLS_21[0]);
  assert.deepEqual(plain(st.cell(3)), DOC_CELLS_21[0]);
  const table = 149 + 100;
  assert.deepEqual([...encodeStore(big, cells).subarray(table, table + 8)], [0, 0, 0, 0, 14, 0, 0, 0]);
});

test('S19: a non-canonical endpoint, before degeneracy, first in file order', () => {
  const d = docs()[0];
  const a = p(1, 256 - 30, 256 + 60);
  const e = throwsFormat(() => Store.parse(withVo(d, 0, voBytes({ a, b: p(0, 336, 376), level: 5 }, 2))), 'NonCanonicalVo', { cell: 0, vo: 0, offset: 0xa6, endpoint: 'a' });
  assert.equal(e.message, 'VO 0 of cell 0 at offset 166: endpoint a is not canonical (a smaller exponent holds it)');
  throwsFormat(() => Store.parse(withVo(d, 1, voBytes({ a: p(3, 194, 406), b: p(4, 256 + 44, 256 + 75), level: 20 }, 2))), 'NonCanonicalVo', { cell: 0, vo: 1, offset: 0xac, endpoint: 'b' });
  throwsFormat(() => Store.parse(withVo(d, 2, voBytes({ a, b: p(0, 196, 376), level: 5 }, 2))), 'NonCanonicalVo', { cell: 0, vo: 2, offset: 0xb2, endpoint: 'a' });
  const s = withVo(d, 0, voBytes({ a, b: p(0, 196, 376), level: 5 }, 2));
  s.set(voBytes(q([1, 1, 1, 1, 0]), 2), 0xb2);
  fixStoreCrc(s);
  assert.equal(throwsFormat(() => Store.parse(s), 'NonCanonicalVo').fields.vo, 0);
});

// Section 8.3: the blob.

test('B1 to B13: the blob rules, in order, on both majors', () => {
  const f = docFrame();
  for (const [major, name, vb] of [[2, 'blob-cell0', 6], [1, 'blob-1.0-cell0', 5]]) {
    const b = docHex(/** @type {string} */ (name));
    const n = b.length;
    for (const k of [0, 5, 13]) throwsFormat(() => decodeBlob(f, b.subarray(0, k)), 'Truncated', { needed: 14, got: k });
    throwsFormat(() => decodeBlob(f, patched(b, 0, [0x57], false)), 'BadMagic');
    for (const m of [0, 3, 255]) throwsFormat(() => decodeBlob(f, patched(b, 4, [m], false)), 'UnsupportedVersion', { major: m });
    // B4: 11..=20 announce a rise byte in 2.1 (section 13): reserved in 1.0 only.
    for (const value of major === 1 ? [11, 20, 21, 254] : [21, 254]) {
      throwsFormat(() => decodeBlob(f, patched(b, 9, [value], false)), 'BadIndexByte', { cell: 0, value, offset: 9 });
    }
    throwsFormat(() => decodeBlob(f, b.subarray(0, n - 1)), 'Truncated', { needed: n, got: n - 1 });
    const long = new Uint8Array(n + 1);
    long.set(b);
    throwsFormat(() => decodeBlob(f, long), 'TrailingBytes', { expected: n, got: n + 1 });
    const flip = b.slice();
    flip[12] ^= 1;
    throwsFormat(() => decodeBlob(f, flip), 'Checksum');
    const out = patched(b, 5, u32(3), false);
    fixBlobCrc(out);
    const e = throwsFormat(() => decodeBlob(f, out), 'CellOutOfGrid', { id: 3, cells: 3 });
    assert.equal(e.message, 'cell 3 is outside the grid of 3 cells');
    const deg = patched(b, 11, voBytes(q([9, 9, 9, 9, 1]), /** @type {number} */ (major)), false);
    fixBlobCrc(deg);
    throwsFormat(() => decodeBlob(f, deg), 'DegenerateVo', { cell: 0, vo: 0, offset: 11 });
    // B10: no VOs, or skipped: 14 bytes.
    for (const r of [{}, { skipped: true }]) {
      const e14 = encodeBlob(f, 2, r, /** @type {number} */ (major));
      assert.equal(e14.length, 14);
      assert.equal(decodeBlob(f, e14).record.skipped, !!r.skipped);
    }
    assert.equal(vb, major === 2 ? 6 : 5);
  }
  // B11 (2.1): bit 47 is the deep flag; B12 (2.0).
  const b = docHex('blob-cell0');
  const r = b.slice();
  r[0x17 + 5] |= 0x80; // bit 47 of VO 2
  fixBlobCrc(r);
  const deep = decodeBlob(f, r).record;
  assert.deepEqual(deep.vos.map((x) => x.deep), [false, false, true]);
  assert.deepEqual(plain(deep), plain({ ...DOC_CELLS[0], vos: [DOC_CELLS[0].vos[0], DOC_CELLS[0].vos[1], { ...DOC_CELLS[0].vos[2], deep: true }] }));
  const nc = patched(b, 11, voBytes({ a: p(1, 226, 316), b: p(0, 336, 376), level: 5 }, 2), false);
  fixBlobCrc(nc);
  throwsFormat(() => decodeBlob(f, nc), 'NonCanonicalVo', { cell: 0, vo: 0, offset: 11, endpoint: 'a' });
});

test('B4, B5, B6, B14: the 2.1 blob (a count with a rise, its length, its rise)', () => {
  const f = docFrame();
  const b = docHex('blob-2.1-cell0');
  const n = b.length;
  // B5, B6: the length is 14 + 6n + 2 with a rise byte.
  throwsFormat(() => decodeBlob(f, b.subarray(0, n - 1)), 'Truncated', { needed: n, got: n - 1 });
  const long = new Uint8Array(n + 1);
  long.set(b);
  throwsFormat(() => decodeBlob(f, long), 'TrailingBytes', { expected: n, got: n + 1 });
  // A 2.0 blob's count raised by 10: one byte short of its rise.
  const b0 = docHex('blob-cell0');
  throwsFormat(() => decodeBlob(f, patched(b0, 9, [13], false)), 'Truncated', { needed: b0.length + 1, got: b0.length });
  // B14: rise 0 at offset 11, and ground + rise past 255.
  for (const [ground, rise] of [[4, 0], [4, 252], [255, 1]]) {
    const bad = patched(b, 10, [ground, rise], false);
    fixBlobCrc(bad);
    throwsFormat(() => decodeBlob(f, bad), 'BadRise', { cell: 0, ground, rise, offset: 11 });
  }
  const edge = patched(b, 10, [4, 251], false);
  fixBlobCrc(edge);
  assert.equal(decodeBlob(f, edge).record.rise, 251);
  // B4: without ground bytes (flat ground), 11..=20 are refused.
  const flat = docFrame();
  flat.groundStep = 0;
  throwsFormat(() => decodeBlob(flat, b), 'BadIndexByte', { cell: 0, value: 12, offset: 9 });
  // B8 before B14: an id outside the grid is named first.
  const out = patched(b, 5, u32(3), false);
  out[11] = 0;
  fixBlobCrc(out);
  throwsFormat(() => decodeBlob(f, out), 'CellOutOfGrid', { id: 3, cells: 3 });
});

test('VO tops power as Rust does, hypot has glibc bits on pinned values', () => {
  // Values of Rust's f64::hypot on this project's machine (glibc 2.36), from examples/js_oracle.
  /** @type {[number, number, number][]} */
  const pinned = [
    [3, 4, 5],
    [1, 1, 1.4142135623730951],
    [-141.0, 0.25, 141.00022163103148],
    [1e-300, 1e-300, 1.414213562373095e-300],
    [123.456, 789.012, 798.6121211702211],
    [0.1, 0.2, 0.223606797749979],
    [2540.5, -0.0009765625, 2540.500000000188],
  ];
  for (const [x, y, h] of pinned) assert.equal(hypot(x, y), h);
  assert.equal(hypot(Infinity, NaN), Infinity);
  assert.ok(Number.isNaN(hypot(NaN, 1)));
  assert.equal(new QVo(new QPoint(0, 1, 2), new QPoint(0, 3, 4), 5).isDegenerate(), false);
  const f = docFrame();
  assert.equal(f.voTop(164, 20), 506.9446951953614);
});
