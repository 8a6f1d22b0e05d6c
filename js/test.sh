#!/usr/bin/env bash
# make test's check of the JavaScript runtime (js/src): node's test runner on js/test/*.test.js,
# with the Rust side they compare against: the CLI and examples/js_oracle as `cargo test` builds
# them (after `cargo test` nothing is compiled again), the bundled Lyon baked, and its viewer page
# written by `vocc view` (the PVS tests read the boxes the page holds). Needs node 18 or newer;
# no npm package (the runtime has no dependencies).
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
VOCC_BIN="$PWD/target/debug/vocc" VOCC_ORACLE="$PWD/target/debug/examples/js_oracle" \
  VOCC_JS_DATA="$PWD/$out" VOCC_REQUIRE=1 node --test js/test/*.test.js
