// @ts-check
// The culler: the tree's PVS against the box-by-box rule on random scenes (walls around a cell,
// boxes of every size, invalid ones, ones touching the cell, ones reaching below the VOs), also
// with 2.1 records (a rise, deep VOs, boxes downhill), the cases that keep everything, the
// document's stores driving it (tests/format.rs's doc_stores_drive_the_culler, and section 13's
// rise and deep VO), and f32Below.

import { test } from 'node:test';
import assert from 'node:assert/strict';

import { Store, BoxTree, pvs, PreparedVo, hides, Frame, QPoint, QVo, f32Below } from '../src/index.js';
import { docHex } from './helpers.js';

/** A fixed linear congruential sequence in [0, 1). */
function lcg(seed = 1) {
  let s = seed;
  return () => {
    s = (s * 1103515245 + 12345) % 2147483648;
    return s / 2147483648;
  };
}

/** The 5x5 grid of 100 m cells of culler.rs's tests. */
const frame = () =>
  new Frame({
    origin: [843000.0, 6518000.0, 0.0], minX: 0, minY: 0, cellSize: 100, nx: 5, ny: 5,
    quantum: 0.5, eyeLo: 1.5, eyeHi: 2.0, groundZ0: 160, groundStep: 0.5, h0: 4, hRatio: 1.25,
  });

/**
 * @param {Frame} f @param {number} id @param {any} rec @param {number[][]} boxes
 */
function bruteForce(f, id, rec, boxes) {
  const view = f.cellView(id, rec);
  if (!view || rec.skipped) return boxes.map((_, i) => i);
  const prepared = rec.vos.map((/** @type {QVo} */ q) => new PreparedVo(view, /** @type {any} */ (f.dequantize(id, rec, q))));
  const out = [];
  for (let i = 0; i < boxes.length; i++) {
    const b = boxes[i];
    const valid = b.every(Number.isFinite) && b[0] <= b[3] && b[1] <= b[4] && b[2] <= b[5];
    if (!valid || !prepared.some((/** @type {PreparedVo} */ p) => hides(view, p, b))) out.push(i);
  }
  return out;
}

/**
 * A random cell record and boxes; with `v21`, a rise (0 to 40 ground steps), deep VOs (one in
 * three) and boxes reaching down to 12 m under the cell's ground.
 * @param {() => number} r @param {number} nBoxes @param {boolean} [v21]
 */
function randomScene(r, nBoxes, v21 = false) {
  const k = (/** @type {number} */ x) => Math.trunc(256 + (x - 250) / 0.5);
  const vos = [];
  const nVos = 1 + Math.trunc(r() * 10);
  while (vos.length < nVos) {
    let q;
    if (r() < 0.8) {
      const d = 55 + r() * 70, s0 = -127 + r() * 107, s1 = 20 + r() * 107;
      const side = Math.trunc(r() * 4);
      const c = 250;
      const [a, b] = side === 0 ? [[c + s0, c + d], [c + s1, c + d]] : side === 1 ? [[c + s0, c - d], [c + s1, c - d]] : side === 2 ? [[c + d, c + s0], [c + d, c + s1]] : [[c - d, c + s0], [c - d, c + s1]];
      q = new QVo(new QPoint(0, k(a[0]), k(a[1])), new QPoint(0, k(b[0]), k(b[1])), 6 + Math.trunc(r() * 10));
    } else {
      q = new QVo(new QPoint(Math.trunc(r() * 3), Math.trunc(r() * 512), Math.trunc(r() * 512)), new QPoint(0, Math.trunc(r() * 512), Math.trunc(r() * 512)), Math.trunc(r() * 32));
    }
    if (v21) q.deep = r() < 1 / 3;
    if (!q.isDegenerate()) vos.push(q);
  }
  const ground = v21 ? 20 + Math.trunc(r() * 8) : Math.trunc(r() * 8);
  const rise = v21 && r() < 0.8 ? 1 + Math.trunc(r() * 40) : 0;
  const g = 160 + ground * 0.5;
  const boxes = [];
  for (let i = 0; i < nBoxes; i++) {
    const x = r() * 500, y = r() * 500, w = r() * 20, h = r() * 20;
    const z = v21 ? g + (r() * 15 - 12) : g + (r() * 3.2 - 0.2);
    const b = [x, y, z, x + w, y + h, z + r() * 15];
    if (r() < 0.02) b[Math.trunc(r() * 6)] = NaN;
    else if (r() < 0.02) [b[0], b[3]] = [b[3], b[0]];
    boxes.push(b);
  }
  return { rec: { skipped: false, ground, rise, vos }, boxes };
}

test('the tree equals the box-by-box rule on random scenes', () => {
  const f = frame();
  const r = lcg(0x5eed0007 % 2147483648);
  let visible = 0, total = 0;
  for (let scene = 0; scene < 80; scene++) {
    const { rec, boxes } = randomScene(r, 50 + scene * 40);
    const tree = new BoxTree(boxes.flat());
    for (const id of [12, 6, 0, 24]) {
      const got = Array.from(pvs(f, id, rec, tree));
      assert.deepEqual(got, bruteForce(f, id, rec, boxes), `scene ${scene} cell ${id}`);
      visible += got.length;
      total += boxes.length;
    }
  }
  assert.ok(visible < 0.9 * total && visible > 0.3 * total, `${visible} of ${total}`);
});

