#!/usr/bin/env python3
"""Independent check of memcontact's VTU files: read them with meshio and print the arrays.

Usage:  pip install meshio && python3 scripts/check_vtu.py FILE.vtu [FILE.vtu ...]

Prints, for each file, the number of points and triangles, the range of z, and every point
and cell data array (name, dtype, length, min, max, first values). Exits non-zero if meshio
cannot read a file or if the cells are not all triangles. Not needed by the Rust tests;
the Rust unit tests in crates/memcontact/src/io/vtu.rs already parse both encodings back.
"""
import sys

import meshio
import numpy as np


def show(path):
    m = meshio.read(path)
    kinds = [c.type for c in m.cells]
    if kinds != ["triangle"]:
        raise SystemExit(f"{path}: expected only triangle cells, found {kinds}")
    tri = m.cells[0].data
    print(f"{path}: {len(m.points)} points, {len(tri)} triangles, "
          f"z in [{m.points[:, 2].min():.6g}, {m.points[:, 2].max():.6g}]")
    print(f"  first triangles: {tri[:3].tolist()}")
    for kind, arrays in (("point", m.point_data), ("cell", {
            k: v[0] for k, v in m.cell_data.items()})):
        for name, a in arrays.items():
            a = np.asarray(a)
            fin = a[np.isfinite(a)] if a.dtype.kind == "f" else a
            lo, hi = (fin.min(), fin.max()) if fin.size else (np.nan, np.nan)
            print(f"  {kind} data {name!r}: {a.dtype}, {a.shape[0]} values, "
                  f"min {lo:.17g}, max {hi:.17g}, first {a[:4].tolist()}")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    for p in sys.argv[1:]:
        show(p)
