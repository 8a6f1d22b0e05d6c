// The JavaScript culler's speed in node (a benchmark, not a test): the box tree built from a
// page's boxes, then the PVS of every cell with VOs, a warm-up pass and a timed pass, one
// cell entry at a time (`Store.cell` then `pvs`, as an engine does on cell entry).
//
//   node js/bench/pvs.mjs STORE PAGE.html [passes]
//
// PAGE.html is what `vocc view STORE SCENE... -o PAGE.html` writes (its boxes are the ones
// `vocc pvs` culls). Prints one JSON line: objects, cells timed, tree build ms, and ms per cell
// entry (median, mean, p95, max over the timed passes).

import fs from 'node:fs';
import { Store, BoxTree, pvs } from '../src/index.js';
import { pageData } from '../test/helpers.js';

const [storeFile, pageFile, passesArg] = process.argv.slice(2);
if (!storeFile || !pageFile) {
  console.error('usage: node js/bench/pvs.mjs STORE PAGE.html [passes]');
  process.exit(2);
}
const passes = Number(passesArg ?? 3);
const store = Store.parse(new Uint8Array(fs.readFileSync(storeFile)));
const { section } = pageData(pageFile);
const boxes = section('boxes');
let t = performance.now();
const tree = BoxTree.fromWorld(boxes, store.frame.origin);
const buildMs = performance.now() - t;
const cells = [];
for (let id = 0; id < store.cellCount; id++) if (store.cell(id).vos.length > 0) cells.push(id);
const entry = (id) => pvs(store.frame, id, store.cell(id), tree).length;
let visible = 0;
for (const id of cells) visible += entry(id); // warm-up
const ms = [];
for (let p = 0; p < passes; p++) {
  for (const id of cells) {
    t = performance.now();
    entry(id);
    ms.push(performance.now() - t);
  }
}
ms.sort((a, b) => a - b);
const q = (f) => ms[Math.min(ms.length - 1, Math.floor(f * ms.length))];
console.log(JSON.stringify({
  objects: tree.length,
  cells: cells.length,
  passes,
  treeBuildMs: +buildMs.toFixed(1),
  visiblePerCell: +(visible / cells.length).toFixed(1),
  msPerCell: {
    median: +q(0.5).toFixed(3),
    mean: +(ms.reduce((a, b) => a + b, 0) / ms.length).toFixed(3),
    p95: +q(0.95).toFixed(3),
    max: +ms[ms.length - 1].toFixed(3),
  },
}));
