#!/usr/bin/env bash
# The Python package's tests: a virtual environment under target/ with maturin
# and the tools the tests read our files with, the wheel built (dev profile:
# it reuses what `cargo test` compiled) and installed, then pytest. The tests
# use the CLI at target/debug/shapeflow (or $SHAPEFLOW_BIN).
set -euo pipefail
cd "$(dirname "$0")"
venv=../target/python-venv
if [ ! -x "$venv/bin/schemathesis" ]; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check maturin pytest numpy scikit-image tifffile roifile pyvista schemathesis
fi
[ -x ../target/debug/shapeflow ] || (cd .. && cargo build --quiet --bin shapeflow)
rm -rf ../target/wheels
VIRTUAL_ENV="$PWD/$venv" "$venv/bin/maturin" build --quiet --profile dev --out ../target/wheels
"$venv/bin/pip" install --quiet --disable-pip-version-check --force-reinstall --no-deps ../target/wheels/shapeflow-*.whl
cd tests && "../$venv/bin/python" -m pytest -q -rs . "$@"
