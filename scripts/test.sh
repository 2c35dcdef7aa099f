#!/usr/bin/env bash
# Runs every test: the Rust workspace, then the Python package built with maturin in a
# fresh virtual environment (target/test-venv) and its pytest suite.
# Needs the Rust toolchain and Python >= 3.9 with pip (PYTHON selects the interpreter).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo --version
cargo test --workspace --release
# The Python tests compare against the command-line tool.
cargo build --release -p memcontact-cli
PYTHON="${PYTHON:-python3}"
VENV=target/test-venv
rm -rf "$VENV"
"$PYTHON" -m venv "$VENV"
"$VENV/bin/python" -m pip install --quiet --upgrade pip
# The optional packages of the notebook surface (plots, tables, meshes, matrices), the
# property-based tests and the stub check.
"$VENV/bin/python" -m pip install --quiet ./crates/memcontact-py pytest dask distributed meshio \
    matplotlib pandas scipy pyvista hypothesis mypy
TARGET="$(cargo metadata --format-version 1 --no-deps | "$VENV/bin/python" -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')"
cd crates/memcontact-py
MEMCONTACT_BIN="$TARGET/release/memcontact" "../../$VENV/bin/python" -m pytest -q -p no:cacheprovider tests
# The type stubs against the installed module (every class, method and signature).
"../../$VENV/bin/python" -m mypy.stubtest memcontact --allowlist stubtest-allowlist.txt
