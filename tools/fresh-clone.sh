#!/usr/bin/env bash
# Runs the README's two commands in a fresh clone of the committed HEAD, as a new user would.
# Usage: tools/fresh-clone.sh [DIR]   (default: a new temporary folder)
set -euo pipefail
src=$(git rev-parse --show-toplevel)
dir=${1:-$(mktemp -d)}
git clone -q "$src" "$dir/vocc"
cd "$dir/vocc"
echo "== make demo (in $dir/vocc)"
make demo
echo "== make test"
make test
