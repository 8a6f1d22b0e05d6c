// @ts-check
// The JavaScript runtime against the Rust one on a store of format 2.1: Salt River (Cape Town)
// baked on its 25 m DEM (js/test.sh bakes it and writes its viewer page, as for Lyon). The store
// must be minor 1 with cells that have a rise and deep VOs (else the test would prove nothing
// about 2.1); its summary equals `vocc inspect --json`, every cell decodes as `vocc inspect
// --cell ID --json` prints it (eyes raised by the rise, deep VOs' bottoms at ground_z0, bit 47
// in the bytes), and the PVS equals `vocc pvs --cell ID --json` set for set, with cells among
// them whose PVS the rise and the deep flags change (so a runtime ignoring either would differ
// from Rust there). Cells compared: every cell with VOs and every 25th cell
// ($VOCC_JS_SR_CELLS=all: every cell). js/test.sh bakes the 28 cells of a 7 x 4 block on the
// slope (--region), where deep VOs are many: a whole bake of the 529 cells takes 90 s.
// `vocc pvs` is given the footprints without the DEM (the DEM is read in a second, the
// footprints in a tenth): the objects and their boxes are the same, which its scene check
// proves (the store's fingerprint covers every object's box); two cells are also compared with
// the DEM given, as baked.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';

import { Store, BoxTree, pvs, PreparedVo, hides, QVo } from '../src/index.js';
import { ROOT, VOCC, DATA, missing, stdout, pageData } from './helpers.js';
import { summary, sameCellsAsInspect, comparePvs } from './city.js';

const STORE = path.join(DATA, 'saltriver.vocc');
const PAGE = path.join(DATA, 'saltriver.html');
const FOOTPRINTS = path.join(ROOT, 'data', 'capetown', 'salt_river_footprints_utm34s.geojson');
const DEM = path.join(ROOT, 'data', 'capetown', 'capetown_dem25m_utm34s.tif');
/** The scene as the bake read it (data/README.md, tests/terrain.rs). */
const SCENE = [FOOTPRINTS, '--height-attr', 'height', '--base-attr', 'base_z', '--terrain', DEM];
const skip = missing(VOCC, STORE, PAGE, FOOTPRINTS, DEM);

/** The footprints alone: the same objects (the DEM is ground, not an object). */
const OBJECTS = SCENE.slice(0, 5);

/** @param {Store} s */
const ids = (s) => Array.from({ length: s.cellCount }, (_, id) => id);
/** The cells compared with the CLI: every cell with VOs and every 25th cell, or all. @param {Store} s */
const sample = (s) => (process.env.VOCC_JS_SR_CELLS === 'all' ? ids(s) : ids(s).filter((id) => s.cell(id).vos.length > 0 || id % 25 === 0));

test('the Salt River store is 2.1, with rises and deep VOs, and decodes as vocc inspect --json says', { skip }, async () => {
  const s = Store.parse(new Uint8Array(fs.readFileSync(STORE)));
  assert.deepEqual([s.major, s.minor], [2, 1]);
  const want = JSON.parse(await stdout(VOCC, ['inspect', STORE, '--json']));
  for (const [k, v] of Object.entries(summary(s))) assert.deepEqual(v, want[k], k);
  assert.equal(want.version, '2.1');
  let risen = 0;
  let deep = 0;
  let vos = 0;
  for (const id of ids(s)) {
    const r = s.cell(id);
    if (r.rise > 0) risen++;
    deep += r.vos.filter((q) => q.deep).length;
    vos += r.vos.length;
    // A rise is stored only with VOs: an index byte and a record of ground, rise and VOs.
    if (r.rise > 0) assert.deepEqual([r.vos.length > 0, s.cellBytes(id)], [true, 1 + 2 + 6 * r.vos.length]);
  }
  assert.ok(risen >= 10 && deep >= 10, `${risen} cells with a rise, ${deep} deep VOs`);
  console.log(`# salt river: store 2.1, ${s.cellCount} cells, ${risen} with a rise, ${vos} VOs of which ${deep} deep`);
});

