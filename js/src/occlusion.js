// @ts-check
/**
 * Rule 3 (ARCHITECTURE.md, "Rules 2 and 3"): is a box hidden from a cell by one VO? The port of
 * src/runtime/occlusion.rs.
 *
 * Input: a cell view (rectangle and eye heights), a VO's geometry and boxes
 * `[xmin, ymin, zmin, xmax, ymax, zmax]`, all in the store's local frame.
 * Output: {@link PreparedVo}, whose tests say whether a box is hidden, or whether a group of
 * boxes lies outside the VO's umbra (no box inside it is hidden by this VO).
 * Invariants (conservative by construction, the Rust arithmetic operation for operation):
 * - boxes and the cell grow by {@link MARGIN_M} and the VO shrinks by it at each end before any
 *   test; a box touching the (grown) cell is never hidden;
 * - every number is computed with the same IEEE operations in the same order as the Rust code
 *   (including `min`/`max` that pick the second operand on ties, and `hypot` as the GNU C
 *   library computes it, which is what Rust's `f64::hypot` calls on Linux), so a box is hidden
 *   here exactly when `PreparedVo::cover` is `Hidden` there;
 * - `Hidden` for a group implies `Hidden` for every box inside it, `Outside` for a group
 *   implies not hidden for every box inside it (monotone rounding), which lets the culler
 *   decide whole subtrees.
 */

/** Safety margin, metres: boxes and cells grow by it, VOs shrink by it. */
export const MARGIN_M = 0.001;
/** Rust's `f64::MIN_POSITIVE`: the least positive normal number. */
const MIN_POSITIVE = 2.2250738585072014e-308;

/** Rust's private `max` of occlusion.rs: `a` when `a > b`, else `b`. */
const max = (/** @type {number} */ a, /** @type {number} */ b) => (a > b ? a : b);
/** Rust's private `min`: `a` when `a < b`, else `b`. */
const min = (/** @type {number} */ a, /** @type {number} */ b) => (a < b ? a : b);
/** Rust's `f64::max`: the greater, ignoring a NaN operand. */
function fmax(/** @type {number} */ a, /** @type {number} */ b) {
  if (Number.isNaN(a)) return b;
  if (Number.isNaN(b)) return a;
  return a > b ? a : b;
}

const HYPOT_SCALE = 2 ** -600;
const HYPOT_LARGE = 2 ** 511;
const HYPOT_TINY = 2 ** -511;
const HYPOT_EPS = 2 ** -54;

/**
 * The kernel of glibc's `hypot` (sysdeps/ieee754/dbl-64/e_hypot.c, 2.35 and later, built
 * without FMA as for baseline x86-64): the rounded root, then one correction from the
 * exactly expanded residual (C. F. Borges, "An Improved Algorithm for hypot(a,b)", 2019).
 * @param {number} ax
 * @param {number} ay `ax >= ay >= 0`, in range
 */
function hypotKernel(ax, ay) {
  let t1;
  let t2;
  let h = Math.sqrt(ax * ax + ay * ay);
  if (h <= 2.0 * ay) {
    const delta = h - ay;
    t1 = ax * (2.0 * delta - ax);
    t2 = (delta - 2.0 * (ax - ay)) * delta;
  } else {
    const delta = h - ax;
    t1 = 2.0 * delta * (ax - 2.0 * ay);
    t2 = (4.0 * delta - ay) * ay + delta * delta;
  }
  h -= (t1 + t2) / (2.0 * h);
  return h;
}

/**
 * `sqrt(x² + y²)` with the bits of glibc's `hypot`, which Rust's `f64::hypot` calls (the
 * culler's one call into the C library). `Math.hypot` rounds differently.
 * @param {number} x
 * @param {number} y
 */
export function hypot(x, y) {
  if (!Number.isFinite(x) || !Number.isFinite(y)) {
    if (Math.abs(x) === Infinity || Math.abs(y) === Infinity) return Infinity;
    return x + y;
  }
  x = Math.abs(x);
  y = Math.abs(y);
  let ax = x < y ? y : x;
  let ay = x < y ? x : y;
  if (ax > HYPOT_LARGE) {
    if (ay <= ax * HYPOT_EPS) return ax + ay;
    return hypotKernel(ax * HYPOT_SCALE, ay * HYPOT_SCALE) / HYPOT_SCALE;
  }
  if (ay < HYPOT_TINY) {
    if (ax >= ay / HYPOT_EPS) return ax + ay;
    return hypotKernel(ax / HYPOT_SCALE, ay / HYPOT_SCALE) * HYPOT_SCALE;
  }
  if (ay <= ax * HYPOT_EPS) return ax + ay;
  return hypotKernel(ax, ay);
}

