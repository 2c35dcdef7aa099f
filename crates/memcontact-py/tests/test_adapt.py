"""memcontact.adapt: the adaptive loop from Python, against the command-line tool's run of
the same case, an independent reader of its files (meshio), and the data given per vertex
(interpolated onto new vertices, which for a linear function is exact)."""

import csv
import pickle
import subprocess

import meshio
import numpy as np
import pytest

import memcontact as mc


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_adapt_equals_the_command_line_run(cli, examples, tmp_path):
    case = examples / "roof-corner.toml"
    out = tmp_path / "cli"
    subprocess.run([str(cli), "solve", str(case), "-o", str(out), "-q"], check=True)
    a = mc.adapt(case)
    rows = read_csv(out / "adapt.csv")
    assert a.columns == list(rows[0].keys())
    assert len(a) == len(rows) == len(a.rows)
    for mine, theirs in zip(a.rows, rows):
        for column in a.columns:
            if column == "seconds":
                continue
            assert mine[column] == pytest.approx(float(theirs[column]), rel=1e-12, abs=0), column
    assert a.stop == "max_vertices"
    assert a.mesh.n_vertices == int(rows[-1]["vertices"]) == len(a.result.u)
    assert a.interpolated == []


def test_write_gives_the_final_mesh_and_its_estimator(tmp_path):
    a = mc.adapt(str(mc_example("roof-corner.toml")), check=True)
    summary = a.write(tmp_path / "out")
    assert summary["adapt_steps"] == len(a.rows)
    assert summary["adapt_stop"] == "max_vertices"
    m = meshio.read(tmp_path / "out" / "solution.vtu")
    assert len(m.points) == a.rows[-1]["vertices"]
    eta = m.cell_data["estimator"][0]
    assert len(eta) == a.mesh.n_triangles == len(a.estimator)
    # The total is (Σ η_T²)^½.
    assert np.sqrt(np.sum(eta**2)) == pytest.approx(a.rows[-1]["estimator"], rel=1e-12)
    np.testing.assert_allclose(m.point_data["u"], a.result.u, rtol=0, atol=1e-12)
    names = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert "adapt.csv" in names and "mesh.png" in names
    with open(tmp_path / "out" / "mesh.png", "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"


def mc_example(name):
    from conftest import EXAMPLES

    return EXAMPLES / name


DATA = {
    "membrane": {"tension": 1.0},
    "obstacle": {"shape": 0.05, "stiffness": 200.0},
    "solver": {"tolerance": 1e-11},
    "adapt": {"steps": 6},
}


def test_data_given_per_vertex_are_interpolated_onto_new_vertices():
    mesh = mc.rectangle(0.0, 0.0, 1.0, 1.0, 8, 8)
    x = mesh.vertices[:, 0]
    given = {**DATA, "membrane": {"tension": 1.0, "load": 1.0 + 2.0 * x}}
    by_array = mc.adapt(given, mesh=mesh)
    by_expression = mc.adapt({**DATA, "membrane": {"tension": 1.0, "load": "1 + 2*x"}}, mesh=mesh)
    assert by_array.interpolated == ["membrane.load"]
    assert by_array.totals["adapt_interpolated"] == ["membrane.load"]
    assert by_expression.interpolated == []
    # A linear load: its P1 interpolant is itself, so both loops refine alike.
    assert [r["vertices"] for r in by_array.rows] == [r["vertices"] for r in by_expression.rows]
    np.testing.assert_allclose(by_array.result.u, by_expression.result.u, rtol=0, atol=1e-12)
    assert by_array.mesh.n_vertices > mesh.n_vertices
    # The final result pickles and writes again on the final mesh with its data there.
    again = pickle.loads(pickle.dumps(by_array.result))
    np.testing.assert_array_equal(again.u, by_array.result.u)


def test_the_result_rebuilt_after_pickling_writes(tmp_path):
    mesh = mc.rectangle(0.0, 0.0, 1.0, 1.0, 8, 8)
    x = mesh.vertices[:, 0]
    a = mc.adapt({**DATA, "membrane": {"tension": 1.0, "load": 1.0 + 2.0 * x}}, mesh=mesh)
    again = pickle.loads(pickle.dumps(a.result))
    again.write(tmp_path / "again")
    m = meshio.read(tmp_path / "again" / "solution.vtu")
    assert len(m.points) == a.mesh.n_vertices
    np.testing.assert_allclose(m.point_data["u"], a.result.u, rtol=0, atol=1e-12)


def test_bad_input_and_other_runs_are_refused():
    case = mc.load_case(mc_example("roof-corner.toml"))
    with pytest.raises(ValueError, match=r"memcontact\.adapt"):
        mc.solve(case)
    with pytest.raises(ValueError, match="adapt.theta"):
        mc.adapt(mc.load_case(mc_example("roof-corner.toml"), {"adapt.theta": 1.5}))
    with pytest.raises(ValueError, match="adapt.max_vertices"):
        mc.adapt(mc.load_case(mc_example("roof-corner.toml"), {"adapt.max_vertices": 50}))
    with pytest.raises(ValueError, match=r"\[adapt\]"):
        mc.adapt(mc.load_case(mc_example("roof.toml")))
    # A case file with [mesh] and mesh= is refused; a Case's own mesh is replaced.
    start = mc.rectangle(0.0, 0.0, 12.0, 8.0, 6, 4)
    with pytest.raises(ValueError, match=r"\[mesh\]"):
        mc.adapt(mc_example("roof-corner.toml"), mesh=start)
    small = mc.load_case(mc_example("roof-corner.toml"), {"adapt.max_vertices": 120})
    a = mc.adapt(small, mesh=start)
    assert a.rows[0]["vertices"] == start.n_vertices == 35
    assert a.case.to_dict()["adapt"]["max_vertices"] == 120
