"""2-D circle fits (Sec. 6.2): least squares, minimum circumscribed (MC, Eq. 6.1),
maximum inscribed within MC (MI, Eq. 6.2) and minimum zone (MZ, roundness, Eqs. 6.5-6.8).

The exact fits run in the Rust kernels of ``gagekit._core``: Welzl's algorithm for MC,
the nearest-point Voronoi diagram for MI, nearest and farthest Voronoi diagrams for MZ.
The result, :class:`CircleFit`, is the Rust object (``gagekit_form::result::CircleResult``:
radius, zone, control points, arc and its warnings, assembled once there).
"""

from __future__ import annotations

from typing import Any

from .. import _core
from .._core.form import CircleFit
from ..errors import ConfigError
from .criteria import CIRCLE_CRITERIA, criterion_name
from .fits import _points

__all__ = ["CircleFit", "fit_circle", "CIRCLE_CRITERIA"]

def fit_circle(points: Any, criterion: str = "lsq", method: str = "exact", seed: int = 0, **options: Any) -> CircleFit:
    """Fit a circle to (n, 2) points, or to (n, 3) points in any pose.

    Parameters
    ----------
    points : array_like, shape (n, 2) or (n, 3)
        Coordinates in mm. Points in space are fitted in their least-squares plane (the
        NIST convention: plane, projection, fit; a set with an exactly constant
        coordinate uses that coordinate plane exactly), with every criterion.
    criterion : {"lsq", "mc", "mi", "mz"} or the long names "least-squares",
        "min-circumscribed", "max-inscribed", "minimum-zone".
        - ``lsq``: geometric least squares (orthogonal distances), as CMM software does.
        - ``mc``: minimum circumscribed circle, Eq. 6.1 (Welzl, exact).
        - ``mi``: maximum inscribed circle constrained within MC, Eq. 6.2 (nearest
          Voronoi vertices plus the MC-tangent cases I and II of Sec. 6.2.2, exact).
        - ``mz``: minimum zone (roundness), Eq. 6.5, exact over cases 3+1, 1+3 and 2+2
          (Eqs. 6.6-6.8).
    method : "exact" or "pso"
        The computational-geometry solvers above, or the seeded particle swarm over the
        centre followed by Nelder-Mead (Eqs. 6.1, 6.4, 6.5; mc, mi, mz only), a
        cross-check of the exact solvers. Options for "pso": ``seed`` (0), ``particles``
        (20), ``iterations`` (2000), ``stall_iterations`` (100).
    seed : int
        Seed of the "pso" method; the exact methods do not use it.

    Raises
    ------
    InvalidInputError
        Wrong shape, NaN/inf (the message names the point), too few points.
    DegenerateGeometryError
        All points coincident or collinear (MI, MZ, least squares).
    ConfigError
        Unknown criterion or method.

    References
    ----------
    Dissertation Sec. 6.2, Eqs. 6.1, 6.2, 6.5-6.8.
    """
    crit = _criterion(criterion)
    if method == "exact" and options:
        raise ConfigError(f"unexpected options for method 'exact': {', '.join(sorted(options))}")
    if method == "pso" and (set(options) - {"seed", "particles", "iterations", "stall_iterations"} or crit == "least-squares"):
        raise ConfigError(
            "method 'pso' fits mc, mi and mz and takes the options seed, particles, iterations, stall_iterations"
        )
    pts = _points(points, (2, 3), "circle")
    return _core.form.fit_circle(
        pts, crit, str(method), int(options.get("seed", seed)), int(options.get("particles", 20)),
        int(options.get("iterations", 2000)), int(options.get("stall_iterations", 100)),
    )


def _criterion(criterion: str) -> str:
    """The canonical name (the package's one table); the error lists the circle codes."""
    try:
        return criterion_name(criterion, shape="circle")
    except ConfigError:
        choices = ", ".join(f"{k} ({v})" for k, v in CIRCLE_CRITERIA.items())
        raise ConfigError(f"unknown circle criterion {criterion!r}; choose one of {choices}") from None
