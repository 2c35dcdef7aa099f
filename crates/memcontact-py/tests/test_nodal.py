"""Data as NumPy arrays of nodal values: for data whose P1 interpolant is the function
itself (linear f, h, φ), arrays and expressions give the same answer."""

import pickle

import numpy as np
import pytest

import memcontact as mc

F, H, PHI = "6 + 2*x - y", "80 + 30*x + 10*y", "0.9 - 0.2*x + 0.1*y"


def nodal(mesh, f):
    x, y = mesh.vertices.T
    return f(x, y)


@pytest.mark.parametrize("foundation", ["consistent", "lumped"])
@pytest.mark.parametrize("method", ["active-set", "qp"])
def test_arrays_equal_expressions_for_linear_data(foundation, method):
    mesh = mc.disk(radius=1.0, size=0.1)
    solver = mc.Solver(method=method)
    by_expr = mc.solve(mesh=mesh, membrane=mc.Membrane(1.5, F),
                       obstacle=mc.Obstacle(PHI, H, foundation=foundation), solver=solver)
    by_array = mc.solve(
        mesh=mesh,
        membrane=mc.Membrane(1.5, nodal(mesh, lambda x, y: 6 + 2 * x - y)),
        obstacle=mc.Obstacle(
            shape=nodal(mesh, lambda x, y: 0.9 - 0.2 * x + 0.1 * y),
            stiffness=nodal(mesh, lambda x, y: 80 + 30 * x + 10 * y),
            foundation=foundation,
        ),
        solver=solver,
    )
    # A vectorised function of (x, y) is its values at the vertices.
    by_function = mc.solve(
        mesh=mesh,
        membrane=mc.Membrane(1.5, lambda x, y: 6 + 2 * x - y),
        obstacle=mc.Obstacle(shape=lambda x, y: 0.9 - 0.2 * x + 0.1 * y,
                             stiffness=lambda x, y: 80 + 30 * x + 10 * y,
                             foundation=foundation),
        solver=solver,
    )
    assert np.array_equal(by_function.u, by_array.u)
    assert (by_expr.state == 1).sum() > 10, "the case must have contact"
    assert np.array_equal(by_expr.state, by_array.state)
    for name in ["u", "penetration", "pressure", "contact_force"]:
        a, b = getattr(by_expr, name), getattr(by_array, name)
        assert np.max(np.abs(a - b)) <= 1e-12 * max(1.0, np.max(np.abs(a))), name
    # φ's values are its samples, bit for bit.
    assert np.array_equal(by_array.phi, nodal(mesh, lambda x, y: 0.9 - 0.2 * x + 0.1 * y))


def test_a_nodal_obstacle_is_sampled_exactly_and_solved_consistently():
    mesh = mc.rectangle(nx=24)
    rng = np.random.default_rng(7)
    phi = 0.3 + 0.05 * rng.random(mesh.n_vertices)
    r = mc.solve(mesh=mesh, membrane=mc.Membrane(1.0, 20.0),
                 obstacle=mc.Obstacle(phi, "rigid"))
    assert np.array_equal(r.phi, phi)
    inner = ~mesh.boundary
    # The rigid obstacle: u ≤ φ inside, with equality where the membrane touches.
    assert np.all(r.u[inner] <= phi[inner] + 1e-12)
    touching = r.state == 0
    assert touching.sum() > 0
    assert np.array_equal(r.u[touching], phi[touching])


def test_nodal_arrays_in_a_case_dict_and_pickling(tmp_path):
    mesh = mc.disk(radius=1.0, size=0.3)
    load = nodal(mesh, lambda x, y: 8 + x)
    r = mc.solve({"membrane": {"tension": 1.0, "load": load},
                  "obstacle": {"shape": 1.0, "stiffness": 100.0}}, mesh=mesh)
    back = pickle.loads(pickle.dumps(r))
    assert np.array_equal(back.u, r.u)
    # Writing after unpickling assembles again from the stored values.
    back.write(tmp_path / "o")
    data = np.loadtxt(tmp_path / "o" / "nodes.csv", delimiter=",", skiprows=1)
    assert np.max(np.abs(data[:, 2] - r.u)) <= 1e-15
    assert back.case.to_dict()["membrane"]["load"] == pytest.approx(list(load), abs=0)


@pytest.mark.filterwarnings("ignore:solve_mesh is deprecated:DeprecationWarning")
def test_bad_nodal_arrays():
    mesh = mc.disk(radius=1.0, size=0.3)
    n = mesh.n_vertices
    kw = dict(tension=1.0, shape=1.0, stiffness=100.0)
    with pytest.raises(ValueError, match=r"load: nodal values must have shape"):
        mc.solve_mesh(mesh, load=np.ones(n + 1), **kw)
    bad = np.ones(n)
    bad[3] = np.nan
    with pytest.raises(ValueError, match=r"load\[3\]"):
        mc.solve_mesh(mesh, load=bad, **kw)
    neg = np.full(n, 10.0)
    neg[5] = -1.0
    with pytest.raises(ValueError, match=r"stiffness\[5\]"):
        mc.solve_mesh(mesh, tension=1.0, load=1.0, shape=1.0, stiffness=neg)
    with pytest.raises(ValueError, match="sampling"):
        mc.solve_mesh(mesh, tension=1.0, load=1.0, shape=np.ones(n), stiffness=1.0,
                      sampling="mollified")
    # An array in a case with a mesh of another size is refused when the mesh is known.
    case = mc.Case({
        "mesh": {"generator": "disk", "size": 0.5},
        "membrane": {"tension": 1.0, "load": np.ones(4)},
        "obstacle": {"shape": 1.0, "stiffness": 1.0},
    })
    with pytest.raises(ValueError, match="4 nodal values"):
        mc.solve(case)
