// Bundles the viewer page's script (viewer/main.js, three.js and the runtime of src/) into
// dist/viewer.js, which src/view/mod.rs puts inside every page `vocc view` writes. Run it after
// changing either (`node viewer/build.mjs`, or `make web-bundle`); `make test-web` checks that
// the committed bundle is what this script builds.
import { build } from 'esbuild';
import { fileURLToPath } from 'node:url';
import path from 'node:path';

const here = path.dirname(fileURLToPath(import.meta.url));
const out = process.argv[2] ?? path.join(here, '..', 'dist', 'viewer.js');
await build({
  entryPoints: [path.join(here, 'main.js')],
  bundle: true,
  minify: true,
  format: 'iife',
  target: 'es2020',
  legalComments: 'eof',
  charset: 'utf8',
  outfile: out,
  logLevel: 'warning',
});
