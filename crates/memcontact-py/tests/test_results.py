"""Results, cases and meshes pickle; an unconverged solve raises SolverError with its
result; solves release the GIL; solve_mesh from arrays equals solve_mesh from a Mesh."""

import pickle
import threading
import time

import numpy as np
import pytest

import memcontact as mc

FIELDS = ["u", "phi", "penetration", "pressure", "contact_force", "state"]

DISK = {
    "mesh": {"generator": "disk", "radius": 1.0, "size": 0.15},
    "membrane": {"tension": 1.0, "load": 8.0},
    "obstacle": {"shape": 1.0, "stiffness": 100.0},
}


def assert_same(a, b):
    for name in FIELDS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype, name
        assert np.array_equal(x, y), name
    assert a.status == b.status
    assert np.array_equal(a.mesh.vertices, b.mesh.vertices)
    assert np.array_equal(a.mesh.triangles, b.mesh.triangles)


def test_result_survives_pickling(tmp_path):
    r = mc.solve(mc.Case(DISK, "disk"))
    back = pickle.loads(pickle.dumps(r))
    assert_same(r, back)
    assert back.summary == r.summary
    assert back.report == r.report
    assert back.case == r.case and back.case.label == "disk"
    # Writing after unpickling assembles again and writes the same numbers.
    r.write(tmp_path / "a")
    back.write(tmp_path / "b")
    a = (tmp_path / "a" / "nodes.csv").read_bytes()
    b = (tmp_path / "b" / "nodes.csv").read_bytes()
    assert a == b


def test_result_on_a_hierarchy_pickles_with_its_levels(tmp_path):
    mesh = mc.rectangle(nx=16)
    assert mesh.levels == 4
    r = mc.solve(mesh=mesh, membrane=mc.Membrane(1.0, 20.0),
                 obstacle=mc.Obstacle("0.3 + 0.2*x*y", "rigid"))
    assert r.method == "multigrid"
    back = pickle.loads(pickle.dumps(r))
    assert_same(r, back)
    assert back.mesh.levels == 4
    assert back.write(tmp_path / "o")["levels"] == 4


def test_case_and_mesh_pickle():
    case = mc.Case(DISK, "x")
    assert pickle.loads(pickle.dumps(case)) == case
    mesh = mc.disk(radius=2.0, size=0.5).refine(2)
    back = pickle.loads(pickle.dumps(mesh))
    assert back.levels == 3
    assert back.circle == (0.0, 0.0, 2.0)
    assert np.array_equal(back.vertices, mesh.vertices)
    assert np.array_equal(back.triangles, mesh.triangles)
    # The circle travels too: refining the copy moves boundary vertices onto it.
    finer = back.refine(1).vertices[back.refine(1).boundary]
    assert np.allclose(np.hypot(finer[:, 0], finer[:, 1]), 2.0, rtol=0, atol=1e-12)


def test_unconverged_solve_raises_solver_error_with_the_result():
    case = mc.Case({**DISK, "solver": {"method": "active-set", "max_iterations": 1}})
    with pytest.raises(mc.SolverError) as e:
        mc.solve(case)
    err = e.value
    assert isinstance(err, RuntimeError)
    assert err.result.status == "iteration_limit"
    assert err.status == "iteration_limit"
    assert not err.result.converged and not err.result.accepted
    assert err.result.iterations == 1
    assert err.result.kkt_residual > 1e-10
    assert err.result.u.shape == (err.result.mesh.n_vertices,)
    assert "iteration" in str(err)
    # The error crosses processes with its result.
    again = pickle.loads(pickle.dumps(err))
    assert isinstance(again, mc.SolverError)
    assert again.result.status == "iteration_limit"
    assert str(again) == str(err)
    # check=False hands the result back instead.
    r = mc.solve_many([case], check=False)[0]
    assert r.status == "iteration_limit"
    assert r.summary["converged"] is False and r.summary["accepted"] is False


@pytest.mark.filterwarnings("ignore:solve_mesh is deprecated:DeprecationWarning")
def test_solve_mesh_arrays_equal_mesh_object_and_case():
    mesh = mc.disk(radius=1.0, size=0.15)
    kwargs = dict(tension=1.0, load=8.0, shape=1.0, stiffness=100.0)
    from_mesh = mc.solve_mesh(mesh, **kwargs)
    from_arrays = mc.solve_mesh(mesh.vertices, mesh.triangles, **kwargs)
    from_case = mc.solve(DISK)
    assert_same(from_mesh, from_arrays)
    assert_same(from_mesh, from_case)


