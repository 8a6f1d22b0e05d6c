// @ts-check
/**
 * The viewer page of `vocc view` (bundled with three.js into js/dist/viewer.js by build.mjs).
 *
 * Input: the page's data block (written by src/view/mod.rs): the store's bytes, the objects'
 * world boxes and feature numbers, and their geometry as polygons. Output: the city in 3D, the
 * cell grid, and for the picked cell (a click, or walking the camera into it) its VOs as
 * translucent quads, the culled buildings greyed ("all") or hidden ("PVS"), and the counts.
 * Invariants: the PVS is built here by the JavaScript runtime (js/src/) from the store's bytes
 * and the very boxes `vocc pvs` culls, so the count shown is `vocc pvs`'s; frames are drawn
 * on demand only (after a change), never in a loop.
 */

import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { Earcut } from 'three/src/extras/Earcut.js';
import { Store, BoxTree, pvs } from '../src/index.js';

const timings = /** @type {Record<string, number>} */ ({});
let mark = performance.now();
/** @param {string} what */
const lap = (what) => {
  const now = performance.now();
  timings[what] = now - mark;
  mark = now;
};

/** @param {string} id */
const el = (id) => /** @type {HTMLElement} */ (document.getElementById(id));

/**
 * The bytes of a base64 text.
 * @param {string} s
 * @returns {Uint8Array}
 */
function fromBase64(s) {
  const U = /** @type {any} */ (Uint8Array);
  if (typeof U.fromBase64 === 'function') return U.fromBase64(s.trim());
  const bin = atob(s.trim());
  const out = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
  return out;
}

const meta = JSON.parse(el('vocc-meta').textContent || '{}');
const data = fromBase64(el('vocc-data').textContent || '');
const TYPES = /** @type {Record<string, any>} */ ({ u8: Uint8Array, u32: Uint32Array, f32: Float32Array, f64: Float64Array });
/**
 * A section of the data block as its typed array.
 * @param {string} name
 * @returns {any}
 */
function section(name) {
  const [off, count, type] = meta.sections[name];
  return new TYPES[type](data.buffer, data.byteOffset + off, count);
}
lap('decode base64');

const store = Store.parse(section('store'));
const frame = store.frame;
const boxes = section('boxes');
const features = section('features');
const n = features.length;
const tree = BoxTree.fromWorld(boxes, frame.origin);
// One PVS at load, so that the first cell picked does not pay for compiling the culler.
for (let id = 0; id < store.cellCount; id++) {
  const rec = store.cell(id);
  if (rec.vos.length > 0) {
    pvs(frame, id, rec, tree);
    break;
  }
}
lap('store and box tree');

// ---------------------------------------------------------------------------------------------
// Geometry: footprints extruded, mesh faces triangulated; each object's triangles contiguous.

const fpObject = section('fpObject'), fpBase = section('fpBase'), fpTop = section('fpTop');
const fpRings = section('fpRings'), fpRingLen = section('fpRingLen'), fpXy = section('fpXy');
const faceObject = section('faceObject'), faceRings = section('faceRings');
const faceRingLen = section('faceRingLen'), faceXyz = section('faceXyz');

