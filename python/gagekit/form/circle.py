"""2-D circle fits (Sec. 6.2): least squares, minimum circumscribed (MC, Eq. 6.1),
maximum inscribed within MC (MI, Eq. 6.2) and minimum zone (MZ, roundness, Eqs. 6.5-6.8).

The exact fits run in the Rust kernels of ``gagekit._core``: Welzl's algorithm for MC,
the nearest-point Voronoi diagram for MI, nearest and farthest Voronoi diagrams for MZ.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from .. import _core
from ..errors import ConfigError

__all__ = ["CircleFit", "fit_circle", "CIRCLE_CRITERIA"]

#: Canonical criterion codes and the long names accepted as aliases.
CIRCLE_CRITERIA: dict[str, str] = {
    "lsq": "least-squares",
    "mc": "min-circumscribed",
    "mi": "max-inscribed",
    "mz": "minimum-zone",
}
_ALIASES = {**{k: k for k in CIRCLE_CRITERIA}, **{v: k for k, v in CIRCLE_CRITERIA.items()}}

#: Below this arc (degrees) the maximum inscribed circle is ill-posed.
MIN_ARC_DEG = 90.0


@dataclass(frozen=True)
class CircleFit:
    """A fitted 2-D circle.

    ``radius`` is the fitted radius; for the minimum zone it is the mean of ``r_in`` and
    ``r_out``. ``r_in`` / ``r_out`` are the smallest / largest distance of the points from
    ``center`` (for MZ the inner and outer zone circles), ``width = r_out - r_in`` is the
    roundness (peak-to-valley radial deviation about ``center``). ``control_points`` are
    input indices of the points that fix the fit (for MZ ``control_in`` + ``control_out``).
    ``arc_deg`` is the arc the points cover seen from the centre; ``warnings`` explains
    when the result is ill-posed (MI of an arc below 90 degrees).

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
    width: float
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

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {
            "shape": "circle",
            "criterion": CIRCLE_CRITERIA[self.criterion],
            "method": self.method,
            "n_points": self.n_points,
            "form_error": self.width,
            "center": list(self.center),
            "radius": self.radius,
        }
        if self.normal is not None:
            d["normal"] = list(self.normal)
            d["out_of_plane"] = self.out_of_plane
        if self.criterion == "mz":
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


def _criterion(criterion: str) -> str:
    key = _ALIASES.get(str(criterion).strip().lower())
    if key is None:
        choices = ", ".join(f"{k} ({v})" for k, v in CIRCLE_CRITERIA.items())
        raise ConfigError(f"unknown circle criterion {criterion!r}; choose one of {choices}")
    return key


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
    n = int(pts.shape[0])
    control_in: tuple[int, ...] = ()
    control_out: tuple[int, ...] = ()
    if method == "pso":
        # 3-D fits helper: PSO over the centre (Eqs. 6.1, 6.4, 6.5) as a cross-check
        allowed = {"seed", "particles", "iterations", "stall_iterations"}
        if set(options) - allowed or crit == "lsq":
            raise ConfigError(
                "method 'pso' fits mc, mi and mz and takes the options seed, particles, "
                "iterations, stall_iterations"
            )
        center, r_in, r_out, cin, cout, _, _ = _core.form_circle_pso(
            pts, crit, int(options.get("seed", 0)), int(options.get("particles", 20)),
            int(options.get("iterations", 2000)), int(options.get("stall_iterations", 100)),
        )
        control_in, control_out = tuple(cin), tuple(cout)
        control = {"mc": control_out, "mi": control_in}.get(crit, control_in + tuple(i for i in control_out if i not in control_in))
        radius = {"mc": r_out, "mi": r_in}.get(crit, 0.5 * (r_in + r_out))
        if crit != "mz":
            control_in = control_out = ()
            d = np.hypot(pts[:, 0] - center[0], pts[:, 1] - center[1])
            r_in, r_out = float(d.min()), float(d.max())
        return _result(crit, method, pts, center, radius, r_in, r_out, control, control_in, control_out)
    if crit == "mz":
        center, r_in, r_out, cin, cout = _core.form_circle_mz(pts)
        control_in, control_out = tuple(int(i) for i in cin), tuple(int(i) for i in cout)
        control = control_in + tuple(i for i in control_out if i not in control_in)
        radius = 0.5 * (r_in + r_out)
    else:
        fn = {"lsq": _core.form_circle_lsq, "mc": _core.form_circle_mc, "mi": _core.form_circle_mi}[crit]
        center, radius, ctrl = fn(pts)
        control = tuple(int(i) for i in ctrl)
        d = np.hypot(pts[:, 0] - center[0], pts[:, 1] - center[1])
        r_in, r_out = float(d.min()), float(d.max())
    return _result(crit, method, pts, center, radius, r_in, r_out, control, control_in, control_out)