def test_region_data_from_python():
    # The square [0, 2]², eight triangles around its one interior vertex (1, 1); the
    # left half is region 1, the right half region 2.
    v = np.array([[0, 0], [1, 0], [2, 0], [0, 1], [1, 1], [2, 1], [0, 2], [1, 2], [2, 2]], float)
    t = np.array([[0, 1, 4], [1, 2, 4], [2, 5, 4], [5, 8, 4],
                  [8, 7, 4], [7, 6, 4], [6, 3, 4], [3, 0, 4]])
    regions = np.array([1, 2, 2, 2, 2, 1, 1, 1])
    mesh = mc.Mesh(v, t, regions, {1: "soft", 2: "hard"})
    assert mesh.region_names == {1: "soft", 2: "hard"}
    assert mesh.boundary.sum() == 8
    tension, f, phi, h = 2.0, 5.0, 0.1, {1: 3.0, 2: 40.0}
    r = mc.solve(mesh=mesh, membrane=mc.Membrane(tension, f),
                 obstacle=mc.Obstacle(phi, {"soft": h[1], "hard": h[2]}))
    # The one-unknown problem by hand: S = t Σ area |∇λ|², D = f Σ area/3,
    # L = Σ h area/6 (the consistent mass of a constant h), U = (D + L φ)/(S + L) if > φ.
    S = D = L = 0.0
    for tri, reg in zip(t, regions):
        p = v[tri]
        k = list(tri).index(4)
        e1, e2 = p[1] - p[0], p[2] - p[0]
        area = 0.5 * abs(e1[0] * e2[1] - e1[1] * e2[0])
        a, b = p[(k + 1) % 3], p[(k + 2) % 3]
        grad_sq = np.sum((b - a) ** 2) / (2 * area) ** 2
        S += tension * area * grad_sq
        D += f * area / 3
        L += h[reg] * area / 6
    u = (D + L * phi) / (S + L)
    assert u > phi and D / S > phi
    assert r.u[4] == pytest.approx(u, rel=1e-13)
    assert r.state[4] == 1
    assert r.pressure[4] == pytest.approx(mesh_h_at_vertex(h, regions, t) * (u - phi), rel=1e-12)
    # Regions by tag as well as by name:
    r2 = mc.solve(mesh=mesh, membrane=mc.Membrane(tension, f),
                  obstacle=mc.Obstacle(phi, {1: h[1], "2": h[2]}))
    assert r2.u[4] == r.u[4]


def mesh_h_at_vertex(h, regions, t):
    """h at vertex 4 as the library samples it on a region interface: the mean over the
    triangles around it (four soft, four hard)."""
    touching = [h[reg] for tri, reg in zip(t, regions) if 4 in tri]
    return sum(touching) / len(touching)


def test_solves_release_the_gil():
    mesh = mc.rectangle(nx=256)
    span = {}

    def work():
        span["start"] = time.perf_counter()
        mc.solve(mesh=mesh, membrane=mc.Membrane(1.0, 20.0),
                 obstacle=mc.Obstacle("0.5 + 0.1*sin(2*pi*x)*cos(2*pi*y)", 1000.0),
                 solver=mc.Solver(method="active-set"))
        span["end"] = time.perf_counter()

    ticks = []
    t = threading.Thread(target=work)
    t.start()
    while t.is_alive():
        ticks.append(time.perf_counter())
    t.join()
    # Were the GIL held by the solve, this thread could run only in a switch interval
    # (5 ms) at either end of it, never in its middle half.
    start, end = span["start"], span["end"]
    assert end - start > 0.05, "the solve is too short to tell"
    quarter = (end - start) / 4
    inside = [x for x in ticks if start + quarter < x < end - quarter]
    assert len(inside) > 0


def test_polygon_regions_and_gmsh_names(examples):
    outer = [[0, 0], [12, 0], [12, 8], [0, 8]]
    block = [[1.5, 2.5], [5, 2.5], [5, 5.5], [1.5, 5.5]]
    a = mc.polygon(outer, 0.5, holes=[[[7, 3], [9, 3], [9, 5], [7, 5]]],
                   regions={"block": block}, min_angle=28.0)
    b = mc.polygon(np.array(outer, float), 0.5, holes=[np.array([[7, 3], [9, 3], [9, 5], [7, 5]])],
                   regions=[{"name": "block", "polygon": block}], min_angle=28.0)
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.regions, b.regions)
    assert "block" in a.region_names.values()
    # The triangles tagged "block" are those whose centroid lies in the block.
    tag = next(t for t, n in a.region_names.items() if n == "block")
    c = a.vertices[a.triangles].mean(axis=1)
    inside = (c[:, 0] > 1.5) & (c[:, 0] < 5) & (c[:, 1] > 2.5) & (c[:, 1] < 5.5)
    assert np.array_equal(a.regions == tag, inside)
    # The same mesh as the case file's polygon generator.
    case = mc.load_case(examples / "roof.toml", {"mesh.size": 0.5})
    assert np.array_equal(mc.solve(case).mesh.vertices, a.vertices)
    g = mc.read_gmsh(examples / "disk.msh")
    assert set(g.region_names.values()) == {"foam", "soil"}
    fine = mc.refine(g, 2)
    assert fine.n_triangles == 16 * g.n_triangles and fine.levels == 3
    # Every triangle's four children keep its region.
    assert np.array_equal(np.bincount(fine.regions), 16 * np.bincount(g.regions))
