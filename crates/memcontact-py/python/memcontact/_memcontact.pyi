"""Type stub of the native module (the Rust part of memcontact): the classes the package
exports (:class:`Case`, :class:`Mesh`, :class:`Result`, :class:`Sweep`, :class:`Study`,
:class:`Adapt`) and the functions the package's own functions call."""

from os import PathLike
from typing import Any, Dict, List, Literal, Mapping, Optional, Sequence, Tuple, Union, final

import numpy as np
import numpy.typing as npt

__version__: str
__all__ = [
    "Adapt",
    "Case",
    "Fit",
    "FitProblem",
    "Mesh",
    "Result",
    "Sensitivities",
    "Study",
    "Sweep",
    "__version__",
    "_case_table",
    "_mesh_from_state",
    "_result_from_state",
    "_toml_value",
    "adapt",
    "adapt_on",
    "case_on",
    "convergence",
    "disk",
    "fit",
    "fit_problem",
    "polygon",
    "read_gmsh",
    "rectangle",
    "sensitivities",
    "solve",
    "solve_on",
    "sweep",
]

#: The encodings of ``solution.vtu`` (``[output] vtu``): raw appended binary, text, or
#: zlib-compressed appended binary.
_VtuEncoding = Literal["binary", "ascii", "compressed"]

@final
class Case:
    """A case: the problem (mesh, membrane, obstacle, and optionally boundary and lower),
    the solver settings, the output options and the exact solution, exactly as a case file
    holds them. Immutable; pickles; equal cases compare equal.

    Parameters
    ----------
    data : dict or Case
        The case file's sections (``mesh``, ``membrane``, ``obstacle``, optionally
        ``boundary``, ``lower``, ``solver``, ``output``, ``units``, ``exact``, ``sweep``,
        ``load_case``, ``adapt``) and keys; a section may be its dataclass
        (:class:`memcontact.Membrane`, ...). A relative mesh ``file`` is relative to the
        current directory.
    label : str, optional
        The case's name in ``summary.json`` (default ``"case"``).

    Raises
    ------
    ValueError
        Unknown keys and bad values, naming the key, before any work.
    TypeError
        ``data`` is not a dict.
    """

    def __new__(
        cls, data: Union[Mapping[str, Any], "Case"], label: Optional[str] = None
    ) -> "Case": ...
    @staticmethod
    def load(path: Union[str, PathLike[str]], overrides: Sequence[str] = ...) -> "Case":
        """Reads a case file.

        Parameters
        ----------
        path : str or os.PathLike
            The case file; relative mesh paths are relative to it.
        overrides : sequence of str
            ``"key=value"`` overrides (dotted keys, TOML values), applied first.

        Returns
        -------
        Case
            The case.

        Raises
        ------
        ValueError
            Bad data, naming the file, the line and the key.
        FileNotFoundError
            No such file.
        """
        ...
    @staticmethod
    def from_toml(text: str, label: Optional[str] = None) -> "Case":
        """A case from TOML text (a case file's content).

        Parameters
        ----------
        text : str
            The case file's text; relative mesh paths are relative to the current
            directory.
        label : str, optional
            The case's name.

        Returns
        -------
        Case
            The case.

        Raises
        ------
        ValueError
            Bad data, naming the line and the key.
        """
        ...
    def to_dict(self) -> Dict[str, Any]:
        """The case as a dict.

        Returns
        -------
        dict
            Every section, defaults filled in; ``Case(case.to_dict())`` is an equal case.
        """
        ...
    def to_toml(self) -> str:
        """The case as TOML text.

        Returns
        -------
        str
            A case file.
        """
        ...
    @property
    def label(self) -> str:
        """The case's name in ``summary.json`` (its file, or what the caller chose)."""
        ...
    def with_label(self, label: str) -> "Case":
        """A copy with another label.

        Parameters
        ----------
        label : str
            The new name.

        Returns
        -------
        Case
            The copy.
        """
        ...
    def __eq__(self, other: object, /) -> bool: ...
    def __dask_tokenize__(self) -> Tuple[str, str]: ...

