"""The notebook side of the result types: pictures (matplotlib), tables (pandas), HTML
summaries, meshes in and out (meshio, pyvista) and the assembled matrices (scipy.sparse).

Each optional package is imported only by the function that needs it, with an
``ImportError`` that says what to install. The native classes' methods (``Result.plot``,
``Sweep.to_pandas``, ``Mesh.from_meshio``, ...) call these functions; they are not part of
the public API themselves.
"""

from __future__ import annotations

import html
import importlib
import math
import warnings
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

#: The point fields of ``nodes.csv`` (after x and y) and of ``solution.vtu``, in order.
POINT_FIELDS = ("u", "phi", "penetration", "pressure", "contact_force", "state")
#: The point fields a body below adds.
LOWER_FIELDS = ("phi_low", "penetration_low", "pressure_low", "contact_force_low", "state_low")

#: How fields are named on colour bars.
_LABELS = {
    "u": "deflection u",
    "phi": "obstacle surface φ",
    "penetration": "penetration (u − φ)⁺",
    "pressure": "contact pressure",
    "contact_force": "nodal contact force",
    "state": "state (−1 clear, 0 touching, 1 penetrating)",
    "phi_low": "surface of the body below φ_low",
    "penetration_low": "penetration into the body below (φ_low − u)⁺",
    "pressure_low": "contact pressure of the body below",
    "contact_force_low": "nodal contact force of the body below",
    "state_low": "state toward the body below (−1 clear, 0 touching, 1 sunk in)",
    "gap": "gap to the obstacle φ − u",
    "gap_low": "gap to the body below u − φ_low",
    "estimator": "error estimator η_T",
    "region": "region tag",
}

#: The outline colours and names of each body's contact.
OBSTACLE_OUTLINE: Dict[str, Any] = {"colors": "black", "linestyles": "solid", "label": "contact with the obstacle"}
LOWER_OUTLINE: Dict[str, Any] = {"colors": "tab:red", "linestyles": "dashed", "label": "contact with the body below"}


def require(module: str, what: str, package: Optional[str] = None) -> Any:
    """``module`` imported, or an ``ImportError`` saying that ``what`` needs it and how to
    install it."""
    try:
        return importlib.import_module(module)
    except ImportError as e:
        name = package or module.split(".")[0]
        raise ImportError(
            f"{what} needs {name}, which is not installed: pip install {name}"
        ) from e


# ---------------------------------------------------------------------------------------
# Pictures.


def _field(r: Any, field: Any) -> Tuple[np.ndarray, str, str]:
    """The values of ``field`` on the result ``r``: (values, "point" or "cell", label)."""
    mesh = r.mesh
    n, m = mesh.n_vertices, mesh.n_triangles
    if isinstance(field, str):
        name = field
        if name in POINT_FIELDS or name in LOWER_FIELDS:
            values = getattr(r, name)
            if values is None:
                raise ValueError(f"field {name!r}: the case has no body below")
            return np.asarray(values, dtype=np.float64), "point", _LABELS[name]
        if name == "gap":
            return np.asarray(r.phi) - np.asarray(r.u), "point", _LABELS[name]
        if name == "gap_low":
            if r.phi_low is None:
                raise ValueError("field 'gap_low': the case has no body below")
            return np.asarray(r.u) - np.asarray(r.phi_low), "point", _LABELS[name]
        if name == "estimator":
            if r.estimator is None:
                raise ValueError(
                    "field 'estimator': only the result of an adaptive loop has one"
                )
            return np.asarray(r.estimator), "cell", _LABELS[name]
        if name == "region":
            return np.asarray(mesh.regions, dtype=np.float64), "cell", _LABELS[name]
        known = list(POINT_FIELDS) + ["gap", "region"]
        if r.phi_low is not None:
            known += list(LOWER_FIELDS) + ["gap_low"]
        if r.estimator is not None:
            known.append("estimator")
        raise ValueError(f"field {name!r} is unknown: choose one of {', '.join(known)}")
    if isinstance(field, (bytes, bool)) or field is None:
        raise TypeError(f"field: give a field's name or an array, got {type(field).__name__}")
    try:
        values = np.asarray(field)
    except Exception as e:  # an object NumPy cannot take
        raise TypeError(f"field: {type(field).__name__} is not an array of values") from e
    if values.dtype.kind not in "iuf":
        raise TypeError(f"field: an array of real numbers is needed, got dtype {values.dtype}")
    values = values.astype(np.float64)
    if values.shape == (n,):
        return values, "point", "value"
    if values.shape == (m,):
        return values, "cell", "value"
    raise ValueError(
        f"field: an array of one value per vertex ({n},) or per triangle ({m},) is needed, "
        f"got shape {values.shape}"
    )