const nVerts = fpXy.length + faceXyz.length / 3;
const positions = new Float32Array(3 * nVerts);
/** @type {number[]} */
let tris = [];
const objTri = new Uint32Array(n + 1);
let v = 0; // vertices written
let fp = 0, fpRing = 0, fpPt = 0; // next footprint polygon, ring, point
let face = 0, faceRing = 0, facePt = 0;
for (let o = 0; o < n; o++) {
  objTri[o] = tris.length;
  for (; fp < fpObject.length && fpObject[fp] === o; fp++) {
    const base = fpBase[fp], top = fpTop[fp];
    const first = v;
    /** @type {number[]} */
    const holes = [];
    const flat = [];
    for (let r = 0; r < fpRings[fp]; r++, fpRing++) {
      const len = fpRingLen[fpRing];
      if (r > 0) holes.push(flat.length / 2);
      const ringStart = v;
      for (let k = 0; k < len; k++, fpPt++) {
        const x = fpXy[2 * fpPt], y = fpXy[2 * fpPt + 1];
        flat.push(x, y);
        positions.set([x, y, top, x, y, base], 3 * v);
        v += 2;
      }
      for (let k = 0; k < len; k++) {
        const t0 = ringStart + 2 * k, t1 = ringStart + 2 * ((k + 1) % len);
        tris.push(t0 + 1, t1 + 1, t1, t0 + 1, t1, t0);
      }
    }
    for (const i of Earcut.triangulate(flat, holes, 2)) tris.push(first + 2 * i);
  }
  for (; face < faceObject.length && faceObject[face] === o; face++) {
    const first = v;
    /** @type {number[]} */
    const holes = [];
    const pts = [];
    for (let r = 0; r < faceRings[face]; r++, faceRing++) {
      const len = faceRingLen[faceRing];
      if (r > 0) holes.push(pts.length / 3);
      for (let k = 0; k < len; k++, facePt++) {
        pts.push(faceXyz[3 * facePt], faceXyz[3 * facePt + 1], faceXyz[3 * facePt + 2]);
        positions.set(pts.slice(-3), 3 * v);
        v++;
      }
    }
    // Newell's normal picks the plane to project on: drop its largest axis.
    let nx = 0, ny = 0, nz = 0;
    const m = pts.length / 3;
    for (let k = 0; k < m; k++) {
      const j = (k + 1) % m;
      const [x0, y0, z0, x1, y1, z1] = [pts[3 * k], pts[3 * k + 1], pts[3 * k + 2], pts[3 * j], pts[3 * j + 1], pts[3 * j + 2]];
      nx += (y0 - y1) * (z0 + z1);
      ny += (z0 - z1) * (x0 + x1);
      nz += (x0 - x1) * (y0 + y1);
    }
    const [ax, ay, az] = [Math.abs(nx), Math.abs(ny), Math.abs(nz)];
    const [u, w] = az >= ax && az >= ay ? [0, 1] : ay >= ax ? [0, 2] : [1, 2];
    const flat = [];
    for (let k = 0; k < m; k++) flat.push(pts[3 * k + u], pts[3 * k + w]);
    for (const i of Earcut.triangulate(flat, holes, 2)) tris.push(first + i);
  }
}
objTri[n] = tris.length;
const triIndex = Uint32Array.from(tris);
tris = [];
lap('triangulate');

// ---------------------------------------------------------------------------------------------
// The scene.

const canvas = /** @type {HTMLCanvasElement} */ (el('view'));
const renderer = new THREE.WebGLRenderer({ canvas, antialias: false });
renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
renderer.setClearColor(0xeef1f4);
const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(45, 1, 1, 1e6);
camera.up.set(0, 0, 1);
scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8f96, 2.2));
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
sun.position.set(-0.5, -0.8, 1.2);
scene.add(sun);

const gridX0 = frame.minX, gridY0 = frame.minY;
const gridX1 = frame.minX + frame.nx * frame.cellSize, gridY1 = frame.minY + frame.ny * frame.cellSize;
const groundZ = frame.groundZ0;

const cityGeom = new THREE.BufferGeometry();
cityGeom.setAttribute('position', new THREE.BufferAttribute(positions, 3));
const order = new Uint32Array(triIndex.length);
order.set(triIndex);
const indexAttr = new THREE.BufferAttribute(order, 1);
cityGeom.setIndex(indexAttr);
cityGeom.computeBoundingSphere();
const visibleMat = new THREE.MeshLambertMaterial({ color: 0xe8b04a, flatShading: true, side: THREE.DoubleSide });
const culledMat = new THREE.MeshLambertMaterial({ color: 0x9aa3ad, flatShading: true, side: THREE.DoubleSide, transparent: true, opacity: 0.55 });
const neutralMat = new THREE.MeshLambertMaterial({ color: 0xd9d4cb, flatShading: true, side: THREE.DoubleSide });
const city = new THREE.Mesh(cityGeom, [neutralMat, visibleMat, culledMat]);
cityGeom.addGroup(0, order.length, 0);
scene.add(city);

