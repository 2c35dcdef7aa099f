#!/usr/bin/env bash
# Regenerates the pictures of the documentation (docs/images/) from the examples:
#   - disk-*.png: the four pictures of `memcontact solve examples/disk.toml`
#     (getting-started.md);
#   - adapt-mesh.png: the final mesh of `examples/roof-corner.toml`'s adaptive loop
#     (adaptivity.md);
#   - geomembrane-deflection.png, geomembrane-liftoff.png: the pictures of a membrane
#     between two bodies, `examples/geomembrane.toml` (outputs.md, "Pictures");
#   - soils-fit.png: fit.png of the back-analysis `examples/soils.toml` (sensitivities.md).
# The Python guide's pictures (images/python/) are drawn by its own session:
# MEMCONTACT_DOCS_IMAGES=1 pytest crates/memcontact-py/tests/test_walkthrough.py.
# Usage: docs/make_images.sh   (MEMCONTACT: the binary; default: a release build made with
# cargo, a no-op when it is up to date)
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -z "${MEMCONTACT:-}" ]; then
    cargo build --release -q -p memcontact-cli
    MEMCONTACT=target/release/memcontact
fi
IMAGES=docs/images
mkdir -p "$IMAGES"
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT

"$MEMCONTACT" solve examples/disk.toml -o "$TMP/disk" -q >/dev/null
for p in deflection pressure liftoff profile; do
    cp "$TMP/disk/$p.png" "$IMAGES/disk-$p.png"
done

"$MEMCONTACT" solve examples/roof-corner.toml -o "$TMP/roof-corner" -q \
    --set 'output.plots=["profile"]' >/dev/null
cp "$TMP/roof-corner/mesh.png" "$IMAGES/adapt-mesh.png"

"$MEMCONTACT" solve examples/geomembrane.toml -o "$TMP/geomembrane" -q \
    --set 'output.plots=["deflection", "liftoff"]' >/dev/null
for p in deflection liftoff; do
    cp "$TMP/geomembrane/$p.png" "$IMAGES/geomembrane-$p.png"
done

"$MEMCONTACT" solve examples/soils.toml -o "$TMP/soils" -q >/dev/null
cp "$TMP/soils/fit.png" "$IMAGES/soils-fit.png"


ls -l "$IMAGES"
