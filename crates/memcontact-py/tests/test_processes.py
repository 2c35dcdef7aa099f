"""Processes, signals and studies from Python: a default ProcessPoolExecutor after a solve in
the parent (Linux forks the workers) gives a loop's results; Ctrl-C stops a long solve
within 2 s with KeyboardInterrupt; memcontact.convergence is the command-line tool's
study, column for column."""

import csv
import json
import math
import signal
import subprocess
import sys
import textwrap
import time

import pytest

import memcontact as mc

POOL_SCRIPT = textwrap.dedent(
    """
    import concurrent.futures, json, multiprocessing, sys
    import memcontact as mc
    cases = [mc.load_case(sys.argv[1], {"membrane.load": f}) for f in (2.0, 4.0, 6.0)]
    # A solve in the parent first: its worker threads exist in the parent only.
    loop = [mc.solve(c).summary["total_contact_force"] for c in cases]
    with concurrent.futures.ProcessPoolExecutor(2) as pool:
        pooled = [r.summary["total_contact_force"] for r in mc.solve_many(cases, executor=pool)]
    print(json.dumps({"loop": loop, "pooled": pooled,
                      "method": multiprocessing.get_start_method()}))
    """
)


def test_default_process_pool_after_a_solve_in_the_parent(examples, tmp_path):
    script = tmp_path / "pool.py"
    script.write_text(POOL_SCRIPT)
    # Before the worker pool was the process's own, this hung for ever: bounded here.
    done = subprocess.run(
        [sys.executable, str(script), str(examples / "roof.toml")],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout.strip().splitlines()[-1])
    # Linux's default start method forks the workers.
    if sys.platform.startswith("linux"):
        assert out["method"] == "fork"
    assert out["pooled"] == out["loop"]


CTRL_C_SCRIPT = textwrap.dedent(
    """
    import sys, time
    import memcontact as mc
    # Nonsmooth Gauss-Seidel alone on a 512 × 512 square: many minutes of sweeps, so
    # the signal always comes in the middle of the solve, whatever the machine's load.
    case = mc.load_case(sys.argv[1], {"mesh.nx": 512, "mesh.ny": 512,
                                      "solver.method": "coordinate",
                                      "solver.max_iterations": 10000000,
                                      "output.plot": False})
    print("solving", flush=True)
    try:
        mc.solve(case)
        print("finished", flush=True)
    except KeyboardInterrupt:
        print("interrupted", time.time(), flush=True)
    """
)


def test_ctrl_c_stops_a_long_solve(examples, tmp_path):
    script = tmp_path / "ctrl_c.py"
    script.write_text(CTRL_C_SCRIPT)
    child = subprocess.Popen(
        [sys.executable, str(script), str(examples / "bench-square.toml")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert child.stdout.readline().strip() == "solving"
        time.sleep(2.0)
        assert child.poll() is None, "the solve ended before the signal"
        child.send_signal(signal.SIGINT)
        sent = time.time()
        out, err = child.communicate(timeout=60)
    finally:
        if child.poll() is None:
            child.kill()
    line = out.strip().splitlines()[-1]
    assert line.startswith("interrupted"), (out, err)
    caught = float(line.split()[1])
    # Within a few sweeps (milliseconds each); the bound leaves room for a loaded machine
    # and is still far below the solve's own minutes.
    assert caught - sent < 10.0, f"KeyboardInterrupt {caught - sent:.2f} s after SIGINT"


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


@pytest.mark.parametrize("args", [[], ["--compare", "foundation"]])
def test_convergence_equals_the_cli_study(cli, examples, tmp_path, args):
    case = examples / "manufactured-square.toml"
    out = tmp_path / "cli"
    subprocess.run(
        [str(cli), "convergence", str(case), "--levels", "2", "-q", "-o", str(out)] + args,
        check=True,
        capture_output=True,
    )
    compare = args[1] if args else None
    study = mc.convergence(case, 2, compare=compare)
    files = ["convergence.csv"] if not args else ["convergence-consistent.csv",
                                                  "convergence-lumped.csv"]
    assert sorted(study.variants) == sorted(files)
    for name in files:
        rows = read_csv(out / name)
        mine = study.variants[name]
        assert len(rows) == len(mine) == 3
        for r, m in zip(rows, mine):
            assert list(r) == list(m)  # the same columns in the same order
            for column, text in r.items():
                if column.endswith("_s"):
                    continue  # seconds
                if text == "":
                    assert m[column] is None, column
                elif column in ("iterations", "level", "vertices", "triangles", "unknowns"):
                    assert m[column] == int(text), column
                else:
                    v = float(text)
                    assert math.isclose(m[column], v, rel_tol=1e-10, abs_tol=1e-14), column
    assert study.rows == study.variants[files[0]]
    # Its own files: the tool's, and the same columns.
    written = study.write(tmp_path / "py")
    assert written[-1] == "manifest.json" and "convergence.png" in written
    assert list(read_csv(tmp_path / "py" / files[0])[0]) == list(read_csv(out / files[0])[0])