// The ground and the cell grid.
const ground = new THREE.Mesh(
  new THREE.PlaneGeometry(gridX1 - gridX0, gridY1 - gridY0),
  new THREE.MeshBasicMaterial({ color: 0xf7f8fa }),
);
ground.position.set((gridX0 + gridX1) / 2, (gridY0 + gridY1) / 2, groundZ - 0.05);
scene.add(ground);
{
  const pts = [];
  for (let i = 0; i <= frame.nx; i++) {
    const x = gridX0 + i * frame.cellSize;
    pts.push(x, gridY0, groundZ, x, gridY1, groundZ);
  }
  for (let j = 0; j <= frame.ny; j++) {
    const y = gridY0 + j * frame.cellSize;
    pts.push(gridX0, y, groundZ, gridX1, y, groundZ);
  }
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(pts, 3));
  scene.add(new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: 0x7d8a99, transparent: true, opacity: 0.6 })));
}
const cellOutline = new THREE.LineLoop(
  new THREE.BufferGeometry(),
  new THREE.LineBasicMaterial({ color: 0x1060d0 }),
);
scene.add(cellOutline);
const cellFill = new THREE.Mesh(
  new THREE.BufferGeometry(),
  new THREE.MeshBasicMaterial({ color: 0x1060d0, transparent: true, opacity: 0.25, side: THREE.DoubleSide, depthWrite: false }),
);
scene.add(cellFill);
const voMesh = new THREE.Mesh(
  new THREE.BufferGeometry(),
  new THREE.MeshBasicMaterial({ color: 0xd0308a, transparent: true, opacity: 0.35, side: THREE.DoubleSide, depthWrite: false }),
);
voMesh.renderOrder = 2;
scene.add(voMesh);
const voEdges = new THREE.LineSegments(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0x9a1060 }));
scene.add(voEdges);

const controls = new OrbitControls(camera, canvas);
const span = Math.max(gridX1 - gridX0, gridY1 - gridY0);
controls.target.set((gridX0 + gridX1) / 2, (gridY0 + gridY1) / 2, groundZ);
camera.position.set(controls.target.x - 0.15 * span, controls.target.y - 0.85 * span, groundZ + 0.7 * span);
camera.far = 20 * span + 1000;
controls.update();

let frames = 0;
let pending = false;
function render() {
  pending = false;
  renderer.render(scene, camera);
  frames++;
}
function requestRender() {
  if (!pending) {
    pending = true;
    requestAnimationFrame(render);
  }
}
function resize() {
  const w = window.innerWidth, h = window.innerHeight;
  renderer.setSize(w, h, false);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
  requestRender();
}
window.addEventListener('resize', resize);
controls.addEventListener('change', requestRender);

// ---------------------------------------------------------------------------------------------
// A cell: its VOs, its PVS, the counts.

const state = {
  cell: /** @type {number | null} */ (null),
  mode: 'all',
  pvs: /** @type {Uint32Array | null} */ (null),
  pvsMs: 0,
  vos: 0,
};
const visible = new Uint8Array(n);

/** Regroups the triangles: the PVS's objects first, then the culled ones. */
function regroup() {
  cityGeom.clearGroups();
  if (!state.pvs) {
    order.set(triIndex);
    cityGeom.addGroup(0, order.length, 0);
  } else {
    visible.fill(0);
    for (const i of state.pvs) visible[i] = 1;
    let k = 0;
    for (const pass of [1, 0]) {
      for (let o = 0; o < n; o++) {
        if (visible[o] !== pass) continue;
        order.set(triIndex.subarray(objTri[o], objTri[o + 1]), k);
        k += objTri[o + 1] - objTri[o];
      }
      if (pass === 1) {
        cityGeom.addGroup(0, k, 1);
        if (state.mode === 'all') cityGeom.addGroup(k, order.length - k, 2);
      }
    }
  }
  indexAttr.needsUpdate = true;
}

/** @param {number} x */
const fmt = (x) => x.toLocaleString('en-US');

/**
 * Picks cell `id` (or none): builds its PVS and draws its VOs.
 * @param {number | null} id
 */
