"""Sweeps and load cases through Python give the command-line tool's answers and files:
sweep.csv and every step's nodes.csv, read back independently with NumPy, equal the
Python results; `Sweep.write` writes the same set; `solve` refuses a case with steps."""

import json
import pickle
import subprocess

import numpy as np
import pytest

import memcontact as mc

from test_cli_equality import COLUMNS, FIELDS, close, read_nodes

HEADER = (
    "step,name,value,max_deflection,contact_area,liftoff_area,total_contact_force,"
    "max_pressure,energy,iterations,kkt_residual,seconds"
).split(",")

SWEEP = ["mesh.size=0.5", 'sweep.parameter="load_factor"', "sweep.values=[0.3, 1.0, 1.7]"]

LOAD_CASES = """
[[load_case]]
name = "dead"

[[load_case]]
name = "uniform x2"
load = 1.5
load_factor = 2.0

[[load_case]]
name = "soft"
stiffness = { block = 300.0, default = 120.0 }
"""


def read_sweep_csv(path):
    with open(path) as f:
        header = f.readline().strip().split(",")
        rows = [line.strip().split(",") for line in f if line.strip()]
    return header, rows


def cli_solve(cli, case_path, out, overrides=()):
    args = [str(cli), "solve", str(case_path), "-o", str(out), "-q"]
    for o in overrides:
        args += ["--set", o]
    subprocess.run(args, check=True, capture_output=True)


@pytest.fixture
def load_case_file(examples, tmp_path):
    text = (examples / "roof.toml").read_text().replace("size = 0.25", "size = 0.5")
    path = tmp_path / "roof-cases.toml"
    path.write_text(text + LOAD_CASES)
    return path


def check_against_cli(s, cli_dir):
    """The sweep `s` equals the CLI's result set in `cli_dir`."""
    header, rows = read_sweep_csv(cli_dir / "sweep.csv")
    assert header == HEADER == s.columns
    assert len(rows) == len(s) == len(s.rows)
    for row, mine, result in zip(rows, s.rows, s.results):
        assert list(mine) == HEADER
        assert int(row[0]) == mine["step"]
        assert row[1] == mine["name"]
        for k, name in enumerate(HEADER[2:], start=2):
            if name == "seconds":
                continue
            assert float(row[k]) == pytest.approx(mine[name], rel=1e-12, abs=1e-14), name
        nodes = read_nodes(cli_dir / mine["name"] / "nodes.csv")
        for name in FIELDS:
            assert close(getattr(result, name).astype(float), nodes[name]), (mine["name"], name)
        # The row's scalars are the step's result's.
        assert mine["max_deflection"] == np.max(np.abs(result.u))
        assert mine["iterations"] == result.iterations
        summary = json.loads((cli_dir / mine["name"] / "summary.json").read_text())
        assert result.summary["case"] == summary["case"]


def check_written_like_cli(s, py_dir, cli_dir):
    """`Sweep.write` wrote the CLI's files: the same step directories, sweep.csv rows and
    the same pictures byte for byte."""
    assert sorted(p.name for p in py_dir.iterdir()) == sorted(p.name for p in cli_dir.iterdir())
    h_py, rows_py = read_sweep_csv(py_dir / "sweep.csv")
    h_cli, rows_cli = read_sweep_csv(cli_dir / "sweep.csv")
    assert h_py == h_cli
    assert [r[:2] for r in rows_py] == [r[:2] for r in rows_cli]
    for name in s.names:
        py_nodes = read_nodes(py_dir / name / "nodes.csv")
        cli_nodes = read_nodes(cli_dir / name / "nodes.csv")
        for column in COLUMNS:
            assert close(py_nodes[column], cli_nodes[column]), (name, column)
        py_summary = json.loads((py_dir / name / "summary.json").read_text())
        cli_summary = json.loads((cli_dir / name / "summary.json").read_text())
        assert set(py_summary) == set(cli_summary)
        assert py_summary["case"] == cli_summary["case"]
        assert py_summary["plot_options"] == cli_summary["plot_options"]
        for f, record in cli_summary["files"].items():
            if f.endswith(".png"):
                assert py_summary["files"][f] == record, (name, f)


