#!/usr/bin/env bash
# make test's check of the C ABI: builds libvocc (capi/, the runtime without the geometry stack)
# and the C example with the system C compiler, bakes the bundled Lyon store (fast effort), writes
# its box file with `vocc boxes`, and checks that the example's PVS equals `vocc pvs --json` byte
# for byte for a spread of cells (at least one of which must cull something), also on a scene
# whose skipped features make positions and input feature numbers differ (issue 33, defect 2);
# that a box file of another scene is refused (defect 4); and that a damaged store is refused
# with the library's message.
# Builds with cargo's test profile and `cargo test`'s features, so it reuses what that compiled.
set -euo pipefail
cd "$(dirname "$0")/../.."
CARGO=${CARGO:-cargo}
CC=${CC:-cc}
out=target/tmp/c-example
mkdir -p "$out"

$CARGO build --locked --profile test -p vocc-capi
# The CLI as `cargo test` builds it (its features, with the dev-dependencies unified), so after
# `cargo test` nothing is compiled again.
$CARGO test --locked --no-run
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
"$lib/vocc" boxes "$scene" --height-attr HAUTEUR -o "$out/lyon.boxes" 2>/dev/null
head -2 "$out/lyon.boxes" | grep -q "^# scene [0-9a-f]\{16\} objects 2576 crs \"EPSG:3946\"$" || {
  echo "C example: vocc boxes names no scene: $(head -2 "$out/lyon.boxes")" >&2
  exit 1
}

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

# Issue 33, defect 2 (three numberings): with --base-attr Z_MIN_SOL five Lyon features are
# skipped (feature 13 first), so an object's position among the loaded ones is not its input
# feature number. The C example prints input feature numbers, as `vocc pvs` does.
three_numberings_c_pvs_gives_input_feature_numbers() {
  local flags=(--height-attr HAUTEUR --base-attr Z_MIN_SOL)
  "$lib/vocc" bake "$scene" "${flags[@]}" --effort fast --region 1841900,5175950,1842100,5176150 \
    -o "$out/lyon-base.vocc" 2>/dev/null
  "$lib/vocc" boxes "$scene" "${flags[@]}" -o "$out/lyon-base.boxes" 2>/dev/null
  grep -q " objects 2571 " "$out/lyon-base.boxes" && ! grep -q "^13 " "$out/lyon-base.boxes" || {
    echo "defect 2: the box file does not skip feature 13 with its id" >&2
    exit 1
  }
  "$lib/vocc" pvs "$out/lyon-base.vocc" "$scene" "${flags[@]}" --at 1842000,5176050 --json \
    >"$out/want-base.json"
  "$out/pvs" "$out/lyon-base.vocc" "$out/lyon-base.boxes" --at 1842000,5176050 --json \
    >"$out/got-base.json"
  cmp -s "$out/want-base.json" "$out/got-base.json" || {
    echo "defect 2: the C PVS is not numbered as vocc pvs's (see $out/want-base.json, got-base.json)" >&2
    exit 1
  }
  python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); p=d["pvs"]; sys.exit(0 if len(p) < d["objects"] and max(p) > 13 else 1)' \
    "$out/got-base.json" || {
    echo "defect 2: the comparison proves nothing (no cull, or no id past the first skipped feature)" >&2
    exit 1
  }
}
three_numberings_c_pvs_gives_input_feature_numbers

# Issue 33, defect 4: the boxes of another scene (here: the same file read with other reader
# flags) are refused, naming both scenes.
another_scene_box_file_is_refused() {
  if "$out/pvs" "$out/lyon.vocc" "$out/lyon-base.boxes" --cell 0 2>"$out/err-scene.txt" >/dev/null; then
    echo "defect 4: a box file of another scene was accepted" >&2
    exit 1
  fi
  grep -q "holds another scene than the one .* was baked from (2571 objects, .*baked: 2576 objects" \
    "$out/err-scene.txt" || {
    echo "defect 4: unexpected message: $(cat "$out/err-scene.txt")" >&2
    exit 1
  }
}
another_scene_box_file_is_refused

# The C API reads 1.0 stores: the 1.0 example of docs/FORMAT.md, cell 0 (two VOs of exponents 0).
python3 - "$out/doc-1.0.vocc" <<'PY'
import re, sys
doc = open("docs/FORMAT.md").read()
block = re.search(r"```hex example:store-1\.0\n(.*?)```", doc, re.S).group(1)
data = b"".join(bytes.fromhex(l.split("#")[0].split(":", 1)[1].replace(" ", "")) for l in block.splitlines())
open(sys.argv[1], "wb").write(data)
PY
"$out/pvs" "$out/doc-1.0.vocc" "$out/lyon.boxes" --cell 0 >"$out/v1.txt" 2>"$out/v1-err.txt"
grep -q "records no scene: the boxes could not be checked" "$out/v1-err.txt" || {
  echo "C example: no note that a 1.0 store cannot be checked: $(cat "$out/v1-err.txt")" >&2
  exit 1
}
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
echo "C example: $compared passed, 0 failed ($culled of them cull objects; static and shared library); input feature numbers with skipped features; another scene's boxes refused; a 1.0 store read"
