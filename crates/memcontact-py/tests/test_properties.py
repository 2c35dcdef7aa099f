"""Property-based tests (hypothesis) over the API's inputs: case dicts with any values,
arrays of any dtype and shape, NaN and infinities, meshes with bad triangles, functions
that raise or return the wrong thing, meshio meshes, fields to plot. Whatever the input,
the package answers or raises ValueError or TypeError (SolverError for a solve the
settings do not accept): never another exception, a crash (a Rust panic is a
PanicException, which is none of those) or a hang (each call runs under a watchdog that
ends the process with a traceback).

The examples per test are few in the test command; HYPOTHESIS_PROFILE=long runs many (see
conftest.py)."""

import atexit
import faulthandler
import math
import os
import tempfile
import warnings
from contextlib import contextmanager

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, event, given, note, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import memcontact as mc

#: A call taking longer than this is a hang: the watchdog dumps the tracebacks and ends
#: the process (the test run fails).
HANG_SECONDS = float(os.environ.get("MEMCONTACT_HANG_SECONDS", "120"))

ALLOWED = (ValueError, TypeError, mc.SolverError)


#: Where the watchdog writes the tracebacks of a hang (pytest captures the standard
#: error of a test, which a process that ends at once never shows).
HANG_LOG = open(  # noqa: SIM115 - open for the life of the process
    os.environ.get("MEMCONTACT_HANG_LOG",
                   os.path.join(tempfile.gettempdir(), "memcontact-hang.log")), "w")


atexit.register(HANG_LOG.close)


def safe_repr(value):
    try:
        return repr(value)[:2000]
    except Exception:  # an object whose repr fails (meshio's of a bad mesh)
        return f"<{type(value).__name__}>"


@contextmanager
def watchdog():
    faulthandler.dump_traceback_later(HANG_SECONDS, exit=True, file=HANG_LOG)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()


def attempt(f, *args, **kwargs):
    """Calls f: its value, or None when it raised one of the allowed exceptions (any
    other exception fails the test)."""
    # The call, for the watchdog's report of a hang.
    HANG_LOG.seek(0)
    HANG_LOG.truncate()
    HANG_LOG.write(f"{getattr(f, '__qualname__', f)}(*{safe_repr(args)}, "
                   f"**{safe_repr(kwargs)})\n")
    HANG_LOG.flush()
    with watchdog(), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            value = f(*args, **kwargs)
            event(f"{getattr(f, '__name__', 'call')}: answered")
            return value
        except ALLOWED as e:
            event(f"{getattr(f, '__name__', 'call')}: {type(e).__name__}")
            note(f"{type(e).__name__}: {e}")
            assert str(e), "an error without a message"
            return None


# ---------------------------------------------------------------------------------------
# Values.

finite = st.floats(allow_nan=False, allow_infinity=False, width=64)
numbers = st.one_of(
    st.floats(width=64),  # NaN, infinities, subnormals, huge
    st.integers(min_value=-(2**70), max_value=2**70),
    st.sampled_from([0, 1, -1, 0.5, 1e-300, 1e300, 2**31, 2**32, 2**63 - 1, 2**64]),
)
names = st.sampled_from(["rigid", "consistent", "lumped", "nodal", "mollified", "auto",
                         "multigrid", "qp", "active-set", "coordinate", "linear", "default",
                         "left", "top", "block", "", "x", "nonsense", "1e3", "nan"])
expressions = st.sampled_from(["x", "1 - 0.3*x", "sin(pi*x)*y", "exp(x)", "1/x", "log(x)",
                               "sqrt(-1)", "x^1000", "(", "y +", "1e400", "nan", "inf",
                               "0.1*x + 0.2*y", "abs(x) < 1", "max(x, y)", "2**3"])
scalars = st.one_of(numbers, names, expressions, st.booleans(), st.none())
arrays = hnp.arrays(
    dtype=st.one_of(hnp.floating_dtypes(), hnp.integer_dtypes(), hnp.boolean_dtypes(),
                    hnp.complex_number_dtypes(), hnp.unicode_string_dtypes(max_len=3)),
    shape=hnp.array_shapes(min_dims=0, max_dims=3, min_side=0, max_side=6),
)


