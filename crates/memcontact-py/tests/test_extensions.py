"""Beyond the paper's frame from Python: cases with [boundary] and [lower] in dicts give
the command-line tool's answer; solve(mesh=) takes boundary heights, free edges and a body
below as sections (numbers, expressions, region dicts or arrays); meshes carry
named boundary regions; results carry the body below's fields and pickle with them."""

import pickle
import subprocess

import numpy as np
import pytest

import memcontact as mc

LOWER = ["phi_low", "penetration_low", "pressure_low", "contact_force_low", "state_low"]


def read_nodes(path):
    with open(path) as f:
        header = f.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return {name: data[:, k] for k, name in enumerate(header)}, header


@pytest.mark.parametrize("example", ["geomembrane.toml", "roof-frame.toml", "plinth.toml"])
def test_cases_with_a_body_below_equal_the_cli(cli, examples, tmp_path, example):
    out = tmp_path / "cli"
    overrides = ["mesh.size=0.12"] if example == "plinth.toml" else []
    args = [str(cli), "solve", str(examples / example), "-o", str(out), "-q"]
    for o in overrides:
        args += ["--set", o]
    subprocess.run(args + ["--set", "output.plot=false"], check=True, capture_output=True)
    nodes, header = read_nodes(out / "nodes.csv")
    assert header[-5:] == LOWER
    r = mc.solve(mc.load_case(examples / example, overrides))
    for name in ["u", "phi", "state"] + LOWER:
        a = getattr(r, name)
        assert a is not None, name
        assert np.allclose(a.astype(float), nodes[name], rtol=0, atol=1e-12), name
    assert r.summary["contact_low_vertices"] == int(np.sum(nodes["state_low"] >= 0))
    # Through a dict with the same sections: the same case.
    again = mc.Case(mc.load_case(examples / example, overrides).to_dict())
    assert again == mc.load_case(examples / example, overrides)
    # The fields travel with a pickled result.
    back = pickle.loads(pickle.dumps(r))
    for name in LOWER:
        assert np.array_equal(getattr(back, name), getattr(r, name)), name


def test_solve_on_a_mesh_takes_heights_free_edges_and_a_body_below():
    mesh = mc.rectangle(nx=16, ny=16)
    assert mesh.boundary_names == {1: "bottom", 2: "right", 3: "top", 4: "left"}
    assert mesh.boundary_edges.shape == (64, 2)
    # Linear heights, no contact: P1 reproduces them exactly (the top side free, where
    # g = 0.3 + 0.2x has no normal derivative).
    membrane, obstacle = mc.Membrane(1.0, 0.0), mc.Obstacle(5.0, 10.0)
    r = mc.solve(mesh=mesh, membrane=membrane, obstacle=obstacle,
                 boundary=mc.Boundary(height="0.3 + 0.2*x", free=["top"]))
    x = mesh.vertices[:, 0]
    assert np.allclose(r.u, 0.3 + 0.2 * x, atol=1e-10)
    assert r.phi_low is None and r.state_low is None
    # An array of heights gives the same answer as the expression.
    g = 0.3 + 0.2 * x
    a = mc.solve(mesh=mesh, membrane=membrane, obstacle=obstacle,
                 boundary=mc.Boundary(height=g, free=["top"]))
    assert np.allclose(a.u, r.u, atol=1e-13)
    # A body below, as numbers and as arrays of nodal values.
    kw = dict(membrane=mc.Membrane(1.0, "-20*(1 + x)"), obstacle=mc.Obstacle(0.3, 500.0))
    b = mc.solve(mesh=mesh, lower=mc.Lower(-0.1, 400.0), **kw)
    assert np.any(b.state_low >= 0)
    assert np.all(b.penetration_low >= 0)
    c = mc.solve(mesh=mesh, lower=mc.Lower(np.full(mesh.n_vertices, -0.1), 400.0), **kw)
    assert np.allclose(b.u, c.u, atol=1e-12)
    # The body below's forces balance the load it carries (no obstacle contact, g = 0):
    # Σ X_low = −∫ f minus what the fixed boundary takes, so it is positive and smaller.
    assert 0 < b.summary["total_contact_force_low"] < -b.summary["total_load"]


def test_meshes_from_arrays_name_their_boundary_regions():
    grid = mc.rectangle(nx=2)  # 3 × 3 vertices, row by row: the top row is 6, 7, 8
    v, t = grid.vertices, grid.triangles
    m = mc.Mesh(v, t, boundary_edges=[[6, 7], [7, 8]], boundary_tags=[7, 7],
                boundary_names={7: "lid"})
    assert m.boundary_names == {7: "lid"}
    r = mc.solve(mesh=m, membrane=mc.Membrane(1.0, 1.0), obstacle=mc.Obstacle(1.0, 0.0),
                 boundary=mc.Boundary(height=0.0, free=["lid"]))
    # The lid's middle vertex carries an unknown now, with the centre (its corners stay on
    # the fixed sides); with no force across the free edge it rises above the centre's
    # neighbours on the fixed sides.
    assert r.summary["unknowns"] == 2
    assert r.u[7] > r.u[4] > 0
    with pytest.raises(ValueError, match="not an edge of the mesh's boundary"):
        mc.Mesh(v, t, boundary_edges=[[0, 4]], boundary_tags=[1])
    with pytest.raises(ValueError, match="both boundary_edges"):
        mc.Mesh(v, t, boundary_tags=[1])
    # A refined mesh keeps its regions; pickling keeps them.
    fine = pickle.loads(pickle.dumps(m.refine(1)))
    assert fine.boundary_names == {7: "lid"}
    assert len(fine.boundary_edges) == 4  # each lid edge halved


