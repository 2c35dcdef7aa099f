#!/usr/bin/env bash
# Regenerates the pictures of the documentation (docs/images/) from the examples:
#   - disk-*.png: the four pictures of `memcontact solve examples/disk.toml`
#     (getting-started.md);
#   - adapt-mesh.png: the final mesh of `examples/roof-corner.toml`'s adaptive loop
#     (adaptivity.md);
#   - geomembrane-deflection.png, geomembrane-liftoff.png: the pictures of a membrane
#     between two bodies, `examples/geomembrane.toml` (outputs.md, "Pictures");
#   - soils-fit.png: fit.png of the back-analysis `examples/soils.toml` (sensitivities.md);
#   - python-deflection.png: the matplotlib picture of the Python guide (python.md), when
#     the `memcontact` package and matplotlib can be imported by $PYTHON.
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


PYTHON="${PYTHON:-python3}"
# A path to an interpreter (a virtual environment's) holds from the scratch directory too.
case "$PYTHON" in */*) PYTHON="$(cd "$(dirname "$PYTHON")" && pwd)/$(basename "$PYTHON")" ;; esac
if "$PYTHON" -c 'import memcontact, matplotlib' 2>/dev/null; then
    cp -r examples "$TMP/examples"
    (cd "$TMP" && MPLBACKEND=Agg "$PYTHON" - <<'PY'
import matplotlib.pyplot as plt
import memcontact as mc

mesh = mc.disk(radius=1.0, size=0.03)
r = mc.solve_mesh(mesh, tension=1.0, load=8.0, shape="1 - 0.3*x", stiffness=100.0)
x, y = mesh.vertices.T
plt.tripcolor(x, y, mesh.triangles, r.u, shading="gouraud")
plt.colorbar(label="u")
plt.tricontour(x, y, mesh.triangles, r.u - r.phi, levels=[0], colors="k")  # contact edge
plt.gca().set_aspect("equal")
plt.savefig("python-deflection.png", dpi=80)
PY
    )
    cp "$TMP/python-deflection.png" "$IMAGES/python-deflection.png"
else
    echo "make_images.sh: $PYTHON cannot import memcontact and matplotlib; python-deflection.png left as it is" >&2
fi
ls -l "$IMAGES"
