"""memcontact: a stretched membrane in contact with an elastic (tensionless Winkler)
obstacle, discretised exactly as in A. Maceri & F. Maceri, "Analysis of a discrete model
for the contact problem between a membrane and an elastic obstacle", Rend. Lincei 80
(1986).

The same cases as the ``memcontact`` command-line tool, from Python::

    import memcontact as mc

    mesh = mc.disk(radius=1.0, size=0.05)
    r = mc.solve(mesh=mesh,
                 membrane=mc.Membrane(tension=1.0, load=8.0),
                 obstacle=mc.Obstacle(shape=lambda x, y: 1 - 0.3 * x, stiffness=100.0))
    r.u, r.pressure, r.state          # read-only NumPy views over the mesh's vertices
    r.summary["contact_area"]         # the scalars of summary.json
    r.plot("pressure")                # matplotlib, each body's contact outlined
    r.matrices()["S"]                 # S, L, D, φ over the unknowns (scipy.sparse)
    r.write("out/disk")               # solution.vtu, nodes.csv, pictures, summary.json

    case = mc.load_case("examples/disk.toml", {"mesh.size": 0.1})
    results = mc.solve_many([case, ...], executor=client)   # any concurrent.futures-like

    s = mc.sweep("roof-sweep.toml")   # a case with [sweep] or [[load_case]] entries
    s.to_pandas()                     # the rows of sweep.csv
    a = mc.adapt("examples/roof-corner.toml")   # a case with [adapt]

Solves run with the GIL released. Bad data raises ``ValueError`` (or ``TypeError`` for a
value of the wrong kind) naming the key; a solve that does not reach its tolerance raises
:class:`SolverError`, whose ``result`` holds the iterate, its status and its certificate.
Plotting (matplotlib), tables (pandas), interoperability (meshio, pyvista) and the
matrices (scipy) import their package only when used.
"""

from __future__ import annotations

import os
import warnings
from typing import (
    Any,
    Callable,
    Dict,
    Iterable,
    List,
    Mapping,
    Optional,
    Sequence,
    Tuple,
    Union,
)

import numpy as np

from . import _memcontact as _native
from ._memcontact import (
    Adapt,
    Case,
    Fit,
    FitProblem,
    Mesh,
    Result,
    Sensitivities,
    Study,
    Sweep,
)
from ._sections import (
    SECTIONS as _SECTIONS,
    Boundary,
    Data,
    Lower,
    Membrane,
    Obstacle,
    Output,
    Solver,
    Units,
)

__version__: str = _native.__version__

__all__ = [
    "Adapt",
    "Boundary",
    "Case",
    "Fit",
    "FitProblem",
    "Lower",
    "Membrane",
    "Mesh",
    "Obstacle",
    "Output",
    "Result",
    "Sensitivities",
    "Solver",
    "SolverError",
    "Study",
    "Sweep",
    "Units",
    "adapt",
    "convergence",
    "disk",
    "fit",
    "fit_problem",
    "load_case",
    "polygon",
    "read_gmsh",
    "rectangle",
    "refine",
    "sensitivities",
    "solve",
    "solve_many",
    "solve_mesh",
    "sweep",
]

PathLike = Union[str, "os.PathLike[str]"]
#: A case: a :class:`Case`, a dict in the case file's schema (whose sections may be the
#: dataclasses :class:`Membrane`, :class:`Obstacle`, ...), or the path of a case file.
CaseLike = Union[Case, Mapping[str, Any], PathLike]
#: A section: its dataclass or a dict of its keys.
SectionLike = Union[Mapping[str, Any], Membrane, Obstacle, Boundary, Solver, Output, Units]
Point = Tuple[float, float]


class SolverError(RuntimeError):
    """A solve whose outcome the settings do not accept (iteration limit, stall, numerical
    failure, or the rounding floor when the settings do not allow it).

    Parameters
    ----------
    message : str
        What went wrong.
    result : Result
        The result with the best iterate, its status and its certificate.
    sweep : Sweep, optional
        For a sweep: the steps solved until then (``result`` is the last of them).

    Attributes
    ----------
    result : Result
        The best iterate (``result.kkt_residual``: its certificate).
    sweep : Sweep or None
        The steps solved, for a sweep.
    fit : Fit or None
        For a fit that did not converge: the fit with its best iterate.
    """

    def __init__(self, message: str, result: Result, sweep: Optional[Sweep] = None) -> None:
        super().__init__(message, result)
        self.result: Result = result
        self.sweep: Optional[Sweep] = sweep
        self.fit: Optional[Fit] = None

    def __str__(self) -> str:
        return str(self.args[0])

    @property
    def status(self) -> str:
        """How the solve ended (``result.status``)."""
        return self.result.status


# ---------------------------------------------------------------------------------------
# Cases.


def load_case(
    path: PathLike,
    overrides: Optional[Union[Mapping[str, Any], Sequence[str]]] = None,
) -> Case:
    """Reads a case file (TOML).

    Parameters
    ----------
    path : str or os.PathLike
        The case file. Mesh paths in it are relative to it.
    overrides : dict or list of str, optional
        Keys set first, like the command line's ``--set``: a dict of dotted keys to
        values (``{"mesh.nx": 64, "obstacle.foundation": "lumped"}``) or a list of
        ``"key=value"`` strings with TOML values.

    Returns
    -------
    Case
        The case, checked.

    Raises
    ------
    ValueError
        Bad data, naming the file, the line and the key.
    FileNotFoundError
        The file does not exist.
    TypeError
        ``overrides`` is a string.
    """
    if overrides is None:
        items: List[str] = []
    elif isinstance(overrides, Mapping):
        items = [f"{k}={_native._toml_value(v)}" for k, v in overrides.items()]
    elif isinstance(overrides, str):
        raise TypeError("overrides: give a dict or a list of 'key=value' strings")
    else:
        items = [str(s) for s in overrides]
    return Case.load(os.fspath(path), items)


