"""Every class of bad input in a case raises ValueError naming the key, whether the case is
a dict, a file, or the arguments of solve_mesh."""

import copy
import math

import numpy as np
import pytest

import memcontact as mc

GOOD = {
    "mesh": {"generator": "disk", "radius": 1.0, "size": 0.25},
    "membrane": {"tension": 1.0, "load": 8.0},
    "obstacle": {"shape": "1.0", "stiffness": 100.0},
}


def with_value(path, value):
    d = copy.deepcopy(GOOD)
    *parents, last = path.split(".")
    t = d
    for p in parents:
        t = t.setdefault(p, {})
    if value is DELETE:
        del t[last]
    else:
        t[last] = value
    return d


DELETE = object()

# (dotted key, bad value, the key the message must name, a fragment of the message)
BAD = [
    ("obstacle.stifness", 100.0, "obstacle.stifness", "unknown field"),
    ("membrane.tension", -1.0, "membrane.tension", "> 0"),
    ("membrane.tension", 0, "membrane.tension", "> 0"),
    ("membrane.tension", "taut", "membrane.tension", "number"),
    ("membrane.tension", math.inf, "membrane.tension", "finite"),
    ("membrane.load", math.nan, "membrane.load", "finite"),
    ("membrane.load", "1 + z", "membrane.load", "z"),
    ("membrane.load", {}, "membrane.load", "empty"),
    ("obstacle.stiffness", -3.0, "obstacle.stiffness", "≥ 0"),
    # A region may be rigid (mixed bodies), but not "rigidly".
    ("obstacle.stiffness", {"soil": "rigidly"}, "obstacle.stiffness", "rigidly"),
    ("obstacle.shape", True, "obstacle.shape", "a number"),
    ("obstacle.shape", [1, "x"], "obstacle.shape", "a number"),
    ("membrane.load", [], "membrane.load", "empty array"),
    ("obstacle.foundation", "springy", "obstacle.foundation", "springy"),
    ("obstacle.sampling", "random", "obstacle.sampling", "random"),
    ("obstacle.epsilon", 0.1, "obstacle.epsilon", "mollified"),
    ("solver.method", "newton", "solver.method", "newton"),
    ("solver.tolerance", 0.5, "solver.tolerance", "certify"),
    ("solver.tolerance", math.nan, "solver.tolerance", "finite"),
    ("solver.max_iterations", 0, "solver.max_iterations", "at least 1"),
    ("solver.max_iterations", -1, "solver.max_iterations", "integer"),
    ("mesh.generator", "hexagon", "mesh", "hexagon"),
    ("mesh.radius", -1.0, "mesh.radius", "> 0"),
    ("mesh.size", math.nan, "mesh.size", "> 0"),
    ("mesh.nx", 4, "mesh", "nx"),
    ("mesh.refine", 40, "mesh.refine", "too many"),
    ("output.vtu", "xml", "output.vtu", "xml"),
    ("output.colour", True, "output.colour", "unknown field"),
    ("exact.kind", "foo", "exact", "foo"),
    ("membrane", DELETE, "membrane", "missing"),
    ("material.e", 1.0, "material", "unknown field"),
    # Pictures: [output] plots, allowable_pressure, profile; [units].
    ("output.plots", ["contours"], "output.plots", "contours"),
    ("output.plots", "deflection", "output.plots", "array"),
    ("output.plots", ["pressure", "pressure"], "output.plots", "twice"),
    ("output.allowable_pressure", -1.0, "output.allowable_pressure", "> 0"),
    ("output.allowable_pressure", math.inf, "output.allowable_pressure", "finite"),
    ("output.allowable_pressure", "high", "output.allowable_pressure", "a number"),
    ("output.profile", [[0, 0], [0, 0]], "output.profile", "distinct"),
    ("output.profile", [[0, 0]], "output.profile", "length 2"),
    ("output.profile", [[0, 0], [1, math.nan]], "output.profile", "finite"),
    ("units.time", "s", "units.time", "unknown field"),
    ("units.length", 3, "units.length", "a string"),
    # Steps: [sweep] and [[load_case]].
    ("sweep", {"parameter": "gravity", "values": [1]}, "sweep.parameter", "gravity"),
    ("sweep", {"values": [1.0]}, "sweep", "parameter"),
    ("sweep", {"parameter": "tension", "values": [1, -1]}, "sweep.values", "tension"),
    ("sweep", {"parameter": "load_factor", "values": []}, "sweep.values", "empty"),
    ("sweep", {"parameter": "load_factor", "values": [math.nan]}, "sweep.values", "NaN"),
    ("sweep", {"parameter": "load_factor", "from": 0, "to": 1}, "sweep", "steps"),
    (
        "sweep",
        {"parameter": "load_factor", "from": 0, "to": 1, "steps": 1},
        "sweep.steps",
        "at least 2",
    ),
    ("sweep", {"parameter": "load_factor", "values": [1], "step": 2}, "sweep.step", "unknown"),
    ("load_case", [{"name": "../x"}], "load_case.0.name", "directory"),
    ("load_case", [{"name": "a"}, {"name": "a"}], "load_case.1.name", "twice"),
    ("load_case", [{"load": 1.0}], "load_case", "name"),
    ("load_case", [{"name": "a", "tension": 2.0}], "load_case", "unknown field"),
    ("load_case", [{"name": "a", "stiffness": -1.0}], "load_case.0.stiffness", "≥ 0"),
    ("load_case", [{"name": "a", "load": math.nan}], "load_case.0.load", "finite"),
    ("load_case", [{"name": "a", "load_factor": math.inf}], "load_case.0.load_factor", "finite"),
    ("load_case", [{"name": "a", "shape": "x +"}], "load_case", "expression"),
    ("load_case", {"name": "a"}, "load_case", "array"),
]


