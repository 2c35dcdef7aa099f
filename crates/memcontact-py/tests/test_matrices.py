"""Result.matrices(): S, L, D and φ over the unknowns, against an independent P1 assembly
in NumPy (on a mesh whose numbering the solver renumbers), and the certificate of Problem
2f (with the body below, the one-sided derivatives of docs/theory.md#second-body; rigid:
the obstacle problem's conditions) recomputed in scipy from them and the result's u, for
both foundations."""

import numpy as np
import pytest
import scipy.sparse as sp

import memcontact as mc

TOL = 1e-8


def p1_matrices(v, t, tension, f, h):
    """The P1 stiffness t ∫∇g_i·∇g_j, the mass ∫ h g_i g_j and the load ∫ f g_i over all
    vertices, for constant t, f, h (exact: the integrands are polynomials the element
    formulas integrate exactly)."""
    p = v[t]
    e = np.stack([p[:, 2] - p[:, 1], p[:, 0] - p[:, 2], p[:, 1] - p[:, 0]], axis=1)
    det = e[:, 2, 0] * (-e[:, 1, 1]) - e[:, 2, 1] * (-e[:, 1, 0])  # (p1-p0) × (p2-p0)
    area = det / 2
    grad = np.stack([-e[..., 1], e[..., 0]], axis=-1) / det[:, None, None]
    k = tension * area[:, None, None] * np.einsum("tia,tja->tij", grad, grad)
    m = h * area[:, None, None] / 12 * (np.ones((3, 3)) + np.eye(3))
    rows = np.repeat(t, 3, axis=1).ravel()
    cols = np.tile(t, (1, 3)).ravel()
    n = len(v)
    K = sp.csr_array((k.ravel(), (rows, cols)), shape=(n, n))
    M = sp.csr_array((m.ravel(), (rows, cols)), shape=(n, n))
    F = np.zeros(n)
    np.add.at(F, t.ravel(), np.repeat(f * area / 3, 3))
    return K, M, F


def scrambled_square(nx, seed):
    """The unit square's mesh with its vertices in a random order (which the solver
    renumbers for locality)."""
    grid = mc.rectangle(nx=nx)
    rng = np.random.default_rng(seed)
    order = rng.permutation(grid.n_vertices)  # new vertex k is old vertex order[k]
    new = np.empty_like(order)
    new[order] = np.arange(len(order))
    return mc.Mesh(grid.vertices[order], new[grid.triangles])