def _sections_of(data: Mapping[str, Any]) -> Dict[str, Any]:
    """A case dict with its dataclass sections as dicts (a new dict; section dicts are
    copied one level deep)."""
    out: Dict[str, Any] = {}
    for key, value in data.items():
        if not isinstance(key, str):
            raise TypeError(f"a case's sections are named by strings, got {key!r}")
        if hasattr(value, "__dataclass_fields__") and hasattr(value, "to_dict"):
            value = value.to_dict()
        elif isinstance(value, Mapping):
            value = dict(value)
        out[key] = value
    return out


def _section(name: str, value: SectionLike) -> Dict[str, Any]:
    """A section given as a keyword: its dataclass or a dict."""
    if isinstance(value, Mapping):
        return dict(value)
    cls = _SECTIONS[name]
    if hasattr(value, "__dataclass_fields__") and hasattr(value, "to_dict"):
        if name != "lower" and isinstance(value, Lower) and cls is Obstacle:
            raise TypeError(f"{name}: a Lower is the body below; give an Obstacle")
        return value.to_dict()  # type: ignore[union-attr]
    raise TypeError(
        f"{name}: give a {cls.__name__} or a dict of the [{name}] keys, got "
        f"{type(value).__name__}"
    )


def _as_case(case: CaseLike) -> Case:
    if isinstance(case, Case):
        return case
    if isinstance(case, Mapping):
        return Case(_sections_of(case))
    if isinstance(case, (str, os.PathLike)):
        return load_case(case)
    raise TypeError(
        f"a case is a Case, a dict or the path of a case file, got {type(case).__name__}"
    )


def _case_data(case: Optional[CaseLike]) -> Tuple[Dict[str, Any], str, bool]:
    """The sections of a case to be solved on a given mesh, its label, and whether it came
    with a ``[mesh]`` of its own that the given mesh replaces (a :class:`Case` always has
    one)."""
    if case is None:
        return {}, "mesh", False
    if isinstance(case, Case):
        data = _sections_of(case.to_dict())
        data.pop("mesh", None)
        return data, case.label, True
    if isinstance(case, Mapping):
        return _sections_of(case), "mesh", False
    if isinstance(case, (str, os.PathLike)):
        return _sections_of(_native._case_table(os.fspath(case))), os.fspath(case), False
    raise TypeError(
        f"a case is a Case, a dict or the path of a case file, got {type(case).__name__}"
    )


# The data keys that may be arrays of one value per vertex or functions of (x, y).
_NODAL_KEYS = (
    ("membrane", "load"),
    ("obstacle", "shape"),
    ("obstacle", "stiffness"),
    ("boundary", "height"),
    ("lower", "shape"),
    ("lower", "stiffness"),
)


def _real_array(a: np.ndarray, key: str, what: str) -> np.ndarray:
    if a.dtype.kind not in "iuf":
        raise TypeError(f"{key}: {what} must be real numbers, got dtype {a.dtype}")
    return np.ascontiguousarray(a, dtype=np.float64)


def _evaluate(f: Callable[..., Any], mesh: Mesh, key: str) -> np.ndarray:
    """A vectorised function of (x, y) at the mesh's vertices: one float per vertex."""
    v = mesh.vertices
    n = mesh.n_vertices
    try:
        value = f(v[:, 0], v[:, 1])
    except Exception as e:
        raise ValueError(f"{key}: the function raised {type(e).__name__}: {e}") from e
    try:
        a = np.asarray(value)
    except Exception as e:
        raise TypeError(
            f"{key}: the function returned a {type(value).__name__}, not an array of "
            "numbers"
        ) from e
    if a.ndim == 0:
        a = np.full(n, a)
    a = _real_array(a, key, "the function's values")
    if a.shape != (n,):
        raise ValueError(
            f"{key}: the function returned shape {a.shape}, but one value per vertex "
            f"({n},) is needed (a vectorised f(x, y) of the vertex coordinates)"
        )
    bad = ~np.isfinite(a)
    if bad.any():
        i = int(np.argmax(bad))
        raise ValueError(
            f"{key}: the function's value at vertex {i} ({v[i, 0]:g}, {v[i, 1]:g}) is "
            f"{a[i]}; values must be finite ({int(bad.sum())} are not)"
        )
    return a


def _bind(data: Dict[str, Any], mesh: Mesh) -> Dict[str, Any]:
    """The data keys of a case on a known mesh: functions evaluated at its vertices, NumPy
    arrays checked to hold one real number per vertex."""
    n = mesh.n_vertices
    for section, key in _NODAL_KEYS:
        s = data.get(section)
        if not isinstance(s, dict) or key not in s:
            continue
        value = s[key]
        name = f"{section}.{key}"
        if isinstance(value, np.ndarray):
            a = _real_array(value, name, "nodal values")
            if a.shape != (n,):
                raise ValueError(
                    f"{name}: nodal values must have shape ({n},), one per vertex, got "
                    f"shape {value.shape}"
                )
            s[key] = a
        elif callable(value) and not isinstance(value, (str, type)):
            s[key] = _evaluate(value, mesh, name)
    return data


def _refuse_functions(data: Mapping[str, Any]) -> None:
    for section, key in _NODAL_KEYS:
        s = data.get(section)
        if isinstance(s, Mapping) and callable(s.get(key)) and not isinstance(s.get(key), str):
            raise TypeError(
                f"{section}.{key}: a function of (x, y) needs the mesh: give the mesh as "
                "mesh= (and the case without [mesh])"
            )


# ---------------------------------------------------------------------------------------
# Meshes.


def _int(value: Any, name: str) -> int:
    """A count: an integer (or an integral float), not negative."""
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name}: an integer is needed, got a bool")
    if isinstance(value, (float, np.floating)) and float(value).is_integer():
        value = int(value)
    try:
        v = int(value.__index__())
    except (AttributeError, TypeError):
        raise TypeError(f"{name}: an integer is needed, got {type(value).__name__}") from None
    if v < 0:
        raise ValueError(f"{name}: must not be negative, got {v}")
    if v >= 2**63:
        raise ValueError(f"{name}: {v} is too large")
    return v


