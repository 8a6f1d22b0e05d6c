#!/usr/bin/env bash
# make test's check of the Python package: a virtual environment in target/py with maturin,
# numpy and pytest from PyPI, the wheel built by maturin (dev profile), installed, and the pytest
# suite run against the CLI that `cargo test` built.
set -euo pipefail
cd "$(dirname "$0")/.."
CARGO=${CARGO:-cargo}
PYTHON=${PYTHON:-python3}
venv=target/py
if [ ! -x "$venv/bin/python" ]; then
  "$PYTHON" -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check "maturin>=1.8,<2" "numpy>=1.21" pytest
$CARGO test --locked --no-run
rm -rf target/wheels-test
# maturin runs `cargo rustc`, for which `--profile test` means a test harness: build in dev.
"$venv/bin/maturin" build --locked -m python/Cargo.toml -i "$venv/bin/python" \
  -o target/wheels-test --quiet
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check --force-reinstall --no-deps \
  target/wheels-test/vocc-*.whl
VOCC_BIN="$PWD/target/debug/vocc" "$venv/bin/python" -m pytest -q python/tests