/**
 * `orient(a, b, c)`: twice the signed area of the triangle.
 * @param {number[]} a @param {number[]} b @param {number[]} c
 */
function orient(a, b, c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/**
 * `orient(u, v, p)` as a linear form in `p`.
 * @param {number[]} u @param {number[]} v
 */
function linear(u, v) {
  const dx = v[0] - u[0];
  const dy = v[1] - u[1];
  return [-dy, dx, dy * u[0] - dx * u[1]];
}

/**
 * Whether the grown footprint `[x0, y0, x1, y1]` and the grown cell are apart on some axis.
 * @param {number[]} rect the cell's rectangle
 * @param {number} x0 @param {number} y0 @param {number} x1 @param {number} y1
 */
export function apartFrom(rect, x0, y0, x1, y1) {
  const m = MARGIN_M;
  return x0 > rect[2] + m || x1 < rect[0] - m || y0 > rect[3] + m || y1 < rect[1] - m;
}

/** Outcomes of a group test. */
export const HIDDEN = 0;
export const OUTSIDE = 1;
export const PARTIAL = 2;

/** A VO prepared for many box tests against one cell. */
export class PreparedVo {
  /**
   * @param {import('./frame.js').CellView} view
   * @param {import('./frame.js').VoGeom} vo
   */
  constructor(view, vo) {
    const M = MARGIN_M;
    let a = vo.a;
    let b = vo.b;
    const d = [b[0] - a[0], b[1] - a[1]];
    const len = Math.sqrt(d[0] * d[0] + d[1] * d[1]);
    let usable = Number.isFinite(len) && len > 2.0 * M && Number.isFinite(vo.h);
    if (usable) {
      const s = M / len;
      a = [a[0] + d[0] * s, a[1] + d[1] * s];
      b = [b[0] - d[0] * s, b[1] - d[1] * s];
    }
    const [x0, y0, x1, y1] = view.rect;
    const cs = [
      [x0 - M, y0 - M],
      [x1 + M, y0 - M],
      [x1 + M, y1 + M],
      [x0 - M, y1 + M],
    ];
    const sides = cs.map((c) => orient(a, b, c));
    if (sides.every((s) => s < 0.0)) {
      const t = a;
      a = b;
      b = t;
    } else if (!sides.every((s) => s > 0.0)) {
      usable = false;
    }
    const cross = (/** @type {number[]} */ u, /** @type {number[]} */ v) => u[0] * v[1] - u[1] * v[0];
    const away = (/** @type {number[]} */ p, /** @type {number[]} */ c) => [p[0] - c[0], p[1] - c[1]];
    let ca = cs[0];
    let cb = cs[0];
    for (const c of cs.slice(1)) {
      if (cross(away(a, ca), away(a, c)) > 0.0) ca = c;
      if (cross(away(b, cb), away(b, c)) < 0.0) cb = c;
    }
    const l = linear(a, b);
    const planes = [[-l[0], -l[1], -l[2]], linear(ca, a), linear(b, cb)];
    const norm = hypot(planes[0][0], planes[0][1]);
    const beyond = norm > 0.0 ? planes[0].map((k) => k / norm) : [0.0, 0.0, 0.0];
    let dLine = 0.0;
    for (const c of cs) dLine = fmax(dLine, Math.abs(orient(a, b, c)) / norm);
    const lo = dLine - M;
    this.g = vo.g;
    this.h = vo.h;
    /** `1 / d_line`, `d_line` rounded up by the margin. */
    this.invDLine = 1.0 / (dLine + M);
    /** `1 / d_line`, `d_line` rounded down: an upper bound of every box's factor. */
    this.invDLineLo = 1.0 / (lo > 0.0 ? lo : MIN_POSITIVE);
    this.k0 = beyond[0];
    this.k1 = beyond[1];
    this.k2 = beyond[2];
    /** The umbra's three half-planes, `f(p) = k[0] x + k[1] y + k[2] > 0` inside, flat. */
    this.planes = new Float64Array([...planes[0], ...planes[1], ...planes[2]]);
    this.usable = usable && Number.isFinite(dLine);
    this.heightsOk = view.e0 >= vo.g && vo.h >= view.e1;
    this.e0 = view.e0;
    this.e1 = view.e1;
  }

  /**
   * The height part of rule 3 for a grown footprint strictly inside the umbra and apart from
   * the cell (`heights_hide` without its first two tests).
   * @param {number} fx0 @param {number} fy0 @param {number} fx1 @param {number} fy1
   * @param {number} zmin the box's bottom
   * @param {number} z its top grown by the margin
   */
  heightsHide(fx0, fy0, fx1, fy1, zmin, z) {
    if (zmin >= this.g && z <= this.h) return true;
    const x = this.k0 >= 0.0 ? fx0 : fx1;
    const y = this.k1 >= 0.0 ? fy0 : fy1;
    const beyond = fmax(this.k0 * x + this.k1 * y + this.k2 - MARGIN_M, 0.0);
    const f = 1.0 + beyond * this.invDLine;
    const top = this.e1 + (this.h - this.e1) * f;
    const zlo = zmin - MARGIN_M;
    const bottomOk = zmin >= this.g || zlo >= this.e0 - (this.e0 - this.g) * f;
    return z <= top && bottomOk;
  }

  /**
   * Whether the box of grown footprint `fx0..fy1`, bottom `zmin` and grown top `z` is hidden
   * (`cover == Hidden`), `apart` saying whether it is apart from the cell.
   * @param {number} fx0 @param {number} fy0 @param {number} fx1 @param {number} fy1
   * @param {number} zmin @param {number} z @param {boolean} apart
   */
  hidesGrown(fx0, fy0, fx1, fy1, zmin, z, apart) {
    if (!this.usable || !this.heightsOk || !apart) return false;
    const p = this.planes;
    for (let i = 0; i < 9; i += 3) {
      const k0 = p[i];
      const k1 = p[i + 1];
      // The least value over the footprint: the lesser product on each axis.
      if (!(min(k0 * fx0, k0 * fx1) + min(k1 * fy0, k1 * fy1) + p[i + 2] > 0.0)) return false;
    }
    return this.heightsHide(fx0, fy0, fx1, fy1, zmin, z);
  }

  /**
   * How this VO covers a group of boxes of bounds `bx` (not grown) whose least top is
   * `minTop`: {@link HIDDEN}, {@link OUTSIDE} (no box inside is hidden by it) or
   * {@link PARTIAL}; `apart`: the grown bounds are apart from the cell (Rust's
   * `cover_group_probe`).
   * @param {number[] | Float64Array} bx
   * @param {number} at where the bounds start in `bx`
   * @param {number} minTop
   * @param {boolean} apart
   */
  coverGroup(bx, at, minTop, apart) {
    if (!this.usable) return OUTSIDE;
    const M = MARGIN_M;
    const x0 = bx[at] - M;
    const y0 = bx[at + 1] - M;
    const x1 = bx[at + 3] + M;
    const y1 = bx[at + 4] + M;
    const p = this.planes;
    let allIn = true;
    for (let i = 0; i < 9; i += 3) {
      const k0 = p[i];
      const k1 = p[i + 1];
      const px0 = k0 * x0;
      const px1 = k0 * x1;
      const py0 = k1 * y0;
      const py1 = k1 * y1;
      if (!(max(px0, px1) + max(py0, py1) + p[i + 2] > 0.0)) return OUTSIDE;
      allIn = allIn && min(px0, px1) + min(py0, py1) + p[i + 2] > 0.0;
    }
    if (allIn && this.heightsOk && apart) {
      if (this.heightsHide(x0, y0, x1, y1, bx[at + 2], bx[at + 5] + M)) return HIDDEN;
    }
    // Rust's `group_partial`: every top of the group above what rule 3 allows.
    const xm = this.k0 >= 0.0 ? x1 : x0;
    const ym = this.k1 >= 0.0 ? y1 : y0;
    const dlMax = fmax(this.k0 * xm + this.k1 * ym + this.k2 + M, 0.0);
    const fMax = 1.0 + dlMax * this.invDLineLo;
    const topMax = this.e1 + fmax(this.h - this.e1, 0.0) * fMax;
    return minTop > topMax + M ? OUTSIDE : PARTIAL;
  }
}

/**
 * Whether `vo` hides box `bx` from `view` (rule 3), box by box: the reference the culler's
 * hierarchy is tested against.
 * @param {import('./frame.js').CellView} view
 * @param {PreparedVo} p
 * @param {ArrayLike<number>} bx
 */
export function hides(view, p, bx) {
  const M = MARGIN_M;
  const fx0 = bx[0] - M;
  const fy0 = bx[1] - M;
  const fx1 = bx[3] + M;
  const fy1 = bx[4] + M;
  return p.hidesGrown(fx0, fy0, fx1, fy1, bx[2], bx[5] + M, apartFrom(view.rect, fx0, fy0, fx1, fy1));
}