@final
class Mesh:
    """A triangulation and the coarser levels it was refined from (multigrid uses them).
    Immutable; pickles. Its arrays are read-only and made once.

    Parameters
    ----------
    vertices : array_like, shape (n, 2)
        Coordinates (float64).
    triangles : array_like, shape (m, 3)
        Vertex indices (integers).
    regions : array_like, shape (m,), optional
        Region tags (default all 0).
    region_names : dict of int to str, optional
        Names of tags (the keys of region tables).
    boundary_edges : array_like, shape (k, 2), optional
        Vertex pairs of tagged boundary edges (untagged boundary edges form the region
        ``default``).
    boundary_tags : array_like, shape (k,), optional
        Their boundary region tags.
    boundary_names : dict of int to str, optional
        Names of boundary tags (the keys of ``[boundary]`` tables and ``free``).

    Raises
    ------
    ValueError
        A mesh that is not valid: non-finite coordinates, degenerate, inverted or
        duplicate triangles, unused vertices, a boundary that is not manifold, tagged edges
        off the boundary, arrays of the wrong shape or type. Clockwise triangles are
        reoriented.
    """

    def __new__(
        cls,
        vertices: npt.ArrayLike,
        triangles: npt.ArrayLike,
        regions: Optional[npt.ArrayLike] = None,
        region_names: Optional[Mapping[int, str]] = None,
        boundary_edges: Optional[npt.ArrayLike] = None,
        boundary_tags: Optional[npt.ArrayLike] = None,
        boundary_names: Optional[Mapping[int, str]] = None,
    ) -> "Mesh": ...
    @staticmethod
    def from_meshio(mesh: Any, regions: Optional[str] = None) -> "Mesh":
        """A mesh from a ``meshio.Mesh`` (e.g. ``meshio.read("site.msh")``).

        Its 3-node triangles make the mesh (points unused by any triangle are dropped, the
        others keep their order; z must be the same everywhere). Gmsh physical surfaces
        (the cell data ``gmsh:physical`` and the names of ``field_data``) become named
        regions; line cells of physical curves on the boundary become boundary regions
        (lines inside the mesh are skipped with a warning), so that ``[boundary]`` tables
        and ``free`` can name them. A result file's ``region`` cell data serve too.

        Parameters
        ----------
        mesh : meshio.Mesh
            The mesh.
        regions : str, optional
            The cell data holding the region tags (default ``gmsh:physical``, else
            ``region``, else none).

        Returns
        -------
        Mesh
            The mesh.

        Raises
        ------
        ValueError
            Cells other than triangles, lines and vertices, no triangles, a mesh that is
            not plane or not valid.
        TypeError
            Not a meshio mesh.
        """
        ...
    @property
    def vertices(self) -> npt.NDArray[np.float64]:
        """Vertex coordinates, shape (n, 2), float64 (a read-only view)."""
        ...
    @property
    def triangles(self) -> npt.NDArray[np.int64]:
        """Triangles as vertex indices, shape (m, 3), int64, counter-clockwise
        (read-only)."""
        ...
    @property
    def regions(self) -> npt.NDArray[np.int64]:
        """The region tag of every triangle, shape (m,), int64 (read-only)."""
        ...
    @property
    def region_names(self) -> Dict[int, str]:
        """The names of the region tags that have one."""
        ...
    @property
    def boundary(self) -> npt.NDArray[np.bool_]:
        """Whether each vertex lies on the boundary, shape (n,), bool (read-only)."""
        ...
    @property
    def boundary_edges(self) -> npt.NDArray[np.int64]:
        """The tagged boundary edges (vertex pairs), shape (k, 2), int64 (read-only)."""
        ...
    @property
    def boundary_tags(self) -> npt.NDArray[np.int64]:
        """The boundary region tag of each edge of ``boundary_edges``, shape (k,), int64
        (read-only)."""
        ...
    @property
    def boundary_names(self) -> Dict[int, str]:
        """The names of the boundary region tags (``{1: "bottom", 2: "right", 3: "top",
        4: "left"}`` for a rectangle)."""
        ...
    @property
    def n_vertices(self) -> int:
        """The number of vertices."""
        ...
    @property
    def n_triangles(self) -> int:
        """The number of triangles."""
        ...
    @property
    def levels(self) -> int:
        """The number of nested levels (1 for a mesh that was not refined)."""
        ...
    @property
    def circle(self) -> Optional[Tuple[float, float, float]]:
        """The circle a disc mesh approximates, ``(cx, cy, radius)``, or None."""
        ...
    def quality(self) -> Dict[str, float]:
        """Quality figures.

        Returns
        -------
        dict
            vertices, triangles, unknowns, l_n (largest diameter), s_n (largest diameter
            over inscribed diameter), min_angle_deg, area.
        """
        ...
    def refine(self, times: int = 1) -> "Mesh":
        """The mesh refined uniformly.

        Parameters
        ----------
        times : int
            How many times each triangle is cut into four.

        Returns
        -------
        Mesh
            The refined mesh, with its levels.

        Raises
        ------
        ValueError
            Too many refinements.
        """
        ...
    def plot(self, ax: Any = None, **kwargs: Any) -> Any:
        """Draws the mesh with matplotlib: the triangles' edges, the regions filled in
        light colours (when there are several) and the boundary regions coloured, with
        their names in the legend.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Where to draw (default: a new figure).
        **kwargs
            ``regions=False`` and ``boundary=False`` leave those out, ``title`` replaces
            the title; the rest goes to ``Axes.triplot``.

        Returns
        -------
        matplotlib.axes.Axes
            The Axes drawn on.

        Raises
        ------
        ImportError
            matplotlib is not installed (``pip install matplotlib``).
        """
        ...
    def __len__(self) -> int: ...

