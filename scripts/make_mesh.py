#!/usr/bin/env python3
"""Unstructured Gmsh meshes for memcontact's tests and benchmarks.

A site of 2 x 1 (lengths in the mesh's unit) with a circular hole, split at x = 1 into two
physical surfaces, "foam" (left) and "soil" (right), with physical curves "outer" and
"hole". The mesh is graded: element size `size` near the hole, growing to twice that far
from it. No refinement hierarchy: every vertex comes from Gmsh's Delaunay mesher.

    python scripts/make_mesh.py --size 0.0015 -o site.msh            # MSH 4.1 binary
    python scripts/make_mesh.py --size 0.0015 --ascii -o site.msh    # MSH 4.1 ASCII
    python scripts/make_mesh.py --size 0.05 --format 2.2 -o site.msh # MSH 2.2

With --geo FILE.geo it meshes that Gmsh geometry file instead of the site (for the
examples' and the tests' meshes written as .geo files), in any of the four flavours:

    python scripts/make_mesh.py --geo examples/liner-slope.geo --ascii -o examples/liner-slope.msh

Needs the gmsh package (pip install gmsh). About 1 M vertices at --size 0.0015.
"""

import argparse
import sys

import gmsh


def build(size: float, grading: float = 2.0) -> None:
    occ = gmsh.model.occ
    left = occ.addRectangle(0.0, 0.0, 0.0, 1.0, 1.0)
    right = occ.addRectangle(1.0, 0.0, 0.0, 1.0, 1.0)
    hole = occ.addDisk(1.4, 0.5, 0.0, 0.15, 0.15)
    cut, _ = occ.cut([(2, right)], [(2, hole)])
    occ.fragment([(2, left)], cut)
    occ.synchronize()
    surfaces = gmsh.model.getEntities(2)
    foam, soil = [], []
    for dim, tag in surfaces:
        x, _, _ = occ.getCenterOfMass(dim, tag)
        (foam if x < 1.0 else soil).append(tag)
    gmsh.model.addPhysicalGroup(2, foam, name="foam")
    gmsh.model.addPhysicalGroup(2, soil, name="soil")
    outer, hole_curves = [], []
    for dim, tag in gmsh.model.getEntities(1):
        up, _ = gmsh.model.getAdjacencies(dim, tag)
        if len(up) != 1:
            continue  # the interface x = 1 inside the domain
        x0, y0, _, x1, y1, _ = gmsh.model.getBoundingBox(dim, tag)
        on_hole = x0 > 1.2 and x1 < 1.6 and y0 > 0.3 and y1 < 0.7
        (hole_curves if on_hole else outer).append(tag)
    gmsh.model.addPhysicalGroup(1, outer, name="outer")
    gmsh.model.addPhysicalGroup(1, hole_curves, name="hole")
    # Graded: `size` near the hole, `grading * size` from 0.6 away on.
    dist = gmsh.model.mesh.field.add("Distance")
    gmsh.model.mesh.field.setNumbers(dist, "CurvesList", hole_curves)
    thr = gmsh.model.mesh.field.add("Threshold")
    gmsh.model.mesh.field.setNumber(thr, "InField", dist)
    gmsh.model.mesh.field.setNumber(thr, "SizeMin", size)
    gmsh.model.mesh.field.setNumber(thr, "SizeMax", grading * size)
    gmsh.model.mesh.field.setNumber(thr, "DistMin", 0.05)
    gmsh.model.mesh.field.setNumber(thr, "DistMax", 0.6)
    gmsh.model.mesh.field.setAsBackgroundMesh(thr)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.Algorithm", 5)  # Delaunay
    gmsh.model.mesh.generate(2)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", type=float, help="element size near the hole (the site)")
    ap.add_argument("--geo", help="mesh this Gmsh .geo file instead of the site")
    ap.add_argument("--grading", type=float, default=2.0, help="size far from the hole / size near it")
    ap.add_argument("--format", choices=["4.1", "2.2"], default="4.1")
    ap.add_argument("--ascii", action="store_true", help="ASCII instead of binary")
    ap.add_argument("--threads", type=int, default=0, help="Gmsh threads (0: all cores)")
    ap.add_argument("-o", "--output", required=True)
    args = ap.parse_args()
    if (args.size is None) == (args.geo is None):
        ap.error("give either --size (the site) or --geo FILE")
    gmsh.initialize(["-nopopup"])
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", args.threads)
        if args.geo:
            gmsh.open(args.geo)
            gmsh.model.mesh.generate(2)
        else:
            gmsh.model.add("site")
            build(args.size, args.grading)
        gmsh.option.setNumber("Mesh.MshFileVersion", float(args.format))
        gmsh.option.setNumber("Mesh.Binary", 0 if args.ascii else 1)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.write(args.output)
        nodes = gmsh.model.mesh.getNodes()[0]
        print(f"{args.output}: {len(nodes)} vertices", file=sys.stderr)
    finally:
        gmsh.finalize()
    return 0


if __name__ == "__main__":
    sys.exit(main())