def _float(value: Any, name: str) -> float:
    """A real number (its checks are the library's)."""
    if isinstance(value, (str, bytes, bool, np.bool_)) or value is None:
        raise TypeError(f"{name}: a number is needed, got {type(value).__name__}")
    try:
        return float(value)
    except OverflowError:
        raise ValueError(f"{name}: {value} is too large") from None
    except (TypeError, ValueError):
        raise TypeError(f"{name}: a number is needed, got {type(value).__name__}") from None


def _points(p: Any, name: str) -> List[Point]:
    try:
        a = np.asarray(p, dtype=np.float64)
    except OverflowError:
        raise ValueError(f"{name}: a coordinate is too large") from None
    except (TypeError, ValueError) as e:
        raise ValueError(f"{name}: expected points of shape (k, 2): {e}") from None
    if a.ndim != 2 or a.shape[1] != 2:
        raise ValueError(f"{name}: expected points of shape (k, 2), got shape {a.shape}")
    return [(float(x), float(y)) for x, y in a]


def rectangle(
    x0: float = 0.0,
    y0: float = 0.0,
    x1: float = 1.0,
    y1: float = 1.0,
    nx: int = 16,
    ny: Optional[int] = None,
    diagonal: str = "right",
) -> Mesh:
    """The structured mesh of the rectangle [x0, x1] × [y0, y1].

    Parameters
    ----------
    x0, y0, x1, y1 : float
        The corners.
    nx : int
        Cells along x.
    ny : int, optional
        Cells along y (default ``nx``).
    diagonal : {"right", "left", "alternate", "crossed"}
        How each cell is cut: along the diagonal from (xᵢ, yⱼ) to (xᵢ₊₁, yⱼ₊₁)
        (``"right"``), the other one, alternating, or into four triangles. With the right
        or left diagonal and nx, ny sharing a power-of-two factor the coarser levels are
        kept (multigrid).

    Returns
    -------
    Mesh
        The mesh; its sides are the boundary regions ``bottom``, ``right``, ``top``,
        ``left``.

    Raises
    ------
    ValueError
        Bad sizes or corners.
    """
    if not isinstance(diagonal, str):
        raise TypeError(f"diagonal: a string is needed, got {type(diagonal).__name__}")
    return _native.rectangle(
        _float(x0, "x0"), _float(y0, "y0"), _float(x1, "x1"), _float(y1, "y1"),
        _int(nx, "nx"), None if ny is None else _int(ny, "ny"), diagonal,
    )


def disk(
    center: Point = (0.0, 0.0), radius: float = 1.0, size: Optional[float] = None
) -> Mesh:
    """An unstructured mesh of a disc.

    Parameters
    ----------
    center : (float, float)
        The centre.
    radius : float
        The radius.
    size : float, optional
        The elements' size (default radius/8).

    Returns
    -------
    Mesh
        The mesh; boundary vertices lie on the circle, and refining keeps them there. A
        mesh of more than about 150 000 triangles is a coarser Delaunay mesh refined
        uniformly, and carries its levels for multigrid.

    Raises
    ------
    ValueError
        A radius or size that is not positive and finite, or too many triangles.
    """
    try:
        cx, cy = center
    except (TypeError, ValueError):
        raise TypeError("center: a pair of numbers (x, y) is needed") from None
    return _native.disk(
        (_float(cx, "center"), _float(cy, "center")),
        _float(radius, "radius"),
        None if size is None else _float(size, "size"),
    )


def polygon(
    outer: Any,
    size: float,
    holes: Optional[Sequence[Any]] = None,
    regions: Optional[Union[Mapping[str, Any], Sequence[Tuple[str, Any]]]] = None,
    min_angle: float = 25.0,
) -> Mesh:
    """A constrained Delaunay mesh of a polygon.

    Parameters
    ----------
    outer : array_like, shape (k, 2)
        The outer polygon.
    size : float
        The elements' size.
    holes : sequence of array_like, optional
        Polygons cut out.
    regions : dict or sequence, optional
        Named sub-polygons (a dict name → points, a list of ``(name, points)`` or of the
        case file's ``{"name": ..., "polygon": ...}``): their triangles get a tag named
        after them (usable as keys of region tables); the rest is the region
        ``"default"``.
    min_angle : float
        The smallest angle in degrees (≤ 30).

    Returns
    -------
    Mesh
        The mesh (with its levels for multigrid when it is large).

    Raises
    ------
    ValueError
        A bad polygon, size or angle.
    """
    size = _float(size, "size")
    min_angle = _float(min_angle, "min_angle")
    hole_list = [_points(h, "holes") for h in (holes or [])]
    if regions is None:
        region_list: List[Tuple[str, List[Point]]] = []
    elif isinstance(regions, Mapping):
        region_list = [(str(k), _points(v, f"regions[{k!r}]")) for k, v in regions.items()]
    else:
        region_list = []
        for item in regions:
            # (name, points) pairs, or the case file's {"name": ..., "polygon": ...}.
            try:
                k, v = (item["name"], item["polygon"]) if isinstance(item, Mapping) else item
            except KeyError as e:
                raise ValueError(f"regions: a region needs {e.args[0]!r}") from None
            except (TypeError, ValueError):
                raise TypeError(
                    "regions: give (name, points) pairs or {'name': ..., 'polygon': ...}"
                ) from None
            region_list.append((str(k), _points(v, f"regions[{k!r}]")))
    return _native.polygon(_points(outer, "outer"), size, hole_list, region_list, min_angle)


def read_gmsh(path: PathLike) -> Mesh:
    """Reads a Gmsh mesh (MSH 2.2 or 4.1, ASCII or binary, 3-node triangles).

    Physical surfaces become named regions, physical curves on the boundary become
    boundary regions (``boundary_edges``, ``boundary_tags``, ``boundary_names``: the keys
    of ``free`` and of boundary height tables; boundary edges no curve covers form the
    region ``default``). Skipped elements and physical curves inside the mesh are reported
    as warnings.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.msh`` file.

    Returns
    -------
    Mesh
        The mesh.

    Raises
    ------
    ValueError
        A file that does not parse or a mesh that is not valid.
    FileNotFoundError
        The file does not exist.
    """
    mesh, notes = _native.read_gmsh(os.fspath(path))
    for note in notes:
        warnings.warn(f"{os.fspath(path)}: {note}", stacklevel=2)
    return mesh