def values(depth=2):
    base = st.one_of(scalars, arrays)
    if depth == 0:
        return base
    return st.one_of(
        base,
        st.lists(values(depth - 1), max_size=4),
        st.dictionaries(st.one_of(names, st.integers(-3, 3)), values(depth - 1), max_size=4),
    )


# ---------------------------------------------------------------------------------------
# Case dicts.

SCHEMA = {
    "mesh": ["generator", "nx", "ny", "x0", "x1", "y0", "y1", "size", "radius", "center",
             "refine", "diagonal", "outer", "holes", "regions", "min_angle"],
    "membrane": ["tension", "load"],
    "obstacle": ["shape", "stiffness", "foundation", "sampling", "epsilon"],
    "lower": ["shape", "stiffness", "foundation", "sampling", "epsilon"],
    "boundary": ["height", "free"],
    "solver": ["method", "tolerance", "max_iterations", "accept_rounding_floor", "hierarchy"],
    "output": ["vtu", "csv", "plots", "plot", "allowable_pressure", "profile"],
    "units": ["length", "force"],
    "exact": ["kind", "solution", "amplitude"],
    "sweep": ["parameter", "values"],
    "adapt": ["max_vertices", "steps", "theta", "tolerance"],
}
BASE = {
    "mesh": {"generator": "rectangle", "nx": 6},
    "membrane": {"tension": 1.0, "load": 10.0},
    "obstacle": {"shape": 0.05, "stiffness": 200.0},
}
# Keys whose random values would make a valid case arbitrarily large (a mesh of 10⁸
# triangles is refused by the memory check, but one of 10⁶ is solved): bounded in the
# solved cases.
SIZE_KEYS = {("mesh", "nx"), ("mesh", "ny"), ("mesh", "size"), ("mesh", "refine"),
             ("mesh", "radius"), ("mesh", "x1"), ("mesh", "y1"), ("mesh", "x0"),
             ("mesh", "y0"), ("adapt", "max_vertices"), ("adapt", "steps"),
             ("mesh", "outer"), ("mesh", "holes"),
             ("mesh", "center"), ("obstacle", "epsilon"), ("lower", "epsilon"),
             ("solver", "method"), ("mesh", "min_angle"), ("sweep", "values")}


#: Values a key plausibly takes (drawn half the time, so that many cases are valid and
#: solved: the solvers, bodies and boundary data see unusual but legal combinations).
PLAUSIBLE = {
    ("membrane", "tension"): st.one_of(st.floats(1e-3, 1e3), st.just(1e-300)),
    ("membrane", "load"): st.one_of(st.floats(-50, 50), expressions,
                                    st.just({"default": 3.0})),
    ("obstacle", "shape"): st.one_of(st.floats(-1, 1), expressions),
    ("obstacle", "stiffness"): st.one_of(st.floats(0, 1e8), st.just("rigid"),
                                         st.just({"default": "rigid"})),
    ("obstacle", "foundation"): st.sampled_from(["consistent", "lumped"]),
    ("obstacle", "sampling"): st.sampled_from(["nodal", "mollified"]),
    ("obstacle", "epsilon"): st.floats(1e-3, 0.5),
    ("lower", "shape"): st.one_of(st.floats(-1, 1), expressions),
    ("lower", "stiffness"): st.one_of(st.floats(0, 1e8), st.just("rigid")),
    ("lower", "foundation"): st.sampled_from(["consistent", "lumped"]),
    ("lower", "sampling"): st.sampled_from(["nodal", "mollified"]),
    ("boundary", "height"): st.one_of(st.floats(-1, 1), expressions,
                                      st.just({"left": 0.1, "top": "x"})),
    ("boundary", "free"): st.lists(st.sampled_from(["left", "right", "top", "bottom"]),
                                   max_size=4, unique=True),
    ("solver", "method"): st.sampled_from(["auto", "linear", "active-set", "qp",
                                           "coordinate", "multigrid"]),
    ("solver", "tolerance"): st.floats(1e-14, 1e-2),
    ("solver", "max_iterations"): st.integers(0, 50),
    ("solver", "accept_rounding_floor"): st.booleans(),
    ("solver", "hierarchy"): st.sampled_from(["auto", "geometric", "algebraic"]),
}