test('the tree equals the box-by-box rule on random 2.1 scenes (rise, deep VOs, boxes downhill)', () => {
  const f = frame();
  const r = lcg(0x21);
  let visible = 0, total = 0, riseMatters = 0, deepMatters = 0;
  for (let scene = 0; scene < 80; scene++) {
    const { rec, boxes } = randomScene(r, 50 + scene * 40, true);
    const tree = new BoxTree(boxes.flat());
    for (const id of [12, 6, 0, 24]) {
      const got = Array.from(pvs(f, id, rec, tree));
      assert.deepEqual(got, bruteForce(f, id, rec, boxes), `scene ${scene} cell ${id}`);
      visible += got.length;
      total += boxes.length;
      // The rise and the deep flags change the answer (so both are read), and the rise raises
      // the eyes and the VO tops together: the PVS without it holds the PVS with it.
      const flat = Array.from(pvs(f, id, { ...rec, rise: 0 }, tree));
      if (flat.length !== got.length) riseMatters++;
      assert.ok(got.every((i) => flat.includes(i)) || rec.rise === 0, `scene ${scene} cell ${id}`);
      const shallow = { ...rec, vos: rec.vos.map((q) => new QVo(q.a, q.b, q.level, false)) };
      if (Array.from(pvs(f, id, shallow, tree)).length !== got.length) deepMatters++;
    }
  }
  assert.ok(visible < 0.9 * total && visible > 0.3 * total, `${visible} of ${total}`);
  assert.ok(riseMatters > 10 && deepMatters > 10, `rise changed ${riseMatters} PVSs, deep ${deepMatters}`);
});

test('skipped cells, cells without VOs, cells outside the grid and empty trees keep everything', () => {
  const f = frame();
  const { rec, boxes } = randomScene(lcg(3), 300);
  const tree = new BoxTree(boxes.flat());
  const all = boxes.map((_, i) => i);
  assert.deepEqual(Array.from(pvs(f, 12, { skipped: true, ground: 0, rise: 0, vos: [] }, tree)), all);
  assert.deepEqual(Array.from(pvs(f, 12, { skipped: false, ground: 0, rise: 0, vos: [] }, tree)), all);
  assert.deepEqual(Array.from(pvs(f, 25, rec, tree)), all);
  assert.deepEqual(Array.from(pvs(f, 12, rec, new BoxTree([]))), []);
  assert.deepEqual(Array.from(pvs(f, 12, rec, new BoxTree([1, 0, 0, 0, 1, 1, 0, 0, 0, Infinity, 1, 1]))), [0, 1]);
});

test("the document's stores drive the culler (both versions)", () => {
  for (const name of ['store', 'store-1.0']) {
    const s = Store.parse(docHex(name));
    const tree = new BoxTree([50, 115, 162, 55, 118, 164.5, 50, 115, 162, 55, 118, 180, 50, 40, 162, 55, 45, 163, 250, 50, 162, 260, 60, 163]);
    const id = /** @type {number} */ (s.cellAt(10, 10));
    assert.deepEqual(Array.from(pvs(s.frame, id, s.cell(id), tree)), [1, 2, 3], name);
    for (const other of [1, 2]) assert.deepEqual(Array.from(pvs(s.frame, other, s.cell(other), tree)), [0, 1, 2, 3]);
  }
  const s = Store.parse(docHex('store'));
  const tree = new BoxTree([0, 700, 162, 40, 740, 400, 0, 700, 162, 40, 740, 1000]);
  assert.deepEqual(Array.from(pvs(s.frame, 0, s.cell(0), tree)), [1]);
  // World boxes give the same tree.
  const world = BoxTree.fromWorld([843000, 6518700, 162, 843040, 6518740, 400], s.frame.origin);
  assert.deepEqual(Array.from(pvs(s.frame, 0, s.cell(0), world)), []);
});

test("section 13's store drives the culler: the deep far wall hides what lies below the cell", () => {
  const s = Store.parse(docHex('store-2.1'));
  const r = s.cell(0);
  // Behind the far wall (y = 650, x -198..402): a box from 160.5 m (under the cell's ground of
  // 162, over ground_z0 = 160) to 300 m, and one from 159 m (under ground_z0).
  const tree = new BoxTree([0, 700, 160.5, 40, 740, 300, 0, 700, 159, 40, 740, 300]);
  assert.deepEqual(Array.from(pvs(s.frame, 0, r, tree)), [1]);
  // Not deep, the wall stands from 162 m and hides neither.
  const shallow = { ...r, vos: r.vos.map((q) => new QVo(q.a, q.b, q.level, false)) };
  assert.deepEqual(Array.from(pvs(s.frame, 0, shallow, tree)), [0, 1]);
  // The rise: the wall's top is 509.94 m with it (eyes to 167 m), 506.94 m without; a box 1 m
  // behind it up to 509 m is hidden only with the rise.
  const top = new BoxTree([0, 651, 162, 40, 652, 509]);
  assert.deepEqual(Array.from(pvs(s.frame, 0, r, top)), []);
  assert.deepEqual(Array.from(pvs(s.frame, 0, { ...r, rise: 0 }, top)), [0]);
});

test('f32Below rounds down to an f32, and no lower', () => {
  const r = lcg(11);
  for (let i = 0; i < 20000; i++) {
    const x = (r() - 0.5) * 10 ** (r() * 20 - 5);
    const f = f32Below(x);
    assert.ok(f <= x && Math.fround(f) === f, `${x}`);
    const up = new Float32Array([f]);
    const u = new Uint32Array(up.buffer);
    if (f >= 0) u[0] += 1;
    else if (f === -(2 ** -149)) up[0] = 0;
    else u[0] -= 1;
    assert.ok(up[0] > x || f === x, `${x}: ${f}, ${up[0]}`);
  }
  assert.equal(f32Below(0), 0);
  assert.equal(f32Below(1e-50), 0);
  assert.equal(f32Below(-1e-50), -(2 ** -149));
});