def refine(mesh: Mesh, times: int = 1) -> Mesh:
    """A mesh refined uniformly.

    Parameters
    ----------
    mesh : Mesh
        The mesh.
    times : int
        How many times each triangle is cut into four (a disc's new boundary vertices
        move onto its circle).

    Returns
    -------
    Mesh
        The refined mesh, with the levels kept for multigrid.

    Raises
    ------
    ValueError
        Too many refinements for the memory available.
    """
    if not isinstance(mesh, Mesh):
        raise TypeError(f"refine: a Mesh is needed, got {type(mesh).__name__}")
    return mesh.refine(_int(times, "times"))


# ---------------------------------------------------------------------------------------
# Solving.


def _check(result: Result) -> Result:
    for note in result.warnings:
        warnings.warn(note, stacklevel=3)
    if not result.accepted:
        raise SolverError(result.message or f"the solve ended {result.status}", result)
    return result


def _with_sections(data: Dict[str, Any], sections: Dict[str, Any]) -> Dict[str, Any]:
    for name, value in sections.items():
        if value is not None:
            data[name] = _section(name, value)
    return data


def solve(
    case: Optional[CaseLike] = None,
    *,
    mesh: Optional[Mesh] = None,
    membrane: Optional[SectionLike] = None,
    obstacle: Optional[SectionLike] = None,
    lower: Optional[SectionLike] = None,
    boundary: Optional[SectionLike] = None,
    solver: Optional[SectionLike] = None,
    output: Optional[SectionLike] = None,
    units: Optional[SectionLike] = None,
    check: bool = True,
) -> Result:
    """Solves a case end to end, as ``memcontact solve`` does, with the GIL released.

    Parameters
    ----------
    case : Case, dict or path, optional
        The case: a :class:`Case`, a dict in the case file's schema (its sections may be
        dicts or the dataclasses :class:`Membrane`, :class:`Obstacle`, :class:`Lower`,
        :class:`Boundary`, :class:`Solver`, :class:`Output`, :class:`Units`), or the path
        of a case file. With ``mesh``, a case without ``[mesh]`` (a :class:`Case`'s own
        mesh is replaced by ``mesh``).
    mesh : Mesh, optional
        The mesh to solve on (from the generators, :func:`read_gmsh`,
        :meth:`Mesh.from_meshio` or arrays). With it, data may be NumPy arrays of one
        value per vertex or vectorised functions ``f(x, y)`` of the vertex coordinates
        (evaluated once at the vertices): ``membrane.load``, ``obstacle.shape``,
        ``obstacle.stiffness``, ``boundary.height``, ``lower.shape``,
        ``lower.stiffness``.
    membrane, obstacle, lower, boundary, solver, output, units : dataclass or dict, optional
        Sections given one by one; each replaces the case's section of that name.
    check : bool
        Raise :class:`SolverError` when the settings do not accept the outcome (default);
        ``False`` returns the result whatever its status.

    Returns
    -------
    Result
        The fields (read-only arrays over the vertices), status, report and summary.

    Raises
    ------
    ValueError
        Bad data (naming the key), a function that raises or returns non-finite values,
        an array or function result of the wrong shape, a case with ``[mesh]`` and
        ``mesh=``, a case with steps (``[sweep]``, ``[[load_case]]``: see :func:`sweep`) or
        with ``[adapt]`` (see :func:`adapt`).
    TypeError
        A value of the wrong kind (a section that is neither a dict nor its dataclass,
        an array of strings, a function without ``mesh=``).
    SolverError
        The certificate did not reach the tolerance (with ``check``).

    Examples
    --------
    >>> mesh = mc.disk(radius=1.0, size=0.1)
    >>> r = mc.solve(mesh=mesh, membrane=mc.Membrane(tension=1.0, load=8.0),
    ...              obstacle=mc.Obstacle(shape=lambda x, y: 1 - 0.3 * x, stiffness=100.0))
    >>> r.status
    'converged'
    """
    sections = {
        "membrane": membrane,
        "obstacle": obstacle,
        "lower": lower,
        "boundary": boundary,
        "solver": solver,
        "output": output,
        "units": units,
    }
    given = any(v is not None for v in sections.values())
    if mesh is None:
        if case is None:
            raise TypeError("solve needs a case, or a mesh= and the case's sections")
        if isinstance(case, Case) and not given:
            c = case
        else:
            if isinstance(case, Case):
                data, label = _sections_of(case.to_dict()), case.label
            elif isinstance(case, Mapping):
                data, label = _sections_of(case), "case"
            else:
                c = load_case(case)  # type: ignore[arg-type]
                data, label = _sections_of(c.to_dict()), c.label
            data = _with_sections(data, sections)
            _refuse_functions(data)
            c = Case(data, label)
        result = _native.solve(c)
    else:
        if not isinstance(mesh, Mesh):
            raise TypeError(f"mesh: give a memcontact.Mesh, got {type(mesh).__name__}")
        data, label, replaced = _case_data(case)
        if "mesh" in data and not replaced:
            raise ValueError(
                "mesh: the case has a [mesh] section and mesh= gives a mesh: leave one out"
            )
        data = _bind(_with_sections(data, sections), mesh)
        result = _native.solve_on(mesh, data, label)
    return _check(result) if check else result


