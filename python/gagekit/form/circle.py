"""2-D circle fits (Sec. 6.2): least squares, minimum circumscribed (MC, Eq. 6.1),
maximum inscribed within MC (MI, Eq. 6.2) and minimum zone (MZ, roundness, Eqs. 6.5-6.8).

The exact fits run in the Rust kernels of ``gagekit._core``: Welzl's algorithm for MC,
the nearest-point Voronoi diagram for MI, nearest and farthest Voronoi diagrams for MZ.
"""

from __future__ import annotations

import math
import warnings as _warnings
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from .. import _core
from ..errors import ConfigError
from .criteria import CIRCLE_CRITERIA, criterion_name

__all__ = ["CircleFit", "fit_circle", "CIRCLE_CRITERIA"]

#: Below this arc (degrees) the maximum inscribed circle is ill-posed (the kernel's
#: constant, gagekit-form ``circle::MIN_ARC_DEG``).
MIN_ARC_DEG = _core.form.CIRCLE_MIN_ARC_DEG


@dataclass(frozen=True)
class CircleFit:
    """A fitted 2-D circle.

    ``criterion`` is the canonical name (``least-squares``, ``min-circumscribed``,
    ``max-inscribed``, ``minimum-zone``). ``radius`` is the fitted radius; for the minimum
    zone it is the mean of ``r_in`` and ``r_out``. ``r_in`` / ``r_out`` are the smallest /
    largest distance of the points from ``center`` (for MZ the inner and outer zone
    circles), ``form_error = r_out - r_in`` is the roundness (peak-to-valley radial
    deviation about ``center``). ``control_points`` are input indices of the points that
    fix the fit (for MZ ``control_in`` + ``control_out``). ``arc_deg`` is the arc the
    points cover seen from the centre; ``warnings`` explains when the result is ill-posed
    (MI of an arc below 90 degrees). ``width`` is a deprecated alias of ``form_error``.

    For points in space (any pose) ``center`` is 3-D, ``normal`` the unit normal of the
    least-squares plane the circle was fitted in, ``r_in`` / ``r_out`` (the certificate)
    are measured in that plane, and ``out_of_plane`` is the largest distance of a point
    from it.
    """

    criterion: str
    center: tuple[float, ...]
    radius: float
    r_in: float
    r_out: float
    form_error: float
    control_points: tuple[int, ...]
    n_points: int
    method: str = "exact"
    control_in: tuple[int, ...] = ()
    control_out: tuple[int, ...] = ()
    arc_deg: float = 360.0
    ill_posed: bool = False
    warnings: tuple[str, ...] = field(default_factory=tuple)
    normal: Optional[tuple[float, float, float]] = None
    out_of_plane: Optional[float] = None

    @property
    def width(self) -> float:
        """Deprecated alias of :attr:`form_error`."""
        _warnings.warn("CircleFit.width is deprecated; use form_error", DeprecationWarning, stacklevel=2)
        return self.form_error

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {
            "shape": "circle",
            "criterion": self.criterion,
            "method": self.method,
            "n_points": self.n_points,
            "form_error": self.form_error,
            "center": list(self.center),
            "radius": self.radius,
        }
        if self.normal is not None:
            d["normal"] = list(self.normal)
            d["out_of_plane"] = self.out_of_plane
        if self.criterion == "minimum-zone":
            d["inner_radius"] = self.r_in
            d["outer_radius"] = self.r_out
            d["control_in"] = list(self.control_in)
            d["control_out"] = list(self.control_out)
        d["control_points"] = list(self.control_points)
        d["certificate"] = {"min_distance": self.r_in, "max_distance": self.r_out}
        d["arc_deg"] = self.arc_deg
        d["ill_posed"] = self.ill_posed
        d["warnings"] = list(self.warnings)
        return d


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
    if method not in ("exact", "pso"):
        raise ConfigError(f"unknown circle fit method {method!r}; available: 'exact', 'pso'")
    if method == "exact" and options:
        raise ConfigError(f"unexpected options for method 'exact': {', '.join(sorted(options))}")
    pts = _circle_points(points)
    if pts.shape[1] == 3:
        if method != "exact":
            raise ConfigError("method 'pso' fits 2-D points; fit points in space with method 'exact'")
        return _fit_in_plane(pts, crit)
    if method == "pso":
        # PSO over the centre (Eqs. 6.1, 6.4, 6.5) as a cross-check
        allowed = {"seed", "particles", "iterations", "stall_iterations"}
        if set(options) - allowed or crit == "least-squares":
            raise ConfigError(
                "method 'pso' fits mc, mi and mz and takes the options seed, particles, "
                "iterations, stall_iterations"
            )
        r = _core.form.circle_pso(
            pts, crit, int(options.get("seed", 0)), int(options.get("particles", 20)),
            int(options.get("iterations", 2000)), int(options.get("stall_iterations", 100)),
        )
    else:
        r = _core.form.circle_fit(pts, crit)
    return _result(r, method, int(pts.shape[0]))


