// @ts-check
/**
 * What the tests share: FORMAT.md's hex examples (read from the document, as tests/format.rs
 * reads them), a writer of 2.0 (and 2.1) and 1.0 stores and blobs (the runtime reads only; the tests
 * build inputs with this), and the paths of the Rust binaries the cross-checks run.
 *
 * The Rust side: $VOCC_BIN (default target/debug/vocc), $VOCC_ORACLE (default
 * target/debug/examples/js_oracle) and $VOCC_JS_DATA (a folder holding lyon.vocc and lyon.html,
 * made by js/test.sh). Without them the cross-checks are skipped, unless $VOCC_REQUIRE=1
 * (js/test.sh sets it), which makes a missing one a failure.
 */

import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { execFile } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { promisify } from 'node:util';

import { crc32, encodeFrame, Frame, FormatError } from '../src/index.js';

export const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..', '..');
const DOC = fs.readFileSync(path.join(ROOT, 'docs', 'FORMAT.md'), 'utf8');

/**
 * The bytes of the block "```hex example:NAME" of FORMAT.md; each line's offset is checked.
 * @param {string} name
 */
export function docHex(name) {
  const fence = '```hex example:' + name + '\n';
  const start = DOC.indexOf(fence);
  assert.ok(start >= 0, `FORMAT.md has no block ${name}`);
  const body = DOC.slice(start + fence.length, DOC.indexOf('```', start + fence.length));
  const out = [];
  for (const line of body.split('\n')) {
    const data = line.split('#')[0];
    const colon = data.indexOf(':');
    if (colon < 0) continue;
    assert.equal(parseInt(data.slice(0, colon), 16), out.length, `${name}: offset of ${line}`);
    for (const tok of data.slice(colon + 1).trim().split(/\s+/).filter(Boolean)) {
      assert.equal(tok.length, 2);
      out.push(parseInt(tok, 16));
    }
  }
  return Uint8Array.from(out);
}

/** The frame of FORMAT.md section 9. */
export function docFrame() {
  return new Frame({
    origin: [843000.0, 6518000.0, 0.0], minX: 0, minY: 0, cellSize: 100, nx: 3, ny: 1,
    quantum: 0.5, eyeLo: 1.5, eyeHi: 2.0, groundZ0: 160, groundStep: 0.5, h0: 4, hRatio: 1.25,
  });
}

/**
 * A VO's stored bytes in `major` (in 2.x, bit 47 set for a deep VO of 2.1).
 * @param {{a: {e: number, x: number, y: number}, b: {e: number, x: number, y: number}, level: number, deep?: boolean}} q
 * @param {number} major
 */
export function voBytes(q, major) {
  if (major === 1) {
    const w = BigInt(q.a.x) | (BigInt(q.a.y) << 9n) | (BigInt(q.b.x) << 18n) | (BigInt(q.b.y) << 27n) | (BigInt(q.level) << 36n);
    return Array.from({ length: 5 }, (_, k) => Number((w >> BigInt(8 * k)) & 0xffn));
  }
  const p = (/** @type {{e: number, x: number, y: number}} */ e) => BigInt(e.e | (e.x << 3) | (e.y << 12));
  const w = p(q.a) | (p(q.b) << 21n) | (BigInt(q.level) << 42n) | (q.deep ? 1n << 47n : 0n);
  return Array.from({ length: 6 }, (_, k) => Number((w >> BigInt(8 * k)) & 0xffn));
}

/** @typedef {{skipped?: boolean, ground?: number, rise?: number, vos?: any[]}} Rec */

/**
 * A record's payload bytes: the ground byte (with ground bytes), the rise byte (2.1, a rise
 * above 0), the VOs.
 * @param {Frame} f @param {Rec} r @param {number} major
 */
function recordBytes(f, r, major) {
  const vos = r.vos ?? [];
  if (r.skipped || vos.length === 0) return [];
  const out = f.perCellGround() ? [r.ground ?? 0] : [];
  if (r.rise) out.push(r.rise);
  for (const q of vos) out.push(...voBytes(q, major));
  return out;
}

/**
 * A record's index value: 255 skipped, the VO count, or 10 + the count with a rise (2.1).
 * @param {Rec} r
 */
const indexByte = (r) => {
  if (r.skipped) return 255;
  const n = (r.vos ?? []).length;
  return r.rise && n > 0 ? 10 + n : n;
};

/**
 * Whether the records use 2.1 (a rise or a deep VO): the minor a writer gives them.
 * @param {Rec[]} cells
 */
export const minorOf = (cells) => (cells.some((r) => (r.rise ?? 0) > 0 || (r.vos ?? []).some((q) => q.deep)) ? 1 : 0);

/**
 * A store file of `major` (2 or 1) holding `cells` (no checks: it writes what it is given),
 * with the minor a 2.x writer gives them (1 with a rise or a deep VO, else 0) unless given.
 * @param {Frame} f
 * @param {Rec[]} cells
 * @param {{major?: number, minor?: number, objects?: number, scene?: bigint, crs?: string}} [opt]
 */