function selectCell(id) {
  if (id === null || !(id >= 0 && id < store.cellCount)) {
    state.cell = null;
    state.pvs = null;
  } else {
    const rec = store.cell(id);
    const t = performance.now();
    state.pvs = pvs(frame, id, rec, tree);
    state.pvsMs = performance.now() - t;
    state.cell = id;
    state.vos = rec.vos.length;
    const quads = [];
    const edges = [];
    for (const q of rec.vos) {
      const g = frame.dequantize(id, rec, q);
      if (!g) continue;
      const [a, b] = [g.a, g.b];
      quads.push(a[0], a[1], g.g, b[0], b[1], g.g, b[0], b[1], g.h, a[0], a[1], g.g, b[0], b[1], g.h, a[0], a[1], g.h);
      edges.push(a[0], a[1], g.g, b[0], b[1], g.g, b[0], b[1], g.g, b[0], b[1], g.h, b[0], b[1], g.h, a[0], a[1], g.h, a[0], a[1], g.h, a[0], a[1], g.g);
    }
    voMesh.geometry.dispose();
    voMesh.geometry = new THREE.BufferGeometry();
    voMesh.geometry.setAttribute('position', new THREE.Float32BufferAttribute(quads, 3));
    voEdges.geometry.dispose();
    voEdges.geometry = new THREE.BufferGeometry();
    voEdges.geometry.setAttribute('position', new THREE.Float32BufferAttribute(edges, 3));
    const r = /** @type {number[]} */ (frame.cellRect(id));
    const z = frame.groundZ(rec.ground) + 0.1;
    cellOutline.geometry.dispose();
    cellOutline.geometry = new THREE.BufferGeometry();
    cellOutline.geometry.setAttribute('position', new THREE.Float32BufferAttribute([r[0], r[1], z, r[2], r[1], z, r[2], r[3], z, r[0], r[3], z], 3));
    cellFill.geometry.dispose();
    cellFill.geometry = new THREE.BufferGeometry();
    cellFill.geometry.setAttribute('position', new THREE.Float32BufferAttribute([r[0], r[1], z, r[2], r[1], z, r[2], r[3], z, r[0], r[1], z, r[2], r[3], z, r[0], r[3], z], 3));
    el('cell-id').textContent = `${id} (column ${id % frame.nx}, row ${Math.floor(id / frame.nx)})${rec.skipped ? ', skipped' : ''}`;
  }
  const count = state.pvs ? state.pvs.length : n;
  el('pvs-count').textContent = state.pvs ? String(count) : '-';
  el('culled').textContent = state.pvs ? `(${(100 * (1 - count / Math.max(n, 1))).toFixed(1)}% culled)` : '';
  el('vo-count').textContent = state.pvs ? String(state.vos) : '-';
  el('pvs-ms').textContent = state.pvs ? state.pvsMs.toFixed(2) : '-';
  if (state.cell === null) el('cell-id').textContent = '-';
  for (const o of [voMesh, voEdges, cellOutline, cellFill]) o.visible = state.cell !== null;
  regroup();
  requestRender();
}

/** @param {string} mode `all` or `pvs` */
function setMode(mode) {
  state.mode = mode;
  el('mode-all').classList.toggle('on', mode === 'all');
  el('mode-pvs').classList.toggle('on', mode === 'pvs');
  regroup();
  requestRender();
}
el('mode-all').addEventListener('click', () => setMode('all'));
el('mode-pvs').addEventListener('click', () => setMode('pvs'));

// Picking: a click (not a drag) on the ground picks the cell under it.
const raycaster = new THREE.Raycaster();
const groundPlane = new THREE.Plane(new THREE.Vector3(0, 0, 1), -groundZ);
/**
 * The local ground point under client position `(cx, cy)`, or null.
 * @param {number} cx
 * @param {number} cy
 */
function groundAt(cx, cy) {
  const r = canvas.getBoundingClientRect();
  const ndc = new THREE.Vector2(((cx - r.left) / r.width) * 2 - 1, -((cy - r.top) / r.height) * 2 + 1);
  raycaster.setFromCamera(ndc, camera);
  const p = new THREE.Vector3();
  return raycaster.ray.intersectPlane(groundPlane, p) ? p : null;
}
let down = /** @type {{x: number, y: number} | null} */ (null);
canvas.addEventListener('pointerdown', (e) => {
  down = { x: e.clientX, y: e.clientY };
});
canvas.addEventListener('pointerup', (e) => {
  if (!down || Math.hypot(e.clientX - down.x, e.clientY - down.y) > 4 || e.button !== 0) return;
  down = null;
  const p = groundAt(e.clientX, e.clientY);
  if (p) selectCell(frame.cellAt(p.x, p.y));
});

