// @ts-check
// The JavaScript decoders against docs/FORMAT.md, as tests/format.rs checks the Rust ones: the
// worked examples of both versions byte for byte, and one test per row of the "accepted?"
// tables (8.1 store, 8.2 frame, 8.3 blob), on both majors where the row applies to both, with
// the same error kind, fields and message as the Rust decoder.

import { test } from 'node:test';
import assert from 'node:assert/strict';

import {
  Store, decodeBlob, decodeFrame, encodeFrame, crc32, Frame, QPoint, QVo, FormatError, hypot,
} from '../src/index.js';
import {
  docHex, docFrame, encodeStore, encodeBlob, fixStoreCrc, fixBlobCrc, throwsFormat, frameRule, voBytes, u32,
} from './helpers.js';

const p = (/** @type {number} */ e, /** @type {number} */ x, /** @type {number} */ y) => ({ e, x, y });
const q = (/** @type {number[]} */ [x1, y1, x2, y2, level]) => ({ a: p(0, x1, y1), b: p(0, x2, y2), level });
/** @param {any} rec */
const plain = (rec) => JSON.parse(JSON.stringify(rec));

const DOC_CELLS = [
  { skipped: false, ground: 4, vos: [q([196, 376, 336, 376, 5]), { a: p(3, 194, 406), b: p(3, 344, 406), level: 20 }, { a: p(0, 376, 346), b: p(2, 286, 456), level: 16 }] },
  { skipped: true, ground: 0, vos: [] },
  { skipped: false, ground: 0, vos: [] },
];
const DOC_CELLS_V1 = [
  { skipped: false, ground: 4, vos: [q([196, 376, 336, 376, 5]), q([376, 176, 376, 346, 3])] },
  DOC_CELLS[1],
  DOC_CELLS[2],
];

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

test('S10: reserved index values', () => {
  for (const d of docs()) {
    for (const value of [11, 12, 0x80, 254]) {
      throwsFormat(() => Store.parse(patched(d.bytes, d.index + 1, [value])), 'BadIndexByte', { cell: 1, value, offset: d.index + 1 });
    }
  }
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
    assert.deepEqual(plain(st.cell(0)), { skipped: false, ground: 0, vos: flatCells[0].vos });
  }
  // S20: every exponent and level, any objects and scene, a CRS of 255 bytes of UTF-8.
  const vos = [{ a: p(7, 0, 511), b: p(0, 1, 2), level: 31 }, { a: p(1, 127, 256), b: p(6, 511, 0), level: 0 }];
  const st = Store.parse(encodeStore(f, [{ ground: 9, vos }, {}, {}], { objects: 0xffffffff, scene: 0xffffffffffffffffn, crs: 'é'.repeat(127) + 'x' }));
  assert.deepEqual(plain(st.cell(0)), { skipped: false, ground: 9, vos });
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

test('S18: the reserved VO bit', () => {
  const d = docs()[0];
  const s = d.bytes.slice();
  s[voAt(d, 1) + 5] |= 0x80;
  fixStoreCrc(s);
  const e = throwsFormat(() => Store.parse(s), 'ReservedVoBit', { cell: 0, vo: 1, offset: 0xac });
  assert.equal(e.message, 'VO 1 of cell 0 at offset 172 sets the reserved bit 47');
  throwsFormat(() => Store.parse(withVo(d, 0, new Array(6).fill(0xff))), 'ReservedVoBit', { cell: 0, vo: 0, offset: 0xa6 });
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
    for (const value of [11, 254]) throwsFormat(() => decodeBlob(f, patched(b, 9, [value], false)), 'BadIndexByte', { cell: 0, value, offset: 9 });
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
  // B11, B12 (2.0).
  const b = docHex('blob-cell0');
  const r = b.slice();
  r[11 + 6 + 5] |= 0x80;
  fixBlobCrc(r);
  throwsFormat(() => decodeBlob(f, r), 'ReservedVoBit', { cell: 0, vo: 1, offset: 17 });
  const nc = patched(b, 11, voBytes({ a: p(1, 226, 316), b: p(0, 336, 376), level: 5 }, 2), false);
  fixBlobCrc(nc);
  throwsFormat(() => decodeBlob(f, nc), 'NonCanonicalVo', { cell: 0, vo: 0, offset: 11, endpoint: 'a' });
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