@st.composite
def case_dicts(draw):
    """A case dict: the small valid base case with keys of the schema (and unknown keys)
    set to any values, sections added, replaced or removed."""
    case = {k: dict(v) for k, v in BASE.items()}
    for _ in range(draw(st.integers(0, 4))):
        section = draw(st.sampled_from(sorted(SCHEMA) + ["bogus"]))
        action = draw(st.integers(0, 9))
        if action == 0:
            case.pop(section, None)
        elif action == 1:
            case[section] = draw(values(1))
        else:
            key = draw(st.sampled_from(SCHEMA.get(section, ["key"]) + ["unknown_key"]))
            if not isinstance(case.get(section), dict):
                case[section] = {}
                if section == "lower":
                    case[section] = {"shape": -0.05, "stiffness": 100.0}
            plausible = PLAUSIBLE.get((section, key))
            if plausible is not None and draw(st.integers(0, 4)) > 0:
                case[section][key] = draw(plausible)
            else:
                case[section][key] = draw(values(1))
    return case


@st.composite
def plausible_cases(draw):
    """The base case with keys set to plausible values only: mostly valid cases, with
    unusual combinations of bodies, boundary data, foundations and solvers."""
    case = {k: dict(v) for k, v in BASE.items()}
    keys = draw(st.lists(st.sampled_from(sorted(PLAUSIBLE)), min_size=1, max_size=6,
                         unique=True))
    for section, key in keys:
        if section not in case:
            case[section] = {"shape": -0.05, "stiffness": 100.0} if section == "lower" else {}
        case[section][key] = draw(PLAUSIBLE[(section, key)])
    return case


def small_enough(case):
    """Whether a case that passed validation is small enough to solve in a test: its mesh
    keys are left at the base case's."""
    mesh = case.get("mesh")
    if not isinstance(mesh, dict):
        return False
    if mesh != BASE["mesh"]:
        return False
    for section, key in SIZE_KEYS:
        if section != "mesh" and isinstance(case.get(section), dict) and key in case[section]:
            return False
    return "sweep" not in case and "adapt" not in case and "exact" not in case