def adapt(
    case: CaseLike,
    *,
    mesh: Optional[Mesh] = None,
    check: bool = True,
) -> Adapt:
    """Runs the adaptive loop of a case with an ``[adapt]`` section, as ``memcontact
    solve`` does (solve, estimate, mark, refine by newest-vertex bisection, solve again
    from the previous answer), with the GIL released; Ctrl-C stops it.

    Parameters
    ----------
    case : Case, dict or path
        The case. With ``mesh``, a case without ``[mesh]`` (a :class:`Case`'s own mesh is
        replaced).
    mesh : Mesh, optional
        The start mesh. Data given as NumPy arrays of one value per vertex (or functions
        of (x, y), evaluated at its vertices) are interpolated (P1) onto the new vertices
        (``interpolated`` names them).
    check : bool
        Raise :class:`SolverError` when a step is not accepted (default); ``False``
        returns the loop instead.

    Returns
    -------
    Adapt
        ``rows`` (the rows of ``adapt.csv``), ``to_pandas()``, ``result`` (the final
        step's :class:`Result`, with ``estimator``), ``mesh``, ``estimator``, ``stop``,
        ``totals`` and ``write(directory)``.

    Raises
    ------
    ValueError
        Bad data (``[adapt]`` settings included), a case without ``[adapt]`` or with steps.
    TypeError
        A value of the wrong kind.
    SolverError
        A step the settings do not accept (with ``check``; its ``result`` is that step's).
    """
    if mesh is not None:
        if not isinstance(mesh, Mesh):
            raise TypeError(f"mesh: give a memcontact.Mesh, got {type(mesh).__name__}")
        data, label, replaced = _case_data(case)
        if "mesh" in data and not replaced:
            raise ValueError(
                "mesh: the case has a [mesh] section and mesh= gives a mesh: leave one out"
            )
        a = _native.adapt_on(mesh, _bind(data, mesh), label)
    else:
        a = _native.adapt(_as_case(case))
    for note in a.result.warnings:
        warnings.warn(note, stacklevel=2)
    if check and not a.accepted:
        raise SolverError(a.message or "a step of the adaptive loop was not accepted", a.result)
    return a


def sweep(case: CaseLike, warm: bool = True, *, check: bool = True) -> Sweep:
    """Solves the steps of a case with a ``[sweep]`` (one parameter over a list of values)
    or ``[[load_case]]`` entries in turn on one mesh, as ``memcontact solve`` does, with
    the GIL released.

    Parameters
    ----------
    case : Case, dict or path
        The case.
    warm : bool
        Start each step from the previous answer (default); ``False``: each from the
        usual start.
    check : bool
        Raise :class:`SolverError` when a step is not accepted (default); ``False``
        returns the shorter sweep.

    Returns
    -------
    Sweep
        ``results`` (one :class:`Result` per step), ``rows`` (the rows of ``sweep.csv``),
        ``to_pandas()`` and ``write(directory)`` (a directory per step, ``sweep.csv``,
        ``sweep.png``).

    Raises
    ------
    ValueError
        Bad data (every load case's data is checked on the mesh before the first step).
    SolverError
        A step the settings do not accept (with ``check``; its ``sweep`` holds the steps
        solved, its ``result`` the failed one).
    """
    s = _native.sweep(_as_case(case), bool(warm))
    results = s.results
    if results:
        for note in results[0].warnings:
            warnings.warn(note, stacklevel=2)
    if check and not s.accepted:
        raise SolverError(s.message or "the sweep did not complete", results[-1], s)
    return s


def convergence(
    case: CaseLike,
    levels: int,
    *,
    compare: Optional[str] = None,
    h_sweep: bool = False,
    h_values: Optional[Sequence[float]] = None,
) -> Study:
    """The convergence study of a case, as ``memcontact convergence`` runs it, with the GIL
    released: the case's mesh (level 0) and ``levels`` successive uniform refinements,
    each solved and measured against the exact solution of the case's ``[exact]`` section
    (without one, against the finest level's solution).

    Parameters
    ----------
    case : Case, dict or path
        The case.
    levels : int
        Refinements.
    compare : {"foundation", "sampling"}, optional
        Study both variants: consistent against lumped L, or nodal against mollified φ.
    h_sweep : bool
        Run the rigid limit instead, on the case's mesh refined ``levels`` times.
    h_values : sequence of float, optional
        The stiffnesses of the rigid limit (default 10, 10², …, 10⁶).

    Returns
    -------
    Study
        ``rows`` (the rows of ``convergence.csv`` or ``h_sweep.csv``; a missing value is
        None), ``columns``, ``variants``, ``to_pandas()``, ``exact`` and
        ``write(directory)``.

    Raises
    ------
    ValueError
        Bad data or options.
    """
    if compare is not None and not isinstance(compare, str):
        raise TypeError(f"compare: a string is needed, got {type(compare).__name__}")
    s = _native.convergence(
        _as_case(case),
        _int(levels, "levels"),
        compare,
        bool(h_sweep),
        None if h_values is None else [_float(h, "h_values") for h in h_values],
    )
    for note in s.warnings:
        warnings.warn(note, stacklevel=2)
    return s


def _solve_any(case: Case) -> Result:
    """Solves without raising on a status other than converged."""
    return _native.solve(case)


# The keys of solve_mesh's arguments in the case schema.
_MESH_KEYS = {
    "membrane.tension": "tension",
    "membrane.load": "load",
    "obstacle.shape": "shape",
    "obstacle.stiffness": "stiffness",
    "obstacle.foundation": "foundation",
    "obstacle.sampling": "sampling",
    "obstacle.epsilon": "epsilon",
    "solver.method": "method",
    "solver.tolerance": "tolerance",
    "solver.max_iterations": "max_iterations",
    "boundary.height": "boundary_height",
    "boundary.free": "free",
    "lower.shape": "lower_shape",
    "lower.stiffness": "lower_stiffness",
    "lower.foundation": "lower_foundation",
    "lower.sampling": "lower_sampling",
}


def _rename_keys(message: str) -> str:
    for key, name in _MESH_KEYS.items():
        if message.startswith(key):
            return name + message[len(key) :]
    return message