def _outline(
    ax: Any,
    tri: Any,
    state: Optional[np.ndarray],
    depth: Optional[np.ndarray],
    style: Dict[str, Any],
) -> Any:
    """Draws the outline of a body's contact and returns a legend handle, or None when
    nothing or everything is in contact. An elastic body's contact is where the membrane
    penetrates it: the zero level of the P1 interpolant of the signed penetration
    ``depth`` (u − φ for the obstacle, φ_low − u for the body below; negative where the
    body cannot touch); a rigid body's, the line between the touching and the clear
    vertices."""
    if state is None or depth is None:
        return None
    state = np.asarray(state)
    contact = state >= 0
    if not (0 < contact.sum() < contact.size):
        return None
    from matplotlib.lines import Line2D

    if (state == 1).any():
        d = np.asarray(depth, dtype=np.float64)
        scale = max(float(np.max(np.abs(d))), 1e-300)
        # A clear vertex with u above φ is one the body does not cover.
        level = np.where(contact | (d < 0), d, -scale)
        value = 0.0
    else:
        level, value = contact.astype(np.float64), 0.5
    ax.tricontour(
        tri, level, levels=[value], colors=style["colors"], linestyles=style["linestyles"],
        linewidths=1.2,
    )
    return Line2D([], [], color=style["colors"], linestyle=style["linestyles"],
                  label=style["label"])


def _bar_size(v: np.ndarray) -> Dict[str, float]:
    """A colour bar as tall as a map of equal aspect (matplotlib's recipe: 4.6 % of the
    width per unit of the height-to-width ratio)."""
    if len(v) == 0:
        return {}
    dx, dy = np.ptp(v[:, 0]), np.ptp(v[:, 1])
    ratio = dy / dx if dx > 0 else 1.0
    return {"fraction": float(np.clip(0.046 * ratio, 0.02, 0.15)), "pad": 0.04}


def result_plot(
    r: Any,
    field: Any = None,
    ax: Any = None,
    *,
    kind: str = "tripcolor",
    contact: bool = True,
    colorbar: bool = True,
    levels: Any = 20,
    title: Optional[str] = None,
    **kwargs: Any,
) -> Any:
    """``Result.plot``: ``field`` drawn on the mesh, each body's contact outlined, a colour
    bar; returns the Axes."""
    plt = require("matplotlib.pyplot", "Result.plot", "matplotlib")
    from matplotlib.tri import Triangulation

    if field is None:
        field = "u"
    values, where, label = _field(r, field)
    if kind not in ("tripcolor", "tricontourf"):
        raise ValueError(f"kind must be 'tripcolor' or 'tricontourf', not {kind!r}")
    if where == "cell" and kind != "tripcolor":
        raise ValueError("a field per triangle is drawn with kind='tripcolor'")
    if ax is None:
        _, ax = plt.subplots()
    mesh = r.mesh
    v = mesh.vertices
    tri = Triangulation(v[:, 0], v[:, 1], mesh.triangles)
    if where == "cell":
        art = ax.tripcolor(tri, facecolors=values, **kwargs)
    elif kind == "tripcolor":
        kwargs.setdefault("shading", "gouraud")
        art = ax.tripcolor(tri, values, **kwargs)
    else:
        art = ax.tricontourf(tri, values, levels=levels, **kwargs)
    if colorbar:
        ax.figure.colorbar(art, ax=ax, label=label, **_bar_size(v))
    if contact:
        handles = [
            h
            for h in (
                _outline(ax, tri, r.state, np.asarray(r.u) - r.phi, OBSTACLE_OUTLINE),
                _outline(ax, tri, r.state_low,
                         None if r.phi_low is None else r.phi_low - np.asarray(r.u),
                         LOWER_OUTLINE),
            )
            if h is not None
        ]
        if handles:
            ax.legend(handles=handles, loc="best", fontsize="small")
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    if title is None:
        named = r.case.label not in ("mesh", "case")
        title = f"{r.case.label}: {label}" if named else label
    ax.set_title(title)
    return ax


