// @ts-check
/**
 * The cross-checks of a baked city that the Lyon (2.0) and Salt River (2.1, on its DEM) tests
 * share: a store's summary as `vocc inspect --json` prints it, a cell as `vocc inspect --cell ID
 * --json` prints it (world coordinates, eyes with a 2.1 rise, VO bottoms with the deep flag,
 * stored fields and bytes), and the PVS of cells against `vocc pvs --cell ID --json`.
 */

import assert from 'node:assert/strict';

import { Store, BoxTree, pvs, HEIGHT_LEVELS, HEIGHT_LEVELS_V1 } from '../src/index.js';
import { VOCC, stdout, pool, voBytes } from './helpers.js';

/** @param {number[]} b */
const hex = (b) => b.map((x) => x.toString(16).padStart(2, '0')).join('');

/**
 * The fields of `vocc inspect STORE --json` that the runtime gives.
 * @param {Store} s
 */
export function summary(s) {
  const f = s.frame;
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
  return {
    version: `${s.major}.${s.minor}`,
    objects: s.objects,
    scene: s.scene.toString(16).padStart(16, '0'),
    crs: s.crs,
    bytes: s.bytes.length,
    cells: s.cellCount,
    bytes_per_cell: s.bytes.length / s.cellCount,
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
}

/**
 * Cell `id` as `vocc inspect STORE --cell ID --json` prints it.
 * @param {Store} s @param {number} id
 */
export function cellJson(s, id) {
  const f = s.frame;
  const o = f.origin;
  const r = s.cell(id);
  const rect = /** @type {number[]} */ (f.cellRect(id));
  const view = /** @type {import('../src/frame.js').CellView} */ (f.cellView(id, r));
  return {
    cell: id,
    rect: [rect[0] + o[0], rect[1] + o[1], rect[2] + o[0], rect[3] + o[1]],
    skipped: r.skipped,
    ground: f.groundZ(r.ground) + o[2],
    eyes: [view.e0 + o[2], view.e1 + o[2]],
    vos: r.vos.map((q) => {
      const g = /** @type {import('../src/frame.js').VoGeom} */ (f.dequantize(id, r, q));
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
}

/**
 * Asserts that each of `ids` decodes as `vocc inspect --cell ID --json` says; returns the VOs
 * compared.
 * @param {string} file the store @param {Store} s @param {number[]} ids
 */
export async function sameCellsAsInspect(file, s, ids) {
  const wants = await pool(ids.map((id) => async () => JSON.parse(await stdout(VOCC, ['inspect', file, '--cell', String(id), '--json']))), 2);
  let vos = 0;
  ids.forEach((id, k) => {
    assert.deepEqual(cellJson(s, id), wants[k], `cell ${id}`);
    vos += s.cell(id).vos.length;
  });
  return vos;
}

/**
 * The PVS of each of `ids` as input feature numbers, by the runtime and by `vocc pvs --all-cells`; returns
 * the cells that differ and the objects culled (summed over `ids`).
 * @param {string} file the store @param {Store} s @param {BoxTree} tree
 * @param {ArrayLike<number>} features the input feature number of each object
 * @param {number[]} ids @param {string[]} sceneArgs scene files and reader flags
 */
export async function comparePvs(file, s, tree, features, ids, sceneArgs) {
  // One run for every cell of the store (the scene is read once), one JSON line a cell.
  const lines = (await stdout(VOCC, ['pvs', file, ...sceneArgs, '--all-cells', '--json'])).trim().split('\n');
  assert.equal(lines.length, s.cellCount, 'one line a cell');
  const all = lines.map((l) => JSON.parse(l));
  all.forEach((w, i) => assert.equal(w.cell, i, 'cells in order'));
  const wants = ids.map((id) => all[id]);
  /** @type {number[]} */
  const differ = [];
  let culled = 0;
  ids.forEach((id, k) => {
    const got = Array.from(pvs(s.frame, id, s.cell(id), tree), (i) => features[i]);
    const want = wants[k];
    assert.equal(want.objects, features.length, `cell ${id}: objects`);
    const same = got.length === want.pvs.length && got.every((x, j) => x === want.pvs[j]);
    if (!same) differ.push(id);
    culled += features.length - got.length;
  });
  return { differ, culled };
}
