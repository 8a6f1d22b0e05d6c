// @ts-check
// The JavaScript decoders against the Rust ones on the committed fuzz corpora
// (fuzz/corpus/store, fuzz/corpus/blob): each file as given and with its checksum made right
// (so that mutations reach the rules behind it), through examples/js_oracle: the same verdict
// (accepted, or refused with the same message) and, when accepted, the same records, version
// and scene section. Also: the bits of `hypot` against Rust's `f64::hypot` on random pairs.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

import { Store, decodeBlob, decodeFrame, Frame, FormatError, hypot } from '../src/index.js';
import { ROOT, ORACLE, missing, stdout, fixStoreCrc, fixBlobCrc } from './helpers.js';

const skip = missing(ORACLE);

/** The frame the fuzz target `blob` decodes whole inputs with (src/fuzzing.rs, BLOB_FRAME). */
const BLOB_FRAME = new Frame({
  origin: [843000.0, 6518000.0, 0.0], minX: 0, minY: 0, cellSize: 100, nx: 1024, ny: 1024,
  quantum: 0.5, eyeLo: 1.5, eyeHi: 2.0, groundZ0: 160, groundStep: 0.5, h0: 4, hRatio: 1.25,
});

/** @param {import('../src/format.js').CellRecord} r */
const record = (r) => [r.skipped, r.ground, r.vos.map((q) => [q.a.e, q.a.x, q.a.y, q.b.e, q.b.x, q.b.y, q.level])];

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

for (const [target, fix, verdict] of /** @type {const} */ ([
  ['store', fixStoreCrc, storeVerdict],
  ['blob', (/** @type {Uint8Array} */ b) => { if (b.length >= 112 + 4) fixBlobCrc(b.subarray(112)); else fixBlobCrc(b); }, blobVerdict],
])) {
  test(`fuzz corpus ${target}: the same verdicts and records as the Rust decoder`, { skip }, async () => {
    const files = inputs(target, fix);
    const rust = (await stdout(ORACLE, [target, ...files])).trim().split('\n').map((l) => JSON.parse(l));
    assert.equal(rust.length, files.length);
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
    assert.ok(tally.accepted > 5 && tally.refused > 5, JSON.stringify(tally));
    console.log(`# ${target}: ${files.length} inputs, ${tally.accepted} accepted, ${tally.refused} refused (${[...tally.kinds].sort().join(', ')}), all as Rust`);
  });
}

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