@final
class Result:
    """The result of one solve: the fields over the mesh's vertices (read-only NumPy
    views, made once), status, report and summary; pictures, tables and interoperability
    for notebooks. Immutable; pickles."""

    @property
    def u(self) -> npt.NDArray[np.float64]:
        """The deflection u at every vertex (the heights g on the fixed boundary)."""
        ...
    @property
    def phi(self) -> npt.NDArray[np.float64]:
        """The sampled obstacle surface φₙ at every vertex."""
        ...
    @property
    def penetration(self) -> npt.NDArray[np.float64]:
        """The penetration (u − φ)⁺ at every vertex (0 where the obstacle cannot touch)."""
        ...
    @property
    def pressure(self) -> npt.NDArray[np.float64]:
        """The contact pressure h (u − φ)⁺ (rigid obstacle: contact force per nodal
        area)."""
        ...
    @property
    def contact_force(self) -> npt.NDArray[np.float64]:
        """The nodal contact force X₁ = D − SU on M (0 elsewhere)."""
        ...
    @property
    def state(self) -> npt.NDArray[np.int8]:
        """The vertex state: −1 clear, 0 touching (U = φ), 1 penetrating (int8)."""
        ...
    @property
    def phi_low(self) -> Optional[npt.NDArray[np.float64]]:
        """The body below's sampled surface φ_low (None without a body below)."""
        ...
    @property
    def penetration_low(self) -> Optional[npt.NDArray[np.float64]]:
        """The penetration into the body below (φ_low − u)⁺ (None without one)."""
        ...
    @property
    def pressure_low(self) -> Optional[npt.NDArray[np.float64]]:
        """The body below's contact pressure, pushing up (None without one)."""
        ...
    @property
    def contact_force_low(self) -> Optional[npt.NDArray[np.float64]]:
        """The body below's nodal contact force, pushing up (None without one)."""
        ...
    @property
    def state_low(self) -> Optional[npt.NDArray[np.int8]]:
        """The state toward the body below: −1 clear, 0 touching, 1 sunk into it (int8;
        None without one)."""
        ...
    @property
    def estimator(self) -> Optional[npt.NDArray[np.float64]]:
        """For the last step of an adaptive loop: η_T per triangle (energy-norm units);
        None otherwise."""
        ...
    @property
    def status(self) -> str:
        """How the solve ended: ``converged``, ``rounding_floor``, ``iteration_limit``,
        ``stalled`` or ``numerical_failure``."""
        ...
    @property
    def converged(self) -> bool:
        """Whether the certificate reached the tolerance."""
        ...
    @property
    def accepted(self) -> bool:
        """Whether the settings accept the outcome (what ``solve`` checks)."""
        ...
    @property
    def message(self) -> Optional[str]:
        """What went wrong, for a solve that was not accepted (None otherwise)."""
        ...
    @property
    def method(self) -> str:
        """The method that produced the answer."""
        ...
    @property
    def iterations(self) -> int:
        """Iterations of that method."""
        ...
    @property
    def energy(self) -> float:
        """J(U), the energy of Problem 2b."""
        ...
    @property
    def kkt_residual(self) -> float:
        """The scaled KKT residual (the larger of the residuals of 2e and 2f)."""
        ...
    @property
    def report(self) -> Dict[str, Any]:
        """Status, requested and used method and why, iterations, energy, certificate,
        tolerance, history, phase times (a new dict)."""
        ...
    @property
    def summary(self) -> Dict[str, Any]:
        """The scalars of ``summary.json`` (the same keys; ``files`` is filled in by
        ``write``)."""
        ...
    @property
    def mesh(self) -> Mesh:
        """The solved mesh (the same object at every access)."""
        ...
    @property
    def case(self) -> Case:
        """The case solved."""
        ...
    @property
    def warnings(self) -> List[str]:
        """Warnings from reading the mesh."""
        ...
    @property
    def step(self) -> Optional[int]:
        """For a step of a sweep: its index among the case's steps (None otherwise)."""
        ...
    def write(
        self,
        directory: Union[str, PathLike[str]],
        force: bool = False,
        vtu: Optional[_VtuEncoding] = None,
        pictures: bool = True,
    ) -> Dict[str, Any]:
        """Writes the command-line tool's result set, atomically.

        Parameters
        ----------
        directory : str or os.PathLike
            Where: ``solution.vtu``, ``nodes.csv``, the pictures of ``[output] plots``
            and ``summary.json``.
        force : bool
            Replace a directory that holds other files.
        vtu : {"binary", "ascii", "compressed"}, optional
            The encoding of ``solution.vtu`` (default the case's ``[output] vtu``).
        pictures : bool
            Draw the pictures.

        Returns
        -------
        dict
            The summary written.

        Raises
        ------
        ValueError
            A directory holding other files (without ``force``), a bad ``vtu``.
        OSError
            The files cannot be written.
        """
        ...
    def matrices(self) -> Dict[str, Any]:
        """The assembled discrete problem over the unknowns (docs/theory.md#discrete-model,
        docs/theory.md#extensions), so that scipy can check Problems 2e/2f or post-process
        the answer.

        The unknowns are numbered in the order of the user's vertices: unknown ``k`` is
        vertex ``unknowns[k]``, so ``U = result.u[m["unknowns"]]``. U minimises
        ``J(V) = ½ VᵀSV − VᵀD + ½ pᵀLp`` with ``p = (V − φ)⁺`` on ``can_touch`` (and
        ``+ ½ qᵀ L_low q`` with ``q = (φ_low − V)⁺`` with a body below); 2f reads
        ``r = SU − D ≤ 0``, ``r + Lp ≥ 0``, ``pᵀ(r + Lp) = 0``, ``rᵀ(p − (U − φ)) = 0``.

        Returns
        -------
        dict
            ``S`` : scipy.sparse.csr_array
                The stiffness ``t ∫ ∇gᵢ·∇gⱼ``.
            ``L`` : scipy.sparse.csr_array or None
                The foundation matrix ``∫ h gᵢ gⱼ`` (consistent), or the lumped diagonal
                ``∫ h gᵢ`` as a diagonal matrix. None for an obstacle that is rigid
                everywhere: then 2e is ``U ≤ φ``, ``X₁ = D − SU ≥ 0``,
                ``X₁ᵀ(φ − U) = 0``.
            ``D`` : ndarray
                The load ``∫ f gᵢ`` minus the lifting ``S_fix G`` of the boundary heights.
            ``phi`` : ndarray
                The sampled obstacle φ at the unknowns.
            ``unknowns`` : ndarray of int64
                The vertex of each unknown (increasing).
            ``can_touch`` : ndarray of bool
                M: the unknowns the obstacle can touch.
            ``rigid`` : ndarray of bool
                The unknowns the obstacle holds rigidly (``U ≤ φ``).
            ``foundation`` : str
                ``consistent``, ``lumped`` or ``rigid``.
            ``L_low``, ``phi_low``, ``can_touch_low``, ``rigid_low``, ``foundation_low``
                The same for the body below (``U ≥ φ_low`` where rigid), when there is
                one.

        Raises
        ------
        ImportError
            scipy is not installed (``pip install scipy``).
        """
        ...
    def plot(self, field: Any = "u", ax: Any = None, **kwargs: Any) -> Any:
        """Draws a field on the mesh with matplotlib, each body's contact outlined, with a
        colour bar.

        Parameters
        ----------
        field : str or array_like
            A field's name: ``u``, ``phi``, ``penetration``, ``pressure``,
            ``contact_force``, ``state``, ``gap`` (φ − u, the gap to the obstacle), with a
            body below ``phi_low``, ``penetration_low``, ``pressure_low``,
            ``contact_force_low``, ``state_low``, ``gap_low`` (u − φ_low), and the cell
            fields ``region`` and (after an adaptive loop) ``estimator``; or an array of one
            value per vertex or per triangle.
        ax : matplotlib.axes.Axes, optional
            Where to draw (default: a new figure).
        **kwargs
            ``kind`` (``"tripcolor"``, the default, or ``"tricontourf"``), ``levels``
            (for tricontourf), ``contact=False`` (no outlines), ``colorbar=False``,
            ``title``; the rest goes to matplotlib (``cmap``, ``vmin``, ``shading``, ...).
            The contact with the obstacle is outlined in solid black, the contact with the
            body below in dashed red, each named in the legend.

        Returns
        -------
        matplotlib.axes.Axes
            The Axes drawn on.

        Raises
        ------
        ValueError
            An unknown field, an array of the wrong size, a field of a body the case does
            not have.
        TypeError
            An array that does not hold real numbers.
        ImportError
            matplotlib is not installed (``pip install matplotlib``).
        """
        ...
    def to_meshio(self) -> Any:
        """The result as a ``meshio.Mesh``: points (z = 0), triangles, every point field
        of ``nodes.csv`` (``u``, ``phi``, ``penetration``, ``pressure``,
        ``contact_force``, ``state``, and the ``_low`` ones with a body below) and the
        cell fields ``region`` and (after an adaptive loop) ``estimator``, with the types
        of ``solution.vtu``. The arrays are copies: the mesh is the caller's.

        Returns
        -------
        meshio.Mesh
            The mesh and its fields.

        Raises
        ------
        ImportError
            meshio is not installed (``pip install meshio``).
        """
        ...
    def to_pyvista(self) -> Any:
        """The result as a ``pyvista.UnstructuredGrid`` of triangles with the point and
        cell fields of :meth:`to_meshio`.

        Returns
        -------
        pyvista.UnstructuredGrid
            The grid.

        Raises
        ------
        ImportError
            pyvista is not installed (``pip install pyvista``).
        """
        ...
    def _repr_html_(self) -> str:
        """The notebook's summary: status, method, iterations, KKT residual, energy,
        contact area and force of each body."""
        ...
    def _repr_png_(self) -> bytes:
        """The deflection picture of the result set (``deflection.png``), drawn in
        memory."""
        ...

