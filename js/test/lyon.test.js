// @ts-check
// The JavaScript runtime against the Rust one on the bundled Lyon bake (js/test.sh bakes it and
// writes its viewer page): every cell decodes to what `vocc inspect --cell ID --json` prints
// (world coordinates, stored fields and bytes, number for number), the store's summary to
// `vocc inspect --json`, and every cell's PVS, built from the boxes the page holds, equals
// `vocc pvs --cell ID --json` set for set; the same store rewritten as 1.0 gives the same records
// and PVSs.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';

import { Store, BoxTree, pvs, PreparedVo, hides } from '../src/index.js';
import { VOCC, DATA, missing, stdout, pageData, encodeStore } from './helpers.js';
import { summary, sameCellsAsInspect, comparePvs } from './city.js';

const STORE = path.join(DATA, 'lyon.vocc');
const PAGE = path.join(DATA, 'lyon.html');
const LYON = path.resolve(path.dirname(new URL(import.meta.url).pathname), '..', '..', 'data', 'lyon1', 'buildings_lyon1.geojson');
const skip = missing(VOCC, STORE, PAGE, LYON);

test('the store decodes as vocc inspect --json says', { skip }, async () => {
  const s = Store.parse(new Uint8Array(fs.readFileSync(STORE)));
  const want = JSON.parse(await stdout(VOCC, ['inspect', STORE, '--json']));
  for (const [k, v] of Object.entries(summary(s))) assert.deepEqual(v, want[k], k);
  assert.equal(s.objects, 2576);
});

test('every cell decodes as vocc inspect --cell ID --json says, byte for byte', { skip }, async () => {
  const s = Store.parse(new Uint8Array(fs.readFileSync(STORE)));
  const compared = await sameCellsAsInspect(STORE, s, Array.from({ length: s.cellCount }, (_, id) => id));
  assert.ok(compared > 1000, `${compared} VOs compared`);
});

test('the PVS of every Lyon cell equals vocc pvs, set for set', { skip }, async () => {
  const s = Store.parse(new Uint8Array(fs.readFileSync(STORE)));
  const { section } = pageData(PAGE);
  const features = section('features');
  assert.equal(features.length, 2576);
  const tree = BoxTree.fromWorld(section('boxes'), s.frame.origin);
  const ids = Array.from({ length: s.cellCount }, (_, id) => id);
  const { differ, culled } = await comparePvs(STORE, s, tree, features, ids, [LYON, '--height-attr', 'HAUTEUR']);
  assert.equal(differ.length, 0, `${differ.length} of ${s.cellCount} cells differ from vocc pvs: ${differ.slice(0, 10)}`);
  // The comparison proves something: most objects are culled.
  const share = culled / (s.cellCount * features.length);
  assert.ok(share > 0.5, `culled share ${share}`);
  console.log(`# lyon: ${s.cellCount} cells, 0 differences from vocc pvs, ${(100 * share).toFixed(1)}% culled`);
});

test('the tree answers as the box-by-box rule on every Lyon cell', { skip }, () => {
  const s = Store.parse(new Uint8Array(fs.readFileSync(STORE)));
  const f = s.frame;
  const { section } = pageData(PAGE);
  const world = section('boxes');
  const tree = BoxTree.fromWorld(world, f.origin);
  const n = world.length / 6;
  const local = Array.from({ length: n }, (_, i) => Array.from({ length: 6 }, (_, k) => world[6 * i + k] - f.origin[k % 3]));
  for (let id = 0; id < s.cellCount; id++) {
    const r = s.cell(id);
    const view = /** @type {import('../src/frame.js').CellView} */ (f.cellView(id, r));
    const prepared = r.skipped ? [] : r.vos.map((q) => new PreparedVo(view, /** @type {any} */ (f.dequantize(id, r, q))));
    const brute = [];
    for (let i = 0; i < n; i++) if (!prepared.some((p) => hides(view, p, local[i]))) brute.push(i);
    assert.deepEqual(Array.from(pvs(f, id, r, tree)), brute, `cell ${id}`);
  }
});

test('the Lyon store written as 1.0 reads the same records and PVSs', { skip }, () => {
  const s = Store.parse(new Uint8Array(fs.readFileSync(STORE)));
  const cells = Array.from({ length: s.cellCount }, (_, id) => s.cell(id));
  const fits = cells.every((r) => r.vos.every((q) => q.a.e === 0 && q.b.e === 0 && q.level < 16));
  if (!fits) return; // a store with far VOs or high levels has no 1.0 form
  const v1 = Store.parse(encodeStore(s.frame, cells, { major: 1 }));
  assert.equal(v1.major, 1);
  const { section } = pageData(PAGE);
  const tree = BoxTree.fromWorld(section('boxes'), s.frame.origin);
  for (let id = 0; id < s.cellCount; id++) {
    assert.deepEqual(JSON.stringify(v1.cell(id)), JSON.stringify(cells[id]));
    assert.deepEqual(pvs(v1.frame, id, v1.cell(id), tree), pvs(s.frame, id, cells[id], tree));
  }
});
