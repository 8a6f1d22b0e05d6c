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

import { Store, BoxTree, pvs, PreparedVo, hides, HEIGHT_LEVELS, HEIGHT_LEVELS_V1 } from '../src/index.js';
import { VOCC, DATA, missing, stdout, pool, pageData, voBytes, encodeStore } from './helpers.js';

const STORE = path.join(DATA, 'lyon.vocc');
const PAGE = path.join(DATA, 'lyon.html');
const SCENE = path.join(path.dirname(DATA), '..', '..', 'data', 'lyon1', 'buildings_lyon1.geojson');
const LYON = path.resolve(path.dirname(new URL(import.meta.url).pathname), '..', '..', 'data', 'lyon1', 'buildings_lyon1.geojson');
const skip = missing(VOCC, STORE, PAGE, LYON);
void SCENE;

/** @param {number[]} b */
const hex = (b) => b.map((x) => x.toString(16).padStart(2, '0')).join('');

test('the store decodes as vocc inspect --json says', { skip }, async () => {
  const bytes = new Uint8Array(fs.readFileSync(STORE));
  const s = Store.parse(bytes);
  const f = s.frame;
  const want = JSON.parse(await stdout(VOCC, ['inspect', STORE, '--json']));
  const hist = new Array(11).fill(0);
  let vos = 0;
  let skipped = 0;
  for (let id = 0; id < s.cellCount; id++) {
    const r = s.cell(id);
    if (r.skipped) skipped++;
    else {
      hist[r.vos.length]++;
      vos += r.vos.length;
    }
  }
  const levels = s.major === 1 ? HEIGHT_LEVELS_V1 : HEIGHT_LEVELS;
  const got = {
    version: `${s.major}.${s.minor}`,
    objects: s.objects,
    scene: s.scene.toString(16).padStart(16, '0'),
    crs: s.crs,
    bytes: bytes.length,
    cells: s.cellCount,
    bytes_per_cell: bytes.length / s.cellCount,
    skipped_cells: skipped,
    vos,
    vos_per_cell: vos / s.cellCount,
    cells_by_vo_count: hist,
    origin: f.origin,
    grid: { min_x: f.minX, min_y: f.minY, cell_size: f.cellSize, nx: f.nx, ny: f.ny },
    quantum_m: f.quantum,
    eye: [f.eyeLo, f.eyeHi],
    ground: { z0: f.groundZ0, step: f.groundStep },
    vo_top_levels_above_eye_m: Array.from({ length: levels }, (_, k) => f.voTop(0, k)),
  };
  for (const [k, v] of Object.entries(got)) assert.deepEqual(v, want[k], k);
  assert.equal(s.objects, 2576);
});

test('every cell decodes as vocc inspect --cell ID --json says, byte for byte', { skip }, async () => {
  const s = Store.parse(new Uint8Array(fs.readFileSync(STORE)));
  const f = s.frame;
  const o = f.origin;
  const wants = await pool(
    Array.from({ length: s.cellCount }, (_, id) => async () => JSON.parse(await stdout(VOCC, ['inspect', STORE, '--cell', String(id), '--json']))),
    2,
  );
  let compared = 0;
  for (let id = 0; id < s.cellCount; id++) {
    const r = s.cell(id);
    const rect = /** @type {number[]} */ (f.cellRect(id));
    const view = /** @type {{e0: number, e1: number}} */ (f.cellView(id, r.ground));
    const got = {
      cell: id,
      rect: [rect[0] + o[0], rect[1] + o[1], rect[2] + o[0], rect[3] + o[1]],
      skipped: r.skipped,
      ground: f.groundZ(r.ground) + o[2],
      eyes: [view.e0 + o[2], view.e1 + o[2]],
      vos: r.vos.map((q) => {
        const g = /** @type {import('../src/frame.js').VoGeom} */ (f.dequantize(id, r.ground, q));
        return {
          a: [g.a[0] + o[0], g.a[1] + o[1]],
          b: [g.b[0] + o[0], g.b[1] + o[1]],
          bottom: g.g + o[2],
          top: g.h + o[2],
          level: q.level,
          fields: { a: { ...q.a }, b: { ...q.b }, level: q.level },
          bytes: hex(voBytes(q, s.major)),
        };
      }),
    };
    assert.deepEqual(got, wants[id], `cell ${id}`);
    compared += r.vos.length;
  }
  assert.ok(compared > 1000, `${compared} VOs compared`);
});

/**
 * The PVS of every cell, as input feature numbers.
 * @param {Store} s @param {BoxTree} tree @param {Uint32Array} features
 */
const allPvs = (s, tree, features) =>
  Array.from({ length: s.cellCount }, (_, id) => Array.from(pvs(s.frame, id, s.cell(id), tree), (i) => features[i]));

test('the PVS of every Lyon cell equals vocc pvs, set for set', { skip }, async () => {
  const s = Store.parse(new Uint8Array(fs.readFileSync(STORE)));
  const { section } = pageData(PAGE);
  const boxes = section('boxes');
  const features = section('features');
  assert.equal(features.length, 2576);
  const tree = BoxTree.fromWorld(boxes, s.frame.origin);
  const got = allPvs(s, tree, features);
  const wants = await pool(
    Array.from({ length: s.cellCount }, (_, id) => async () =>
      JSON.parse(await stdout(VOCC, ['pvs', STORE, LYON, '--height-attr', 'HAUTEUR', '--cell', String(id), '--json']))),
    2,
  );
  let differences = 0;
  let culled = 0;
  for (let id = 0; id < s.cellCount; id++) {
    assert.equal(wants[id].objects, features.length);
    const same = got[id].length === wants[id].pvs.length && got[id].every((x, k) => x === wants[id].pvs[k]);
    if (!same) differences++;
    culled += features.length - got[id].length;
  }
  assert.equal(differences, 0, `${differences} of ${s.cellCount} cells differ from vocc pvs`);
  // The comparison proves something: most objects are culled.
  assert.ok(culled / (s.cellCount * features.length) > 0.5, `culled share ${culled / (s.cellCount * features.length)}`);
  console.log(`# lyon: ${s.cellCount} cells, 0 differences from vocc pvs, ${(100 * culled / (s.cellCount * features.length)).toFixed(1)}% culled`);
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
    const view = /** @type {import('../src/frame.js').CellView} */ (f.cellView(id, r.ground));
    const prepared = r.skipped ? [] : r.vos.map((q) => new PreparedVo(view, /** @type {any} */ (f.dequantize(id, r.ground, q))));
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