def relative(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return np.max(np.abs(a - b)) / max(1e-300, np.max(np.abs(b)))


@pytest.mark.parametrize("foundation", ["consistent", "lumped"])
def test_matrices_equal_an_independent_assembly(foundation):
    mesh = scrambled_square(24, seed=3)
    t, f, h = 1.3, 7.0, 40.0
    g = "0.05 + 0.1*x"
    r = mc.solve(mesh=mesh, membrane=mc.Membrane(t, f),
                 obstacle=mc.Obstacle(0.2, h, foundation=foundation),
                 boundary=mc.Boundary(height=g))
    m = r.matrices()
    v = mesh.vertices
    # The numbering is scattered (the mean index distance across an edge over √n is far
    # above the library's threshold of 4 for renumbering for locality): the solver's
    # unknowns are not in the user's order, and matrices() puts them back.
    tri = np.asarray(mesh.triangles)
    span = np.mean(np.abs(tri - np.roll(tri, 1, axis=1))) / np.sqrt(mesh.n_vertices)
    assert span > 8
    K, M, F = p1_matrices(v, np.asarray(mesh.triangles), t, f, h)
    fixed = np.flatnonzero(mesh.boundary)
    unknowns = np.flatnonzero(~mesh.boundary)
    # The unknowns are the interior vertices in the user's order.
    assert np.array_equal(m["unknowns"], unknowns)
    assert isinstance(m["S"], sp.csr_array) and m["S"].shape == (len(unknowns),) * 2
    assert relative(m["S"].toarray(), K[unknowns][:, unknowns].toarray()) < 1e-12
    G = 0.05 + 0.1 * v[fixed, 0]
    lifted = F[unknowns] - K[unknowns][:, fixed] @ G
    assert relative(m["D"], lifted) < 1e-12
    if foundation == "consistent":
        assert relative(m["L"].toarray(), M[unknowns][:, unknowns].toarray()) < 1e-12
    else:
        # The lumped diagonal: the row sums of the h-weighted mass over all vertices.
        L = m["L"]
        assert L.nnz == len(unknowns)
        assert np.array_equal(L.indices, np.arange(len(unknowns)))
        assert relative(L.diagonal(), np.asarray(M.sum(axis=1)).ravel()[unknowns]) < 1e-12
    assert m["foundation"] == foundation
    assert np.array_equal(m["phi"], np.full(len(unknowns), 0.2))
    assert m["can_touch"].all() and not m["rigid"].any()
    # The result's u at the unknowns solves 2f with these matrices.
    check_2f(m, r.u)


def check_2f(m, u):
    """Problem 2f for U = u at the unknowns: r ≤ 0, r + Lp ≥ 0, pᵀ(r + Lp) = 0,
    rᵀ(p − (U − φ)) = 0, each relative to ‖D‖∞ (the sums relative to the sizes of p and
    of (φ − U)⁺). Returns the largest scaled violation."""
    U = u[m["unknowns"]]
    S, L, D, phi = m["S"], m["L"], m["D"], m["phi"]
    r = S @ U - D
    p = np.where(m["can_touch"], np.maximum(U - phi, 0.0), 0.0)
    Lp = L @ p
    scale = np.max(np.abs(D))
    gap = np.maximum(phi - U, 0.0)
    violations = [
        max(0.0, r.max()) / scale,
        max(0.0, -(r + Lp).min()) / scale,
        abs(p @ (r + Lp)) / (scale * max(1.0, p.sum())),
        abs(r @ gap) / (scale * max(1.0, gap.sum())),
    ]
    assert max(violations) <= TOL, violations
    return max(violations)


@pytest.mark.parametrize("foundation", ["consistent", "lumped"])
def test_scipy_reproduces_the_certificate(examples, foundation):
    r = mc.solve(mc.load_case(examples / "disk.toml", {"obstacle.foundation": foundation}))
    m = r.matrices()
    worst = check_2f(m, r.u)
    # The solver's own 2f residual is of the same order (a sanity bound only).
    assert worst <= 1e3 * r.summary["residual_2f"] + 1e-13
    assert (r.state == 1).sum() > 10, "the case must have contact"
    # The nodal contact forces are X₁ = D − SU on the vertices that can touch.
    U = r.u[m["unknowns"]]
    x1 = m["D"] - m["S"] @ U
    touch = m["can_touch"]
    assert relative(r.contact_force[m["unknowns"]][touch], x1[touch]) < 1e-9
    # J(U) = ½ UᵀSU − UᵀD + ½ pᵀLp is the reported energy.
    p = np.maximum(U - m["phi"], 0.0)
    J = 0.5 * U @ (m["S"] @ U) - U @ m["D"] + 0.5 * p @ (m["L"] @ p)
    assert J == pytest.approx(r.energy, rel=1e-12)


@pytest.mark.parametrize("foundation", ["consistent", "lumped"])
def test_scipy_reproduces_the_two_body_conditions(examples, foundation):
    """At every unknown, zero lies between the one-sided derivatives of J
    (docs/theory.md#second-body)."""
    r = mc.solve(mc.load_case(examples / "liner-slope.toml",
                              {"obstacle.foundation": foundation,
                               "lower.foundation": foundation}))
    m = r.matrices()
    assert m["foundation"] == m["foundation_low"] == foundation
    U = r.u[m["unknowns"]]
    phi, low = m["phi"], m["phi_low"]
    assert np.array_equal(phi, r.phi[m["unknowns"]])
    assert np.array_equal(low, r.phi_low[m["unknowns"]])
    rr = m["S"] @ U - m["D"]
    p = np.where(m["can_touch"], np.maximum(U - phi, 0.0), 0.0)
    q = np.where(m["can_touch_low"], np.maximum(low - U, 0.0), 0.0)
    Lp, Lq = m["L"] @ p, m["L_low"] @ q
    left = rr + Lp * (U > phi) - Lq * (U <= low)
    right = rr + Lp * (U >= phi) - Lq * (U < low)
    scale = np.max(np.abs(m["D"]))
    assert left.max() <= TOL * scale and right.min() >= -TOL * scale
    assert (r.state_low == 1).sum() > 10 and (r.state == 1).sum() > 10
    # The free crest's vertices carry unknowns; the lifting of the frame's heights is in D.
    assert len(m["unknowns"]) == r.summary["unknowns"] > (~r.mesh.boundary).sum()


def test_a_rigid_obstacle_has_no_L(examples):
    r = mc.solve(mc.load_case(examples / "rigid-square.toml",
                              {"mesh.nx": 32, "mesh.ny": 32}))
    m = r.matrices()
    assert m["L"] is None and m["foundation"] == "rigid"
    assert m["rigid"].all() and m["can_touch"].all()
    U = r.u[m["unknowns"]]
    x1 = m["D"] - m["S"] @ U  # the contact forces
    scale = np.max(np.abs(m["D"]))
    gap = m["phi"] - U
    # The obstacle problem: U ≤ φ, X₁ ≥ 0, X₁ᵀ(φ − U) = 0.
    assert gap.min() >= -TOL * max(1.0, np.abs(m["phi"]).max())
    assert x1.min() >= -TOL * scale
    assert abs(x1 @ gap) <= TOL * scale * max(1.0, gap.sum())
    assert (gap <= 1e-12).sum() > 10, "the case must have contact"


def test_matrices_of_steps_adaptive_results_and_unpickled_results(examples):
    """Every kind of result can give its matrices: a sweep's step (the step's model, its
    load scaled), the last step of an adaptive loop (its final mesh), and a result
    unpickled (assembled again)."""
    import pickle

    s = mc.sweep(mc.load_case(examples / "disk.toml", {
        "sweep.parameter": "load_factor", "sweep.values": [0.5, 1.5]}))
    d = [step.matrices()["D"] for step in s.results]
    assert relative(d[1], 3.0 * d[0]) < 1e-12
    for step in s.results:
        check_2f(step.matrices(), step.u)
    a = mc.adapt({"membrane": {"tension": 1.0, "load": 8.0},
                  "obstacle": {"shape": 1.0, "stiffness": 100.0},
                  "adapt": {"max_vertices": 400}}, mesh=mc.disk(radius=1.0, size=0.3))
    m = a.result.matrices()
    assert len(m["unknowns"]) == (~a.mesh.boundary).sum()
    check_2f(m, a.result.u)
    r = mc.solve(mc.load_case(examples / "disk.toml"))
    back = pickle.loads(pickle.dumps(r))
    mine, theirs = r.matrices(), back.matrices()
    assert (mine["S"] != theirs["S"]).nnz == 0 and np.array_equal(mine["D"], theirs["D"])
    check_2f(theirs, back.u)