def solve_mesh(
    vertices: Union[Mesh, Any],
    triangles: Any = None,
    *,
    tension: float,
    load: Data,
    shape: Data,
    stiffness: Union[Data, str],
    foundation: str = "consistent",
    sampling: str = "nodal",
    epsilon: Optional[float] = None,
    method: str = "auto",
    tolerance: float = 1e-10,
    max_iterations: Optional[int] = None,
    regions: Any = None,
    region_names: Optional[Mapping[int, str]] = None,
    boundary_height: Optional[Data] = None,
    free: Optional[Sequence[str]] = None,
    lower_shape: Optional[Data] = None,
    lower_stiffness: Optional[Union[Data, str]] = None,
    lower_foundation: str = "consistent",
    lower_sampling: str = "nodal",
    check: bool = True,
) -> Result:
    """Deprecated: use :func:`solve` with ``mesh=`` and the sections.

    ``solve_mesh(mesh, tension=t, load=f, shape=φ, stiffness=h, ...)`` is
    ``solve(mesh=mesh, membrane=Membrane(t, f), obstacle=Obstacle(φ, h, ...),
    boundary=Boundary(...), lower=Lower(...), solver=Solver(...))``; it is kept for a
    deprecation period and warns.

    Parameters
    ----------
    vertices : Mesh or array_like, shape (n, 2)
        A :class:`Mesh`, or the vertices (then ``triangles`` and optionally ``regions``
        and ``region_names`` give the rest of the mesh).
    triangles : array_like, shape (m, 3), optional
        Vertex indices of the triangles.
    tension, load, shape, stiffness, foundation, sampling, epsilon : optional
        The keys of ``[membrane]`` and ``[obstacle]``.
    method, tolerance, max_iterations : optional
        The keys of ``[solver]``.
    regions, region_names : optional
        Region tags per triangle and their names.
    boundary_height, free : optional
        The keys of ``[boundary]``.
    lower_shape, lower_stiffness, lower_foundation, lower_sampling : optional
        The keys of ``[lower]``.
    check : bool
        As in :func:`solve`.

    Returns
    -------
    Result
        The result.

    Raises
    ------
    ValueError
        Bad data, naming the argument.
    TypeError
        Inconsistent arguments.
    SolverError
        As in :func:`solve`.
    """
    warnings.warn(
        "solve_mesh is deprecated: use memcontact.solve(mesh=..., membrane=Membrane(...), "
        "obstacle=Obstacle(...), ...)",
        DeprecationWarning,
        stacklevel=2,
    )
    if isinstance(vertices, Mesh):
        if triangles is not None or regions is not None or region_names is not None:
            raise TypeError("give either a Mesh or vertices and triangles, not both")
        mesh = vertices
    else:
        if triangles is None:
            raise TypeError("solve_mesh needs triangles (or a Mesh)")
        mesh = Mesh(vertices, triangles, regions, region_names)
    if (lower_shape is None) != (lower_stiffness is None):
        raise TypeError("a body below needs both lower_shape and lower_stiffness")
    if isinstance(free, str):
        raise TypeError("free: give a list of boundary region names")
    data: Dict[str, Any] = {
        "membrane": {"tension": tension, "load": load},
        "obstacle": Obstacle(shape, stiffness, foundation, sampling, epsilon).to_dict(),
        "solver": Solver(method=method, tolerance=tolerance,
                         max_iterations=max_iterations).to_dict(),
    }
    if boundary_height is not None or free:
        data["boundary"] = Boundary(
            boundary_height, [str(f) for f in free] if free else None
        ).to_dict()
    if lower_shape is not None:
        data["lower"] = Lower(
            lower_shape, lower_stiffness, lower_foundation, lower_sampling  # type: ignore[arg-type]
        ).to_dict()
    # Errors name the case's keys; this function's arguments are named after them.
    try:
        return solve(data, mesh=mesh, check=check)
    except (ValueError, TypeError) as e:
        raise type(e)(_rename_keys(str(e))) from None


def solve_many(
    cases: Iterable[CaseLike],
    executor: Any = None,
    *,
    check: bool = True,
) -> List[Result]:
    """Solves every case and returns the results in the order of ``cases``.

    Parameters
    ----------
    cases : iterable of Case, dict or path
        The cases (each with its ``[mesh]``).
    executor : optional
        Anything with the ``concurrent.futures`` interface (``submit`` returning futures
        with ``result()``): a ``ProcessPoolExecutor``, a ``dask.distributed.Client`` (a
        ``LocalCluster`` or a Slurm cluster of dask-jobqueue), Ray's or submitit's
        executors. Without one the cases are solved here, one after the other (each solve
        uses all cores). Cases and results pickle; mesh files must be readable where the
        case is solved.
    check : bool
        Raise the :class:`SolverError` of a case that does not converge (the remaining
        futures are cancelled); ``False`` returns its result instead.

    Returns
    -------
    list of Result
        In the order of ``cases``.

    Raises
    ------
    ValueError
        Bad data in a case.
    SolverError
        A case that does not converge (with ``check``).
    """
    prepared = [_as_case(c) for c in cases]
    fn: Callable[[Case], Result] = solve if check else _solve_any
    if executor is None:
        return [fn(c) for c in prepared]
    futures = [executor.submit(fn, c) for c in prepared]
    try:
        return [f.result() for f in futures]
    except BaseException:
        for f in futures:
            try:
                f.cancel()
            except Exception:  # pragma: no cover - best effort
                pass
        raise


# ---------------------------------------------------------------------------------------
# Sensitivities and back-analysis.


def _sensor_entries(sensors: Any) -> List[Dict[str, Any]]:
    """``[[sensor]]`` entries from a mapping ``name -> (x, y)`` (or ``name -> dict`` of the
    sensor's keys) or a sequence of dicts with ``name`` and ``at``."""
    if isinstance(sensors, Mapping):
        items = []
        for name, value in sensors.items():
            if isinstance(value, Mapping):
                items.append({"name": name, **dict(value)})
            else:
                items.append({"name": name, "at": value})
    elif isinstance(sensors, (str, bytes)) or not isinstance(sensors, Iterable):
        raise TypeError(
            "sensors: give a dict name -> (x, y) or a list of dicts with name and at, "
            f"not {type(sensors).__name__}"
        )
    else:
        items = []
        for s in sensors:
            if not isinstance(s, Mapping):
                raise TypeError(
                    f"sensors: each sensor is a dict with name and at, not {type(s).__name__}"
                )
            items.append(dict(s))
    out = []
    for s in items:
        entry = dict(s)
        if "at" in entry and isinstance(entry["at"], (np.ndarray, tuple)):
            entry["at"] = np.asarray(entry["at"]).tolist()
        for key in ("measured", "sigma"):
            if isinstance(entry.get(key), np.generic):
                entry[key] = entry[key].item()
        out.append(entry)
    return out


