"""Sensitivities and fits from Python: derivatives against central finite differences of
solves (the same mesh, the same active set), equal to the command-line tool's files; a
noise-free fit recovering the stiffnesses the measurements were made with; scipy's
least_squares driven by our residuals and Jacobian reaching the same answer; bad input
refused with the key named."""

import csv
import json
import subprocess

import numpy as np
import pytest

import memcontact as mc
from conftest import REPO

SITE = REPO / "crates" / "memcontact" / "tests" / "data" / "sens.msh"

SENSORS = {"A": (0.3, 0.3), "B": (1.5, 0.5), "C": (1.2, 0.8), "D": (0.8, 0.5), "E": (1.8, 0.3)}


def site(soft=300.0, stiff=1000.0, foundation="consistent"):
    """The two-soil site (a rigid plinth, a body below, a free top edge) as a dict."""
    return {
        "mesh": {"file": str(SITE)},
        "membrane": {"tension": 1.3,
                     "load": "8 + 4*y - 60*exp(-((x - 1.5)^2 + (y - 0.5)^2)/0.03)"},
        "obstacle": {"shape": "0.02 + 0.01*x", "foundation": foundation,
                     "stiffness": {"soft": soft, "stiff": stiff, "plinth": "rigid"}},
        "lower": {"shape": -0.01, "stiffness": 200.0},
        "boundary": {"height": {"left": "0.004*y", "bottom": 0.0, "right": 0.003},
                     "free": ["top"]},
        "solver": {"method": "active-set", "tolerance": 1e-12},
        "output": {"plots": []},
    }


def deflections(case, names):
    """The sensors' deflections of a plain solve, by P1 interpolation done here."""
    r = mc.solve(case)
    mesh = r.mesh
    out = []
    for name in names:
        x, y = SENSORS[name]
        p = np.array([x, y])
        for tri in mesh.triangles:
            a, b, c = mesh.vertices[tri]
            m = np.column_stack([b - a, c - a])
            lam = np.linalg.solve(m, p - a)
            l0 = 1.0 - lam.sum()
            if min(l0, lam[0], lam[1]) >= -1e-12:
                out.append(l0 * r.u[tri[0]] + lam[0] * r.u[tri[1]] + lam[1] * r.u[tri[2]])
                break
        else:  # pragma: no cover
            raise AssertionError(f"{name} outside the mesh")
    return np.array(out), r


@pytest.mark.parametrize("foundation", ["consistent", "lumped"])
def test_derivatives_agree_with_central_differences(foundation):
    keys = ["obstacle.stiffness.soft", "obstacle.stiffness.stiff", "membrane.tension"]
    s = mc.sensitivities(site(foundation=foundation), outputs=["energy", "sensors"],
                         parameters=keys, sensors=SENSORS)
    assert s.parameters == keys
    assert s.outputs[0] == "energy"
    names = [o.split(":", 1)[1] for o in s.outputs[1:]]
    assert sorted(names) == sorted(SENSORS)
    assert s.jacobian.shape == (1 + len(SENSORS), len(keys))
    # The values: the sensors' deflections interpolated here from the solve's u.
    u, r = deflections(site(foundation=foundation), names)
    np.testing.assert_allclose(s.values[1:], u, rtol=1e-10, atol=1e-14)
    assert s.values[0] == pytest.approx(r.energy, rel=1e-12)
    for j, key in enumerate(keys):
        base = {"obstacle.stiffness.soft": 300.0, "obstacle.stiffness.stiff": 1000.0,
                "membrane.tension": 1.3}[key]
        step = 1e-4 * base
        values = []
        for sign in (1, -1):
            c = site(foundation=foundation)
            if key == "membrane.tension":
                c["membrane"]["tension"] = base + sign * step
            else:
                c["obstacle"]["stiffness"][key.rsplit(".", 1)[1]] = base + sign * step
            uu, rr = deflections(c, names)
            values.append(np.concatenate([[rr.energy], uu]))
        fd = (values[0] - values[1]) / (2 * step)
        scale = np.abs(fd).max()
        np.testing.assert_allclose(s.jacobian[:, j], fd, rtol=1e-5, atol=1e-6 * scale,
                                   err_msg=key)
    # Arrays are read-only, made once.
    assert s.jacobian is s.jacobian and not s.jacobian.flags.writeable
    # The energy's influence map sums to its derivative in a uniform stiffness factor.
    assert "dJ_dh" in s.influence and s.influence["dJ_dh"].shape == (s.result.mesh.n_vertices,)