def mesh_plot(
    mesh: Any,
    ax: Any = None,
    *,
    regions: bool = True,
    boundary: bool = True,
    title: Optional[str] = None,
    **kwargs: Any,
) -> Any:
    """``Mesh.plot``: the triangles' edges, the regions filled in light colours (when there
    are several) and the boundary regions coloured by name; returns the Axes."""
    plt = require("matplotlib.pyplot", "Mesh.plot", "matplotlib")
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Patch
    from matplotlib.tri import Triangulation

    if ax is None:
        _, ax = plt.subplots()
    v = mesh.vertices
    tri = Triangulation(v[:, 0], v[:, 1], mesh.triangles)
    handles: List[Any] = []
    tags = np.asarray(mesh.regions)
    distinct = np.unique(tags)
    if regions and distinct.size > 1:
        cmap = plt.get_cmap("Pastel1" if distinct.size <= 9 else "tab20")
        index = np.searchsorted(distinct, tags)
        colours = cmap(index % cmap.N)
        ax.tripcolor(tri, facecolors=index.astype(float), cmap=cmap,
                     vmin=-0.5, vmax=cmap.N - 0.5)
        names = mesh.region_names
        for k, t in enumerate(distinct):
            handles.append(Patch(color=colours[np.argmax(index == k)],
                                 label=names.get(int(t), f"region {int(t)}")))
    kwargs.setdefault("color", "0.3")
    kwargs.setdefault("linewidth", 0.4)
    ax.triplot(tri, **kwargs)
    if boundary and len(mesh.boundary_tags):
        edges = np.asarray(mesh.boundary_edges)
        btags = np.asarray(mesh.boundary_tags)
        names = mesh.boundary_names
        cmap = plt.get_cmap("tab10")
        for k, t in enumerate(np.unique(btags)):
            seg = v[edges[btags == t]]
            colour = cmap(k % cmap.N)
            ax.add_collection(LineCollection(seg, colors=[colour], linewidths=2.5))
            from matplotlib.lines import Line2D

            handles.append(Line2D([], [], color=colour, linewidth=2.5,
                                  label=names.get(int(t), f"boundary {int(t)}")))
    if handles:
        ax.legend(handles=handles, loc="upper right", fontsize="small")
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_title(title if title is not None else
                 f"{mesh.n_vertices} vertices, {mesh.n_triangles} triangles")
    return ax


# ---------------------------------------------------------------------------------------
# Tables.


def _frame(rows: Sequence[Dict[str, Any]], columns: Sequence[str]) -> Any:
    pd = require("pandas", "to_pandas")
    data = {c: [row[c] for row in rows] for c in columns}
    frame = pd.DataFrame(data, columns=list(columns))
    for c in columns:
        values = data[c]
        # A missing value (an empty field of the CSV file) is NaN, as pandas reads it.
        if values and any(v is None for v in values) and all(
            v is None or isinstance(v, (int, float)) for v in values
        ):
            frame[c] = np.array([np.nan if v is None else float(v) for v in values])
    return frame


def to_pandas(obj: Any, variant: Optional[str] = None) -> Any:
    """The rows of a sweep, a study or an adaptive loop as a DataFrame with the columns
    of its CSV file."""
    from ._memcontact import Study

    if isinstance(obj, Study):
        if variant is None:
            return _frame(obj.rows, obj.columns)
        variants = obj.variants
        if variant not in variants:
            known = ", ".join(variants) or "none: the study compares no variants"
            raise ValueError(f"variant {variant!r} is unknown (the variants: {known})")
        return _frame(variants[variant], obj.columns)
    if variant is not None:
        raise TypeError("variant is for a Study's to_pandas")
    return _frame(obj.rows, obj.columns)