def test_gmsh_physical_curves_are_boundary_regions(examples):
    # The liner example's mesh: six physical curves on the boundary.
    liner = mc.read_gmsh(examples / "liner-slope.msh")
    assert sorted(liner.boundary_names.values()) == [
        "crest_anchor", "crest_east", "crest_west", "flank_east", "flank_west", "toe"]
    assert liner.boundary_edges.shape == (len(liner.boundary_tags), 2)
    # Every tagged edge is an edge of the boundary, and covers all of it here.
    on_boundary = liner.boundary
    assert np.all(on_boundary[liner.boundary_edges])
    lengths = np.linalg.norm(liner.vertices[liner.boundary_edges[:, 0]]
                             - liner.vertices[liner.boundary_edges[:, 1]], axis=1)
    by_name = {name: lengths[liner.boundary_tags == tag].sum()
               for tag, name in liner.boundary_names.items()}
    assert by_name == pytest.approx({"toe": 40.0, "flank_east": 20.0, "crest_east": 15.0,
                                     "crest_anchor": 10.0, "crest_west": 15.0,
                                     "flank_west": 20.0}, abs=1e-9)
    # Free edges and heights per curve on a Gmsh mesh: as on the generator's mesh.
    data = examples.parent / "crates" / "memcontact" / "tests" / "data"
    # Its physical curve "seam" lies inside the mesh: a warning, not an error.
    with pytest.warns(UserWarning, match=r'curve "seam" \(tag 15\): 16 line elements lie'):
        gmsh = mc.read_gmsh(data / "rect_v41_binary.msh")
    assert gmsh.boundary_names == {11: "bottom", 12: "right", 13: "top", 14: "left",
                                   15: "seam"}
    grid = mc.rectangle(x1=2.0, nx=16, ny=8)
    case = {"membrane": {"tension": 1.0, "load": "2 - 4*x*y"},
            "obstacle": {"shape": 0.05, "stiffness": 200.0},
            "boundary": {"free": ["top"], "height": {"bottom": "0.01*x", "left": "0.02*y",
                                                     "right": "0.02"}}}
    a, b = mc.solve(case, mesh=gmsh), mc.solve(case, mesh=grid)
    key = lambda v: [tuple(p) for p in np.round(v, 9)]
    order_a = sorted(range(gmsh.n_vertices), key=lambda i: key(gmsh.vertices)[i])
    order_b = sorted(range(grid.n_vertices), key=lambda i: key(grid.vertices)[i])
    assert np.allclose(a.u[order_a], b.u[order_b], rtol=0, atol=1e-9)
    with pytest.raises(ValueError, match=r"curves: bottom, right, top, left; regions of "
                                         r"triangles, surfaces: lower, upper"):
        mc.solve(case, mesh=gmsh, boundary={"free": ["crest"]})


@pytest.mark.filterwarnings("ignore:solve_mesh is deprecated:DeprecationWarning")
def test_bad_extension_data_raises_value_errors_naming_the_key():
    mesh = mc.rectangle(nx=8)
    kw = dict(tension=1.0, load=1.0, shape=0.5, stiffness=100.0)
    with pytest.raises(ValueError, match="no boundary region named 'lid'"):
        mc.solve_mesh(mesh, free=["lid"], **kw)
    with pytest.raises(ValueError, match="boundary_height"):
        mc.solve_mesh(mesh, boundary_height=float("nan"), **kw)
    with pytest.raises(ValueError, match="not held"):
        mc.solve_mesh(mesh, free=["left", "right", "top", "bottom"],
                      **{**kw, "stiffness": 0.0})
    with pytest.raises(ValueError, match="overlap"):
        mc.solve_mesh(mesh, tension=1.0, load=1.0, shape=0.1, stiffness="rigid",
                      lower_shape="0.3*sin(pi*x)*sin(pi*y) - 0.05", lower_stiffness="rigid")
    with pytest.raises(TypeError, match="lower_shape and lower_stiffness"):
        mc.solve_mesh(mesh, lower_shape=0.0, **kw)
    case = {
        "mesh": {"generator": "rectangle", "nx": 8},
        "membrane": {"tension": 1.0, "load": 1.0},
        "obstacle": {"shape": 0.5, "stiffness": 100.0},
        "boundary": {"free": ["lid"]},
    }
    with pytest.raises(ValueError, match="boundary.free"):
        mc.Case(case)
    # Mixed bodies: a region table may say "rigid".
    poly = mc.polygon([[0, 0], [2, 0], [2, 1], [0, 1]], size=0.15,
                      regions={"plinth": [[0.8, 0.3], [1.2, 0.3], [1.2, 0.7], [0.8, 0.7]]})
    r = mc.solve_mesh(poly, tension=1.0, load=10.0, shape=0.2,
                      stiffness={"plinth": "rigid", "default": 300.0})
    assert r.summary["rigid_vertices"] > 0