@final
class Sweep:
    """The solved steps of a case's ``[sweep]`` or ``[[load_case]]`` entries."""

    @property
    def results(self) -> List[Result]:
        """One result per step solved, in order (the last is the failed step when the
        sweep stopped early)."""
        ...
    @property
    def rows(self) -> List[Dict[str, Any]]:
        """The rows of ``sweep.csv`` (keys: the ``columns``), one per step solved."""
        ...
    @property
    def columns(self) -> List[str]:
        """The columns of ``sweep.csv``, in order."""
        ...
    @property
    def parameter(self) -> str:
        """``load_factor``, ``stiffness_factor``, ``tension``, ``obstacle_offset`` or
        ``load_case``."""
        ...
    @property
    def names(self) -> List[str]:
        """The names of all the case's steps (``step-000``, ... or the load cases')."""
        ...
    @property
    def values(self) -> List[float]:
        """The values of all the case's steps (a load case's: its load factor)."""
        ...
    @property
    def accepted(self) -> bool:
        """Whether every step was solved and accepted."""
        ...
    @property
    def message(self) -> Optional[str]:
        """Why the sweep stopped early (None when it did not)."""
        ...
    @property
    def case(self) -> Case:
        """The case swept."""
        ...
    def write(
        self,
        directory: Union[str, PathLike[str]],
        force: bool = False,
        vtu: Optional[_VtuEncoding] = None,
        pictures: bool = True,
    ) -> List[Dict[str, Any]]:
        """Writes the command-line tool's result set, atomically.

        Parameters
        ----------
        directory : str or os.PathLike
            Where: a directory per step solved, ``sweep.csv``, ``sweep.png``.
        force : bool
            Replace a directory that holds other files.
        vtu : {"binary", "ascii", "compressed"}, optional
            The encoding of ``solution.vtu``.
        pictures : bool
            Draw the pictures.

        Returns
        -------
        list of dict
            The steps' summaries.

        Raises
        ------
        ValueError
            A directory holding other files (without ``force``).
        """
        ...
    def to_pandas(self) -> Any:
        """The rows as a DataFrame with the columns of ``sweep.csv``.

        Returns
        -------
        pandas.DataFrame
            One row per step solved.

        Raises
        ------
        ImportError
            pandas is not installed (``pip install pandas``).
        """
        ...
    def _repr_html_(self) -> str:
        """The notebook's summary and the table of rows."""
        ...
    def __len__(self) -> int: ...
    def __getitem__(self, key: int, /) -> Result: ...

