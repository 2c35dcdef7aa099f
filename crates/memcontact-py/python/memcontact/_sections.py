"""The sections of a case file as small dataclasses: ``Membrane``, ``Obstacle``, ``Lower``,
``Boundary``, ``Solver``, ``Output`` and ``Units``. Each holds the keys of its section;
a key left at ``None`` is left out, so that the case file's default applies. They go
wherever a section's dict goes (``memcontact.solve(mesh=m, membrane=Membrane(...))``, the
values of a case dict, ``Case({...})``) and become that dict by ``to_dict()``.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Callable, Dict, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

#: What a data key may hold: a number, an expression of x and y (a string), a dict of
#: region names (or tags) to numbers or expressions, a NumPy array of one value per mesh
#: vertex, or a vectorised function ``f(x, y)`` of the vertices' coordinates (arrays and
#: functions need the mesh: ``solve(..., mesh=m)``).
Data = Union[
    float,
    int,
    str,
    Mapping[Union[str, int], Union[float, int, str]],
    np.ndarray,
    Callable[[np.ndarray, np.ndarray], Any],
]


def _plain(value: Any) -> Any:
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


class _Section:
    """The common part of the sections: ``to_dict``."""

    def to_dict(self) -> Dict[str, Any]:
        """The section as the dict of its case-file keys (keys left at ``None`` are left
        out, so that their defaults apply).

        Returns
        -------
        dict
            Key → value, as the section of a case dict holds them.
        """
        return {
            f.name: _plain(getattr(self, f.name))
            for f in dataclasses.fields(self)  # type: ignore[arg-type]
            if getattr(self, f.name) is not None
        }


@dataclasses.dataclass(frozen=True)
class Membrane(_Section):
    """``[membrane]``: the stretched membrane.

    Parameters
    ----------
    tension : float
        The uniform tension t > 0 (force per length).
    load : Data
        The transverse load f (force per area, positive in +x₃ toward the obstacle).
    """

    tension: float
    load: Data


@dataclasses.dataclass(frozen=True)
class Obstacle(_Section):
    """``[obstacle]``: the elastic (tensionless Winkler) body above the membrane.

    Parameters
    ----------
    shape : Data
        Its surface φ (where the membrane starts to touch it).
    stiffness : Data or "rigid"
        Its stiffness h ≥ 0 (force per volume), ``"rigid"`` for the obstacle problem
        u ≤ φ, or a dict of regions to either.
    foundation : {"consistent", "lumped"}, optional
        The paper's consistent foundation matrix L (default) or its lumped diagonal.
    sampling : {"nodal", "mollified"}, optional
        φ at the vertices (default), or mollified first as in the paper.
    epsilon : float, optional
        The mollifier's radius (default: the paper's choice).
    """

    shape: Data
    stiffness: Union[Data, str]
    foundation: Optional[str] = None
    sampling: Optional[str] = None
    epsilon: Optional[float] = None


@dataclasses.dataclass(frozen=True)
class Lower(Obstacle):
    """``[lower]``: a second body below the membrane, pushing up where the membrane sinks
    into it (reaction h_low (φ_low − u)⁺). The same keys as :class:`Obstacle`.

    Parameters
    ----------
    shape : Data
        Its surface φ_low.
    stiffness : Data or "rigid"
        Its stiffness h_low ≥ 0, or ``"rigid"`` (u ≥ φ_low).
    foundation : {"consistent", "lumped"}, optional
        The consistent foundation matrix (default) or its lumped diagonal.
    sampling : {"nodal", "mollified"}, optional
        φ_low at the vertices (default), or mollified first.
    epsilon : float, optional
        The mollifier's radius.
    """


@dataclasses.dataclass(frozen=True)
class Boundary(_Section):
    """``[boundary]``: heights on the fixed boundary and free edges.

    Parameters
    ----------
    height : Data, optional
        The height g of the fixed boundary (u = g; default 0): a number, an expression, a
        dict of boundary region names (``"left"``, a Gmsh physical curve) to those, an
        array of one value per vertex, or a function of (x, y).
    free : sequence of str, optional
        Boundary regions left free (the natural condition t ∂u/∂n = 0).
    """

    height: Optional[Data] = None
    free: Optional[Sequence[str]] = None


@dataclasses.dataclass(frozen=True)
class Solver(_Section):
    """``[solver]``: how the discrete problem is solved.

    Parameters
    ----------
    method : str, optional
        ``auto`` (default), ``linear``, ``active-set``, ``qp``, ``coordinate`` or
        ``multigrid``.
    tolerance : float, optional
        The scaled KKT residual to reach (default 1e-10).
    max_iterations : int, optional
        The method's iteration limit.
    accept_rounding_floor : bool, optional
        Accept a solve stopped at the rounding floor of double precision (default true).
    hierarchy : str, optional
        The multigrid hierarchy: ``auto``, ``geometric`` or ``algebraic``.
    """

    method: Optional[str] = None
    tolerance: Optional[float] = None
    max_iterations: Optional[int] = None
    accept_rounding_floor: Optional[bool] = None
    hierarchy: Optional[str] = None


@dataclasses.dataclass(frozen=True)
class Output(_Section):
    """``[output]``: what ``write`` writes besides ``solution.vtu`` and ``summary.json``.

    Parameters
    ----------
    vtu : {"binary", "ascii", "compressed"}, optional
        The encoding of ``solution.vtu``.
    csv : bool, optional
        Whether to write ``nodes.csv`` (default true).
    plots : sequence of str, optional
        The pictures (``deflection``, ``pressure``, ``liftoff``, ``profile``).
    plot : bool, optional
        ``False``: no pictures.
    allowable_pressure : float, optional
        ``pressure.png`` then maps pressure / allowable.
    profile : ((x0, y0), (x1, y1)), optional
        The line of ``profile.png``.
    keep_steps : bool, optional
        With ``[adapt]``: also write each step's result set.
    """

    vtu: Optional[str] = None
    csv: Optional[bool] = None
    plots: Optional[Sequence[str]] = None
    plot: Optional[bool] = None
    allowable_pressure: Optional[float] = None
    profile: Optional[Tuple[Tuple[float, float], Tuple[float, float]]] = None
    keep_steps: Optional[bool] = None


@dataclasses.dataclass(frozen=True)
class Units(_Section):
    """``[units]``: the names of the case's units, for labels.

    Parameters
    ----------
    length : str, optional
        E.g. ``"m"``.
    force : str, optional
        E.g. ``"kN"``.
    """

    length: Optional[str] = None
    force: Optional[str] = None


#: The section classes by the case file's section names.
SECTIONS = {
    "membrane": Membrane,
    "obstacle": Obstacle,
    "lower": Lower,
    "boundary": Boundary,
    "solver": Solver,
    "output": Output,
    "units": Units,
}
