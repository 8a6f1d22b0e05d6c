// @ts-check
// The JavaScript decoders against the Rust ones on the committed fuzz corpora
// (fuzz/corpus/store, fuzz/corpus/blob): each file as given and with its checksum made right
// (so that mutations reach the rules behind it), through examples/js_oracle: the same verdict
// (accepted, or refused with the same message) and, when accepted, the same records (rise and
// deep flags included), version and scene section. The same for the inputs of FORMAT.md's 2.1
// rows (S4, S10, S18, S22, B4, B11, B14 on the section 13 examples, mutated). Also: the bits of
// `hypot` against Rust's `f64::hypot` on random pairs.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

import { Store, decodeBlob, decodeFrame, encodeFrame, Frame, FormatError, hypot } from '../src/index.js';
import { ROOT, ORACLE, missing, stdout, fixStoreCrc, fixBlobCrc, docHex, docFrame, u32, voBytes } from './helpers.js';

const skip = missing(ORACLE);

/** The frame the fuzz target `blob` decodes whole inputs with (src/fuzzing.rs, BLOB_FRAME). */
const BLOB_FRAME = new Frame({
  origin: [843000.0, 6518000.0, 0.0], minX: 0, minY: 0, cellSize: 100, nx: 1024, ny: 1024,
  quantum: 0.5, eyeLo: 1.5, eyeHi: 2.0, groundZ0: 160, groundStep: 0.5, h0: 4, hRatio: 1.25,
});

/** @param {import('../src/format.js').CellRecord} r */
const record = (r) => [r.skipped, r.ground, r.rise, r.vos.map((q) => [q.a.e, q.a.x, q.a.y, q.b.e, q.b.x, q.b.y, q.level, q.deep])];

/** @param {Uint8Array} b */
function storeVerdict(b) {
  const s = Store.parse(b);
  return {
    version: [s.major, s.minor],
    objects: s.objects,
    scene: s.scene.toString(16).padStart(16, '0'),
    crs: s.crs,
    cells: Array.from({ length: s.cellCount }, (_, id) => record(s.cell(id))),
  };
}

/** @param {Uint8Array} b */
function blobVerdict(b) {
  let frame = BLOB_FRAME;
  let rest = b;
  if (b.length >= 112) {
    frame = decodeFrame(b.subarray(0, 112));
    rest = b.subarray(112);
  }
  const { id, record: r } = decodeBlob(frame, rest);
  return { id, record: record(r) };
}

/**
 * Each corpus file, and its checksum-fixed twin in a temporary folder.
 * @param {string} target
 * @param {(b: Uint8Array) => void} fix
 */
function inputs(target, fix) {
  const dir = path.join(ROOT, 'fuzz', 'corpus', target);
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), `vocc-js-${target}-`));
  const files = [];
  for (const name of fs.readdirSync(dir).sort()) {
    const file = path.join(dir, name);
    files.push(file);
    const b = new Uint8Array(fs.readFileSync(file));
    fix(b);
    const fixed = path.join(tmp, name + '.fixed');
    fs.writeFileSync(fixed, b);
    files.push(fixed);
  }
  return files;
}

for (const [target, fix] of /** @type {const} */ ([
  ['store', fixStoreCrc],
  ['blob', (/** @type {Uint8Array} */ b) => { if (b.length >= 112 + 4) fixBlobCrc(b.subarray(112)); else fixBlobCrc(b); }],
])) {
  test(`fuzz corpus ${target}: the same verdicts and records as the Rust decoder`, { skip }, async () => {
    const files = inputs(target, fix);
    const tally = await sameVerdicts(target, files);
    assert.ok(tally.accepted > 5 && tally.refused > 5, JSON.stringify(tally));
    console.log(`# ${target}: ${files.length} inputs, ${tally.accepted} accepted, ${tally.refused} refused (${[...tally.kinds].sort().join(', ')}), all as Rust`);
  });
}

/**
 * The JavaScript verdict on each file against the oracle's.
 * @param {'store' | 'blob'} target
 * @param {string[]} files
 */
