#!/usr/bin/env bash
# Runs every test: the Rust API reference (rustdoc, warnings as errors), the Rust workspace,
# then the Python package built with maturin in a fresh virtual environment
# (target/test-venv) and its pytest suite (which runs the documentation's cases and
# snippets: tests/test_docs.py), then the documentation site, built with mkdocs --strict in
# the same environment.
# Needs the Rust toolchain and Python >= 3.9 with pip (PYTHON selects the interpreter).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo --version
# The Rust API reference: no broken intra-doc link, no public page linking to a private
# item. The command-line tool's pages first (they share the library's name); then every
# crate (the library with the `bench` feature the tool enables); then the library alone,
# as a user's `cargo doc` shows it, whose pages are the ones left in target/doc/memcontact.
RUSTDOCFLAGS="-D warnings" cargo doc --quiet --no-deps -p memcontact-cli --bin memcontact
RUSTDOCFLAGS="-D warnings" cargo doc --quiet --no-deps --workspace
RUSTDOCFLAGS="-D warnings" cargo doc --quiet --no-deps -p memcontact
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
(
    cd crates/memcontact-py
    MEMCONTACT_BIN="$TARGET/release/memcontact" "../../$VENV/bin/python" -m pytest -q -p no:cacheprovider tests
    # The type stubs against the installed module (every class, method and signature).
    "../../$VENV/bin/python" -m mypy.stubtest memcontact --allowlist stubtest-allowlist.txt
)
# The documentation site (docs/, mkdocs.yml): every link and anchor must resolve, and the
# Python API reference is rendered from the package's sources and type stubs.
"$VENV/bin/python" -m pip install --quiet -r docs/requirements.txt
SITE="$(mktemp -d)"
trap 'rm -rf "$SITE"' EXIT
NO_MKDOCS_2_WARNING=1 "$VENV/bin/python" -m mkdocs build --strict --quiet -d "$SITE"
PAGES="$(find "$SITE" -name index.html | wc -l)"
if [ "$PAGES" -lt 10 ] || ! grep -q 'id="memcontact.solve_mesh"' "$SITE/python-api/index.html"; then
    echo "the documentation site has $PAGES pages or lacks the Python API reference" >&2
    exit 1
fi
echo "documentation site: $PAGES pages built with --strict"