@pytest.mark.parametrize("path, value, key, fragment", BAD, ids=[b[0] for b in BAD])
def test_bad_dict_raises_value_error_naming_the_key(path, value, key, fragment):
    with pytest.raises(ValueError) as e:
        mc.Case(with_value(path, value))
    message = str(e.value)
    assert key in message, message
    assert fragment in message, message


def toml_value(v):
    if isinstance(v, dict):
        return "{" + ", ".join(f'"{k}" = {toml_value(x)}' for k, x in v.items()) + "}"
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, float) and math.isnan(v):
        return "nan"
    if isinstance(v, float) and math.isinf(v):
        return "inf" if v > 0 else "-inf"
    return repr(v)


def to_toml(d):
    lines = []
    for section, table in d.items():
        # A list of tables is an array of tables: [[section]] per entry.
        entries = table if isinstance(table, list) else [table]
        header = f"[[{section}]]" if isinstance(table, list) else f"[{section}]"
        for entry in entries:
            if not isinstance(entry, dict):
                lines.append(f"{section} = {toml_value(table)}")
                break
            lines.append(header)
            for k, v in entry.items():
                lines.append(f"{k} = {toml_value(v)}")
            lines.append("")
    return "\n".join(lines)


@pytest.mark.parametrize("path, value, key, fragment", BAD, ids=[b[0] for b in BAD])
def test_bad_file_raises_value_error_naming_file_key_and_line(
    tmp_path, path, value, key, fragment
):
    case = tmp_path / "case.toml"
    case.write_text(to_toml(with_value(path, value)))
    with pytest.raises(ValueError) as e:
        mc.load_case(case)
    message = str(e.value)
    assert str(case) in message, message
    assert key in message, message
    assert fragment in message, message


def test_malformed_toml_names_the_line(tmp_path):
    case = tmp_path / "case.toml"
    case.write_text(to_toml(GOOD) + "\n[solver\nmethod = 'qp'\n")
    with pytest.raises(ValueError) as e:
        mc.load_case(case)
    message = str(e.value)
    assert "malformed TOML" in message, message
    line = to_toml(GOOD).count("\n") + 2
    assert f"case.toml:{line}:" in message, message


