"""The notebook surface, each part against an independent reading: pictures (matplotlib
Axes, the renderer's PNG bytes against the file `write` draws), HTML summaries, tables
(pandas frames against the CSV files read by pandas), read-only views (every array
property), meshes in and out (meshio and pyvista against nodes.csv read with the csv
module; a Gmsh file read by meshio solved as the command-line tool solves the file)."""

import csv
import gc
import json
import subprocess
import sys
import textwrap

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import meshio  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

import memcontact as mc  # noqa: E402

POINT = ["u", "phi", "penetration", "pressure", "contact_force", "state"]
LOWER = ["phi_low", "penetration_low", "pressure_low", "contact_force_low", "state_low"]


def read_nodes_csv(path):
    """nodes.csv as columns of floats, read with the csv module."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    return header, {name: np.array([float(r[k]) for r in body]) for k, name in enumerate(header)}


def assert_frame_equals_csv(frame, path):
    """A DataFrame holds the CSV file's columns, in order, with its values (read by
    pandas); the wall-clock columns are left out of the values."""
    theirs = pd.read_csv(path)
    assert list(frame.columns) == list(theirs.columns)
    assert len(frame) == len(theirs)
    for column in theirs.columns:
        if column == "seconds" or column.endswith("_s"):
            continue
        a, b = frame[column], theirs[column]
        if not pd.api.types.is_numeric_dtype(b):
            assert list(a) == list(b), column
        else:
            assert np.allclose(a.to_numpy(float), b.to_numpy(float), rtol=1e-10, atol=1e-14,
                               equal_nan=True), column
            if b.dtype.kind == "i":
                assert a.dtype.kind == "i", column


@pytest.fixture(scope="module")
def liner(cli, examples, tmp_path_factory):
    """The liner example (a Gmsh mesh, a body below, heights and free edges): the
    command-line tool's result set and Python's result."""
    out = tmp_path_factory.mktemp("liner") / "cli"
    subprocess.run([str(cli), "solve", str(examples / "liner-slope.toml"), "-o", str(out),
                    "-q"], check=True, capture_output=True)
    return out, mc.solve(examples / "liner-slope.toml")


# ---------------------------------------------------------------------------------------
# Read-only views.


def test_every_array_property_is_a_cached_read_only_view(liner):
    _, r = liner
    mesh = r.mesh
    assert mesh is r.mesh
    arrays = [(r, n) for n in POINT + LOWER] + [
        (mesh, n) for n in ["vertices", "triangles", "regions", "boundary", "boundary_edges",
                            "boundary_tags"]]
    for owner, name in arrays:
        a = getattr(owner, name)
        assert a is getattr(owner, name), name  # made once
        assert not a.flags.writeable, name
        with pytest.raises(ValueError):
            a[...] = 0
        with pytest.raises(ValueError):
            a.setflags(write=True)
    # The float fields and the coordinates are views of the Rust data: no copy at all.
    for a in [r.u, r.phi, r.pressure_low, mesh.vertices]:
        assert a.base is not None and not a.flags.owndata
    # Views outlive their result.
    u, x = r.u, mesh.vertices
    expect_u, expect_x = u.copy(), x.copy()
    del owner, a
    gc.collect()
    assert np.array_equal(u, expect_u) and np.array_equal(x, expect_x)
    assert r.u.dtype == np.float64 and r.state.dtype == np.int8
    assert mesh.triangles.dtype == np.int64 and mesh.vertices.shape == (mesh.n_vertices, 2)


def test_views_of_a_result_without_a_body_below_and_of_an_adaptive_loop():
    mesh = mc.rectangle(nx=8)
    r = mc.solve(mesh=mesh, membrane=mc.Membrane(1.0, 10.0), obstacle=mc.Obstacle(0.1, 50.0))
    for name in LOWER + ["estimator"]:
        assert getattr(r, name) is None, name
    a = mc.adapt({"membrane": {"tension": 1.0, "load": 10.0},
                  "obstacle": {"shape": 0.1, "stiffness": 50.0},
                  "adapt": {"max_vertices": 200}}, mesh=mesh)
    assert a.estimator is a.result.estimator is a.estimator
    assert not a.estimator.flags.writeable
    assert a.estimator.shape == (a.mesh.n_triangles,)
    assert np.sqrt(np.sum(a.estimator ** 2)) == pytest.approx(a.rows[-1]["estimator"],
                                                              rel=1e-12)
    # A pickled result keeps its estimator; its arrays are read-only too.
    import pickle

    back = pickle.loads(pickle.dumps(a.result))
    assert np.array_equal(back.estimator, a.estimator) and not back.u.flags.writeable


# ---------------------------------------------------------------------------------------
# Meshes in and out.


def test_to_meshio_and_to_pyvista_equal_nodes_csv(liner, tmp_path):
    out, r = liner
    header, nodes = read_nodes_csv(out / "nodes.csv")
    assert header == ["x", "y"] + POINT + LOWER
    m = r.to_meshio()
    assert np.array_equal(m.points[:, 0], nodes["x"]) and np.array_equal(m.points[:, 1],
                                                                         nodes["y"])
    assert np.all(m.points[:, 2] == 0)
    assert list(m.point_data) == POINT + LOWER
    for name in POINT + LOWER:
        scale = max(1.0, np.max(np.abs(nodes[name])))
        assert np.max(np.abs(m.point_data[name] - nodes[name])) <= 1e-12 * scale, name
    assert m.cells[0].type == "triangle"
    # The cell fields: as solution.vtu holds them (read by meshio).
    vtu = meshio.read(out / "solution.vtu")
    assert np.array_equal(m.cells[0].data, vtu.cells[0].data)
    assert np.array_equal(m.cell_data["region"][0], vtu.cell_data["region"][0])
    # It writes and reads back (an independent mesh: its arrays are its own).
    m.point_data["u"][0] += 1.0
    assert r.u[0] == nodes["u"][0]
    meshio.write(tmp_path / "m.vtu", m)
    assert np.array_equal(meshio.read(tmp_path / "m.vtu").point_data["phi_low"], r.phi_low)

    pv = pytest.importorskip("pyvista")
    g = r.to_pyvista()
    assert isinstance(g, pv.UnstructuredGrid)
    assert g.n_points == len(nodes["x"]) and g.n_cells == r.mesh.n_triangles
    assert np.array_equal(g.points[:, :2], np.column_stack([nodes["x"], nodes["y"]]))
    for name in POINT + LOWER:
        scale = max(1.0, np.max(np.abs(nodes[name])))
        assert np.max(np.abs(g.point_data[name] - nodes[name])) <= 1e-12 * scale, name
    assert np.array_equal(g.cell_data["region"], r.mesh.regions)


def test_the_estimator_is_a_cell_field():
    a = mc.adapt({"membrane": {"tension": 1.0, "load": 10.0},
                  "obstacle": {"shape": 0.1, "stiffness": 50.0},
                  "adapt": {"max_vertices": 150}}, mesh=mc.rectangle(nx=6))
    m = a.result.to_meshio()
    assert np.array_equal(m.cell_data["estimator"][0], a.estimator)
    assert len(m.cells[0].data) == a.mesh.n_triangles


def test_a_gmsh_file_read_by_meshio_solves_as_the_command_line_tool_solves_it(
        liner, examples, tmp_path):
    out, _ = liner
    m = mc.Mesh.from_meshio(meshio.read(examples / "liner-slope.msh"))
    gmsh = mc.read_gmsh(examples / "liner-slope.msh")
    assert m.region_names == gmsh.region_names == {1: "cover_sand", 2: "cover_gravel"}
    assert m.boundary_names == gmsh.boundary_names
    assert np.array_equal(m.vertices, gmsh.vertices)
    assert np.array_equal(m.triangles, gmsh.triangles)
    assert np.array_equal(m.regions, gmsh.regions)
    # The case file without its [mesh]: a file, and the same as a dict.
    text = (examples / "liner-slope.toml").read_text()
    without = text.replace('[mesh]\nfile = "liner-slope.msh"\n', "")
    assert "[mesh]" not in without
    case_file = tmp_path / "liner-no-mesh.toml"
    case_file.write_text(without)
    r = mc.solve(case_file, mesh=m)
    header, nodes = read_nodes_csv(out / "nodes.csv")
    v = r.mesh.vertices
    assert np.array_equal(v[:, 0], nodes["x"]) and np.array_equal(v[:, 1], nodes["y"])
    for name in POINT + LOWER:
        scale = max(1.0, np.max(np.abs(nodes[name])))
        assert np.max(np.abs(getattr(r, name) - nodes[name])) <= 1e-12 * scale, name
    summary = json.loads((out / "summary.json").read_text())
    assert r.summary["contact_area_low"] == pytest.approx(summary["contact_area_low"],
                                                          rel=1e-12)
    # A file with [mesh] and mesh= is refused.
    with pytest.raises(ValueError, match=r"\[mesh\]"):
        mc.solve(examples / "liner-slope.toml", mesh=m)


def test_from_meshio_of_a_result_file_and_bad_meshes(liner):
    out, r = liner
    # solution.vtu's "region" cell data become the regions.
    m = mc.Mesh.from_meshio(meshio.read(out / "solution.vtu"))
    assert np.array_equal(m.regions, r.mesh.regions)
    assert np.array_equal(m.vertices, r.mesh.vertices)
    points = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [5.0, 5.0]])
    tri = np.array([[0, 1, 2]])
    # An unused point is dropped; the others keep their order.
    one = mc.Mesh.from_meshio(meshio.Mesh(points, [("triangle", tri)]))
    assert one.n_vertices == 3 and np.array_equal(one.vertices, points[:3])
    with pytest.raises(ValueError, match="plane"):
        mc.Mesh.from_meshio(meshio.Mesh(np.column_stack([points, [0, 0, 1, 0]]),
                                        [("triangle", tri)]))
    with pytest.raises(ValueError, match="quad"):
        mc.Mesh.from_meshio(meshio.Mesh(points, [("quad", np.array([[0, 1, 3, 2]]))]))
    with pytest.raises(ValueError, match="no triangles"):
        mc.Mesh.from_meshio(meshio.Mesh(points, [("vertex", np.array([[0]]))]))
    with pytest.raises(ValueError, match="beyond"):
        mc.Mesh.from_meshio(meshio.Mesh(points, [("triangle", np.array([[0, 1, 9]]))]))
    with pytest.raises(ValueError, match="repeats a vertex"):
        mc.Mesh.from_meshio(meshio.Mesh(points, [("triangle", np.array([[0, 1, 1]]))]))
    with pytest.raises(TypeError, match="meshio.Mesh"):
        mc.Mesh.from_meshio({"points": points})
    with pytest.raises(ValueError, match="no cell data 'medit:ref'"):
        mc.Mesh.from_meshio(meshio.Mesh(points, [("triangle", tri)]), regions="medit:ref")
    # A line inside the mesh is skipped with a warning (as the Gmsh reader does).
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    two = np.array([[0, 1, 2], [0, 2, 3]])
    lines = np.array([[0, 1], [0, 2]])
    with pytest.warns(UserWarning, match="do not lie on the boundary"):
        b = mc.Mesh.from_meshio(meshio.Mesh(
            square, [("triangle", two), ("line", lines)],
            cell_data={"gmsh:physical": [np.array([1, 1]), np.array([7, 8])]},
            field_data={"floor": np.array([7, 1]), "seam": np.array([8, 1]),
                        "plate": np.array([1, 2])}))
    assert b.boundary_names[7] == "floor" and b.region_names == {1: "plate"}
    assert np.array_equal(b.boundary_edges, [[0, 1]]) and list(b.boundary_tags) == [7]


# ---------------------------------------------------------------------------------------
# Pictures.


def test_plot_draws_fields_and_each_bodys_contact(liner):
    _, r = liner
    fig, ax = plt.subplots()
    assert r.plot(ax=ax) is ax
    assert len(fig.axes) == 2  # the map and its colour bar
    drawn = ax.collections[0].get_array()
    assert np.allclose(drawn, r.u)
    labels = {t.get_text(): h for t, h in zip(ax.get_legend().get_texts(),
                                              ax.get_legend().legend_handles)}
    assert set(labels) == {"contact with the obstacle", "contact with the body below"}
    colours = {k: matplotlib.colors.to_hex(h.get_color()) for k, h in labels.items()}
    assert colours["contact with the obstacle"] != colours["contact with the body below"]
    plt.close(fig)
    # Each body's gap, named separately.
    for field, expect, name in [("gap", r.phi - r.u, "obstacle"),
                                ("gap_low", r.u - r.phi_low, "body below")]:
        ax = r.plot(field)
        assert np.allclose(ax.collections[0].get_array(), expect)
        assert name in ax.figure.axes[1].get_ylabel()
        plt.close(ax.figure)
    ax = r.plot("pressure_low", kind="tricontourf", levels=8, cmap="magma", contact=False)
    assert ax.get_legend() is None and ax.figure.axes[1].get_ylabel().endswith("body below")
    plt.close(ax.figure)
    ax = r.plot(np.arange(r.mesh.n_triangles, dtype=float))  # one value per triangle
    plt.close(ax.figure)
    with pytest.raises(ValueError, match="unknown"):
        r.plot("nothing")
    with pytest.raises(ValueError, match="per vertex"):
        r.plot(np.ones(5))
    with pytest.raises(TypeError):
        r.plot(np.array(["a"] * r.mesh.n_vertices))
    with pytest.raises(ValueError, match="kind"):
        r.plot(kind="surface")
    ax = r.mesh.plot()
    names = {t.get_text() for t in ax.get_legend().get_texts()}
    assert {"cover_sand", "cover_gravel", "toe", "crest_anchor"} <= names
    plt.close(ax.figure)


def test_repr_png_is_the_deflection_picture_write_draws(liner, tmp_path):
    _, r = liner
    png = r._repr_png_()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    r.write(tmp_path / "out")
    assert png == (tmp_path / "out" / "deflection.png").read_bytes()


def test_repr_html_of_the_four_result_types(liner, examples):
    _, r = liner
    html = r._repr_html_()
    assert "converged" in html and "body below" in html and "KKT" in html
    assert f"{r.iterations}" in html
    s = mc.sweep(mc.load_case(examples / "roof.toml",
                              ["mesh.size=0.5", 'sweep.parameter="load_factor"',
                               "sweep.values=[0.5, 1.0]"]))
    html = s._repr_html_()
    assert html.count("<tr>") >= 1 + 2 and "load_factor" in html
    assert all(f"<th>{c}</th>" in html for c in s.columns)
    study = mc.convergence(examples / "disk.toml", 1)
    assert all(f"<th>{c}</th>" in study._repr_html_() for c in study.columns)
    a = mc.adapt({"membrane": {"tension": 1.0, "load": 10.0},
                  "obstacle": {"shape": 0.1, "stiffness": 50.0},
                  "adapt": {"max_vertices": 150}}, mesh=mc.rectangle(nx=6))
    assert "max_vertices" in a._repr_html_() and "estimator" in a._repr_html_()


def test_optional_packages_are_imported_only_when_used(examples):
    script = textwrap.dedent(f"""
        import sys
        import memcontact as mc
        r = mc.solve({str(examples / 'disk.toml')!r})
        r._repr_html_(); r._repr_png_()
        heavy = [m for m in ("matplotlib", "pandas", "scipy", "meshio", "pyvista")
                 if m in sys.modules]
        assert not heavy, heavy
        # Missing packages: a clear message.
        for name in ("matplotlib", "matplotlib.pyplot", "pandas", "scipy", "scipy.sparse",
                     "meshio", "pyvista"):
            sys.modules[name] = None
        for call, package in [(r.plot, "matplotlib"), (r.mesh.plot, "matplotlib"),
                              (r.matrices, "scipy"), (r.to_meshio, "meshio"),
                              (r.to_pyvista, "pyvista")]:
            try:
                call()
            except ImportError as e:
                assert f"pip install {{package}}" in str(e), str(e)
            else:
                raise AssertionError(call)
        print("ok")
    """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"


# ---------------------------------------------------------------------------------------
# Tables.


def test_to_pandas_of_a_sweep_has_sweep_csv(cli, examples, tmp_path):
    overrides = ["mesh.size=0.5", 'sweep.parameter="load_factor"', "sweep.values=[0.3, 1.7]"]
    args = [str(cli), "solve", str(examples / "roof.toml"), "-o", str(tmp_path), "-q"]
    for o in overrides:
        args += ["--set", o]
    subprocess.run(args, check=True, capture_output=True)
    s = mc.sweep(mc.load_case(examples / "roof.toml", overrides))
    frame = s.to_pandas()
    assert_frame_equals_csv(frame, tmp_path / "sweep.csv")
    assert frame["name"].tolist() == ["step-000", "step-001"]


def test_to_pandas_of_studies_has_their_csv_files(cli, examples, tmp_path):
    for args, files in [(["--compare", "foundation"],
                         ["convergence-consistent.csv", "convergence-lumped.csv"]),
                        (["--h-sweep", "--h-values", "100,10000"], ["h_sweep.csv"])]:
        out = tmp_path / args[0].strip("-")
        levels = "0" if "--h-sweep" in args else "1"
        subprocess.run([str(cli), "convergence", str(examples / "disk.toml"), "--levels",
                        levels, "-q", "-o", str(out)] + args, check=True, capture_output=True)
        if "--h-sweep" in args:
            study = mc.convergence(examples / "disk.toml", 0, h_sweep=True,
                                   h_values=[100.0, 10000.0])
        else:
            study = mc.convergence(examples / "disk.toml", 1, compare="foundation")
        for name in files:
            frame = study.to_pandas(name if len(files) > 1 else None)
            assert_frame_equals_csv(frame, out / name)
        if len(files) > 1:
            with pytest.raises(ValueError, match="unknown"):
                study.to_pandas("convergence.csv")


def test_to_pandas_of_an_adaptive_loop_has_adapt_csv(cli, examples, tmp_path):
    case = examples / "roof-corner.toml"
    subprocess.run([str(cli), "solve", str(case), "-o", str(tmp_path), "-q", "--set",
                    "adapt.max_vertices=400"], check=True, capture_output=True)
    a = mc.adapt(mc.load_case(case, {"adapt.max_vertices": 400}))
    assert_frame_equals_csv(a.to_pandas(), tmp_path / "adapt.csv")
