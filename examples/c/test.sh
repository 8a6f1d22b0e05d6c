#!/usr/bin/env bash
# make test's check of the C ABI: builds libvocc (capi/, the runtime without the geometry stack)
# and the C example with the system C compiler, bakes the bundled Lyon store (fast effort), and
# checks that the example's PVS equals `vocc pvs --json` byte for byte for a spread of cells (at
# least one of which must cull something), and that a damaged store is refused with the
# library's message.
# Builds with cargo's test profile and `cargo test`'s features, so it reuses what that compiled.
set -euo pipefail
cd "$(dirname "$0")/../.."
CARGO=${CARGO:-cargo}
CC=${CC:-cc}
out=target/tmp/c-example
mkdir -p "$out"

$CARGO build --locked --profile test -p vocc-capi
# The CLI and the box writer as `cargo test` builds them (its features, with the dev-dependencies
# unified), so after `cargo test` nothing is compiled again.
$CARGO test --locked --no-run --test all --example boxes
lib=target/debug
"$CC" -std=c99 -O2 -Wall -Wextra -Werror -pedantic -Icapi/include examples/c/pvs.c \
  "$lib/libvocc.a" -lm -lpthread -ldl -o "$out/pvs"
"$CC" -std=c99 -O2 -Wall -Wextra -Werror -Icapi/include examples/c/bench.c \
  "$lib/libvocc.a" -lm -lpthread -ldl -o "$out/bench"
# The same program against the shared library.
"$CC" -std=c99 -O2 -Wall -Wextra -Werror -Icapi/include examples/c/pvs.c \
  -L"$lib" -lvocc -Wl,-rpath,"$PWD/$lib" -o "$out/pvs-shared"

scene=data/lyon1/buildings_lyon1.geojson
# The fast effort: the comparison needs a store that culls, not the best one.
"$lib/vocc" bake "$scene" --height-attr HAUTEUR --effort fast -o "$out/lyon.vocc" 2>/dev/null
"$lib/examples/boxes" "$scene" --height-attr HAUTEUR -o "$out/lyon.boxes"

culled=0
compared=0
for cell in 0 23 57 100 113 131 150 171 200 227 "--at 1842000,5176050"; do
  case $cell in --at*) sel=$cell ;; *) sel="--cell $cell" ;; esac
  # shellcheck disable=SC2086
  "$lib/vocc" pvs "$out/lyon.vocc" "$scene" --height-attr HAUTEUR $sel --json >"$out/want.json"
  # shellcheck disable=SC2086
  "$out/pvs" "$out/lyon.vocc" "$out/lyon.boxes" $sel --json >"$out/got.json"
  # shellcheck disable=SC2086
  "$out/pvs-shared" "$out/lyon.vocc" "$out/lyon.boxes" $sel --json >"$out/got-shared.json"
  if ! cmp -s "$out/want.json" "$out/got.json" || ! cmp -s "$out/want.json" "$out/got-shared.json"; then
    echo "C example: the PVS of $sel differs from vocc pvs (see $out/want.json, got.json)" >&2
    exit 1
  fi
  compared=$((compared + 1))
  python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); sys.exit(0 if len(d["pvs"]) < d["objects"] else 1)' \
    "$out/got.json" && culled=$((culled + 1))
done
if [ "$culled" -eq 0 ]; then
  echo "C example: none of the $compared cells culled anything; the comparison proves nothing" >&2
  exit 1
fi
"$out/pvs" "$out/lyon.vocc" "$out/lyon.boxes" --at 1842000,5176050 | tee "$out/text.txt"
grep -q "^store 2\.0, baked for 2576 objects" "$out/text.txt" || {
  echo "C example: the store's version and scene are not 2.0 and 2576 objects" >&2
  exit 1
}

# The C API reads 1.0 stores: the 1.0 example of docs/FORMAT.md, cell 0 (two VOs of exponents 0).
python3 - "$out/doc-1.0.vocc" <<'PY'
import re, sys
doc = open("docs/FORMAT.md").read()
block = re.search(r"```hex example:store-1\.0\n(.*?)```", doc, re.S).group(1)
data = b"".join(bytes.fromhex(l.split("#")[0].split(":", 1)[1].replace(" ", "")) for l in block.splitlines())
open(sys.argv[1], "wb").write(data)
PY
"$out/pvs" "$out/doc-1.0.vocc" "$out/lyon.boxes" --cell 0 >"$out/v1.txt"
grep -q "^store 1\.0, baked for 0 objects, scene 0000000000000000, CRS \"\"" "$out/v1.txt" &&
  grep -q "2 VOs" "$out/v1.txt" &&
  grep -q "VO 0: (e 0, x 196, y 376) - (e 0, x 336, y 376), level 5" "$out/v1.txt" || {
  echo "C example: the 1.0 example store reads otherwise: $(cat "$out/v1.txt")" >&2
  exit 1
}

# A damaged store is refused with the library's message, and the example exits 1.
head -c 500 "$out/lyon.vocc" >"$out/damaged.vocc"
if "$out/pvs" "$out/damaged.vocc" "$out/lyon.boxes" --cell 0 2>"$out/err.txt"; then
  echo "C example: a truncated store was accepted" >&2
  exit 1
fi
grep -q "truncated: .* bytes needed, 500 given" "$out/err.txt" || {
  echo "C example: unexpected message for a truncated store: $(cat "$out/err.txt")" >&2
  exit 1
}
echo "C example: $compared passed, 0 failed ($culled of them cull objects; static and shared library); a 1.0 store read"
