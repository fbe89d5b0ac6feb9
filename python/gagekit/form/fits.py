"""Least-squares lines, planes, spheres and 3-D circles (geometric fits, ASME B89.4.10).

Every fit minimises the sum of squared *orthogonal* distances of the points to
the feature, as the NIST Algorithm Testing System defines it; the kernels work on
centred data, so parts far from the origin lose no accuracy. Each result carries a
certificate: the minimum and maximum distance of the input points to the reported
feature, recomputed from the reported parameters.

The results are the Rust objects of ``gagekit._core.form`` (assembled once in
``gagekit_form::result``); these functions read the arguments in.

References: dissertation Ch. 6 (Sec. 6.2-6.3; Eqs. 6.1-6.5 for circles, 6.9-6.11
for cylinders); the 3-D circle follows NIST's convention (least-squares plane,
projection, least-squares circle in that plane).
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np

from .. import _core
from .._core.form import Certificate, Circle3DFit, LineFit, PlaneFit, SphereFit
from .._util import as_points
from ..errors import InvalidInputError
from .search import search_settings

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
    pts = _points(points, (2, 3), "line")
    nominal, tilt = search_settings(axis, max_tilt, "line")
    return _core.form.fit_line(pts, str(criterion), int(seed), nominal, tilt)


def fit_plane(points: Any, criterion: str = "least-squares") -> PlaneFit:
    """Plane of (n, 3) points.

    ``least-squares``: through the centroid, normal along the direction of least spread;
    ``form_error`` is the peak-to-valley about that plane. ``minimum-zone`` (flatness): the
    two parallel planes of least separation, by LP in the least-squares frame (clarabel),
    an exact solve of the active constraints and re-linearisation until the tilt vanishes;
    the mid-plane is reported and ``form_error`` is recomputed from its normal.
    """
    return _core.form.fit_plane(_points(points, (3,), "plane"), str(criterion))


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
    return _core.form.fit_sphere(_points(points, (2, 3), "sphere"), str(criterion))


def fit_circle_3d(points: Any, criterion: str = "least-squares") -> Circle3DFit:
    """Least-squares circle of (n, 3) points in space (NIST's convention): least-squares
    plane, projection of the points onto it, least-squares circle in that plane."""
    return _core.form.fit_circle_3d(_points(points, (3,), "3-D circle"), str(criterion))