export function encodeStore(f, cells, opt = {}) {
  const major = opt.major ?? 2;
  const minor = opt.minor ?? (major === 2 ? minorOf(cells) : 0);
  /** @type {number[]} */
  const index = [];
  /** @type {number[]} */
  const table = [];
  /** @type {number[]} */
  const payload = [];
  cells.forEach((r, i) => {
    if (i % 64 === 0) table.push(...u32(payload.length));
    index.push(indexByte(r));
    payload.push(...recordBytes(f, r, major));
  });
  const out = [0x89, 0x56, 0x4f, 0x43, 0x43, 0x0d, 0x0a, 0x1a, major, 0, minor & 0xff, minor >> 8, 0, 0, 0, 0];
  out.push(...encodeFrame(f), ...u32(payload.length), 0, 0, 0, 0);
  if (major === 2) {
    const crs = new TextEncoder().encode(opt.crs ?? '');
    const scene = opt.scene ?? 0n;
    out.push(...u32(opt.objects ?? 0));
    for (let k = 0n; k < 8n; k++) out.push(Number((scene >> (8n * k)) & 0xffn));
    out.push(crs.length, ...crs);
  }
  out.push(...index, ...table, ...payload);
  const b = Uint8Array.from(out);
  fixStoreCrc(b);
  return b;
}

/**
 * A blob of `major` for cell `id`.
 * @param {Frame} f @param {number} id @param {Rec} r @param {number} [major]
 */
export function encodeBlob(f, id, r, major = 2) {
  const out = [0x56, 0x4f, 0x43, 0x42, major, ...u32(id), indexByte(r), ...recordBytes(f, r, major), 0, 0, 0, 0];
  const b = Uint8Array.from(out);
  fixBlobCrc(b);
  return b;
}

/** @param {number} v */
export const u32 = (v) => [v & 0xff, (v >>> 8) & 0xff, (v >>> 16) & 0xff, (v >>> 24) & 0xff];

/** @param {Uint8Array} b */
export function fixStoreCrc(b) {
  if (b.length < 136) return;
  b.fill(0, 132, 136);
  b.set(u32(crc32(b)), 132);
}

/** @param {Uint8Array} b */
export function fixBlobCrc(b) {
  if (b.length < 4) return;
  b.set(u32(crc32(b, 0, b.length - 4)), b.length - 4);
}

/**
 * Asserts that `f` throws the FormatError `kind` with exactly `fields` (when given).
 * @param {() => unknown} f
 * @param {string} kind
 * @param {Record<string, any>} [fields]
 */
export function throwsFormat(f, kind, fields) {
  try {
    f();
  } catch (e) {
    assert.ok(e instanceof FormatError, `not a FormatError: ${e}`);
    assert.equal(e.kind, kind, e.message);
    if (fields) assert.deepEqual(e.fields, fields);
    return /** @type {FormatError} */ (e);
  }
  assert.fail(`expected ${kind}, nothing thrown`);
}

/**
 * The rule number of a `BadFrame` thrown by `f` (`F1`..`F12`).
 * @param {() => unknown} f
 */
export function frameRule(f) {
  const e = throwsFormat(f, 'BadFrame');
  return e.fields.rule.split(':')[0];
}

const run = promisify(execFile);
const bin = (/** @type {string} */ env, /** @type {string} */ rel) => process.env[env] ?? path.join(ROOT, rel);
export const VOCC = bin('VOCC_BIN', 'target/debug/vocc');
export const ORACLE = bin('VOCC_ORACLE', 'target/debug/examples/js_oracle');
export const DATA = process.env.VOCC_JS_DATA ?? path.join(ROOT, 'target', 'tmp', 'js');

/**
 * Why the cross-checks cannot run (a missing binary or file), or `false` when they can. With
 * $VOCC_REQUIRE=1 a missing one throws instead.
 * @param {string[]} files
 */
export function missing(...files) {
  const gone = files.filter((f) => !fs.existsSync(f));
  if (gone.length === 0) return false;
  const why = `missing ${gone.join(', ')} (run js/test.sh, or set VOCC_BIN, VOCC_ORACLE, VOCC_JS_DATA)`;
  if (process.env.VOCC_REQUIRE === '1') throw new Error(why);
  return why;
}

/**
 * Runs a binary, returns its standard output.
 * @param {string} file @param {string[]} args
 */
export async function stdout(file, args) {
  const { stdout } = await run(file, args, { maxBuffer: 1 << 28 });
  return stdout;
}

/**
 * Runs `tasks` with at most `k` at once, in order of their results.
 * @template T
 * @param {(() => Promise<T>)[]} tasks
 * @param {number} k
 */
export async function pool(tasks, k) {
  /** @type {T[]} */
  const out = new Array(tasks.length);
  let next = 0;
  const worker = async () => {
    while (next < tasks.length) {
      const i = next++;
      out[i] = await tasks[i]();
    }
  };
  await Promise.all(Array.from({ length: k }, worker));
  return out;
}

/**
 * The meta directory and typed sections of a page written by `vocc view`.
 * @param {string} file
 */
export function pageData(file) {
  const html = fs.readFileSync(file, 'utf8');
  const grab = (/** @type {string} */ id) => {
    const open = `<script type="application/${id === 'vocc-meta' ? 'json' : 'octet-stream'}" id="${id}">`;
    const s = html.indexOf(open);
    assert.ok(s >= 0, `${file} has no ${id}`);
    return html.slice(s + open.length, html.indexOf('</script>', s));
  };
  const meta = JSON.parse(grab('vocc-meta'));
  const b = Buffer.from(grab('vocc-data'), 'base64');
  const data = new Uint8Array(b.length);
  data.set(b);
  /** @type {Record<string, any>} */
  const T = { u8: Uint8Array, u32: Uint32Array, f32: Float32Array, f64: Float64Array };
  /** @param {string} name */
  const section = (name) => {
    const [off, count, type] = meta.sections[name];
    return new T[type](data.buffer, off, count);
  };
  return { meta, section };
}