def test_overrides_are_checked_like_the_file(examples):
    with pytest.raises(ValueError, match="membrane.tension"):
        mc.load_case(examples / "disk.toml", {"membrane.tension": -2.0})
    with pytest.raises(ValueError, match="solver.method"):
        mc.load_case(examples / "disk.toml", ["solver.method=newton"])
    case = mc.load_case(
        examples / "disk.toml", {"obstacle.foundation": "lumped", "mesh.size": np.float64(0.3)}
    )
    assert case.to_dict()["obstacle"]["foundation"] == "lumped"
    assert case.to_dict()["mesh"]["size"] == 0.3


def test_missing_case_file_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError):
        mc.load_case(tmp_path / "nothing.toml")


def test_values_python_cannot_put_in_a_case():
    with pytest.raises(ValueError, match="membrane.load: None"):
        mc.Case(with_value("membrane.load", None))
    with pytest.raises(ValueError, match="mesh.radius"):
        mc.Case(with_value("mesh.radius", object()))
    with pytest.raises(TypeError):
        mc.Case([1, 2, 3])


def test_region_tables_are_checked_against_the_mesh():
    case = mc.Case(with_value("obstacle.stiffness", {"clay": 10.0}))
    with pytest.raises(ValueError, match="no region named 'clay'"):
        mc.solve(case)


def test_what_only_the_mesh_reveals_is_refused_before_solving():
    # A load case's region the mesh lacks: refused before the first step, naming the key.
    case = mc.Case(
        with_value("load_case", [{"name": "a"}, {"name": "b", "stiffness": {"clay": 5.0}}])
    )
    with pytest.raises(ValueError, match=r"load_case\.1\.stiffness: no region named 'clay'"):
        mc.sweep(case)
    # A load case's expression that is NaN inside the domain.
    case = mc.Case(
        with_value("load_case", [{"name": "a", "load": "if(r < 0.3, sqrt(-1), 8)"}])
    )
    with pytest.raises(ValueError, match=r"load_case\.0\.load f is NaN"):
        mc.sweep(case)
    # A profile line that misses the mesh.
    case = mc.Case(with_value("output.profile", [[10, 10], [20, 20]]))
    with pytest.raises(ValueError, match=r"output\.profile: the line .* does not cross the mesh"):
        mc.solve(case)


@pytest.mark.filterwarnings("ignore:solve_mesh is deprecated:DeprecationWarning")
def test_solve_mesh_errors_name_the_argument():
    mesh = mc.rectangle(nx=4)
    kwargs = dict(tension=1.0, load=1.0, shape=0.5, stiffness=10.0)
    for name, value, fragment in [
        ("tension", -1.0, "> 0"),
        ("load", float("nan"), "finite"),
        ("stiffness", -2.0, "≥ 0"),
        ("shape", "x +", "expression"),
        ("method", "newton", "newton"),
        ("foundation", "springy", "springy"),
        ("tolerance", 1.0, "certify"),
    ]:
        with pytest.raises(ValueError) as e:
            mc.solve_mesh(mesh, **{**kwargs, name: value})
        message = str(e.value)
        assert message.startswith(name), message
        assert fragment in message, message


def test_bad_mesh_arrays():
    v = np.array([[0, 0], [1, 0], [0, 1], [1, 1]], dtype=float)
    t = np.array([[0, 1, 2], [1, 3, 2]])
    assert mc.Mesh(v, t).n_triangles == 2
    with pytest.raises(ValueError, match="vertex 7"):
        mc.Mesh(v, [[0, 1, 7]])
    with pytest.raises(ValueError, match="shape"):
        mc.Mesh(v[:, :1], t)
    with pytest.raises(ValueError, match="integers"):
        mc.Mesh(v, t.astype(float))
    with pytest.raises(ValueError, match="one tag per triangle"):
        mc.Mesh(v, t, regions=[1])
    with pytest.raises(ValueError, match="degenerate"):
        mc.Mesh(np.array([[0, 0], [1, 0], [2, 0]], dtype=float), [[0, 1, 2]])
    with pytest.raises(ValueError, match="diagonal"):
        mc.rectangle(diagonal="up")
    with pytest.raises(ValueError):
        mc.disk(radius=-1.0)