def _number(v: Any) -> str:
    if v is None:
        return "—"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        if math.isnan(v):
            return "—"
        return f"{v:.6g}"
    return html.escape(str(v))


def _table(rows: Sequence[Dict[str, Any]], columns: Sequence[str], limit: int = 60) -> str:
    head = "".join(f"<th>{html.escape(c)}</th>" for c in columns)
    shown: List[Optional[Dict[str, Any]]] = list(rows)
    body = []
    if len(shown) > limit:
        half = limit // 2
        shown = shown[:half] + [None] + shown[-half:]
    for row in shown:
        if row is None:
            body.append(f"<tr><td colspan='{len(columns)}'>…</td></tr>")
            continue
        cells = "".join(f"<td>{_number(row[c])}</td>" for c in columns)
        body.append(f"<tr>{cells}</tr>")
    return (
        "<table class='memcontact'><thead><tr>" + head + "</tr></thead><tbody>"
        + "".join(body) + "</tbody></table>"
    )


def _pairs(title: str, items: Sequence[Tuple[str, Any]]) -> str:
    rows = "".join(
        f"<tr><th style='text-align:left'>{html.escape(k)}</th><td>{_number(v)}</td></tr>"
        for k, v in items
    )
    return f"<div><strong>{html.escape(title)}</strong><table>{rows}</table></div>"


def result_html(r: Any) -> str:
    s = r.summary
    items: List[Tuple[str, Any]] = [
        ("status", r.status + ("" if r.accepted else " (not accepted)")),
        ("method", r.method),
        ("iterations", r.iterations),
        ("KKT residual", r.kkt_residual),
        ("energy J", r.energy),
        ("vertices", s.get("vertices")),
        ("unknowns", s.get("unknowns")),
        ("foundation", s.get("foundation")),
        ("contact area (obstacle)", s.get("contact_area")),
        ("total contact force (obstacle)", s.get("total_contact_force")),
        ("max pressure (obstacle)", s.get("max_pressure")),
    ]
    if r.phi_low is not None:
        items += [
            ("contact area (body below)", s.get("contact_area_low")),
            ("total contact force (body below)", s.get("total_contact_force_low")),
            ("max pressure (body below)", s.get("max_pressure_low")),
        ]
    items += [("max deflection", s.get("max_deflection")), ("total load", s.get("total_load"))]
    if r.step is not None:
        items.insert(0, ("step", r.step))
    if r.message:
        items.append(("message", r.message))
    return _pairs(f"memcontact Result: {r.case.label}", items)


def sweep_html(s: Any) -> str:
    head = _pairs(
        f"memcontact Sweep: {s.case.label}",
        [
            ("parameter", s.parameter),
            ("steps solved", f"{len(s)} of {len(s.names)}"),
            ("accepted", s.accepted),
        ]
        + ([("message", s.message)] if s.message else []),
    )
    return head + _table(s.rows, s.columns)


def study_html(s: Any) -> str:
    items: List[Tuple[str, Any]] = [("kind", s.kind), ("rows", len(s)), ("exact", s.exact)]
    parts = [_pairs(f"memcontact Study: {s.kind}", items)]
    variants = s.variants
    if len(variants) > 1:
        for name, rows in variants.items():
            parts.append(f"<div><em>{html.escape(name)}</em></div>" + _table(rows, s.columns))
    else:
        parts.append(_table(s.rows, s.columns))
    return "".join(parts)


def adapt_html(a: Any) -> str:
    t = a.totals
    head = _pairs(
        f"memcontact Adapt: {a.case.label}",
        [
            ("steps", len(a)),
            ("stopped", a.stop),
            ("estimator", t.get("adapt_estimator")),
            ("vertices", a.mesh.n_vertices),
            ("accepted", a.accepted),
        ]
        + ([("message", a.message)] if a.message else []),
    )
    return head + _table(a.rows, a.columns)


# ---------------------------------------------------------------------------------------
# Meshes in and out.