def test_sweep_through_python_equals_the_cli(cli, examples, tmp_path):
    roof = examples / "roof.toml"
    cli_dir = tmp_path / "cli"
    cli_solve(cli, roof, cli_dir, SWEEP)
    case = mc.load_case(roof, SWEEP)
    s = mc.sweep(case)
    assert s.accepted and s.message is None
    assert s.parameter == "load_factor"
    assert s.names == ["step-000", "step-001", "step-002"]
    assert s.values == [0.3, 1.0, 1.7]
    assert [r.step for r in s.results] == [0, 1, 2]
    check_against_cli(s, cli_dir)
    py_dir = tmp_path / "py"
    summaries = s.write(py_dir)
    assert [x["case"] for x in summaries] == [f"{roof} [{n}]" for n in s.names]
    check_written_like_cli(s, py_dir, cli_dir)
    # Load factor up, deflection up.
    deflections = [r["max_deflection"] for r in s.rows]
    assert deflections == sorted(deflections) and len(set(deflections)) == 3


def test_load_cases_through_python_equal_the_cli(cli, load_case_file, tmp_path):
    cli_dir = tmp_path / "cli"
    cli_solve(cli, load_case_file, cli_dir)
    s = mc.sweep(mc.load_case(load_case_file))
    assert s.parameter == "load_case"
    assert s.names == ["dead", "uniform x2", "soft"]
    assert s.values == [1.0, 2.0, 1.0]
    check_against_cli(s, cli_dir)
    py_dir = tmp_path / "py"
    s.write(py_dir)
    check_written_like_cli(s, py_dir, cli_dir)


def test_a_pickled_step_writes_its_own_files(cli, load_case_file, tmp_path):
    s = mc.sweep(mc.load_case(load_case_file))
    step = pickle.loads(pickle.dumps(s[1]))
    assert step.step == 1
    np.testing.assert_array_equal(step.u, s[1].u)
    step.write(tmp_path / "again")
    s[1].write(tmp_path / "first")
    a = read_nodes(tmp_path / "again" / "nodes.csv")
    b = read_nodes(tmp_path / "first" / "nodes.csv")
    for column in COLUMNS:
        assert close(a[column], b[column]), column
    # The rebuilt step has the load case's data (twice a uniform 1.5), not the base case's.
    base = mc.solve(mc.Case(dict(mc.load_case(load_case_file).to_dict(), load_case=[])))
    assert not close(a["u"], base.u)


def test_warm_and_cold_sweeps_agree(examples):
    case = mc.load_case(examples / "roof.toml", SWEEP)
    warm = mc.sweep(case)
    cold = mc.sweep(case, warm=False)
    for w, c in zip(warm.results, cold.results):
        assert close(w.u, c.u, 1e-8)


def test_solve_refuses_a_case_with_steps(examples, load_case_file):
    with pytest.raises(ValueError, match=r"\[sweep\].*memcontact.sweep"):
        mc.solve(mc.load_case(examples / "roof.toml", SWEEP))
    with pytest.raises(ValueError, match=r"\[\[load_case\]\].*memcontact.sweep"):
        mc.solve(load_case_file)
    with pytest.raises(ValueError, match="memcontact.solve"):
        mc.sweep(examples / "disk.toml")


def test_a_step_that_does_not_converge_ends_the_sweep(examples):
    case = mc.load_case(
        examples / "roof.toml",
        SWEEP + ['solver.method="active-set"', "solver.max_iterations=2"],
    )
    with pytest.raises(mc.SolverError) as e:
        mc.sweep(case)
    assert e.value.sweep is not None
    assert not e.value.sweep.accepted
    assert e.value.result.status == "iteration_limit"
    s = mc.sweep(case, check=False)
    assert not s.accepted and s.message
    assert 1 <= len(s) < len(s.names)
    assert all(r.accepted for r in s.results[:-1])
    assert not s.results[-1].accepted
