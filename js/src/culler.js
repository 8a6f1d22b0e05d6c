// @ts-check
/**
 * The culler: a cell's potentially visible set (PVS) from its VOs and the engine's object boxes.
 * The JavaScript counterpart of src/runtime/culler.rs.
 *
 * Input: object boxes `[xmin, ymin, zmin, xmax, ymax, zmax]` (six numbers per object, in the
 * store's local frame, or in world coordinates with {@link BoxTree.fromWorld}); per query, a
 * frame, a cell id and its record.
 * Output: {@link BoxTree}, a bounding volume hierarchy built once per scene (binary, leaves of
 * up to {@link LEAF_SIZE} boxes, typed arrays), and per cell entry the ascending indices of the
 * objects that may be visible ({@link pvs}).
 * Invariants:
 * - the PVS is the set of objects that no VO of the cell hides by rule 3 (occlusion.js, the
 *   Rust arithmetic operation for operation), so it equals the Rust culler's set for set; the
 *   hierarchy only saves work: a subtree is culled when its bounds are hidden (rule 3 is
 *   monotone under inclusion) and a VO is dropped for a subtree when the bounds are outside
 *   its umbra or every top below is above what it can hide (the least top rounded down to an
 *   `f32`, as Rust's `f32_below` does);
 * - never culled: boxes touching the cell, invalid boxes (a non-finite coordinate or `min > max`
 *   on an axis), every object of a skipped cell, of a cell without VOs or outside the grid.
 * The tree's shape is not Rust's (its split is simpler); the answer does not depend on it.
 */

import { MARGIN_M, PreparedVo, apartFrom, HIDDEN, OUTSIDE } from './occlusion.js';

/** Most boxes in a leaf. */
export const LEAF_SIZE = 8;
/** How a metre of box top weighs against a metre of extent in the split key (as Rust's). */
const TOP_WEIGHT = 10.0;

const F32 = new Float32Array(1);
const U32 = new Uint32Array(F32.buffer);

/**
 * `x` rounded down to an `f32` (Rust's `f32_below`; `x` is finite).
 * @param {number} x
 */
export function f32Below(x) {
  const f = Math.fround(x);
  if (f <= x) return f;
  if (f === 0) return -(2 ** -149);
  F32[0] = f;
  if (f > 0) U32[0] -= 1;
  else U32[0] += 1;
  return F32[0];
}

/**
 * Finite, and `min <= max` on every axis.
 * @param {ArrayLike<number>} b
 * @param {number} at
 */
export function boxIsValid(b, at) {
  for (let k = 0; k < 6; k++) if (!Number.isFinite(b[at + k])) return false;
  return b[at] <= b[at + 3] && b[at + 1] <= b[at + 4] && b[at + 2] <= b[at + 5];
}

/** A bounding volume hierarchy over object boxes in the store's local frame. */
export class BoxTree {
  /**
   * Builds the tree over boxes in world coordinates: `local = world - origin` (the same
   * subtraction as Rust's `BoxTree::from_world`).
   * @param {ArrayLike<number>} world six numbers per object
   * @param {number[]} origin the frame's origin
   */
  static fromWorld(world, origin) {
    const n = Math.floor(world.length / 6);
    const local = new Float64Array(6 * n);
    for (let i = 0; i < n; i++) {
      for (let k = 0; k < 6; k++) local[6 * i + k] = world[6 * i + k] - origin[k % 3];
    }
    return new BoxTree(local);
  }