def _criterion(criterion: str) -> str:
    """The canonical name (the package's one table); the error lists the circle codes."""
    try:
        return criterion_name(criterion, shape="circle")
    except ConfigError:
        choices = ", ".join(f"{k} ({v})" for k, v in CIRCLE_CRITERIA.items())
        raise ConfigError(f"unknown circle criterion {criterion!r}; choose one of {choices}") from None


def _circle_points(points: Any) -> np.ndarray:
    from .fits import _points

    return _points(points, (2, 3), "circle")


def _fit_in_plane(pts: np.ndarray, crit: str) -> CircleFit:
    """A circle in space: the 2-D fit in the least-squares plane, in Rust."""
    r = _core.form.circle_in_plane(pts, crit)
    arc = math.degrees(r.arc)
    mz = crit == "minimum-zone"
    return CircleFit(
        criterion=crit,
        center=tuple(float(v) for v in r.center),
        radius=float(r.radius),
        r_in=float(r.min_distance),
        r_out=float(r.max_distance),
        form_error=float(r.max_distance - r.min_distance),
        control_points=tuple(int(i) for i in r.control),
        n_points=int(pts.shape[0]),
        control_in=tuple(int(i) for i in r.control_in) if mz else (),
        control_out=tuple(int(i) for i in r.control_out) if mz else (),
        arc_deg=float(arc),
        ill_posed=bool(r.ill_posed),
        warnings=tuple(_arc_warnings(crit, arc)),
        normal=(float(r.normal[0]), float(r.normal[1]), float(r.normal[2])),
        out_of_plane=float(r.out_of_plane),
    )


def _arc_warnings(crit: str, arc: float) -> list[str]:
    """The reader's explanation of a short arc (the ill-posed flag itself is Rust's)."""
    if arc >= MIN_ARC_DEG:
        return []
    if crit == "max-inscribed":
        return [
            f"the points cover only {arc:.1f} degrees of arc (< {MIN_ARC_DEG:.0f}): the maximum "
            "inscribed circle is ill-posed and its radius is not a meaningful size"
        ]
    return [f"the points cover only {arc:.1f} degrees of arc: centre and radius are poorly determined"]


def _result(r: Any, method: str, n_points: int) -> CircleFit:
    """The Python view of a complete 2-D fit from Rust (``_core.form.CircleResult``)."""
    arc = math.degrees(r.arc)
    return CircleFit(
        criterion=str(r.criterion),
        center=(float(r.center[0]), float(r.center[1])),
        radius=float(r.radius),
        r_in=float(r.r_in),
        r_out=float(r.r_out),
        form_error=float(r.form_error),
        control_points=tuple(int(i) for i in r.control),
        n_points=n_points,
        method=method,
        control_in=tuple(int(i) for i in r.control_in),
        control_out=tuple(int(i) for i in r.control_out),
        arc_deg=float(arc),
        ill_posed=bool(r.ill_posed),
        warnings=tuple(_arc_warnings(str(r.criterion), arc)),
    )