@final
class Study:
    """A convergence study (or the rigid-limit sweep) of a case."""

    @property
    def kind(self) -> str:
        """``"convergence"`` or ``"h sweep"``."""
        ...
    @property
    def rows(self) -> List[Dict[str, Any]]:
        """The rows of ``convergence.csv`` (of the first variant when comparing) or of
        ``h_sweep.csv``, keyed by its columns (a missing value is None)."""
        ...
    @property
    def columns(self) -> List[str]:
        """The columns of ``convergence.csv`` (or ``h_sweep.csv``), in order."""
        ...
    @property
    def variants(self) -> Dict[str, List[Dict[str, Any]]]:
        """The rows of every variant by its file name."""
        ...
    @property
    def exact(self) -> Optional[str]:
        """The exact solution the errors are measured against (None: the finest
        level's)."""
        ...
    @property
    def warnings(self) -> List[str]:
        """Warnings from reading the mesh."""
        ...
    def write(
        self, directory: Union[str, PathLike[str]], force: bool = False, pictures: bool = True
    ) -> List[str]:
        """Writes the files ``memcontact convergence`` writes, atomically.

        Parameters
        ----------
        directory : str or os.PathLike
            Where: the CSV files, ``convergence.png`` or ``h_sweep.png``,
            ``manifest.json``.
        force : bool
            Replace a directory that holds other files.
        pictures : bool
            Draw the pictures.

        Returns
        -------
        list of str
            The names of the files written.

        Raises
        ------
        ValueError
            A directory holding other files (without ``force``).
        """
        ...
    def to_pandas(self, variant: Optional[str] = None) -> Any:
        """The rows of one CSV file as a DataFrame with its columns (a missing value is
        NaN).

        Parameters
        ----------
        variant : str, optional
            A file name of ``variants`` (default: the first, the file of ``rows``).

        Returns
        -------
        pandas.DataFrame
            One row per level (or stiffness).

        Raises
        ------
        ValueError
            An unknown variant.
        ImportError
            pandas is not installed (``pip install pandas``).
        """
        ...
    def _repr_html_(self) -> str:
        """The notebook's summary and the table of rows."""
        ...
    def __len__(self) -> int: ...

