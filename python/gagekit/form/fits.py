"""Least-squares lines, planes, spheres and 3-D circles (geometric fits, ASME B89.4.10).

Every fit minimises the sum of squared *orthogonal* distances of the points to
the feature, as the NIST Algorithm Testing System defines it; the kernels work on
centred data, so parts far from the origin lose no accuracy. Each result carries a
certificate: the minimum and maximum distance of the input points to the reported
feature, recomputed from the reported parameters.

References: dissertation Ch. 6 (Sec. 6.2-6.3; Eqs. 6.1-6.5 for circles, 6.9-6.11
for cylinders); the 3-D circle follows NIST's convention (least-squares plane,
projection, least-squares circle in that plane).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from .. import _core
from .._util import as_points
from ..errors import ConfigError, InvalidInputError
from .criteria import SHAPE_CRITERIA, criterion_name

__all__ = [
    "Certificate",
    "LineFit",
    "PlaneFit",
    "SphereFit",
    "Circle3DFit",
    "fit_line",
    "fit_plane",
    "fit_sphere",
    "fit_circle_3d",
]

def _points(points: Any, dims: tuple[int, ...], shape: str) -> np.ndarray:
    try:
        arr = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"{shape}: points cannot be read as numbers ({exc})") from None
    if arr.ndim == 2 and arr.shape[1] in dims:
        return as_points(arr, arr.shape[1], "points")
    want = " or ".join(f"(n, {d})" for d in dims)
    raise InvalidInputError(f"{shape}: expected points as an {want} array, got shape {np.shape(arr)}")


def _vec(v: Any) -> tuple[float, ...]:
    return tuple(float(x) for x in v)


@dataclass(frozen=True)
class Certificate:
    """Minimum and maximum distance of the input points to the reported feature,
    recomputed from the reported parameters (mm)."""

    min_distance: float
    max_distance: float

    def to_dict(self) -> dict[str, float]:
        return {"min_distance": self.min_distance, "max_distance": self.max_distance}


def _fit_dict(fit: Any, **fields: Any) -> dict[str, Any]:
    """The JSON of a 3-D fit (issue 3's keys): shape, criterion, n_points, form_error, then
    the feature's own ``fields`` in order, then the certificate."""
    return {
        "shape": fit.shape,
        "criterion": fit.criterion,
        "n_points": fit.n_points,
        "form_error": fit.form_error,
        **fields,
        "certificate": fit.certificate.to_dict(),
    }


def _radii(fit: Any) -> dict[str, Any]:
    """The radius keys of an axis fit's JSON (cylinders, cones): ``radius``, and for the
    minimum zone the zone's ``inner_radius`` / ``outer_radius``."""
    radii: dict[str, Any] = {"radius": fit.radius}
    if fit.criterion == "minimum-zone":
        radii.update(inner_radius=fit.inner_radius, outer_radius=fit.outer_radius)
    return radii


@dataclass(frozen=True)
class LineFit:
    """A fitted line. ``certificate``: signed distances (2-D) or distances (3-D) to the line;
    ``form_error``: max - min of the signed distances (2-D), twice the largest distance (3-D)."""

    criterion: str
    n_points: int
    point: tuple[float, ...]
    direction: tuple[float, ...]
    form_error: float
    certificate: Certificate
    control_points: tuple[int, ...] = ()
    tilt_deg: Optional[float] = None
    warnings: tuple[str, ...] = ()
    shape: str = field(default="line", init=False)

    def to_dict(self) -> dict[str, Any]:
        d = _fit_dict(
            self, point=list(self.point), direction=list(self.direction), control_points=list(self.control_points)
        )
        if self.tilt_deg is not None:
            d["tilt_deg"] = self.tilt_deg
            d["warnings"] = list(self.warnings)
        return d


@dataclass(frozen=True)
class _Diameter:
    """An enclosing cylinder's optimum outside the cone, as its straightness (diameter)."""

    _outside: Any

    @property
    def value(self) -> float:
        return 2.0 * float(self._outside.value)

    @property
    def tilt(self) -> float:
        return float(self._outside.tilt)


@dataclass(frozen=True)
class PlaneFit:
    """A fitted plane. ``certificate``: signed distances to it; ``form_error`` = max - min."""

    criterion: str
    n_points: int
    point: tuple[float, float, float]
    normal: tuple[float, float, float]
    form_error: float
    certificate: Certificate
    control_points: tuple[int, ...] = ()
    shape: str = field(default="plane", init=False)

    def to_dict(self) -> dict[str, Any]:
        return _fit_dict(
            self, point=list(self.point), normal=list(self.normal), control_points=list(self.control_points)
        )


@dataclass(frozen=True)
class SphereFit:
    """A fitted sphere (3-D) or circle (2-D). ``certificate``: distances to the centre;
    ``form_error`` = max - min (sphericity about this centre; the zone width for the
    minimum zone). Chebyshev spheres also give ``inner_radius`` / ``outer_radius`` (the
    zone, minimum zone only), ``control_points`` and ``global_bound``: the certificate of
    the global search (minimum zone: no centre gives a narrower zone; maximum inscribed:
    no larger sphere; within 1e-9 mm of the value)."""

    criterion: str
    n_points: int
    center: tuple[float, ...]
    radius: float
    form_error: float
    certificate: Certificate
    shape: str = "sphere"
    inner_radius: Optional[float] = None
    outer_radius: Optional[float] = None
    control_points: Optional[tuple[int, ...]] = None
    global_bound: Optional[float] = None

    def to_dict(self) -> dict[str, Any]:
        if self.control_points is None:
            return _fit_dict(self, radius=self.radius, center=list(self.center))
        radii: dict[str, Any] = {"radius": self.radius}
        if self.criterion == "minimum-zone":
            radii.update(inner_radius=self.inner_radius, outer_radius=self.outer_radius)
        if self.global_bound is not None:
            radii.update(global_bound=self.global_bound)
        return _fit_dict(self, **radii, center=list(self.center), control_points=list(self.control_points))


@dataclass(frozen=True)
class Circle3DFit:
    """A circle in space. ``certificate``: radial distances of the points, projected onto
    the circle's plane, to its centre; ``form_error`` = max - min (roundness about the fit)."""

    criterion: str
    n_points: int
    center: tuple[float, float, float]
    normal: tuple[float, float, float]
    radius: float
    form_error: float
    certificate: Certificate
    shape: str = field(default="circle3d", init=False)

    def to_dict(self) -> dict[str, Any]:
        return _fit_dict(self, radius=self.radius, center=list(self.center), normal=list(self.normal))


def _cert(fit: Any) -> Certificate:
    """The certificate of a result from Rust (its ``min_distance`` / ``max_distance``)."""
    return Certificate(float(fit.min_distance), float(fit.max_distance))


def fit_line(
    points: Any,
    criterion: str = "least-squares",
    seed: int = 0,
    *,
    axis: Optional[Any] = None,
    max_tilt: float = 10.0,
) -> LineFit:
    """Line through (n, 2) or (n, 3) points.

    ``least-squares``: orthogonal distances; the line passes through the centroid along
    the principal axis. ``minimum-zone`` (straightness): in 2-D the two parallel lines of
    least separation (LP, then exact active-set solve); in 3-D the thinnest enclosing
    cylinder (MCC of Sec. 6.3, Eq. 6.13, with the seeded PSO), searched within
    ``max_tilt`` degrees (default 10) of the nominal ``axis`` or, by default, of the
    least-squares direction; its diameter is the ``form_error``. ``tilt_deg`` and
    ``warnings`` as for :func:`fit_cylinder`. Exactly collinear points give 0.
    Raises :class:`DegenerateGeometryError` when all points coincide.
    """
    from .search import outside_warning, search_settings

    crit = criterion_name(criterion, SHAPE_CRITERIA["line"], "line")
    pts = _points(points, (2, 3), "line")
    if crit == "minimum-zone" and pts.shape[1] == 3:
        # straightness in space: the thinnest cylinder around the points (MCC, Eq. 6.13);
        # the zone is its diameter
        nominal, tilt_rad = search_settings(axis, max_tilt, "line")
        z = _core.form.line3_min_zone(pts, int(seed), nominal, tilt_rad)
        cert = _cert(z)
        warnings = () if z.outside is None else (outside_warning("minimum-zone", _Diameter(z.outside), max_tilt),)
        return LineFit(
            crit, len(pts), _vec(z.point), _vec(z.direction), float(z.form_error), cert,
            tuple(int(i) for i in z.control), tilt_deg=math.degrees(z.tilt), warnings=warnings,
        )
    if crit == "minimum-zone":
        z = _core.form.min_zone_flat(pts)
        cert = _cert(z)
        return LineFit(crit, len(pts), _vec(z.point), _vec(z.direction), float(z.form_error), cert, tuple(z.control))
    ls = _core.form.line_lsq(pts)
    return LineFit(crit, len(pts), _vec(ls.point), _vec(ls.direction), float(ls.form_error), _cert(ls))


def fit_plane(points: Any, criterion: str = "least-squares") -> PlaneFit:
    """Plane of (n, 3) points.

    ``least-squares``: through the centroid, normal along the direction of least spread;
    ``form_error`` is the peak-to-valley about that plane. ``minimum-zone`` (flatness): the
    two parallel planes of least separation, by LP in the least-squares frame (clarabel),
    an exact solve of the active constraints and re-linearisation until the tilt vanishes;
    the mid-plane is reported and ``form_error`` is recomputed from its normal.
    """
    crit = criterion_name(criterion, SHAPE_CRITERIA["plane"], "plane")
    pts = _points(points, (3,), "plane")
    if crit == "minimum-zone":
        z = _core.form.min_zone_flat(pts)
        cert = _cert(z)
        return PlaneFit(crit, len(pts), _vec(z.point), _vec(z.normal), float(z.form_error), cert, tuple(z.control))
    ls = _core.form.plane_lsq(pts)
    return PlaneFit(crit, len(pts), _vec(ls.point), _vec(ls.normal), float(ls.form_error), _cert(ls))


def fit_sphere(points: Any, criterion: str = "least-squares") -> SphereFit:
    """Sphere of (n, 3) points (or least-squares circle of (n, 2) points).

    ``least-squares``: minimises the squared orthogonal distances |p - c| - r
    (Levenberg-Marquardt from an algebraic start). ``min-circumscribed``: the smallest
    sphere containing every point (Welzl's algorithm in 3-D, exact; the 3-D form of
    Eq. 6.1). ``max-inscribed``: the largest sphere with no point inside, within the
    circumscribed one (the 3-D form of Eq. 6.2). ``minimum-zone`` (sphericity): two
    concentric spheres of least radial separation enclosing the points (the 3-D form of
    Eq. 6.5). MI and MZ are global: a certified branch and bound over the centre (interval
    and linearised bounds of the distances on cubes of centres) to 1e-9 mm (or 1e-13 of
    the part's size), then the exact local step (sequential linear programming) from its
    best centre; MZ searches centres within the least-squares radius of the least-squares
    centre, MI the whole MC sphere. Coplanar points raise
    :class:`DegenerateGeometryError` (except for the circumscribed sphere).
    """
    crit = criterion_name(criterion, SHAPE_CRITERIA["sphere"], "sphere")
    pts = _points(points, (2, 3), "sphere")
    if crit != "least-squares":
        if pts.shape[1] != 3:
            raise ConfigError(f"sphere: {crit} needs (n, 3) points; for 2-D points use fit_circle")
        return chebyshev_sphere(_core.form.sphere_fit(pts, crit), crit, len(pts))
    ls = _core.form.sphere_lsq(pts)
    shape = "sphere" if pts.shape[1] == 3 else "circle"
    return SphereFit(crit, len(pts), _vec(ls.center), float(ls.radius), float(ls.form_error), _cert(ls), shape)


def chebyshev_sphere(z: Any, crit: str, n_points: int) -> SphereFit:
    """The :class:`SphereFit` of a Chebyshev sphere from Rust (``_core.form.SphereResult``)."""
    radius = {"min-circumscribed": z.r_out, "max-inscribed": z.r_in}.get(crit, 0.5 * (z.r_in + z.r_out))
    cert = _cert(z)
    if crit == "minimum-zone":
        inner = list(z.control_in)
        seen = set(inner)
        control = inner + [i for i in z.control_out if i not in seen]
    else:
        control = z.control_out
    return SphereFit(
        crit, n_points, _vec(z.center), float(radius), cert.max_distance - cert.min_distance, cert,
        inner_radius=float(z.r_in) if crit == "minimum-zone" else None,
        outer_radius=float(z.r_out) if crit == "minimum-zone" else None,
        control_points=tuple(int(i) for i in control),
        global_bound=float(z.bound) if crit != "min-circumscribed" else None,
    )


def fit_circle_3d(points: Any, criterion: str = "least-squares") -> Circle3DFit:
    """Least-squares circle of (n, 3) points in space (NIST's convention): least-squares
    plane, projection of the points onto it, least-squares circle in that plane."""
    crit = criterion_name(criterion, ("least-squares",), "3-D circle")
    pts = _points(points, (3,), "3-D circle")
    ls = _core.form.circle3d_lsq(pts)
    return Circle3DFit(crit, len(pts), _vec(ls.center), _vec(ls.normal), float(ls.radius), float(ls.form_error), _cert(ls))