async function sameVerdicts(target, files) {
  const verdict = target === 'store' ? storeVerdict : blobVerdict;
  const rust = (await stdout(ORACLE, [target, ...files])).trim().split('\n').map((l) => JSON.parse(l));
  assert.equal(rust.length, files.length);
  /** @type {{accepted: number, refused: number, kinds: Set<string>}} */
  const tally = { accepted: 0, refused: 0, kinds: new Set() };
  for (let i = 0; i < files.length; i++) {
    const b = new Uint8Array(fs.readFileSync(files[i]));
    let got;
    try {
      got = { ok: true, value: verdict(b) };
    } catch (e) {
      assert.ok(e instanceof FormatError, `${files[i]}: ${e}`);
      got = { ok: false, error: e.message };
      tally.kinds.add(e.kind);
    }
    const want = rust[i];
    assert.equal(got.ok, want.ok, `${files[i]}: ${JSON.stringify(got).slice(0, 200)} against ${JSON.stringify(want).slice(0, 200)}`);
    if (want.ok) assert.deepEqual(got.value, want.value, files[i]);
    else assert.equal(got.error, want.error, files[i]);
    tally[want.ok ? 'accepted' : 'refused']++;
  }
  return tally;
}

test('the 2.1 rows of FORMAT.md 8.1 and 8.3: the same verdicts, reasons and records as the Rust decoder', { skip }, async () => {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'vocc-js-21-'));
  /** @type {Record<'store' | 'blob', string[]>} */
  const files = { store: [], blob: [] };
  /** @type {Record<'store' | 'blob', string[]>} */
  const expect = { store: [], blob: [] };
  /**
   * @param {'store' | 'blob'} kind @param {string} name @param {Uint8Array} b
   * @param {string} want the kind of FormatError FORMAT.md's row gives, or 'ok'
   */
  const add = (kind, name, b, want) => {
    const file = path.join(dir, `${kind}-${name}`);
    fs.writeFileSync(file, b);
    files[kind].push(file);
    expect[kind].push(want);
  };
  /** @param {Uint8Array} b @param {number} at @param {number[]} v */
  const store = (b, at, v) => {
    const s = b.slice();
    s.set(v, at);
    fixStoreCrc(s);
    return s;
  };
  const s21 = docHex('store-2.1');
  const s20 = docHex('store');
  const s10 = docHex('store-1.0');
  add('store', 'doc', s21, 'ok');
  add('store', 's4-minor-7', store(s21, 10, [7, 0]), 'ok');
  add('store', 's18-deep-in-2.0-example', store(s20, 0xac + 5, [0xd3]), 'ok');
  add('store', 's18-deep-all-ones', store(s21, 0xa7, [0xff, 0xff, 0xff, 0xff, 0xff, 0xff]), 'DegenerateVo');
  add('store', 's18-deep-not-canonical', store(s21, 0xad, voBytes({ a: { e: 1, x: 226, y: 316 }, b: { e: 0, x: 336, y: 376 }, level: 5, deep: true }, 2)), 'NonCanonicalVo');
  for (const rise of [0, 252]) add('store', `s22-rise-${rise}`, store(s21, 0xa6, [rise]), 'BadRise');
  add('store', 's22-rise-251', store(s21, 0xa6, [251]), 'ok');
  add('store', 's22-ground-255', store(s21, 0xa5, [255]), 'BadRise');
  add('store', 's22-rise-0-degenerate-vo', store(s21, 0xa6, [0, 0, 0, 0, 0, 0, 0]), 'BadRise');
  for (const value of [11, 20, 21, 254]) add('store', `s10-2.0-${value}`, store(s20, 0x9f, [value]), value <= 20 ? 'PayloadLength' : 'BadIndexByte');
  for (const value of [11, 20, 21]) add('store', `s10-1.0-${value}`, store(s10, 0x89, [value]), 'BadIndexByte');
  add('store', 's10-2.1-21', store(s21, 0x9e, [21]), 'BadIndexByte');
  add('store', 's12-2.1-11', store(s21, 0x9e, [11]), 'PayloadLength');
  // A flat frame: no ground bytes, so no rise either (S10).
  const flat = docFrame();
  flat.groundStep = 0;
  add('store', 's10-flat', store(s21, 16, [...encodeFrame(flat)]), 'BadIndexByte');
  // Blobs: with the frame of FORMAT.md 9 before them (the oracle reads 112 bytes of frame).
  const frame = encodeFrame(docFrame());
  /** @param {Uint8Array} b @param {number} at @param {number[]} v @param {Uint8Array} [f] */
  const blob = (b, at, v, f = frame) => {
    const out = new Uint8Array(112 + b.length);
    out.set(f);
    out.set(b, 112);
    out.set(v, 112 + at);
    fixBlobCrc(out.subarray(112));
    return out;
  };
  const b21 = docHex('blob-2.1-cell0');
  const b20 = docHex('blob-cell0');
  const b10 = docHex('blob-1.0-cell0');
  add('blob', 'doc', blob(b21, 0, []), 'ok');
  add('blob', 'b11-deep', blob(b20, 0x17 + 5, [0xc3]), 'ok');
  for (const [ground, rise] of [[4, 0], [4, 252], [255, 1]]) add('blob', `b14-${ground}-${rise}`, blob(b21, 10, [ground, rise]), 'BadRise');
  add('blob', 'b14-4-251', blob(b21, 10, [4, 251]), 'ok');
  for (const value of [21, 254]) add('blob', `b4-2.0-${value}`, blob(b20, 9, [value]), 'BadIndexByte');
  for (const value of [11, 20]) add('blob', `b4-1.0-${value}`, blob(b10, 9, [value]), 'BadIndexByte');
  add('blob', 'b5-2.0-13', blob(b20, 9, [13]), 'Truncated');
  add('blob', 'b4-flat', blob(b21, 0, [], encodeFrame(flat)), 'BadIndexByte');
  const long = new Uint8Array(b21.length + 1);
  long.set(b21);
  add('blob', 'b6-2.1', blob(long, 0, []), 'TrailingBytes');
  add('blob', 'b8-before-b14', blob(b21, 5, [...u32(3), 12, 4, 0]), 'CellOutOfGrid');
  for (const kind of /** @type {const} */ (['store', 'blob'])) {
    await sameVerdicts(kind, files[kind]);
    // And each verdict is the row's (so the inputs test what they are named for).
    for (let i = 0; i < files[kind].length; i++) {
      const b = new Uint8Array(fs.readFileSync(files[kind][i]));
      let got = 'ok';
      try {
        (kind === 'store' ? storeVerdict : blobVerdict)(b);
      } catch (e) {
        got = /** @type {FormatError} */ (e).kind;
      }
      assert.equal(got, expect[kind][i], files[kind][i]);
    }
  }
  console.log(`# 2.1 rows: ${files.store.length} stores and ${files.blob.length} blobs, the same verdicts as Rust`);
});