@final
class Adapt:
    """The steps of an adaptive loop (a case with ``[adapt]``) and its final result."""

    @property
    def rows(self) -> List[Dict[str, Any]]:
        """The rows of ``adapt.csv`` (step, vertices, unknowns, estimator, energy,
        contact_area, iterations, kkt_residual, seconds), one per step."""
        ...
    @property
    def columns(self) -> List[str]:
        """The columns of ``adapt.csv``, in order."""
        ...
    @property
    def result(self) -> Result:
        """The last step's result, on the final mesh (with its ``estimator``)."""
        ...
    @property
    def mesh(self) -> Mesh:
        """The final mesh (every step's mesh is one of its levels)."""
        ...
    @property
    def estimator(self) -> npt.NDArray[np.float64]:
        """η_T of the last step, one per triangle of the final mesh (read-only;
        ``result.estimator``)."""
        ...
    @property
    def totals(self) -> Dict[str, Any]:
        """The loop's totals as in ``summary.json`` (``adapt_steps``, ``adapt_stop``,
        ...)."""
        ...
    @property
    def stop(self) -> str:
        """Why the loop stopped: ``tolerance``, ``steps``, ``max_vertices``,
        ``not_accepted``, ``estimator_not_finite`` or ``memory``."""
        ...
    @property
    def interpolated(self) -> List[str]:
        """The data given per vertex that were interpolated onto new vertices."""
        ...
    @property
    def message(self) -> Optional[str]:
        """What stopped the loop early, or None."""
        ...
    @property
    def accepted(self) -> bool:
        """Whether the last step was accepted by the settings."""
        ...
    @property
    def case(self) -> Case:
        """The case run (with its ``[adapt]`` section)."""
        ...
    def write(
        self,
        directory: Union[str, PathLike[str]],
        force: bool = False,
        vtu: Optional[_VtuEncoding] = None,
        pictures: bool = True,
    ) -> Dict[str, Any]:
        """Writes the command-line tool's result set, atomically.

        Parameters
        ----------
        directory : str or os.PathLike
            Where: the final step's files with the estimator per triangle, ``adapt.csv``,
            ``mesh.png``, ``summary.json``.
        force : bool
            Replace a directory that holds other files.
        vtu : {"binary", "ascii", "compressed"}, optional
            The encoding of ``solution.vtu``.
        pictures : bool
            Draw the pictures.

        Returns
        -------
        dict
            The summary.

        Raises
        ------
        ValueError
            A directory holding other files (without ``force``).
        """
        ...
    def to_pandas(self) -> Any:
        """The rows as a DataFrame with the columns of ``adapt.csv``.

        Returns
        -------
        pandas.DataFrame
            One row per step.

        Raises
        ------
        ImportError
            pandas is not installed (``pip install pandas``).
        """
        ...
    def _repr_html_(self) -> str:
        """The notebook's summary and the table of rows."""
        ...
    def __len__(self) -> int: ...