  /**
   * @param {ArrayLike<number>} boxes six numbers per object, local frame; object `i` is
   *   `boxes[6i .. 6i + 6]`
   */
  constructor(boxes) {
    const n = Math.floor(boxes.length / 6);
    /** Number of objects (valid or not). */
    this.length = n;
    /** @type {number[]} */
    const valid = [];
    /** @type {number[]} */
    const invalid = [];
    for (let i = 0; i < n; i++) (boxIsValid(boxes, 6 * i) ? valid : invalid).push(i);
    /** The objects whose boxes are invalid: always in the PVS. */
    this.invalid = Uint32Array.from(invalid);
    const m = valid.length;
    const ids = Uint32Array.from(valid);
    const keys = new Float64Array(3 * n);
    for (const i of valid) {
      const b = 6 * i;
      keys[3 * i] = 0.5 * boxes[b] + 0.5 * boxes[b + 3];
      keys[3 * i + 1] = 0.5 * boxes[b + 1] + 0.5 * boxes[b + 4];
      keys[3 * i + 2] = TOP_WEIGHT * boxes[b + 5];
    }
    // A split leaves at least half of LEAF_SIZE boxes on each side: leaves of at least 4 boxes.
    const maxNodes = 2 * Math.ceil(m / (LEAF_SIZE >> 1)) + 1;
    const bounds = new Float64Array(6 * maxNodes);
    const minTop = new Float64Array(maxNodes);
    const start = new Uint32Array(maxNodes);
    const end = new Uint32Array(maxNodes);
    const left = new Int32Array(maxNodes).fill(-1);
    let count = 0;
    if (m > 0) {
      count = 1;
      /** @type {number[][]} */
      const todo = [[0, 0, m]];
      while (todo.length) {
        const [ni, s, e] = /** @type {number[]} */ (todo.pop());
        let b0 = Infinity, b1 = Infinity, b2 = Infinity, b3 = -Infinity, b4 = -Infinity, b5 = -Infinity;
        let top = Infinity;
        const cmin = [Infinity, Infinity, Infinity];
        const cmax = [-Infinity, -Infinity, -Infinity];
        for (let p = s; p < e; p++) {
          const i = ids[p];
          const b = 6 * i;
          b0 = Math.min(b0, boxes[b]);
          b1 = Math.min(b1, boxes[b + 1]);
          b2 = Math.min(b2, boxes[b + 2]);
          b3 = Math.max(b3, boxes[b + 3]);
          b4 = Math.max(b4, boxes[b + 4]);
          b5 = Math.max(b5, boxes[b + 5]);
          top = Math.min(top, boxes[b + 5]);
          for (let k = 0; k < 3; k++) {
            const c = keys[3 * i + k];
            if (c < cmin[k]) cmin[k] = c;
            if (c > cmax[k]) cmax[k] = c;
          }
        }
        bounds.set([b0, b1, b2, b3, b4, b5], 6 * ni);
        minTop[ni] = f32Below(top);
        start[ni] = s;
        end[ni] = e;
        if (e - s > LEAF_SIZE) {
          let axis = 0;
          for (let k = 1; k < 3; k++) if (cmax[k] - cmin[k] > cmax[axis] - cmin[axis]) axis = k;
          const half = s + ((e - s) >> 1);
          const part = Array.from(ids.subarray(s, e));
          part.sort((x, y) => keys[3 * x + axis] - keys[3 * y + axis]);
          ids.set(part, s);
          const l = count;
          count += 2;
          left[ni] = l;
          todo.push([l + 1, half, e], [l, s, half]);
        }
      }
    }
    /** Node `i`'s bounds are `bounds[6i .. 6i + 6]` (boxes below, not grown). */
    this.bounds = bounds.subarray(0, 6 * count);
    /** The least top below each node, rounded down to an `f32`. */
    this.minTop = minTop.subarray(0, count);
    /** Each node's boxes are `ids[start[i] .. end[i]]`. */
    this.start = start.subarray(0, count);
    this.end = end.subarray(0, count);
    /** Node `i`'s children are `left[i]` and `left[i] + 1`; -1 for a leaf. */
    this.left = left.subarray(0, count);
    /** Object indices in tree order. */
    this.ids = ids;
    /** The grown boxes in tree order: `[x0 - m, y0 - m, x1 + m, y1 + m, zmin, zmax + m]`. */
    const grown = new Float64Array(6 * m);
    for (let p = 0; p < m; p++) {
      const b = 6 * ids[p];
      grown[6 * p] = boxes[b] - MARGIN_M;
      grown[6 * p + 1] = boxes[b + 1] - MARGIN_M;
      grown[6 * p + 2] = boxes[b + 3] + MARGIN_M;
      grown[6 * p + 3] = boxes[b + 4] + MARGIN_M;
      grown[6 * p + 4] = boxes[b + 2];
      grown[6 * p + 5] = boxes[b + 5] + MARGIN_M;
    }
    this.grown = grown;
    /** Scratch for the visible flags of a query. */
    this.marks = new Uint8Array(n);
    /** Scratch stack of the walk: node, VO mask, apart flag. */
    this.stack = new Int32Array(3 * (count + 2));
  }
}

