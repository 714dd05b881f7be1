#!/usr/bin/env bash
# The Python module's tests, as CI runs them (.ci/run, after `cargo test --workspace`):
# a virtual environment in target/python-venv (git-ignored; made once, reused), the module
# built from this workspace and installed there, then pytest.
#
#   bash crates/pt-python/tests/run.sh [PT_BINARY]      # default target/debug/pt
#
# The module is built with the dev profile, which is the test profile (Cargo.toml): it reuses
# the artefacts `cargo test` built instead of a release build with LTO (minutes on 2 cores).
# PT_BINARY is the `pt` the bit-for-bit comparisons run.
set -euo pipefail
repo="$(cd "$(dirname "$0")/../../.." && pwd)"
pt_bin="$(realpath "${1:-$repo/target/debug/pt}")"
venv="$repo/target/python-venv"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
# numpy, pytest and matplotlib (the README's example plots) come from PyPI; maturin too, into
# pip's isolated build environment.
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check numpy pytest matplotlib
MATURIN_PEP517_ARGS="--profile dev" \
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check --force-reinstall --no-deps "$repo/crates/pt-python"
cd "$repo"
PT_BIN="$pt_bin" MPLBACKEND=Agg "$venv/bin/python" -m pytest -q "$repo/crates/pt-python/tests" -p no:cacheprovider