def solve(case: Case) -> Result: ...
def adapt(case: Case) -> Adapt: ...
def adapt_on(mesh: Mesh, data: Mapping[str, Any], label: Optional[str] = None) -> Adapt: ...
def convergence(
    case: Case,
    levels: int,
    compare: Optional[str] = None,
    h_sweep: bool = False,
    h_values: Optional[Sequence[float]] = None,
) -> Study: ...
def sweep(case: Case, warm: bool = True) -> Sweep: ...
def solve_on(mesh: Mesh, data: Mapping[str, Any], label: Optional[str] = None) -> Result: ...
def rectangle(
    x0: float = 0.0,
    y0: float = 0.0,
    x1: float = 1.0,
    y1: float = 1.0,
    nx: int = 16,
    ny: Optional[int] = None,
    diagonal: str = "right",
) -> Mesh: ...
def disk(
    center: Tuple[float, float] = ..., radius: float = 1.0, size: Optional[float] = None
) -> Mesh: ...
def polygon(
    outer: Sequence[Tuple[float, float]],
    size: float,
    holes: Optional[Sequence[Sequence[Tuple[float, float]]]] = None,
    regions: Optional[Sequence[Tuple[str, Sequence[Tuple[float, float]]]]] = None,
    min_angle: float = 25.0,
) -> Mesh: ...
def read_gmsh(path: Union[str, PathLike[str]]) -> Tuple[Mesh, List[str]]: ...
def _mesh_from_state(state: Dict[str, Any]) -> Mesh: ...
def _result_from_state(state: Dict[str, Any]) -> Result: ...
def _toml_value(value: Any) -> str: ...
def _case_table(path: Union[str, PathLike[str]]) -> Dict[str, Any]: ...

@final
class Sensitivities:
    """The derivatives of a case's outputs in its parameters (docs/sensitivities.md)."""

    @property
    def outputs(self) -> List[str]:
        """The outputs' names, the rows of ``jacobian``."""
        ...
    @property
    def parameters(self) -> List[str]:
        """The parameters' case keys, the columns of ``jacobian``."""
        ...
    @property
    def kinds(self) -> List[str]:
        """``value``, ``factor`` or ``offset`` for each parameter."""
        ...
    @property
    def parameter_values(self) -> npt.NDArray[np.float64]:
        """The parameters' values in the case (1 for a factor, 0 for an offset)."""
        ...
    @property
    def values(self) -> npt.NDArray[np.float64]:
        """The outputs' values."""
        ...
    @property
    def jacobian(self) -> npt.NDArray[np.float64]:
        """dQ/dp, outputs × parameters."""
        ...
    @property
    def derivative_plus(self) -> npt.NDArray[np.float64]:
        """The derivative in the direction +δp, outputs × parameters."""
        ...
    @property
    def derivative_minus(self) -> npt.NDArray[np.float64]:
        """Minus the derivative in the direction −δp, outputs × parameters."""
        ...
    @property
    def nonsmooth(self) -> npt.NDArray[np.bool_]:
        """Where the one-sided derivatives differ, outputs × parameters."""
        ...
    @property
    def elasticity(self) -> npt.NDArray[np.float64]:
        """(p/Q) dQ/dp, outputs × parameters (NaN for an offset, p = 0 or Q = 0)."""
        ...
    @property
    def influence(self) -> Dict[str, npt.NDArray[np.float64]]:
        """The influence maps over the vertices (``dJ_dh``, ``dsensor_NAME_dh``, ...)."""
        ...
    @property
    def biactive(self) -> int:
        """The number of biactive vertices."""
        ...
    @property
    def biactive_vertices(self) -> List[int]:
        """The biactive vertices."""
        ...
    @property
    def mode(self) -> str:
        """``adjoint``, ``tangent`` or ``one_sided``."""
        ...
    @property
    def solves(self) -> List[Dict[str, Any]]:
        """Every linear solve (what, solver, iterations, residual, seconds)."""
        ...
    @property
    def result(self) -> Result:
        """The solve the derivatives were taken at."""
        ...
    @property
    def columns(self) -> List[str]:
        """The columns of ``rows``: those of ``sensitivity.csv``, then ``nonsmooth`` and
        ``kind`` (the same as ``biactive`` and ``parameter_kind``, under their earlier
        names)."""
        ...
    @property
    def rows(self) -> List[Dict[str, Any]]:
        """The rows of ``sensitivity.csv``, one per output and parameter (None where the
        file's cell is empty)."""
        ...
    def write(
        self,
        directory: Union[str, PathLike[str]],
        force: bool = False,
        vtu: Optional[_VtuEncoding] = None,
        pictures: bool = True,
    ) -> Dict[str, Any]:
        """Writes the command-line tool's result set (with ``sensitivity.csv`` and the
        influence maps), atomically; returns the summary."""
        ...
    def to_pandas(self) -> Any:
        """The rows as a DataFrame."""
        ...