def _circle_points(points: Any) -> np.ndarray:
    from .fits import _points

    return _points(points, (2, 3), "circle")


def _fit_in_plane(pts: np.ndarray, crit: str) -> CircleFit:
    """A circle in space: the 2-D fit in the least-squares plane, in Rust."""
    r = _core.form_circle_in_plane(pts, crit)
    arc = math.degrees(r.arc)
    if crit == "mi" and arc < 270.0:
        # as in 2-D: MI's own centre can sit anywhere inside a short arc
        arc = math.degrees(_core.form_circle_in_plane(pts, "lsq").arc)
    if crit == "mz":
        control_in, control_out = tuple(r.control_in), tuple(r.control_out)
        control = control_in + tuple(i for i in control_out if i not in control_in)
    else:
        control_in = control_out = ()
        control = tuple(r.control_out)
    ill_posed, warnings = _arc_warnings(crit, arc)
    return CircleFit(
        criterion=crit,
        center=tuple(float(v) for v in r.center),
        radius=float(r.radius),
        r_in=float(r.min_distance),
        r_out=float(r.max_distance),
        width=float(r.max_distance - r.min_distance),
        control_points=tuple(int(i) for i in control),
        n_points=int(pts.shape[0]),
        control_in=tuple(int(i) for i in control_in),
        control_out=tuple(int(i) for i in control_out),
        arc_deg=float(arc),
        ill_posed=ill_posed,
        warnings=tuple(warnings),
        normal=(float(r.normal[0]), float(r.normal[1]), float(r.normal[2])),
        out_of_plane=float(r.out_of_plane),
    )


def _arc_warnings(crit: str, arc: float) -> tuple[bool, list[str]]:
    warnings: list[str] = []
    ill_posed = False
    if crit == "mi" and arc < MIN_ARC_DEG:
        ill_posed = True
        warnings.append(
            f"the points cover only {arc:.1f} degrees of arc (< {MIN_ARC_DEG:.0f}): the maximum "
            "inscribed circle is ill-posed and its radius is not a meaningful size"
        )
    elif arc < MIN_ARC_DEG:
        warnings.append(f"the points cover only {arc:.1f} degrees of arc: centre and radius are poorly determined")
    return ill_posed, warnings


def _result(crit, method, pts, center, radius, r_in, r_out, control, control_in, control_out) -> CircleFit:
    gap = _core.form_circle_angular_gap(pts, (float(center[0]), float(center[1])))
    arc = math.degrees(2.0 * math.pi - gap)
    if crit == "mi" and arc < 270.0:
        # MI's own centre can sit anywhere inside a short arc: judge the arc about the
        # least-squares centre instead
        ref = _core.form_circle_lsq(pts)[0]
        arc = math.degrees(2.0 * math.pi - _core.form_circle_angular_gap(pts, (float(ref[0]), float(ref[1]))))
    ill_posed, warnings = _arc_warnings(crit, arc)
    return CircleFit(
        criterion=crit,
        center=(float(center[0]), float(center[1])),
        radius=float(radius),
        r_in=float(r_in),
        r_out=float(r_out),
        width=float(r_out - r_in),
        control_points=tuple(control),
        n_points=int(pts.shape[0]),
        method=method,
        control_in=control_in,
        control_out=control_out,
        arc_deg=float(arc),
        ill_posed=ill_posed,
        warnings=tuple(warnings),
    )
