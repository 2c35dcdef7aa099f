#!/usr/bin/env python3
"""A Gmsh mesh of three soils for the back-analysis tests and benchmark.

The rectangle (0, 2) x (0, 1) cut at x = 0.7 and x = 1.3 into three physical surfaces,
"clay" (left), "sand" (middle) and "gravel" (right), with the physical curve "outer".
Unstructured (Delaunay), uniform element size `size`:

    python scripts/make_strips.py --size 0.0045 -o strips-1e5.msh   # about 110 000 vertices
    python scripts/make_strips.py --size 0.0015 -o strips-1e6.msh   # about 1 000 000 vertices

Needs the gmsh package (pip install gmsh). Writes MSH 4.1 binary.
"""

import argparse
import sys

import gmsh


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", type=float, required=True, help="element size")
    ap.add_argument("-o", "--output", required=True)
    args = ap.parse_args()
    gmsh.initialize(["-nopopup"])
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("strips")
        occ = gmsh.model.occ
        cuts = [0.0, 0.7, 1.3, 2.0]
        rects = [occ.addRectangle(cuts[k], 0.0, 0.0, cuts[k + 1] - cuts[k], 1.0) for k in range(3)]
        occ.fragment([(2, rects[0])], [(2, r) for r in rects[1:]])
        occ.synchronize()
        names = ["clay", "sand", "gravel"]
        groups = {n: [] for n in names}
        for dim, tag in gmsh.model.getEntities(2):
            x, _, _ = occ.getCenterOfMass(dim, tag)
            groups[names[0 if x < 0.7 else 1 if x < 1.3 else 2]].append(tag)
        for n in names:
            gmsh.model.addPhysicalGroup(2, groups[n], name=n)
        outer = [t for d, t in gmsh.model.getEntities(1) if len(gmsh.model.getAdjacencies(d, t)[0]) == 1]
        gmsh.model.addPhysicalGroup(1, outer, name="outer")
        gmsh.option.setNumber("Mesh.MeshSizeMin", args.size)
        gmsh.option.setNumber("Mesh.MeshSizeMax", args.size)
        gmsh.option.setNumber("Mesh.Algorithm", 5)
        gmsh.model.mesh.generate(2)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.option.setNumber("Mesh.Binary", 1)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.write(args.output)
        print(f"{args.output}: {len(gmsh.model.mesh.getNodes()[0])} vertices", file=sys.stderr)
    finally:
        gmsh.finalize()
    return 0


if __name__ == "__main__":
    sys.exit(main())