def test_equal_to_the_command_line_tool(cli, tmp_path):
    case = site()
    case["sensor"] = [{"name": n, "at": list(p)} for n, p in SENSORS.items()]
    case["sensitivity"] = {
        "outputs": ["energy", "sensors", "contact_force:soft"],
        "parameters": ["obstacle.stiffness.soft", "membrane.load", "obstacle.shape"],
    }
    s = mc.sensitivities(case)
    path = tmp_path / "case.toml"
    path.write_text(mc.Case(case).to_toml())
    out = tmp_path / "out"
    o = subprocess.run([str(cli), "solve", str(path), "-o", str(out), "-q"],
                       capture_output=True, text=True)
    assert o.returncode == 0, o.stderr
    with open(out / "sensitivity.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(s.rows)
    # The rows have the file's columns (then two earlier names of two of them).
    assert s.columns == list(rows[0].keys()) + ["nonsmooth", "kind"]
    for got, want in zip(s.rows, rows):
        assert list(got.keys()) == s.columns
        assert got["biactive"] == int(want["biactive"]) == int(got["nonsmooth"])
        assert got["parameter_kind"] == want["parameter_kind"] == got["kind"]
        assert got["parameter_value"] == pytest.approx(float(want["parameter_value"]),
                                                       rel=1e-12)
        assert got["output"] == want["output"] and got["parameter"] == want["parameter"]
        assert got["derivative"] == pytest.approx(float(want["derivative"]), rel=1e-9,
                                                  abs=1e-15)
        assert got["value"] == pytest.approx(float(want["value"]), rel=1e-12, abs=1e-15)
    # Its own result set holds the same file.
    s.write(tmp_path / "py", pictures=False)
    with open(tmp_path / "py" / "sensitivity.csv") as f:
        assert [r["derivative"] for r in csv.DictReader(f)] == [r["derivative"] for r in rows]
    frame = s.to_pandas()
    assert list(frame.columns[:5]) == ["output", "parameter", "value", "derivative",
                                       "elasticity"]


def measured(soft, stiff, names):
    u, _ = deflections(site(soft, stiff), names)
    return {n: float(v) for n, v in zip(names, u)}


def test_fit_recovers_the_stiffnesses_and_scipy_agrees(cli, tmp_path):
    names = list(SENSORS)
    truth = measured(450.0, 1500.0, names)
    bounds = {"obstacle.stiffness.soft": (10.0, 1e5), "obstacle.stiffness.stiff": (10.0, 1e5)}
    start = site(soft=90.0, stiff=300.0)  # a factor 5 away
    start["sensor"] = [{"name": n, "at": list(p)} for n, p in SENSORS.items()]
    f = mc.fit(start, measurements=truth, parameters=bounds, tolerance=1e-12)
    assert f.converged and f.iterations <= 15, f
    assert f.names == list(bounds)
    assert f.parameters["obstacle.stiffness.soft"] == pytest.approx(450.0, rel=1e-6)
    assert f.parameters["obstacle.stiffness.stiff"] == pytest.approx(1500.0, rel=1e-6)
    assert f.rms < 1e-6
    assert f.values is f.values and not f.values.flags.writeable
    assert f.to_pandas().columns[0] == "iteration"
    # The same fit through the command-line tool (measurements from a CSV file).
    data = tmp_path / "points.csv"
    with open(data, "w") as fh:
        fh.write("name,x,y,u\n")
        for n in names:
            fh.write(f"{n},{SENSORS[n][0]!r},{SENSORS[n][1]!r},{truth[n]!r}\n")
    case = site(soft=90.0, stiff=300.0)
    case["fit"] = {"parameters": {k: list(v) for k, v in bounds.items()},
                   "measurements": str(data), "tolerance": 1e-12}
    path = tmp_path / "fit.toml"
    path.write_text(mc.Case(case).to_toml())
    o = subprocess.run([str(cli), "solve", str(path), "-o", str(tmp_path / "out"), "-q"],
                       capture_output=True, text=True)
    assert o.returncode == 0, o.stderr
    doc = json.loads((tmp_path / "out" / "fit.json").read_text())
    for k in bounds:
        assert doc["parameters"][k] == pytest.approx(f.parameters[k], rel=1e-8)
    # Python's measurements from the same file give the same fit.
    g = mc.fit(site(soft=90.0, stiff=300.0), measurements=data, parameters=bounds,
               tolerance=1e-12)
    np.testing.assert_allclose(g.values, f.values, rtol=1e-10)
    # scipy's least_squares with our residuals and Jacobian.
    scipy_optimize = pytest.importorskip("scipy.optimize")
    problem = mc.fit_problem(start, measurements=truth, parameters=bounds)
    assert problem.names == list(bounds)
    np.testing.assert_allclose(problem.x0, [90.0, 300.0])
    ls = scipy_optimize.least_squares(problem.residuals, problem.x0, jac=problem.jacobian,
                                      bounds=problem.bounds, x_scale="jac", xtol=1e-14,
                                      ftol=1e-14, gtol=1e-14)
    np.testing.assert_allclose(ls.x, f.values, rtol=1e-6)
    # The Jacobian against central differences of the residuals.
    p = np.array([200.0, 700.0])
    r, jac = problem.residuals_and_jacobian(p)
    for j in range(2):
        h = 1e-4 * p[j]
        dp = np.zeros(2)
        dp[j] = h
        fd = (problem.residuals(p + dp) - problem.residuals(p - dp)) / (2 * h)
        np.testing.assert_allclose(jac[:, j], fd, rtol=1e-5, atol=1e-8 * np.abs(fd).max())


def test_two_sensors_cannot_tell_two_soils_apart():
    # Both sensors on the soft soil: the stiff soil's stiffness is not seen.
    sensors = {"A": SENSORS["A"], "D": SENSORS["D"]}
    truth = measured(450.0, 1500.0, ["A", "D"])
    with pytest.warns(UserWarning):
        f = mc.fit(site(90.0, 300.0), sensors={
            n: {"at": list(p), "measured": truth[n]} for n, p in sensors.items()},
            parameters={"obstacle.stiffness.soft": (10, 1e5),
                        "obstacle.stiffness.stiff": (10, 1e5)}, check=False)
    assert f.warning


def test_bad_input_is_refused_with_the_key_named():
    with pytest.raises(ValueError, match="obstacle.stiffness.clay"):
        mc.sensitivities(site(), outputs=["energy"], parameters=["obstacle.stiffness.clay"])
    with pytest.raises(ValueError, match="outside|Z"):
        mc.sensitivities(site(), outputs=["sensors"], parameters=["membrane.tension"],
                         sensors={"Z": (10.0, 10.0)})
    with pytest.raises(ValueError, match="sigma"):
        mc.fit(site(), sensors={"A": {"at": [0.3, 0.3], "measured": 0.0, "sigma": -1.0}},
               parameters={"obstacle.stiffness.soft": (10, 1e5)})
    with pytest.raises(ValueError, match="bound|start"):
        mc.fit(site(), sensors={"A": {"at": [0.3, 0.3], "measured": 0.0}},
               parameters={"obstacle.stiffness.soft": (500, 1e5)})
    with pytest.raises(ValueError, match="Q"):
        mc.fit(site(), measurements={"Q": 1.0}, parameters={"obstacle.stiffness.soft": (1, 1e5)})
    with pytest.raises(TypeError):
        mc.sensitivities(site(), outputs=["energy"], parameters=["membrane.tension"],
                         sensors=3)