@final
class Fit:
    """A fit of case parameters to measured deflections (``fit.json``)."""

    @property
    def names(self) -> List[str]:
        """The fitted case keys, in order."""
        ...
    @property
    def parameters(self) -> Dict[str, float]:
        """Key -> fitted value."""
        ...
    @property
    def values(self) -> npt.NDArray[np.float64]:
        """The fitted values, in the order of ``names``."""
        ...
    @property
    def start(self) -> npt.NDArray[np.float64]:
        """The start values."""
        ...
    @property
    def std_errors(self) -> npt.NDArray[np.float64]:
        """The standard errors."""
        ...
    @property
    def correlation(self) -> npt.NDArray[np.float64]:
        """The correlation matrix."""
        ...
    @property
    def singular_values(self) -> npt.NDArray[np.float64]:
        """The singular values of the scaled Jacobian."""
        ...
    @property
    def bounds(self) -> npt.NDArray[np.float64]:
        """One ``[min, max]`` row per parameter."""
        ...
    @property
    def condition_number(self) -> float:
        """The condition number of the scaled Jacobian."""
        ...
    @property
    def rms(self) -> float:
        """The root-mean-square of the weighted residuals."""
        ...
    @property
    def iterations(self) -> int:
        """Accepted iterations."""
        ...
    @property
    def solves(self) -> int:
        """Forward solves, trial steps included."""
        ...
    @property
    def converged(self) -> bool:
        """Whether the fit converged."""
        ...
    @property
    def stop(self) -> str:
        """Why it stopped."""
        ...
    @property
    def warning(self) -> Optional[str]:
        """The identifiability warning (None when the parameters are identifiable)."""
        ...
    @property
    def measurements(self) -> List[Dict[str, Any]]:
        """The measurements and the deflections computed there."""
        ...
    @property
    def summary(self) -> Dict[str, Any]:
        """Everything of the fit as a dict."""
        ...
    @property
    def result(self) -> Result:
        """The solve at the fitted (or best) parameters."""
        ...
    @property
    def case(self) -> Case:
        """The case with the fitted values."""
        ...
    @property
    def columns(self) -> List[str]:
        """The columns of ``rows`` (those of ``fit.csv``)."""
        ...
    @property
    def rows(self) -> List[Dict[str, Any]]:
        """The accepted iterates, as the rows of ``fit.csv``."""
        ...
    def write(
        self,
        directory: Union[str, PathLike[str]],
        force: bool = False,
        vtu: Optional[_VtuEncoding] = None,
        pictures: bool = True,
    ) -> Dict[str, Any]:
        """Writes the command-line tool's result set (with ``fit.json``, ``fit.csv`` and
        ``fit.png``), atomically; returns the summary."""
        ...
    def to_pandas(self) -> Any:
        """The iterates as a DataFrame."""
        ...

@final
class FitProblem:
    """A fit's model: residuals and their exact Jacobian, for an optimiser of one's own."""

    @property
    def names(self) -> List[str]:
        """The fitted case keys, in order."""
        ...
    @property
    def x0(self) -> npt.NDArray[np.float64]:
        """The start (the case's values)."""
        ...
    @property
    def bounds(self) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """``(lower, upper)``."""
        ...
    @property
    def measurements(self) -> List[str]:
        """The measured sensors' names (the rows of the residuals)."""
        ...
    @property
    def solves(self) -> int:
        """Forward solves so far."""
        ...
    def residuals(self, p: Sequence[float]) -> npt.NDArray[np.float64]:
        """The weighted residuals (Q(p) − m)/σ."""
        ...
    def jacobian(self, p: Sequence[float]) -> npt.NDArray[np.float64]:
        """Their Jacobian in p, measurements × parameters."""
        ...
    def residuals_and_jacobian(
        self, p: Sequence[float]
    ) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """Both at once."""
        ...

def sensitivities(
    case: Case,
    outputs: Optional[Sequence[str]] = None,
    parameters: Optional[Sequence[str]] = None,
    influence: bool = True,
) -> Tuple[Optional[Sensitivities], Result]: ...
def fit(case: Case) -> Fit: ...
def fit_problem(case: Case) -> FitProblem: ...
def case_on(mesh: Mesh, data: Mapping[str, Any], label: Optional[str] = None) -> Case: ...
