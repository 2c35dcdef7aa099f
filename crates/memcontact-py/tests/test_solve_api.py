"""solve(case, mesh=) and the sections as dataclasses: every form of the same problem (a
case file, a dict, the dataclasses, a Case, data as expressions, arrays or functions of
(x, y)) gives the same answer; functions are checked (they raise, return the wrong shape
or type, or non-finite values: ValueError or TypeError); solve_mesh is a deprecated alias
of the same solve."""

import numpy as np
import pytest

import memcontact as mc


@pytest.fixture(scope="module")
def disk():
    return mc.disk(radius=1.0, size=0.12)


def test_every_form_gives_the_same_answer(disk, tmp_path):
    sections = dict(membrane=mc.Membrane(tension=1.0, load=8.0),
                    obstacle=mc.Obstacle(shape="1 - 0.3*x", stiffness=100.0,
                                         foundation="lumped"),
                    solver=mc.Solver(tolerance=1e-11))
    a = mc.solve(mesh=disk, **sections)
    as_dict = {k: v.to_dict() for k, v in sections.items()}
    assert as_dict["obstacle"] == {"shape": "1 - 0.3*x", "stiffness": 100.0,
                                   "foundation": "lumped"}
    b = mc.solve(as_dict, mesh=disk)
    c = mc.solve(sections, mesh=disk)  # a dict of dataclasses
    path = tmp_path / "no-mesh.toml"
    path.write_text('[membrane]\ntension = 1.0\nload = 8.0\n[obstacle]\nshape = "1 - 0.3*x"\n'
                    'stiffness = 100.0\nfoundation = "lumped"\n[solver]\ntolerance = 1e-11\n')
    d = mc.solve(path, mesh=disk)
    e = mc.solve(mesh=disk, membrane=mc.Membrane(1.0, lambda x, y: np.full_like(x, 8.0)),
                 obstacle=mc.Obstacle(lambda x, y: 1 - 0.3 * x, 100.0, foundation="lumped"),
                 solver={"tolerance": 1e-11})
    # A Case: its own mesh is replaced by mesh=.
    case = mc.Case({"mesh": {"generator": "rectangle", "nx": 4}, **sections})
    f = mc.solve(case, mesh=disk)
    for other in (b, c, d, f):
        assert np.array_equal(other.u, a.u)
    # Functions: their values at the vertices (φ's samples are the expression's to the
    # last bit or so; f enters as its P1 interpolant, the same function here).
    assert np.max(np.abs(e.phi - a.phi)) <= 1e-15
    assert np.max(np.abs(e.u - a.u)) <= 1e-12 * np.max(np.abs(a.u))
    for other in (b, c, d, e, f):
        assert other.summary["foundation"] == "lumped"
    assert d.summary["case"] == str(path)
    # A function of a constant returning a scalar is broadcast.
    g = mc.solve(mesh=disk, membrane=mc.Membrane(1.0, lambda x, y: 8.0),
                 obstacle=sections["obstacle"], solver=sections["solver"])
    assert np.array_equal(g.u, e.u)
    # Sections override a case's.
    h = mc.solve(as_dict, mesh=disk, obstacle=mc.Obstacle("1 - 0.3*x", 100.0))
    assert h.summary["foundation"] == "consistent"
    # Without mesh=, a case with [mesh]; sections may be dataclasses there too.
    k = mc.solve({"mesh": {"generator": "disk", "size": 0.12}, **sections})
    assert k.mesh.n_vertices == disk.n_vertices


def test_the_dataclasses_mirror_the_case_file():
    assert mc.Boundary(height={"left": 0.1}, free=("top",)).to_dict() == {
        "height": {"left": 0.1}, "free": ["top"]}
    assert mc.Solver().to_dict() == {}
    assert mc.Output(plots=("deflection",), vtu="ascii").to_dict() == {
        "vtu": "ascii", "plots": ["deflection"]}
    assert mc.Lower(-0.1, "rigid").to_dict() == {"shape": -0.1, "stiffness": "rigid"}
    assert mc.Units(length="m").to_dict() == {"length": "m"}
    case = mc.Case({"mesh": {"generator": "rectangle", "nx": 4},
                    "membrane": mc.Membrane(2.0, 1.0), "obstacle": mc.Obstacle(0.5, "rigid"),
                    "lower": mc.Lower(-0.5, 10.0), "output": mc.Output(plot=False)})
    d = case.to_dict()
    assert d["membrane"] == {"tension": 2.0, "load": 1.0}
    assert d["lower"]["stiffness"] == 10.0 and d["output"]["plot"] is False
    # A section of the wrong kind.
    with pytest.raises(TypeError, match="membrane"):
        mc.solve(mesh=mc.rectangle(nx=2), membrane=3.0, obstacle=mc.Obstacle(1.0, 1.0))
    with pytest.raises(TypeError, match="Obstacle"):
        mc.solve(mesh=mc.rectangle(nx=2), membrane=mc.Membrane(1.0, 1.0),
                 obstacle=mc.Lower(1.0, 1.0))
    # Unknown keys in a section dict are the case file's errors.
    with pytest.raises(ValueError, match="membrane"):
        mc.solve(mesh=mc.rectangle(nx=2), membrane={"tension": 1.0, "lode": 1.0},
                 obstacle=mc.Obstacle(1.0, 1.0))


