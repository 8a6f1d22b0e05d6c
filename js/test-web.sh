#!/usr/bin/env bash
# make test-web: the viewer page in a real browser. Installs Debian's Chromium when
# /usr/bin/chromium is missing (as root, with apt-get), the npm packages of js/ (npm ci:
# three, esbuild, playwright-core, typescript), checks that the committed bundle
# js/dist/viewer.js is what js/viewer/build.mjs builds and that the runtime's types check (tsc),
# bakes Lyon (2.0) and a block of Salt River on its DEM (2.1), writes their pages with `vocc
# view`, and runs js/test/web.mjs on each in headless Chromium (a click on a cell and a walk,
# checked against `vocc pvs`; screenshots in target/tmp/web/; load and PVS times printed).
set -euo pipefail
cd "$(dirname "$0")/.."
CARGO=${CARGO:-cargo}
export CHROMIUM=${CHROMIUM:-/usr/bin/chromium}
out=target/tmp/web
mkdir -p "$out"
if [ ! -x "$CHROMIUM" ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "test-web: installing chromium from the system packages" >&2
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
  else
    echo "test-web: $CHROMIUM not found: install Debian's chromium (apt-get install chromium) or set CHROMIUM" >&2
    exit 1
  fi
fi
(cd js && npm ci --no-audit --no-fund --loglevel=error)
node js/viewer/build.mjs "$PWD/$out/viewer.js"
if ! cmp -s "$out/viewer.js" js/dist/viewer.js; then
  echo "test-web: js/dist/viewer.js is not what js/viewer/build.mjs builds: run make web-bundle and commit it" >&2
  exit 1
fi
(cd js && npx tsc -p jsconfig.json)
$CARGO test --locked --no-run --test all
scene=data/lyon1/buildings_lyon1.geojson
target/debug/vocc bake "$scene" --height-attr HAUTEUR -o "$out/lyon.vocc" 2>/dev/null
target/debug/vocc view "$out/lyon.vocc" "$scene" --height-attr HAUTEUR -o "$out/lyon.html"
node js/test/web.mjs --page "$out/lyon.html" --store "$out/lyon.vocc" --vocc target/debug/vocc \
  --shot "$out/lyon.png" --cell 104 -- "$scene" --height-attr HAUTEUR
# A 2.1 store (rises and deep VOs): the block of Salt River on its DEM that js/test.sh bakes.
sr=(data/capetown/salt_river_footprints_utm34s.geojson --height-attr height --base-attr base_z
  --terrain data/capetown/capetown_dem25m_utm34s.tif)
target/debug/vocc bake "${sr[@]}" --region 264910,6242690,265600,6243080 -o "$out/saltriver.vocc" 2>/dev/null
target/debug/vocc view "$out/saltriver.vocc" "${sr[@]}" -o "$out/saltriver.html"
node js/test/web.mjs --page "$out/saltriver.html" --store "$out/saltriver.vocc" --vocc target/debug/vocc \
  --shot "$out/saltriver.png" --cell 257 -- "${sr[@]}"
echo "test-web: 2 passed, 0 failed"