@settings(suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(st.one_of(case_dicts(), plausible_cases()))
def test_any_case_dict_is_a_case_or_a_named_error(case):
    c = attempt(mc.Case, case)
    if c is None:
        return
    # A valid case round-trips through its dict and its TOML text.
    assert mc.Case(c.to_dict()) == c
    assert mc.Case.from_toml(c.to_toml()) == c
    if small_enough(case):
        r = attempt(mc.solve, c)
        if r is not None:
            assert r.u.shape == (r.mesh.n_vertices,)
            assert np.all(np.isfinite(r.u))


@settings(suppress_health_check=[HealthCheck.too_slow])
@given(st.dictionaries(st.one_of(st.text(max_size=6), st.integers(), st.none()),
                       values(2), max_size=5))
def test_any_dict_at_all(data):
    attempt(mc.Case, data)
    attempt(mc.solve, data)
    attempt(mc.solve, data, mesh=mc.rectangle(nx=3))


# ---------------------------------------------------------------------------------------
# Meshes from arrays.


@st.composite
def triangle_meshes(draw):
    """Arrays of a mesh, often almost valid: a small grid's triangles with some vertices
    moved (NaN, infinities, duplicates), triangles changed (out of range, repeated,
    degenerate, inverted, duplicated) and arrays of other dtypes and shapes."""
    nx = draw(st.integers(1, 4))
    grid = mc.rectangle(nx=nx)
    v = np.array(grid.vertices)
    t = np.array(grid.triangles)
    r = np.zeros(len(t), dtype=np.int64)
    for _ in range(draw(st.integers(0, 3))):
        if v.ndim != 2 or t.ndim != 2 or v.shape[1] != 2 or t.shape[1] != 3 or \
                len(v) == 0 or len(t) == 0 or v.dtype != np.float64 or t.dtype != np.int64:
            break  # already replaced by arbitrary arrays or types
        kind = draw(st.integers(0, 9))
        if kind == 0:
            v[draw(st.integers(0, len(v) - 1))] = draw(st.sampled_from(
                [np.nan, np.inf, -np.inf, 1e308, 0.0]))
        elif kind == 1:
            t[draw(st.integers(0, len(t) - 1)), draw(st.integers(0, 2))] = draw(
                st.integers(-3, len(v) + 3))
        elif kind == 2:
            k = draw(st.integers(0, len(t) - 1))
            t[k] = t[k][::-1]  # inverted
        elif kind == 3:
            t = np.concatenate([t, t[:1]])  # duplicated
            r = np.concatenate([r, r[:1]])
        elif kind == 4:
            v = np.concatenate([v, [[5.0, 5.0]]])  # unused vertex
        elif kind == 5:
            r[draw(st.integers(0, len(r) - 1))] = draw(st.integers(-2**40, 2**40))
        elif kind == 6:
            v = v.astype(draw(st.sampled_from([np.float16, np.float32, np.int32,
                                               np.complex128, np.bool_, object])))
        elif kind == 7:
            t = t.astype(draw(st.sampled_from([np.float64, np.int8, np.uint8, np.uint64,
                                               np.int16, np.bool_, object])))
        elif kind == 8:
            t = draw(hnp.arrays(dtype=hnp.integer_dtypes(), shape=hnp.array_shapes(
                min_dims=0, max_dims=3, max_side=5)))
        else:
            v = draw(arrays)
    return v, t, r


@settings(suppress_health_check=[HealthCheck.too_slow])
@given(triangle_meshes(), st.booleans())
def test_meshes_from_any_arrays(arrays_, with_regions):
    v, t, r = arrays_
    mesh = attempt(mc.Mesh, v, t, r if with_regions else None)
    if mesh is None:
        return
    assert mesh.vertices.shape == (mesh.n_vertices, 2)
    result = attempt(mc.solve, mesh=mesh, membrane=mc.Membrane(1.0, 5.0),
                     obstacle=mc.Obstacle(0.05, 100.0))
    if result is not None:
        assert np.all(np.isfinite(result.u))


@settings(suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.integers(-2, 12), st.integers(-2, 12)), max_size=6),
       st.lists(st.integers(-2**33, 2**33), max_size=6),
       st.dictionaries(st.integers(-3, 2**33), st.text(max_size=4), max_size=3))
def test_boundary_regions_from_any_arrays(edges, tags, names):
    grid = mc.rectangle(nx=2)
    attempt(mc.Mesh, grid.vertices, grid.triangles, boundary_edges=np.array(edges),
            boundary_tags=np.array(tags), boundary_names=names)


# ---------------------------------------------------------------------------------------
# Data on a mesh: arrays, functions, scalars.

MESH = mc.rectangle(nx=5)
N = MESH.n_vertices


class Boom(Exception):
    pass


def functions():
    """Functions of (x, y) that answer, raise, or return the wrong thing."""
    good = st.sampled_from([lambda x, y: x + y, lambda x, y: 1.0, lambda x, y: np.ones(N),
                            lambda x, y: 0.1 * x * y, lambda x, y: np.float32(2.0)])
    bad = st.sampled_from([
        lambda x, y: 1 / 0,
        lambda x, y: (_ for _ in ()).throw(Boom("boom")),
        lambda x, y: None,
        lambda x, y: "text",
        lambda x, y: [1, 2],
        lambda x, y: np.ones((N, 2)),
        lambda x, y: np.full(N, np.nan),
        lambda x, y: x + 1j,
        lambda x, y: x > 0,
        lambda x, y: {"a": x},
        lambda x, y: np.array([object()] * N),
        lambda x, y: x.reshape(-1, 1),
        lambda: 1.0,  # wrong arity
        lambda x, y, z: x,
        lambda x, y: np.ma.masked_array(x, mask=x > 0.5),
        lambda x, y: np.full(N, 1e400),
        lambda x, y: x.__setitem__(0, 1.0),
    ])
    returned = hnp.arrays(dtype=st.one_of(hnp.floating_dtypes(), hnp.integer_dtypes(),
                                          hnp.complex_number_dtypes()),
                          shape=st.sampled_from([(N,), (N - 1,), (), (1,), (N, 1)]))
    return st.one_of(good, bad, returned.map(lambda a: (lambda x, y: a)))


