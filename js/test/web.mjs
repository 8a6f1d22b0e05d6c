// The viewer page in headless Chromium (a fresh profile: playwright's temporary user data dir) (make test-web, through js/test-web.sh): opens a page
// that `vocc view` wrote from a file:// URL, waits until it is ready (data decoded, box tree
// built, triangles made, first frame drawn), clicks a cell on the canvas and checks that the cell
// and PVS count the panel shows are `vocc pvs`'s, walks the camera into the next cell with the
// keyboard and checks again, switches to "PVS", saves screenshots, and reports the load time
// and the PVS build times of every cell in the page. Exits non-zero on a mismatch or a page error.
//
// node js/test/web.mjs --page P.html --store S.vocc --vocc BIN --shot OUT.png [--cell ID]
//   [--no-check] -- SCENE... [reader flags]
// (--no-check only opens and times the page: for large scenes, e.g. Tokyo.)

import { execFileSync } from 'node:child_process';
import path from 'node:path';
import { chromium } from 'playwright-core';

const argv = process.argv.slice(2);
const dash = argv.indexOf('--');
const opts = Object.fromEntries(
  argv.slice(0, dash < 0 ? argv.length : dash).reduce((acc, a, i, all) => {
    if (a.startsWith('--')) acc.push([a.slice(2), all[i + 1] && !all[i + 1].startsWith('--') ? all[i + 1] : true]);
    return acc;
  }, []),
);
const sceneArgs = dash < 0 ? [] : argv.slice(dash + 1);
const check = !opts['no-check'];
const fail = (msg) => {
  console.error(`test-web: ${msg}`);
  process.exitCode = 1;
};

const vocc = (id) =>
  JSON.parse(execFileSync(opts.vocc, ['pvs', opts.store, ...sceneArgs, '--cell', String(id), '--json']).toString());

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
  args: [
    '--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--no-first-run', '--disable-quic',
    '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
  ],
});
const errors = [];
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  page.on('pageerror', (e) => errors.push(e.stack ?? e.message));
  page.on('console', (m) => m.type() === 'error' && errors.push(m.text()));
  const t0 = Date.now();
  await page.goto('file://' + path.resolve(opts.page));
  await page.waitForFunction(() => window.vocc && window.vocc.ready, null, { timeout: 120000 });
  // Two animation frames after ready: the first frame has been presented.
  const presentedMs = await page.evaluate(
    () => new Promise((done) => requestAnimationFrame(() => requestAnimationFrame(() => done(performance.now())))),
  );
  const wallMs = Date.now() - t0;
  const load = await page.evaluate(() => ({ loadMs: window.vocc.loadMs, timings: window.vocc.timings }));
  const report = { page: opts.page, wallMs, presentedMs, ...load };
  const text = async (id) => (await page.textContent('#' + id)).trim();
  if (check) {
    // Click the cell: its centre on the ground, projected to the canvas.
    const id = Number(opts.cell ?? 104);
    const at = await page.evaluate((id) => {
      const c = window.vocc.cellCentre(id);
      const o = window.vocc.store.frame.origin;
      return { ...window.vocc.screenOf(c[0], c[1]), world: [c[0] + o[0], c[1] + o[1]] };
    }, id);
    await page.mouse.click(at.x, at.y);
    await page.waitForFunction(() => document.getElementById('pvs-count').textContent !== '-');
    const shown = { cell: Number((await text('cell-id')).split(' ')[0]), pvs: Number(await text('pvs-count')), objects: Number(await text('objects')) };
    const want = vocc(shown.cell);
    report.click = { asked: id, ...shown, voccPvs: want.pvs.length };
    if (shown.cell !== id) fail(`clicked cell ${id} at (${at.x.toFixed(0)}, ${at.y.toFixed(0)}), the page picked ${shown.cell}`);
    if (shown.pvs !== want.pvs.length || shown.objects !== want.objects) fail(`cell ${shown.cell}: the page shows ${shown.pvs} of ${shown.objects}, vocc pvs ${want.pvs.length} of ${want.objects}`);
    // The page's PVS is vocc pvs's set, by feature number.
    const set = await page.evaluate(() => Array.from(window.vocc.state.pvs, (i) => window.vocc.features[i]));
    if (JSON.stringify(set) !== JSON.stringify(want.pvs)) fail(`cell ${shown.cell}: the page's PVS differs from vocc pvs`);
    await page.waitForTimeout(300);
    await page.screenshot({ path: opts.shot });
    // Walk east from the cell's centre into the next cell.
    await page.check('#walk');
    let walked = shown.cell;
    for (let k = 0; k < 40 && walked === shown.cell; k++) {
      await page.keyboard.press('d');
      walked = Number((await text('cell-id')).split(' ')[0]);
    }
    const wantWalk = vocc(walked);
    report.walk = { cell: walked, pvs: Number(await text('pvs-count')), voccPvs: wantWalk.pvs.length };
    if (walked === shown.cell) fail('walking did not leave the cell');
    if (report.walk.pvs !== wantWalk.pvs.length) fail(`walked into cell ${walked}: the page shows ${report.walk.pvs}, vocc pvs ${wantWalk.pvs.length}`);
    await page.uncheck('#walk');
    await page.evaluate((id) => window.vocc.selectCell(id), id);
    await page.click('#mode-pvs');
    await page.waitForTimeout(300);
    await page.screenshot({ path: opts.shot.replace(/\.png$/, '_pvs.png') });
  }
  // The PVS of every cell with VOs, timed in the page (a first pass warms the JIT).
  await page.evaluate(() => window.vocc.benchCells());
  report.pvsInPage = await page.evaluate(() => window.vocc.benchCells());
  report.objects = await page.evaluate(() => window.vocc.tree.length);
  console.log(JSON.stringify(report));
} finally {
  await browser.close();
}
if (errors.length) fail(`page errors:\n${errors.join('\n')}`);
