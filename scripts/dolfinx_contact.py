#!/usr/bin/python3
"""The standard benchmark (docs/benchmarks.md) in DOLFINx, as the peer beside which
memcontact's figures in "Beside DOLFINx" (docs/benchmarks.md#dolfinx) were measured.

Problem: u = 0 on the whole boundary, t = 1, f = 20, h = 1000 with the lumped foundation
(L_ii = int h g_i, zero on the boundary), phi = 0.5 + 0.1 sin(2 pi x) cos(2 pi y) at the
vertices; on the unit square N x N cut along (x_i, y_j)-(x_i+1, y_j+1), or on a triangle
mesh read from XDMF (a Gmsh .msh converted by meshio, 2-D points):

    python -c "import meshio, sys; m = meshio.read(sys.argv[1]); meshio.write(sys.argv[2],
        meshio.Mesh(m.points[:, :2], [('triangle', m.cells_dict['triangle'])]))" site.msh site.xdmf

The contact problem S u - D + L (u - phi)^+ = 0 is solved by the primal-dual active-set
(semismooth Newton) iteration (S + L_A) u = D + L_A phi, A = {u > phi}, each linear system
by CG + GAMG (rtol 1e-10, warm started), until A repeats. It prints
J(u) = 1/2 u'Su - D'u + 1/2 sum_i L_ii ((u_i - phi_i)^+)^2, to compare with memcontact's
summary.json "energy", and the seconds of each phase (rank 0, after a barrier).

    mpiexec -n 2 python3 scripts/dolfinx_contact.py 1024 contact        # the square
    mpiexec -n 2 python3 scripts/dolfinx_contact.py site.xdmf contact   # a mesh file

The second argument is "contact", "poisson" (one linear solve S u = D) or "both".
Written for DOLFINx 0.5 (Debian bookworm's python3-dolfinx).
"""
import sys
import time

t_start = time.perf_counter()
from mpi4py import MPI  # noqa: E402
from petsc4py import PETSc  # noqa: E402
import numpy as np  # noqa: E402
import ufl  # noqa: E402
from dolfinx import fem, mesh  # noqa: E402
from dolfinx.fem.petsc import (  # noqa: E402
    apply_lifting, assemble_matrix, assemble_vector, set_bc)

comm = MPI.COMM_WORLD
N = sys.argv[1] if len(sys.argv) > 1 else "1024"
what = sys.argv[2] if len(sys.argv) > 2 else "both"
T = {}


def tick(name, t0):
    comm.Barrier()
    T[name] = T.get(name, 0.0) + time.perf_counter() - t0
    return time.perf_counter()


t0 = tick("import", t_start)
if N.isdigit():
    msh = mesh.create_unit_square(comm, int(N), int(N), mesh.CellType.triangle,
                                  diagonal=mesh.DiagonalType.right)
else:
    from dolfinx.io import XDMFFile

    with XDMFFile(comm, N, "r") as xf:
        msh = xf.read_mesh(name="Grid")
V = fem.FunctionSpace(msh, ("Lagrange", 1))
msh.topology.create_connectivity(1, 2)
facets = mesh.locate_entities_boundary(msh, 1, lambda x: np.full(x.shape[1], True))
bdofs = fem.locate_dofs_topological(V, 1, facets)
bc = fem.dirichletbc(PETSc.ScalarType(0.0), bdofs, V)
t0 = tick("mesh", t0)

u_, v_ = ufl.TrialFunction(V), ufl.TestFunction(V)
tension, f, h = 1.0, 20.0, 1000.0
a = fem.form(tension * ufl.inner(ufl.grad(u_), ufl.grad(v_)) * ufl.dx)
Lf = fem.form(fem.Constant(msh, PETSc.ScalarType(f)) * v_ * ufl.dx)
Lh = fem.form(fem.Constant(msh, PETSc.ScalarType(h)) * v_ * ufl.dx)
t0 = tick("jit", t0)

A = assemble_matrix(a, bcs=[bc])
A.assemble()
b = assemble_vector(Lf)
apply_lifting(b, [a], [[bc]])
b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
set_bc(b, [bc])
m = assemble_vector(Lh)  # lumped foundation L_ii = int h g_i
m.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
# No foundation on the fixed boundary (the unknowns are the interior vertices).
nloc = V.dofmap.index_map.size_local
mloc = m.getArray()
bloc = bdofs[bdofs < nloc]
mloc[bloc] = 0.0
phi = fem.Function(V)
phi.interpolate(lambda x: 0.5 + 0.1 * np.sin(2 * np.pi * x[0]) * np.cos(2 * np.pi * x[1]))
phiv = phi.vector
t0 = tick("assembly", t0)


def make_ksp(op):
    ksp = PETSc.KSP().create(comm)
    ksp.setOperators(op)
    ksp.setType("cg")
    ksp.getPC().setType("gamg")
    ksp.setTolerances(rtol=1e-10, atol=0.0, max_it=1000)
    ksp.setInitialGuessNonzero(True)
    return ksp


def energy(x):
    Sx = A.createVecLeft()
    A.mult(x, Sx)
    pen = np.maximum(x.getArray() - phiv.getArray(), 0.0)
    loc = 0.5 * x.dot(Sx) - b.dot(x)
    foundation = comm.allreduce(0.5 * float(np.dot(mloc, pen * pen)), op=MPI.SUM)
    return loc + foundation


u = fem.Function(V)
x = u.vector
if what in ("both", "poisson"):
    x.set(0.0)
    ksp = make_ksp(A)
    ksp.setUp()
    t0 = tick("poisson setup", t0)
    ksp.solve(b, x)
    t0 = tick("poisson solve", t0)
    if comm.rank == 0:
        print(f"poisson: {ksp.getIterationNumber()} CG its, reason {ksp.getConvergedReason()}")

if what in ("both", "contact"):
    x.set(0.0)
    active_prev = None
    newton = 0
    cg_total = 0
    Ak = A.duplicate(copy=True)
    d0 = A.getDiagonal()
    rhs = b.duplicate()
    while True:
        newton += 1
        active = (x.getArray() > phiv.getArray()) & (mloc > 0.0)
        n_active = comm.allreduce(int(active.sum()), op=MPI.SUM)
        changed = comm.allreduce(
            int(active_prev is None or (active != active_prev).any()), op=MPI.SUM)
        if newton > 1 and changed == 0:
            break
        dk = d0.copy()
        dk.getArray()[:] += np.where(active, mloc, 0.0)
        Ak.setDiagonal(dk)
        b.copy(rhs)
        rhs.getArray()[:] += np.where(active, mloc * phiv.getArray(), 0.0)
        ksp = make_ksp(Ak)
        ksp.solve(rhs, x)
        cg_total += ksp.getIterationNumber()
        if comm.rank == 0:
            print(f"  newton {newton}: |A| = {n_active}, {ksp.getIterationNumber()} CG its")
        active_prev = active
        if newton > 60:
            break
    t0 = tick("contact solve", t0)
    J = energy(x)
    umax = comm.allreduce(float(x.getArray().max()), op=MPI.SUM if False else MPI.MAX)
    if comm.rank == 0:
        print(f"contact: {newton - 1} Newton solves, {cg_total} CG its, J = {J:.12e}, "
              f"contact vertices {n_active}, max u {umax:.7e}")
T["total"] = time.perf_counter() - t_start
if comm.rank == 0:
    nglob = V.dofmap.index_map.size_global
    print(f"mesh {N}, ranks {comm.size}, dofs {nglob}")
    print("seconds: " + ", ".join(f"{k} {v:.2f}" for k, v in T.items()))
