#!/usr/bin/env bash
# make test's check of the JavaScript runtime (js/src): node's test runner on js/test/*.test.js,
# with the Rust side they compare against: the CLI and examples/js_oracle as `cargo test` builds
# them (after `cargo test` nothing is compiled again), the bundled Lyon baked (a 2.0 store) and
# Salt River on its DEM (data/capetown: a 2.1 store, with rises and deep VOs), and their viewer
# pages written by `vocc view` (the PVS tests read the boxes a page holds). Needs node 18 or
# newer; no npm package (the runtime has no dependencies).
set -euo pipefail
cd "$(dirname "$0")/.."
CARGO=${CARGO:-cargo}
if ! command -v node >/dev/null 2>&1; then
  echo "node not found: make test runs the JavaScript runtime's tests with node (18 or newer)" >&2
  exit 1
fi
$CARGO test --locked --no-run
$CARGO build --locked --profile test --example js_oracle
out=target/tmp/js
mkdir -p "$out"
scene=data/lyon1/buildings_lyon1.geojson
target/debug/vocc bake "$scene" --height-attr HAUTEUR -o "$out/lyon.vocc" 2>/dev/null
target/debug/vocc view "$out/lyon.vocc" "$scene" --height-attr HAUTEUR -o "$out/lyon.html"
# Salt River as tests/terrain.rs reads it; the 28 cells of a block on the slope (7 x 4 cells of
# 100 m) are baked, in 6 s (all 529 take 90 s).
sr=(data/capetown/salt_river_footprints_utm34s.geojson --height-attr height --base-attr base_z
  --terrain data/capetown/capetown_dem25m_utm34s.tif)
target/debug/vocc bake "${sr[@]}" --region 264910,6242690,265600,6243080 -o "$out/saltriver.vocc" 2>/dev/null
target/debug/vocc view "$out/saltriver.vocc" "${sr[@]}" -o "$out/saltriver.html"
VOCC_BIN="$PWD/target/debug/vocc" VOCC_ORACLE="$PWD/target/debug/examples/js_oracle" \
  VOCC_JS_DATA="$PWD/$out" VOCC_REQUIRE=1 node --test js/test/*.test.js