test('the Salt River cells decode as vocc inspect --cell ID --json says, byte for byte', { skip }, async () => {
  const s = Store.parse(new Uint8Array(fs.readFileSync(STORE)));
  const compared = await sameCellsAsInspect(STORE, s, sample(s));
  assert.ok(compared >= 50, `${compared} VOs compared`);
});

test('the PVS of the Salt River cells equals vocc pvs, set for set, where the rise and deep VOs matter', { skip }, async () => {
  const s = Store.parse(new Uint8Array(fs.readFileSync(STORE)));
  const { section } = pageData(PAGE);
  const features = section('features');
  const tree = BoxTree.fromWorld(section('boxes'), s.frame.origin);
  const cells = sample(s);
  const baked = cells.filter((id) => s.cell(id).vos.length > 0);
  assert.ok(baked.length >= 20, `${baked.length} cells with VOs`);
  const t = performance.now();
  const { differ, culled } = await comparePvs(STORE, s, tree, features, cells, OBJECTS);
  assert.equal(differ.length, 0, `${differ.length} of ${cells.length} cells differ from vocc pvs: ${differ.slice(0, 10)}`);
  // Two cells with the DEM given, as the store was baked: the same sets.
  const withDem = await comparePvs(STORE, s, tree, features, baked.slice(0, 2), SCENE);
  assert.equal(withDem.differ.length, 0);
  // The comparison proves something: objects are culled, and on cells whose PVS the rise and
  // the deep flags change.
  let riseMatters = 0;
  let deepMatters = 0;
  for (const id of cells) {
    const r = s.cell(id);
    const n = pvs(s.frame, id, r, tree).length;
    if (r.rise > 0 && pvs(s.frame, id, { ...r, rise: 0 }, tree).length !== n) riseMatters++;
    if (r.vos.some((q) => q.deep)) {
      const shallow = { ...r, vos: r.vos.map((q) => new QVo(q.a, q.b, q.level, false)) };
      if (pvs(s.frame, id, shallow, tree).length !== n) deepMatters++;
    }
  }
  // (Cells without VOs cull nothing: the share is over the cells with VOs.)
  const share = culled / (baked.length * features.length);
  assert.ok(culled >= baked.length, `${culled} objects culled in ${baked.length} cells`);
  assert.ok(riseMatters > 0 && deepMatters > 0, `the rise changes ${riseMatters} PVSs, deep VOs ${deepMatters}`);
  console.log(`# salt river: ${cells.length} cells (${baked.length} with VOs), 0 differences from vocc pvs, ${culled} objects culled (${(100 * share).toFixed(1)}% over the cells with VOs); the rise changes ${riseMatters} PVSs, deep VOs ${deepMatters} (${((performance.now() - t) / 1000).toFixed(1)} s)`);
});

test('the tree answers as the box-by-box rule on every Salt River cell', { skip }, () => {
  const s = Store.parse(new Uint8Array(fs.readFileSync(STORE)));
  const f = s.frame;
  const { section } = pageData(PAGE);
  const world = section('boxes');
  const tree = BoxTree.fromWorld(world, f.origin);
  const n = world.length / 6;
  const local = Array.from({ length: n }, (_, i) => Array.from({ length: 6 }, (_, k) => world[6 * i + k] - f.origin[k % 3]));
  for (const id of ids(s)) {
    const r = s.cell(id);
    const view = /** @type {import('../src/frame.js').CellView} */ (f.cellView(id, r));
    const prepared = r.skipped ? [] : r.vos.map((q) => new PreparedVo(view, /** @type {any} */ (f.dequantize(id, r, q))));
    const brute = [];
    for (let i = 0; i < n; i++) if (!prepared.some((p) => hides(view, p, local[i]))) brute.push(i);
    assert.deepEqual(Array.from(pvs(f, id, r, tree)), brute, `cell ${id}`);
  }
});