def test_bad_functions_and_arrays_are_named(disk):
    n = disk.n_vertices
    obstacle = mc.Obstacle(1.0, 100.0)

    def solve(load):
        return mc.solve(mesh=disk, membrane=mc.Membrane(1.0, load), obstacle=obstacle)

    def boom(x, y):
        raise RuntimeError("no data here")

    with pytest.raises(ValueError, match=r"membrane.load: the function raised RuntimeError: "
                                         r"no data here"):
        solve(boom)
    with pytest.raises(ValueError, match=r"membrane.load: the function returned shape \(3,\)"):
        solve(lambda x, y: np.ones(3))
    with pytest.raises(ValueError, match=r"shape \(%d, 2\)" % n):
        solve(lambda x, y: np.column_stack([x, y]))
    with pytest.raises(ValueError, match=r"membrane.load: the function's value at vertex \d+ "
                                         r"\(.*\) is nan"):
        solve(lambda x, y: np.where(x > 0.5, np.nan, 1.0))
    with pytest.raises(ValueError, match="inf"):
        with np.errstate(divide="ignore"):
            solve(lambda x, y: 1.0 / (x - x))
    with pytest.raises(TypeError, match="dtype complex128"):
        solve(lambda x, y: x + 1j * y)
    with pytest.raises(TypeError, match="real numbers"):
        solve(lambda x, y: np.array(["a"] * len(x)))
    with pytest.raises(TypeError, match="dtype bool"):
        solve(lambda x, y: x > 0)
    with pytest.raises(TypeError, match="object"):
        solve(lambda x, y: {"a": 1})
    # The coordinates are read-only: a function cannot move the mesh.
    with pytest.raises(ValueError, match="read-only"):
        solve(lambda x, y: x.__setitem__(0, 5.0))
    assert disk.vertices[0, 0] != 5.0
    # Arrays: one real number per vertex.
    with pytest.raises(ValueError, match=r"membrane.load: nodal values must have shape"):
        solve(np.ones(n + 1))
    with pytest.raises(TypeError, match="real numbers"):
        solve(np.array(["1"] * n))
    with pytest.raises(ValueError, match=r"load\[3\]"):
        bad = np.ones(n)
        bad[3] = np.inf
        solve(bad)
    # A function needs the mesh.
    with pytest.raises(TypeError, match="needs the mesh"):
        mc.solve({"mesh": {"generator": "disk", "size": 0.5},
                  "membrane": {"tension": 1.0, "load": lambda x, y: x},
                  "obstacle": {"shape": 1.0, "stiffness": 1.0}})
    with pytest.raises(TypeError, match="mesh"):
        mc.solve({"membrane": {"tension": 1.0, "load": 1.0}}, mesh="disk")
    with pytest.raises(TypeError):
        mc.solve()


def test_functions_of_a_body_below_and_heights(disk):
    r = mc.solve(mesh=disk, membrane=mc.Membrane(1.0, -20.0),
                 obstacle=mc.Obstacle(0.3, 500.0),
                 lower=mc.Lower(shape=lambda x, y: -0.1 + 0.05 * x, stiffness=400.0),
                 boundary=mc.Boundary(height=lambda x, y: 0.02 * y))
    x, y = disk.vertices.T
    assert np.array_equal(r.phi_low, -0.1 + 0.05 * x)
    on = disk.boundary
    assert np.allclose(r.u[on], 0.02 * y[on], rtol=0, atol=1e-15)
    assert (r.state_low >= 0).sum() > 10


def test_solve_mesh_is_a_deprecated_alias(disk):
    kw = dict(tension=1.0, load=8.0, shape="1 - 0.3*x", stiffness=100.0)
    with pytest.warns(DeprecationWarning, match="solve_mesh is deprecated"):
        old = mc.solve_mesh(disk, **kw)
    new = mc.solve(mesh=disk, membrane=mc.Membrane(1.0, 8.0),
                   obstacle=mc.Obstacle("1 - 0.3*x", 100.0))
    assert np.array_equal(old.u, new.u)
    # Its errors still name its arguments.
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="^tension"):
        mc.solve_mesh(disk, **{**kw, "tension": -1.0})
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="^load: the function"):
        mc.solve_mesh(disk, **{**kw, "load": lambda x, y: np.ones(2)})
