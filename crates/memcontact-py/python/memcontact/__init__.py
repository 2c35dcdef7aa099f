"""memcontact: a stretched membrane in contact with an elastic (tensionless Winkler)
obstacle, discretised exactly as in A. Maceri & F. Maceri, "Analysis of a discrete model
for the contact problem between a membrane and an elastic obstacle", Rend. Lincei 80
(1986).

The same cases as the ``memcontact`` command-line tool, from Python::

    import memcontact as mc

    mesh = mc.disk(radius=1.0, size=0.05)
    r = mc.solve_mesh(mesh, tension=1.0, load=8.0, shape=1.0, stiffness=100.0)
    r.u, r.pressure, r.state          # NumPy arrays over the mesh's vertices
    r.summary["contact_area"]         # the scalars of summary.json
    r.write("out/disk")               # solution.vtu, nodes.csv, summary.json

    case = mc.load_case("examples/disk.toml", {"mesh.size": 0.1})
    results = mc.solve_many([case, ...], executor=client)   # any concurrent.futures-like

    s = mc.sweep("roof-sweep.toml")   # a case with [sweep] or [[load_case]] entries
    s.rows                            # the rows of sweep.csv
    s.write("out/roof-sweep")         # a directory per step, sweep.csv, sweep.png

Solves run with the GIL released. Bad data raises ``ValueError`` naming the key; a solve
that does not reach its tolerance raises :class:`SolverError`, whose ``result`` holds the
iterate, its status and its certificate.
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
from ._memcontact import Case, Mesh, Result, Study, Sweep

__version__: str = _native.__version__

__all__ = [
    "Case",
    "Mesh",
    "Result",
    "Study",
    "Sweep",
    "SolverError",
    "convergence",
    "load_case",
    "rectangle",
    "disk",
    "polygon",
    "read_gmsh",
    "refine",
    "solve",
    "solve_mesh",
    "solve_many",
    "sweep",
]

PathLike = Union[str, "os.PathLike[str]"]
#: What a data argument may be: a number, an expression of x and y (a string), a dict of
#: region names (or tags) to numbers or expressions, or (where noted) a NumPy array of
#: one value per mesh vertex.
Data = Union[float, int, str, Mapping[Union[str, int], Union[float, int, str]], np.ndarray]
CaseLike = Union[Case, Mapping[str, Any], PathLike]
Point = Tuple[float, float]


class SolverError(RuntimeError):
    """A solve whose outcome the settings do not accept (iteration limit, stall, numerical
    failure, or the rounding floor when the settings do not allow it). ``result`` is the
    :class:`Result` with the best iterate, its ``status`` and its certificate
    (``result.kkt_residual``); for a sweep, ``sweep`` holds the steps solved until then
    (``result`` is the last of them)."""

    def __init__(self, message: str, result: Result, sweep: Optional[Sweep] = None) -> None:
        super().__init__(message, result)
        self.result: Result = result
        self.sweep: Optional[Sweep] = sweep

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
    """Reads a case file (TOML). ``overrides`` sets keys first, like the command line's
    ``--set``: a dict of dotted keys to values (``{"mesh.nx": 64, "obstacle.foundation":
    "lumped"}``) or a list of ``"key=value"`` strings with TOML values. Mesh paths are
    relative to the case file. Bad data raises ``ValueError`` naming the file, the line and
    the key."""
    if overrides is None:
        items: List[str] = []
    elif isinstance(overrides, Mapping):
        items = [f"{k}={_native._toml_value(v)}" for k, v in overrides.items()]
    elif isinstance(overrides, str):
        raise TypeError("overrides: give a dict or a list of 'key=value' strings")
    else:
        items = [str(s) for s in overrides]
    return Case.load(os.fspath(path), items)


def _as_case(case: CaseLike) -> Case:
    if isinstance(case, Case):
        return case
    if isinstance(case, Mapping):
        return Case(dict(case))
    if isinstance(case, (str, os.PathLike)):
        return load_case(case)
    raise TypeError(
        f"a case is a Case, a dict or the path of a case file, got {type(case).__name__}"
    )


# ---------------------------------------------------------------------------------------
# Meshes.


def _points(p: Any, name: str) -> List[Point]:
    a = np.asarray(p, dtype=np.float64)
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
    """The structured mesh of [x0, x1] × [y0, y1] with nx × ny cells (ny defaults to nx),
    each cut along ``diagonal``: ``"right"`` (from (xᵢ, yⱼ) to (xᵢ₊₁, yⱼ₊₁)), ``"left"``,
    ``"alternate"`` or ``"crossed"`` (four triangles). With the right or left diagonal and
    nx, ny sharing a power-of-two factor the coarser levels are kept (multigrid)."""
    return _native.rectangle(x0, y0, x1, y1, int(nx), None if ny is None else int(ny), diagonal)


def disk(
    center: Point = (0.0, 0.0), radius: float = 1.0, size: Optional[float] = None
) -> Mesh:
    """An unstructured mesh of a disc with elements of about ``size`` (default radius/8);
    the boundary vertices lie on the circle, and refining keeps them there. A mesh of more
    than about 150 000 triangles is a coarser Delaunay mesh refined uniformly, and carries
    its levels for multigrid."""
    return _native.disk((float(center[0]), float(center[1])), float(radius), size)


def polygon(
    outer: Any,
    size: float,
    holes: Optional[Sequence[Any]] = None,
    regions: Optional[Union[Mapping[str, Any], Sequence[Tuple[str, Any]]]] = None,
    min_angle: float = 25.0,
) -> Mesh:
    """A constrained Delaunay mesh of the polygon ``outer`` (k × 2 points) minus ``holes``,
    elements of about ``size``, angles of at least ``min_angle`` degrees (≤ 30).
    ``regions`` names sub-polygons (a dict name → points, or a list of ``(name, points)``
    or of the case file's ``{"name": ..., "polygon": ...}``): their triangles get a tag named
    after them (usable as keys of region tables); the rest is the region ``"default"``.
    A mesh of more than about 150 000 triangles is a coarser Delaunay mesh refined
    uniformly, and carries its levels for multigrid."""
    hole_list = [_points(h, "holes") for h in (holes or [])]
    if regions is None:
        region_list: List[Tuple[str, List[Point]]] = []
    elif isinstance(regions, Mapping):
        region_list = [(str(k), _points(v, f"regions[{k!r}]")) for k, v in regions.items()]
    else:
        region_list = []
        for item in regions:
            # (name, points) pairs, or the case file's {"name": ..., "polygon": ...}.
            k, v = (item["name"], item["polygon"]) if isinstance(item, Mapping) else item
            region_list.append((str(k), _points(v, f"regions[{k!r}]")))
    return _native.polygon(
        _points(outer, "outer"), float(size), hole_list, region_list, float(min_angle)
    )


def read_gmsh(path: PathLike) -> Mesh:
    """Reads a Gmsh mesh (MSH 2.2 or 4.1, ASCII or binary, 3-node triangles); physical
    surfaces become named regions, physical curves on the boundary become boundary regions
    (`boundary_edges`, `boundary_tags`, `boundary_names`: the keys of `free` and of
    boundary height tables; boundary edges no curve covers form the region `default`).
    Skipped elements and physical curves inside the mesh are reported as warnings."""
    mesh, notes = _native.read_gmsh(os.fspath(path))
    for note in notes:
        warnings.warn(f"{os.fspath(path)}: {note}", stacklevel=2)
    return mesh


def refine(mesh: Mesh, times: int = 1) -> Mesh:
    """``mesh`` refined uniformly ``times`` times (each triangle into four; a disc's new
    boundary vertices move onto its circle). The levels are kept for multigrid."""
    return mesh.refine(int(times))


# ---------------------------------------------------------------------------------------
# Solving.


def _check(result: Result) -> Result:
    for note in result.warnings:
        warnings.warn(note, stacklevel=3)
    if not result.accepted:
        raise SolverError(result.message or f"the solve ended {result.status}", result)
    return result


def solve(case: CaseLike) -> Result:
    """Solves a case (a :class:`Case`, a dict in the case file's schema, or the path of a
    case file) end to end, as ``memcontact solve`` does, with the GIL released.

    Raises ``ValueError`` for bad data and :class:`SolverError` (with the result) when the
    certificate does not reach the tolerance. A case with a ``[sweep]`` or
    ``[[load_case]]`` entries raises ``ValueError``: solve its steps with :func:`sweep`."""
    return _check(_native.solve(_as_case(case)))


def sweep(case: CaseLike, warm: bool = True, *, check: bool = True) -> Sweep:
    """Solves the steps of a case with a ``[sweep]`` (one parameter over a list of values)
    or ``[[load_case]]`` entries in turn on one mesh, as ``memcontact solve`` does: each
    step is warm-started from the previous answer (``warm=False``: each from the usual
    start), with the GIL released.

    Returns a :class:`Sweep`: ``results`` (one :class:`Result` per step), ``rows`` (the
    rows of ``sweep.csv``: step, name, value, max_deflection, contact_area, liftoff_area,
    total_contact_force, max_pressure, energy, iterations, kkt_residual, seconds), and
    ``write(directory)``, which writes the command-line tool's files (a directory per
    step, ``sweep.csv``, ``sweep.png``).

    Raises ``ValueError`` for bad data (every load case's data is checked on the mesh
    before the first step is solved). A step the settings do not accept ends the sweep:
    with ``check`` that raises :class:`SolverError` (its ``sweep`` holds the steps solved,
    its ``result`` the failed one); ``check=False`` returns the shorter sweep instead."""
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
    """The convergence study of a case, as ``memcontact convergence`` runs it (the same
    options as keywords): the case's mesh (level 0) and ``levels`` successive uniform
    refinements, each solved and measured against the exact solution of the case's
    ``[exact]`` section (without one, against the finest level's solution), with the GIL
    released. ``compare="foundation"`` (consistent against lumped L) or ``"sampling"``
    (nodal against mollified φ) studies both variants; ``h_sweep=True`` runs the rigid
    limit instead, on the case's mesh refined ``levels`` times, with the stiffnesses
    ``h_values`` (default 10, 10², …, 10⁶).

    Returns a :class:`Study`: ``rows`` (one dict per level keyed by the columns of
    ``convergence.csv``, or of ``h_sweep.csv`` for the rigid limit; a missing value is
    None), ``variants`` (the rows of every variant by file name), ``exact``, and
    ``write(directory)``, which writes the command-line tool's files. Raises
    ``ValueError`` for bad data."""
    s = _native.convergence(
        _as_case(case),
        int(levels),
        compare,
        bool(h_sweep),
        None if h_values is None else [float(h) for h in h_values],
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
    """Solves the membrane problem on a mesh given as arrays (``vertices`` (n, 2),
    ``triangles`` (m, 3), optional ``regions`` (m,) tags and ``region_names``) or as a
    :class:`Mesh` (then ``triangles`` is left out and its levels serve multigrid).

    ``tension`` is t > 0; ``load`` f, ``shape`` φ and ``stiffness`` h (or ``"rigid"``) are
    numbers, expressions of x and y, dicts of region names (or tags) to those, or NumPy
    arrays of one value per vertex: their P1 interpolant enters the quadrature of f and h,
    and φ's values are its samples (nodal sampling only). A stiffness dict may make some
    regions ``"rigid"`` and others elastic.
    ``foundation`` is ``"consistent"`` or ``"lumped"``, ``sampling`` ``"nodal"`` or
    ``"mollified"`` (with ``epsilon``), ``method`` one of ``auto``, ``linear``,
    ``active-set``, ``qp``, ``coordinate``, ``multigrid``.

    Beyond the paper's frame: ``boundary_height`` g (the same kinds of data, a dict keyed
    by boundary region names such as ``"left"``, or an array) fixes u = g on the boundary
    except on the boundary regions listed in ``free``; ``lower_shape`` and
    ``lower_stiffness`` (with ``lower_foundation``, ``lower_sampling``) add a body below
    the membrane, whose fields the result gives as ``phi_low``, ``pressure_low``, ...

    Raises ``ValueError`` naming the argument for bad data and :class:`SolverError` when
    the certificate does not reach ``tolerance`` (``check=False`` returns the result
    instead)."""
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
    # NumPy arrays (one value per vertex) go to the library as they are.
    given: Dict[str, Any] = {"load": load, "shape": shape, "stiffness": stiffness}
    if boundary_height is not None:
        given["height"] = boundary_height
    if lower_shape is not None:
        given["lower_shape"] = lower_shape
        given["lower_stiffness"] = lower_stiffness
    for name, value in given.items():
        if isinstance(value, np.ndarray):
            a = np.ascontiguousarray(value, dtype=np.float64)
            if a.ndim != 1 or a.shape[0] != mesh.n_vertices:
                raise ValueError(
                    f"{name}: nodal values must have shape ({mesh.n_vertices},), one per "
                    f"vertex, got shape {value.shape}"
                )
            given[name] = a
    obstacle: Dict[str, Any] = {
        "shape": given["shape"],
        "stiffness": given["stiffness"],
        "foundation": foundation,
        "sampling": sampling,
    }
    if epsilon is not None:
        obstacle["epsilon"] = epsilon
    solver: Dict[str, Any] = {"method": method, "tolerance": tolerance}
    if max_iterations is not None:
        solver["max_iterations"] = max_iterations
    data: Dict[str, Any] = {
        "membrane": {"tension": tension, "load": given["load"]},
        "obstacle": obstacle,
        "solver": solver,
    }
    if boundary_height is not None or free:
        boundary: Dict[str, Any] = {}
        if boundary_height is not None:
            boundary["height"] = given["height"]
        if free:
            if isinstance(free, str):
                raise TypeError("free: give a list of boundary region names")
            boundary["free"] = [str(f) for f in free]
        data["boundary"] = boundary
    if lower_shape is not None:
        data["lower"] = {
            "shape": given["lower_shape"],
            "stiffness": given["lower_stiffness"],
            "foundation": lower_foundation,
            "sampling": lower_sampling,
        }
    # Errors name the case's keys; this function's arguments are named after them.
    try:
        result = _native.solve_on(mesh, data, "mesh")
    except ValueError as e:
        raise ValueError(_rename_keys(str(e))) from None
    return _check(result) if check else result


def solve_many(
    cases: Iterable[CaseLike],
    executor: Any = None,
    *,
    check: bool = True,
) -> List[Result]:
    """Solves every case and returns the results in the order of ``cases``.

    ``executor`` is anything with the ``concurrent.futures`` interface (``submit``
    returning futures with ``result()``): a ``ProcessPoolExecutor``, a
    ``dask.distributed.Client`` (a ``LocalCluster`` or a Slurm cluster of
    dask-jobqueue), Ray's or submitit's executors. Without one the cases are solved here,
    one after the other (each solve uses all cores). Cases and results pickle, so they
    cross processes and machines; mesh files must be readable where the case is solved.

    With ``check`` a case that does not converge raises its :class:`SolverError` (the
    remaining futures are cancelled); ``check=False`` returns its result instead."""
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
