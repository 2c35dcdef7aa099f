"""A solve through Python gives the command-line tool's answer: the CLI's nodes.csv, read
back with NumPy, equals the Python result's arrays and the nodes.csv Python writes."""

import json
import subprocess

import numpy as np
import pytest

import memcontact as mc

COLUMNS = ["x", "y", "u", "phi", "penetration", "pressure", "contact_force", "state"]
FIELDS = COLUMNS[2:]


def read_nodes(path):
    with open(path) as f:
        header = f.readline().strip().split(",")
    assert header == COLUMNS
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return {name: data[:, k] for k, name in enumerate(header)}


def close(a, b, tol=1e-12):
    scale = max(1.0, float(np.max(np.abs(b))) if b.size else 1.0)
    return float(np.max(np.abs(a - b))) <= tol * scale if a.size else True


@pytest.mark.parametrize(
    "example, overrides",
    [
        ("disk.toml", []),
        ("roof.toml", ["mesh.size=0.5"]),
        ("rigid-square.toml", ["mesh.nx=32", "mesh.ny=32"]),
        ("gmsh-disk.toml", []),
        ("disk-step.toml", ["obstacle.sampling=\"mollified\""]),
    ],
)
def test_python_solve_equals_cli_nodes_csv(cli, examples, tmp_path, example, overrides):
    case_path = examples / example
    cli_dir = tmp_path / "cli"
    args = [str(cli), "solve", str(case_path), "-o", str(cli_dir), "-q"]
    for o in overrides:
        args += ["--set", o]
    subprocess.run(args, check=True, capture_output=True)
    cli_nodes = read_nodes(cli_dir / "nodes.csv")

    result = mc.solve(mc.load_case(case_path, overrides))
    assert result.accepted
    v = result.mesh.vertices
    assert np.array_equal(cli_nodes["x"], v[:, 0])
    assert np.array_equal(cli_nodes["y"], v[:, 1])
    for name in FIELDS:
        assert close(getattr(result, name).astype(float), cli_nodes[name]), name

    # The files Python writes hold the same numbers, and the summary the same keys and
    # scalars.
    py_dir = tmp_path / "py"
    written = result.write(py_dir)
    py_nodes = read_nodes(py_dir / "nodes.csv")
    for name in COLUMNS:
        assert close(py_nodes[name], cli_nodes[name]), name
    cli_summary = json.loads((cli_dir / "summary.json").read_text())
    py_summary = json.loads((py_dir / "summary.json").read_text())
    assert set(py_summary) == set(cli_summary)
    assert written["run_id"] == py_summary["run_id"]
    for key in ["vertices", "triangles", "unknowns", "levels", "solver", "foundation",
                "sampling", "status", "contact_vertices", "iterations"]:
        assert py_summary[key] == cli_summary[key], key
    for key in ["energy", "total_load", "total_contact_force", "contact_area", "max_u"]:
        assert py_summary[key] == pytest.approx(cli_summary[key], rel=1e-12, abs=1e-14), key
    assert py_summary["input_hash"] == cli_summary["input_hash"]
    assert (py_dir / "solution.vtu").stat().st_size > 0
    # The same pictures, drawn from the same numbers: the same bytes.
    assert set(py_summary["files"]) == set(cli_summary["files"])
    pictures = [n for n in cli_summary["files"] if n.endswith(".png")]
    assert pictures, "the CLI drew no picture"
    for name in pictures:
        assert py_summary["files"][name] == cli_summary["files"][name], name
    # The in-memory summary has the keys of the file, but for the picture options that
    # only writing sets.
    assert set(result.summary) | {"plot_options"} == set(cli_summary)
