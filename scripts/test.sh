#!/usr/bin/env bash
# The test command of the README: the Rust test suite and the Python test suite (pytest).
# On first use it creates the virtual environment .venv (or $SEPG_VENV) and installs maturin,
# numpy, gymnasium, pytest, dask, tqdm, tensorboardX and pandas into it by package name (and
# ray with SEPG_TEST_RAY=1, see docs/PYTHON.md); then it builds the Python package with maturin and runs both suites. Fails
# if either suite fails or pytest collects no test (pytest's exit status 5).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
venv=${SEPG_VENV:-$root/.venv}

if [ ! -x "$venv/bin/python" ]; then
    echo "== creating the virtual environment $venv"
    python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check \
    maturin numpy gymnasium pytest dask tqdm tensorboardX pandas
if [ "${SEPG_TEST_RAY:-0}" = 1 ]; then
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check ray
fi

# One interpreter and one build mode for cargo and maturin, so that neither rebuilds pyo3
# after the other: the extension module does not link libpython.
export PYO3_PYTHON="$venv/bin/python"
export PYO3_BUILD_EXTENSION_MODULE=1

echo "== cargo test --workspace --release"
cargo test --workspace --release

echo "== maturin develop --release --features verify (crates/python)"
(cd crates/python && VIRTUAL_ENV="$venv" "$venv/bin/maturin" develop --release --quiet --features verify)

echo "== pytest (crates/python/tests)"
"$venv/bin/python" -m pytest crates/python/tests -q -p no:cacheprovider