def _measurement_entries(measurements: Any, data: Dict[str, Any]) -> Dict[str, Any]:
    """The case's sensors and ``[fit]`` keys for ``measurements``: a path of a CSV file
    (``name,x,y,u[,sigma]``), a mapping ``sensor name -> measured deflection`` (for the
    case's own sensors), or a table with the columns ``name, x, y, u`` and optionally
    ``sigma`` (a dict of columns or a ``pandas.DataFrame``)."""
    if isinstance(measurements, (str, os.PathLike)):
        return {"measurements": os.fspath(measurements)}
    columns = getattr(measurements, "columns", None)
    if columns is not None or (
        isinstance(measurements, Mapping) and {"name", "x", "y", "u"} <= set(measurements)
    ):
        table = {str(c): list(np.asarray(measurements[c]).tolist()) for c in
                 (columns if columns is not None else measurements.keys())}
        missing = {"name", "x", "y", "u"} - set(table)
        if missing:
            raise ValueError(
                f"measurements: the table has no column {', '.join(sorted(missing))} "
                "(the columns: name, x, y, u and optionally sigma)"
            )
        sensors = []
        for k, name in enumerate(table["name"]):
            s: Dict[str, Any] = {
                "name": str(name),
                "at": [table["x"][k], table["y"][k]],
                "measured": table["u"][k],
            }
            if "sigma" in table:
                s["sigma"] = table["sigma"][k]
            sensors.append(s)
        return {"sensor": sensors}
    if isinstance(measurements, Mapping):
        sensors = [dict(s) for s in data.get("sensor", [])]
        known = {s.get("name") for s in sensors}
        unknown = [str(n) for n in measurements if n not in known]
        if unknown:
            raise ValueError(
                f"measurements: {', '.join(unknown)} is not a sensor of the case (its "
                f"sensors: {', '.join(sorted(str(n) for n in known if n)) or 'none'})"
            )
        for s in sensors:
            if s.get("name") in measurements:
                v = measurements[s["name"]]
                s["measured"] = v.item() if isinstance(v, np.generic) else v
        return {"sensor": sensors}
    raise TypeError(
        "measurements: give a CSV file's path, a dict sensor name -> deflection, or a "
        f"table with the columns name, x, y, u, not {type(measurements).__name__}"
    )


def _case_with(
    case: Optional[CaseLike], mesh: Optional[Mesh], extra: Callable[[Dict[str, Any]], None]
) -> Case:
    """``case`` (a Case, dict or path; with ``mesh``, a case without ``[mesh]``) with its
    dict changed by ``extra``, as a :class:`Case`."""
    if mesh is None:
        if case is None:
            raise TypeError("a case is needed (a Case, a dict or a case file's path)")
        if isinstance(case, Case):
            data, label = _sections_of(case.to_dict()), case.label
        elif isinstance(case, Mapping):
            data, label = _sections_of(case), "case"
        else:
            c = load_case(case)  # type: ignore[arg-type]
            data, label = _sections_of(c.to_dict()), c.label
        extra(data)
        _refuse_functions(data)
        return Case(data, label)
    if not isinstance(mesh, Mesh):
        raise TypeError(f"mesh: give a memcontact.Mesh, got {type(mesh).__name__}")
    data, label, replaced = _case_data(case)
    if "mesh" in data and not replaced:
        raise ValueError(
            "mesh: the case has a [mesh] section and mesh= gives a mesh: leave one out"
        )
    extra(data)
    return _native.case_on(mesh, _bind(data, mesh), label)


def _names(value: Any, what: str) -> List[str]:
    if isinstance(value, str):
        return [value]
    if not isinstance(value, Iterable):
        raise TypeError(f"{what}: give a list of names, not {type(value).__name__}")
    return [str(v) for v in value]


def sensitivities(
    case: Optional[CaseLike] = None,
    *,
    outputs: Optional[Sequence[str]] = None,
    parameters: Optional[Sequence[str]] = None,
    sensors: Optional[Any] = None,
    mesh: Optional[Mesh] = None,
    influence: bool = True,
) -> Sensitivities:
    """Solves a case and differentiates its outputs in its parameters exactly through the
    contact, as ``memcontact solve`` does for a case with ``[sensitivity]``
    (docs/sensitivities.md).

    Parameters
    ----------
    case : Case, dict or path
        The case (with ``mesh``, a case without ``[mesh]``). Its ``[sensitivity]`` section,
        if any, gives the outputs and parameters not given here.
    outputs : list of str, optional
        ``energy``, ``max_deflection``, ``total_contact_force``,
        ``total_contact_force_low``, ``contact_area``, ``sensors`` (every sensor),
        ``sensor:NAME``, ``contact_force:REGION``.
    parameters : list of str, optional
        Case keys holding a number (``membrane.tension``, ``obstacle.stiffness``, a region's
        ``obstacle.stiffness.soft``, ``lower.stiffness.clay``, ...), or ``membrane.load``,
        ``obstacle.shape``, ``lower.shape`` given as expressions (then a factor on the load,
        an offset of the surface).
    sensors : dict or list, optional
        Sensors added to the case's: ``{"S1": (x, y), ...}`` or a list of dicts with
        ``name`` and ``at`` (and ``measured``, ``sigma``).
    mesh : Mesh, optional
        The mesh to solve on (as :func:`solve`).
    influence : bool
        Also compute the influence maps (dQ/dh per vertex).

    Returns
    -------
    Sensitivities
        ``outputs``, ``parameters``, ``values`` (one per output), ``jacobian`` (outputs ×
        parameters), ``elasticity``, the one-sided derivatives and ``nonsmooth`` where
        biactive vertices make the map only directionally differentiable, ``influence``
        (arrays over the vertices), ``result`` (the solve), ``rows`` and ``to_pandas()``
        (the rows of ``sensitivity.csv``), ``write(dir)``.

    Raises
    ------
    ValueError
        An unknown output or parameter (the message lists the valid ones), a sensor
        outside the mesh, bad data.
    SolverError
        The solve was not accepted (no derivatives of an uncertified answer).

    Examples
    --------
    >>> s = mc.sensitivities(mc.load_case("examples/disk.toml", {"mesh.size": 0.2}),
    ...                      outputs=["energy"], parameters=["obstacle.stiffness"])
    >>> s.jacobian.shape
    (1, 1)
    """

    def extra(data: Dict[str, Any]) -> None:
        if sensors is not None:
            data["sensor"] = list(data.get("sensor", [])) + _sensor_entries(sensors)

    c = _case_with(case, mesh, extra)
    out = None if outputs is None else _names(outputs, "outputs")
    par = None if parameters is None else _names(parameters, "parameters")
    s, result = _native.sensitivities(c, out, par, bool(influence))
    _check(result)
    if s is None:  # pragma: no cover - an accepted solve has its derivatives
        raise SolverError("no derivatives were computed", result)
    return s