def _point_fields(r: Any) -> Dict[str, np.ndarray]:
    """Every point field of the result (those of ``nodes.csv``), as new arrays with the
    types of ``solution.vtu`` (float64, the states int32)."""
    names = list(POINT_FIELDS) + (list(LOWER_FIELDS) if r.phi_low is not None else [])
    out = {}
    for name in names:
        a = np.asarray(getattr(r, name))
        out[name] = a.astype(np.int32) if name.startswith("state") else np.array(a)
    return out


def _cell_fields(r: Any) -> Dict[str, np.ndarray]:
    out = {"region": np.asarray(r.mesh.regions).astype(np.int32)}
    if r.estimator is not None:
        out["estimator"] = np.array(r.estimator)
    return out


def _points3(mesh: Any) -> np.ndarray:
    v = mesh.vertices
    p = np.zeros((len(v), 3))
    p[:, :2] = v
    return p


def result_to_meshio(r: Any) -> Any:
    """``Result.to_meshio``: the mesh (points with z = 0, triangles) with every point field
    and the cell fields, as ``solution.vtu`` holds them."""
    meshio = require("meshio", "Result.to_meshio")
    mesh = r.mesh
    cells = _cell_fields(r)
    return meshio.Mesh(
        _points3(mesh),
        [("triangle", np.array(mesh.triangles))],
        point_data=_point_fields(r),
        cell_data={k: [v] for k, v in cells.items()},
    )


def result_to_pyvista(r: Any) -> Any:
    """``Result.to_pyvista``: an ``UnstructuredGrid`` of triangles with every point field
    and the cell fields."""
    pv = require("pyvista", "Result.to_pyvista")
    mesh = r.mesh
    grid = pv.UnstructuredGrid({pv.CellType.TRIANGLE: np.array(mesh.triangles)}, _points3(mesh))
    for name, values in _point_fields(r).items():
        grid.point_data[name] = values
    for name, values in _cell_fields(r).items():
        grid.cell_data[name] = values
    return grid


def _names(field_data: Any, dim: int) -> Dict[int, str]:
    """Gmsh physical names of dimension ``dim`` from meshio's ``field_data`` (name →
    [tag, dimension])."""
    out: Dict[int, str] = {}
    for name, value in (field_data or {}).items():
        a = np.asarray(value).ravel()
        if a.size >= 2 and int(a[1]) == dim:
            out[int(a[0])] = str(name)
    return out