test('hypot has the bits of Rust f64::hypot on 200,000 random pairs', { skip }, async () => {
  let seed = 987654321;
  const r = () => {
    seed = (seed * 1103515245 + 12345) % 2147483648;
    return seed / 2147483648;
  };
  const dv = new DataView(new ArrayBuffer(8));
  const bits = (/** @type {number} */ x) => {
    dv.setFloat64(0, x);
    return dv.getBigUint64(0).toString(16).padStart(16, '0');
  };
  const pairs = [];
  for (let i = 0; i < 200000; i++) {
    const k = i % 4;
    if (k === 0) pairs.push([(r() - 0.5) * 4000, (r() - 0.5) * 4000]);
    else if (k === 1) pairs.push([Math.round((r() - 0.5) * 8000) / 512, Math.round((r() - 0.5) * 8000) / 512]);
    else if (k === 2) pairs.push([(r() - 0.5) * 10 ** (r() * 40 - 20), (r() - 0.5) * 10 ** (r() * 40 - 20)]);
    else {
      const x = (r() - 0.5) * 1e6;
      pairs.push([x, x * (1 + (r() - 0.5) * 1e-9)]);
    }
  }
  const file = path.join(fs.mkdtempSync(path.join(os.tmpdir(), 'vocc-js-hypot-')), 'pairs');
  fs.writeFileSync(file, pairs.map(([x, y]) => `${bits(x)} ${bits(y)}`).join('\n') + '\n');
  const { execFileSync } = await import('node:child_process');
  const rust = execFileSync(ORACLE, ['hypot'], { input: fs.readFileSync(file), maxBuffer: 1 << 26 }).toString().trim().split('\n');
  let differ = 0;
  let mathDiffers = 0;
  pairs.forEach(([x, y], i) => {
    if (bits(hypot(x, y)) !== rust[i]) differ++;
    if (bits(Math.hypot(x, y)) !== rust[i]) mathDiffers++;
  });
  assert.equal(differ, 0);
  console.log(`# hypot: 0 of ${pairs.length} differ from Rust (Math.hypot: ${mathDiffers})`);
});