// Walking: the camera at the top eye height above the cell's ground; the cell follows it.
const walk = { on: false, x: 0, y: 0, heading: Math.PI / 2 };
function placeWalker() {
  const id = frame.cellAt(walk.x, walk.y);
  const rec = id === null ? null : store.cell(id);
  const z = frame.topEye(rec ?? 0);
  camera.position.set(walk.x, walk.y, z);
  camera.lookAt(walk.x + Math.cos(walk.heading), walk.y + Math.sin(walk.heading), z);
  if (id !== state.cell) selectCell(id);
  requestRender();
}
/** @param {boolean} on */
function setWalk(on) {
  walk.on = on;
  /** @type {HTMLInputElement} */ (el('walk')).checked = on;
  controls.enabled = !on;
  if (on) {
    const c = state.cell !== null ? frame.cellCentre(state.cell) : [controls.target.x, controls.target.y];
    [walk.x, walk.y] = /** @type {number[]} */ (c);
    placeWalker();
  } else {
    camera.position.set(controls.target.x - 0.15 * span, controls.target.y - 0.85 * span, groundZ + 0.7 * span);
    controls.update();
    requestRender();
  }
}
el('walk').addEventListener('change', (e) => setWalk(/** @type {HTMLInputElement} */ (e.target).checked));
window.addEventListener('keydown', (e) => {
  if (!walk.on) return;
  const step = Math.max(frame.cellSize / 20, 1);
  const k = e.key.toLowerCase();
  const fx = Math.cos(walk.heading), fy = Math.sin(walk.heading);
  if (k === 'w' || k === 'arrowup') { walk.x += step * fx; walk.y += step * fy; }
  else if (k === 's' || k === 'arrowdown') { walk.x -= step * fx; walk.y -= step * fy; }
  else if (k === 'a') { walk.x -= step * fy; walk.y += step * fx; }
  else if (k === 'd') { walk.x += step * fy; walk.y -= step * fx; }
  else if (k === 'q' || k === 'arrowleft') walk.heading += Math.PI / 24;
  else if (k === 'e' || k === 'arrowright') walk.heading -= Math.PI / 24;
  else return;
  e.preventDefault();
  placeWalker();
});

// ---------------------------------------------------------------------------------------------
// The panel, the first frame, and a handle for scripts and tests.

el('inputs').textContent = `${meta.store}: ${meta.scene.join(', ')}`;
el('store-info').textContent =
  `store ${store.major}.${store.minor}, ${fmt(store.cellCount)} cells of ${frame.cellSize} m (${frame.nx} x ${frame.ny})` +
  `${store.crs ? ', ' + store.crs : ''}; ${fmt(n)} objects${store.objects && store.objects !== n ? ` (baked for ${fmt(store.objects)})` : ''}`;
el('objects').textContent = String(n);
resize();
render();
lap('first frame');
const loadMs = performance.now();
el('status').textContent = `loaded in ${loadMs.toFixed(0)} ms (${(meta.bytes / 1e6).toFixed(1)} MB of data, ${fmt(triIndex.length / 3)} triangles)`;

/** Times the PVS of every cell with VOs: `{cells, medianMs, maxMs, meanMs}`. */
function benchCells() {
  const ms = [];
  for (let id = 0; id < store.cellCount; id++) {
    const rec = store.cell(id);
    if (rec.vos.length === 0) continue;
    const t = performance.now();
    pvs(frame, id, rec, tree);
    ms.push(performance.now() - t);
  }
  ms.sort((a, b) => a - b);
  const mean = ms.reduce((a, b) => a + b, 0) / Math.max(ms.length, 1);
  return { cells: ms.length, medianMs: ms[ms.length >> 1] ?? 0, maxMs: ms[ms.length - 1] ?? 0, meanMs: mean };
}

/**
 * The client position of a local point at the ground (for scripts that click a cell).
 * @param {number} x
 * @param {number} y
 */
function screenOf(x, y) {
  const p = new THREE.Vector3(x, y, groundZ).project(camera);
  const r = canvas.getBoundingClientRect();
  return { x: r.left + ((p.x + 1) / 2) * r.width, y: r.top + ((1 - p.y) / 2) * r.height };
}

/** @type {any} */ (window).vocc = {
  ready: true,
  loadMs,
  timings,
  store,
  tree,
  features,
  state,
  frames: () => frames,
  selectCell,
  setMode,
  setWalk,
  benchCells,
  screenOf,
  /** @param {number} id */
  cellCentre: (id) => frame.cellCentre(id),
};
document.body.dataset.ready = 'true';