def mesh_from_meshio(m: Any, regions: Optional[str] = None) -> Any:
    """``Mesh.from_meshio``: a :class:`Mesh` from a ``meshio.Mesh``."""
    from ._memcontact import Mesh

    for attr in ("points", "cells", "cell_data"):
        if not hasattr(m, attr):
            raise TypeError(f"from_meshio needs a meshio.Mesh, got {type(m).__name__}")
    try:
        points = np.asarray(m.points, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise ValueError(f"from_meshio: the points are not numbers: {e}") from None
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise ValueError(f"from_meshio: points of shape (n, 2) or (n, 3) are needed, got "
                         f"shape {points.shape}")
    if points.shape[1] == 3:
        z = points[:, 2]
        if z.size and not (np.all(np.isfinite(z)) and np.all(z == z[0])):
            raise ValueError("from_meshio: the mesh is not plane (its points have different z)")
        points = points[:, :2]
    if regions is None:
        regions = next((k for k in ("gmsh:physical", "region") if k in m.cell_data), None)
    elif regions not in m.cell_data:
        raise ValueError(f"from_meshio: the mesh has no cell data {regions!r} (it has: "
                         f"{', '.join(m.cell_data) or 'none'})")
    tag_blocks = m.cell_data.get(regions) if regions is not None else None
    triangles, tags, lines, line_tags = [], [], [], []
    for k, block in enumerate(m.cells):
        kind, data = block.type, np.asarray(block.data)
        block_tags = None if tag_blocks is None else np.asarray(tag_blocks[k]).ravel()
        if kind == "triangle":
            triangles.append(data)
            tags.append(block_tags if block_tags is not None else np.zeros(len(data), np.int64))
        elif kind == "line":
            if block_tags is not None:
                lines.append(data)
                line_tags.append(block_tags)
        elif kind == "vertex":
            continue
        else:
            raise ValueError(
                f"from_meshio: cell block {k} holds {kind} cells; only 3-node triangles "
                "(with line and vertex cells) are read"
            )
    if not triangles:
        raise ValueError("from_meshio: the mesh has no triangles")
    tri = np.concatenate(triangles)
    tag = np.concatenate(tags)
    for name, a in (("triangles", tri), ("region tags", tag)):
        if a.dtype.kind not in "iu":
            raise ValueError(f"from_meshio: the {name} must be integers, got dtype {a.dtype}")
    n = len(points)
    if tri.size and (tri.min() < 0 or tri.max() >= n):
        raise ValueError(f"from_meshio: a triangle refers to a point beyond the {n} points")
    # Points no triangle uses (a Gmsh file's geometry points) are dropped; the others keep
    # their order.
    used = np.zeros(n, dtype=bool)
    used[tri.ravel()] = True
    new = np.cumsum(used) - 1
    tri = new[tri]
    points = points[used]
    kwargs: Dict[str, Any] = {}
    if lines:
        edges = np.concatenate(lines).astype(np.int64)
        etags = np.concatenate(line_tags)
        if edges.ndim != 2 or edges.shape[1] != 2 or etags.dtype.kind not in "iu":
            raise ValueError("from_meshio: line cells must be point pairs with integer tags")
        if edges.size and (edges.min() < 0 or edges.max() >= n):
            raise ValueError(f"from_meshio: a line refers to a point beyond the {n} points")
        # The boundary: the triangle edges of one triangle only. Lines inside the mesh
        # (physical curves across it) are skipped, as the Gmsh reader skips them.
        all_edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]),
                            axis=1)
        unique, counts = np.unique(all_edges, axis=0, return_counts=True)
        boundary = {tuple(e) for e in unique[counts == 1].tolist()}
        ok = np.array([used[a] and used[b] and tuple(sorted((int(new[a]), int(new[b]))))
                       in boundary for a, b in edges], dtype=bool)
        if not ok.all():
            names = _names(getattr(m, "field_data", None), 1)
            inside = sorted({names.get(int(t), str(int(t))) for t in etags[~ok]})
            warnings.warn(
                f"from_meshio: {int((~ok).sum())} line cells of {', '.join(inside)} do not "
                "lie on the boundary: skipped", stacklevel=3)
        if ok.any():
            kwargs = dict(
                boundary_edges=new[edges[ok]],
                boundary_tags=etags[ok].astype(np.int64),
                boundary_names=_names(getattr(m, "field_data", None), 1),
            )
    return Mesh(points, tri, tag.astype(np.int64), _names(getattr(m, "field_data", None), 2),
                **kwargs)


# ---------------------------------------------------------------------------------------
# Matrices.


def matrices(parts: Dict[str, Any]) -> Dict[str, Any]:
    """``Result.matrices``: the parts the native side assembled, with S and L as
    ``scipy.sparse.csr_array``."""
    sp = require("scipy.sparse", "Result.matrices", "scipy")
    n = len(parts["D"])

    def csr(rows: Any) -> Any:
        ptr, col, val = rows
        return sp.csr_array((val, col, ptr), shape=(n, n))

    def body(b: Dict[str, Any], suffix: str) -> Dict[str, Any]:
        kind = "rigid" if b["L"] is None else ("lumped" if b["lumped"] else "consistent")
        return {
            "L" + suffix: None if b["L"] is None else csr(b["L"]),
            "phi" + suffix: b["phi"],
            "can_touch" + suffix: b["can_touch"],
            "rigid" + suffix: b["rigid"],
            "foundation" + suffix: kind,
        }

    out: Dict[str, Any] = {
        "S": csr(parts["S"]),
        "D": parts["D"],
        "unknowns": parts["unknowns"],
    }
    out.update(body(parts["obstacle"], ""))
    if parts["lower"] is not None:
        out.update(body(parts["lower"], "_low"))
    return out