data = st.one_of(scalars, arrays, functions(),
                 hnp.arrays(np.float64, (N,), elements=st.floats(width=64)),
                 st.dictionaries(names, st.one_of(numbers, expressions), max_size=3))


@settings(suppress_health_check=[HealthCheck.too_slow])
@given(data, data, data, st.one_of(st.none(), data), st.one_of(st.none(), data),
       st.one_of(st.none(), data))
def test_any_data_on_a_mesh(load, shape, stiffness, height, lower_shape, lower_stiffness):
    sections = dict(
        membrane=mc.Membrane(1.0, load),
        obstacle=mc.Obstacle(shape, stiffness),
    )
    if height is not None:
        sections["boundary"] = mc.Boundary(height=height)
    if lower_shape is not None and lower_stiffness is not None:
        sections["lower"] = mc.Lower(lower_shape, lower_stiffness)
    r = attempt(mc.solve, mesh=MESH, solver=mc.Solver(max_iterations=200), **sections)
    if r is not None:
        assert np.all(np.isfinite(r.u))


@settings(suppress_health_check=[HealthCheck.too_slow])
@given(st.one_of(numbers, arrays), data)
def test_any_tension_and_solver_values(tension, load):
    attempt(mc.solve, {"membrane": {"tension": tension, "load": load},
                       "obstacle": {"shape": 0.1, "stiffness": 10.0}}, mesh=MESH)


# ---------------------------------------------------------------------------------------
# The result's methods.

RESULT = mc.solve(mesh=MESH, membrane=mc.Membrane(1.0, 10.0),
                  obstacle=mc.Obstacle(0.05, 200.0), lower=mc.Lower(-0.05, 100.0))


@settings(suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(st.one_of(st.sampled_from(["u", "gap", "gap_low", "state_low", "estimator", "region",
                                  "", "U", "phi "]), arrays, data, st.none()),
       st.dictionaries(st.sampled_from(["kind", "contact", "colorbar", "title", "cmap",
                                        "shading", "vmin"]), values(0), max_size=3),
       # matplotlib's contour levels: a count (a huge one is matplotlib's long work, not
       # ours) or values.
       st.one_of(st.none(), st.integers(-2, 50), arrays))
def test_plot_any_field(field, kwargs, levels):
    if levels is not None:
        kwargs["levels"] = levels
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    # matplotlib's own errors for bad options passed through to it (its colour bar's
    # callbacks once recursed without end in a long run, inside matplotlib).
    allowed = ALLOWED + (AttributeError, KeyError, RecursionError)

    with watchdog(), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            if field is None:
                RESULT.plot(**kwargs)
            else:
                RESULT.plot(field, **kwargs)
        except allowed:
            pass
        finally:
            plt.close("all")


@settings(suppress_health_check=[HealthCheck.too_slow])
@given(st.builds(
    lambda points, cells, cell_data, field_data: (points, cells, cell_data, field_data),
    arrays,
    st.lists(st.tuples(st.sampled_from(["triangle", "line", "vertex", "quad", "tetra"]),
                       hnp.arrays(dtype=st.one_of(hnp.integer_dtypes(),
                                                  hnp.floating_dtypes()),
                                  shape=hnp.array_shapes(min_dims=1, max_dims=2,
                                                         max_side=5),
                                  elements={"min_value": -2, "max_value": 8})),
             max_size=3),
    st.booleans(),
    st.dictionaries(st.text(max_size=4), hnp.arrays(np.int64, (2,),
                                                    elements=st.integers(-1, 3)),
                    max_size=3),
))
def test_from_meshio_of_any_mesh(parts):
    import meshio

    points, cells, with_tags, field_data = parts
    try:
        m = meshio.Mesh(points, cells, field_data=field_data)
        if with_tags:
            m.cell_data["gmsh:physical"] = [np.arange(len(c.data)) % 3 for c in m.cells]
    except Exception:
        assume(False)  # not a mesh meshio accepts
        return
    attempt(mc.Mesh.from_meshio, m)


@settings(suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.text(max_size=20), max_size=3),
       st.dictionaries(st.text(max_size=12), values(1), max_size=3))