def _fit_case(
    case: Optional[CaseLike],
    measurements: Any,
    parameters: Optional[Mapping[str, Sequence[float]]],
    sensors: Any,
    mesh: Optional[Mesh],
    options: Dict[str, Any],
) -> Case:
    def extra(data: Dict[str, Any]) -> None:
        if sensors is not None:
            data["sensor"] = list(data.get("sensor", [])) + _sensor_entries(sensors)
        section = dict(data.get("fit", {}))
        if parameters is not None:
            if not isinstance(parameters, Mapping):
                raise TypeError(
                    "parameters: give a dict case key -> (min, max), not "
                    f"{type(parameters).__name__}"
                )
            section["parameters"] = {
                str(k): np.asarray(v, dtype=float).tolist() for k, v in parameters.items()
            }
        if measurements is not None:
            found = _measurement_entries(measurements, data)
            if "measurements" in found:
                section["measurements"] = found["measurements"]
            else:
                section.pop("measurements", None)
                data["sensor"] = found["sensor"]
        for key, value in options.items():
            if value is not None:
                section[key] = value
        data["fit"] = section

    return _case_with(case, mesh, extra)


def fit(
    case: Optional[CaseLike] = None,
    measurements: Any = None,
    parameters: Optional[Mapping[str, Sequence[float]]] = None,
    *,
    sensors: Any = None,
    mesh: Optional[Mesh] = None,
    max_iterations: Optional[int] = None,
    tolerance: Optional[float] = None,
    prior: Optional[float] = None,
    check: bool = True,
) -> Fit:
    """Fits case parameters (soil stiffnesses, ...) to measured deflections: bounded
    Levenberg-Marquardt in the logarithm of positive parameters with the exact Jacobian, as
    ``memcontact solve`` does for a case with ``[fit]`` (docs/sensitivities.md).

    Parameters
    ----------
    case : Case, dict or path
        The case; its values of the fitted keys are the start. Its ``[fit]`` section, if
        any, gives what is not given here.
    measurements : path, dict or table, optional
        A CSV file (``name,x,y,u`` and optionally ``sigma``), a dict ``sensor name ->
        measured deflection`` for the case's sensors, or a table (dict of columns or
        ``pandas.DataFrame``) with the columns ``name, x, y, u`` (and ``sigma``). Without
        it, the sensors' ``measured`` values.
    parameters : dict, optional
        Case key -> ``(min, max)`` bounds.
    sensors : dict or list, optional
        Sensors added to the case's (as :func:`sensitivities`).
    mesh : Mesh, optional
        The mesh to solve on (as :func:`solve`).
    max_iterations, tolerance, prior : optional
        The ``[fit]`` options (``prior``: the weight of a pull toward the start).
    check : bool
        Raise :class:`SolverError` when the fit does not converge (default; its ``fit``
        attribute holds the best iterate); ``False`` returns it.

    Returns
    -------
    Fit
        ``parameters`` (key -> fitted value), ``std_errors``, ``correlation``,
        ``singular_values``, ``rms``, ``iterations``, ``converged``, ``stop``, ``warning``
        (the parameters cannot be told apart by the measurements), ``measurements``,
        ``rows``/``to_pandas()`` (the rows of ``fit.csv``), ``result`` (the solve at the
        fitted values), ``case`` (the case with them), ``write(dir)``.

    Raises
    ------
    ValueError
        Unknown keys, bounds that exclude the start, sensors outside the mesh, NaN or
        negative sigma, fewer measurements than parameters without a prior.
    SolverError
        The start's solve was not accepted, or (with ``check``) the fit did not converge.
    """
    c = _fit_case(
        case,
        measurements,
        parameters,
        sensors,
        mesh,
        {"max_iterations": max_iterations, "tolerance": tolerance, "prior": prior},
    )
    f = _native.fit(c)
    if check and not f.converged:
        err = SolverError(
            f"the fit did not converge (stop: {f.stop}, rms {f.rms:.3e} after "
            f"{f.iterations} iterations); .fit holds its best iterate",
            f.result,
        )
        err.fit = f
        raise err
    if f.warning:
        warnings.warn(f.warning, stacklevel=2)
    return f


def fit_problem(
    case: Optional[CaseLike] = None,
    measurements: Any = None,
    parameters: Optional[Mapping[str, Sequence[float]]] = None,
    *,
    sensors: Any = None,
    mesh: Optional[Mesh] = None,
) -> FitProblem:
    """The model of a fit for an optimiser of one's own: residuals and their exact
    Jacobian in the parameters, for ``scipy.optimize.least_squares`` (arguments as
    :func:`fit`).

    Returns
    -------
    FitProblem
        ``names``, ``x0`` (the case's values), ``bounds`` (``(lower, upper)``),
        ``residuals(p)``, ``jacobian(p)``, ``residuals_and_jacobian(p)`` (one warm-started
        solve per new p), ``solves``.

    Examples
    --------
    >>> from scipy.optimize import least_squares
    >>> problem = mc.fit_problem(case)                                 # doctest: +SKIP
    >>> least_squares(problem.residuals, problem.x0, jac=problem.jacobian,
    ...               bounds=problem.bounds)                           # doctest: +SKIP
    """
    c = _fit_case(case, measurements, parameters, sensors, mesh, {})
    return _native.fit_problem(c)