/**
 * @typedef {object} PvsStats
 * @property {number} vos VOs prepared for the query
 * @property {number} nodesTested
 * @property {number} boxesTested
 */

/**
 * The PVS of cell `id` with record `record`: the ascending indices of the objects that no VO
 * of the cell hides (rule 3). Everything for a skipped cell, a cell without VOs or outside the
 * grid.
 * @param {import('./frame.js').Frame} frame
 * @param {number} id
 * @param {import('./format.js').CellRecord} record
 * @param {BoxTree} tree
 * @param {PvsStats} [stats] filled when given
 * @returns {Uint32Array}
 */
export function pvs(frame, id, record, tree, stats) {
  const n = tree.length;
  // Where the cell stands: its ground level and, in 2.1, its rise (the top eye).
  const view = frame.cellView(id, record);
  const all = () => {
    const out = new Uint32Array(n);
    for (let i = 0; i < n; i++) out[i] = i;
    return out;
  };
  if (!view || record.skipped || record.vos.length === 0) return all();
  /** @type {PreparedVo[]} */
  const prepared = [];
  for (const q of record.vos) {
    const g = frame.dequantize(id, record, q);
    if (!g) continue;
    const p = new PreparedVo(view, g);
    if (p.usable && p.heightsOk) prepared.push(p);
  }
  if (stats) {
    stats.vos = prepared.length;
    stats.nodesTested = 0;
    stats.boxesTested = 0;
  }
  if (prepared.length === 0) return all();
  const marks = tree.marks;
  marks.fill(0);
  for (const i of tree.invalid) marks[i] = 1;
  const { bounds, minTop, start, end, left, ids, grown, stack } = tree;
  const rect = view.rect;
  const full = (1 << prepared.length) - 1;
  let sp = 0;
  if (start.length > 0) {
    stack[0] = 0;
    stack[1] = full;
    stack[2] = 0;
    sp = 3;
  }
  let nodes = 0;
  let boxes = 0;
  while (sp > 0) {
    sp -= 3;
    const ni = stack[sp];
    let mask = stack[sp + 1];
    const b = 6 * ni;
    const apart =
      stack[sp + 2] === 1 ||
      apartFrom(rect, bounds[b] - MARGIN_M, bounds[b + 1] - MARGIN_M, bounds[b + 3] + MARGIN_M, bounds[b + 4] + MARGIN_M);
    nodes++;
    let hidden = false;
    for (let v = 0; v < prepared.length; v++) {
      if (!(mask & (1 << v))) continue;
      const c = prepared[v].coverGroup(bounds, b, minTop[ni], apart);
      if (c === HIDDEN) {
        hidden = true;
        break;
      }
      if (c === OUTSIDE) mask &= ~(1 << v);
    }
    if (hidden) continue;
    const s = start[ni];
    const e = end[ni];
    if (mask === 0) {
      for (let p = s; p < e; p++) marks[ids[p]] = 1;
      continue;
    }
    const l = left[ni];
    if (l < 0) {
      boxes += e - s;
      for (let p = s; p < e; p++) {
        const g = 6 * p;
        const x0 = grown[g], y0 = grown[g + 1], x1 = grown[g + 2], y1 = grown[g + 3];
        const boxApart = apart || apartFrom(rect, x0, y0, x1, y1);
        let hid = false;
        if (boxApart) {
          for (let v = 0; v < prepared.length; v++) {
            if (mask & (1 << v) && prepared[v].hidesGrown(x0, y0, x1, y1, grown[g + 4], grown[g + 5], true)) {
              hid = true;
              break;
            }
          }
        }
        if (!hid) marks[ids[p]] = 1;
      }
      continue;
    }
    const ap = apart ? 1 : 0;
    stack[sp] = l + 1;
    stack[sp + 1] = mask;
    stack[sp + 2] = ap;
    stack[sp + 3] = l;
    stack[sp + 4] = mask;
    stack[sp + 5] = ap;
    sp += 6;
  }
  if (stats) {
    stats.nodesTested = nodes;
    stats.boxesTested = boxes;
  }
  let k = 0;
  for (let i = 0; i < n; i++) k += marks[i];
  const out = new Uint32Array(k);
  k = 0;
  for (let i = 0; i < n; i++) if (marks[i]) out[k++] = i;
  return out;
}