def test_any_overrides(items, mapping):
    from conftest import EXAMPLES

    path = EXAMPLES / "disk.toml"
    with watchdog(), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for o in (items, mapping):
            try:
                mc.load_case(path, o)
            except ALLOWED:
                pass


@settings(suppress_health_check=[HealthCheck.too_slow])
@given(st.text(max_size=200))
def test_any_toml_text(text):
    attempt(mc.Case.from_toml, text)


anything = st.one_of(values(1), st.builds(object), st.just(float("nan")))
# Sizes that ask for little work, or for so much that the limits refuse them at once (a
# valid mesh of 10⁸ triangles is not refused: it is built, which takes minutes), or are
# not sizes at all.
counts = st.one_of(st.integers(-5, 24), st.integers(10**5, 2**70), st.floats(0, 24),
                   st.floats(1e5, 1e300), anything)
lengths = st.one_of(st.floats(0.05, 10), st.floats(-1e300, 1e-5), st.floats(1e5, 1e300),
                    st.integers(-10, 10), anything)
coordinates = st.one_of(finite, numbers, anything)
# A polygon with a sliver angle is refined until the library's budget of added vertices
# (ten per boundary point) runs out: with a long boundary that takes minutes before the
# (correct) refusal. Polygons here have short boundaries.
not_numbers = st.one_of(st.sampled_from([float("nan"), float("inf"), -float("inf"), "x",
                                          None, True]), st.lists(st.integers(), max_size=3),
                        st.builds(object), st.dictionaries(st.text(max_size=2), st.none()))
polygon_points = st.one_of(st.floats(-50, 50), not_numbers)
polygon_sizes = st.one_of(st.floats(0.05, 10), st.floats(-1e300, 0), not_numbers)


@settings(suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(coordinates, min_size=4, max_size=4), counts, counts, lengths, lengths,
       st.one_of(st.integers(-3, 4), st.integers(13, 2**70), anything), anything,
       polygon_points, polygon_points, polygon_sizes)
def test_generators_with_any_arguments(corners, nx, ny, size, radius, times, other, px, py,
                                       psize):
    x0, y0, x1, y1 = corners
    attempt(mc.rectangle, x0, y0, x1, y1, nx, ny)
    attempt(mc.rectangle, nx=nx, diagonal=other)
    attempt(mc.disk, (x0, y0), radius, size)
    attempt(mc.disk, other, radius)
    attempt(mc.polygon, [[0, 0], [1, 0], [px, py]], psize)
    attempt(mc.polygon, px, psize, holes=py, regions=other)
    attempt(mc.refine, mc.rectangle(nx=1), times)
    attempt(mc.rectangle(nx=1).refine, times)
    attempt(mc.convergence, {"mesh": {"generator": "rectangle", "nx": 2},
                             "membrane": {"tension": 1.0, "load": 1.0},
                             "obstacle": {"shape": 1.0, "stiffness": 1.0}},
            times if not isinstance(times, int) or times < 0 or times > 2 else times,
            compare=other)


def test_deep_nesting_is_refused_not_a_crash():
    deep = 1.0
    for _ in range(100_000):
        deep = [deep]
    with pytest.raises(ValueError, match="nests more than"):
        mc.Case({"mesh": {"generator": "rectangle"}, "membrane": {"tension": 1.0,
                                                                  "load": deep}})
    nested = "x = " + "[" * 100_000 + "]" * 100_000
    with pytest.raises(ValueError):
        mc.Case.from_toml(nested)


def test_the_watchdog_is_armed():
    assert math.isfinite(HANG_SECONDS) and HANG_SECONDS > 0
