"""Convex-hull filter (Sec. 5.4.1): keep only the hull vertices ``S'`` of a point set."""

from __future__ import annotations

import numpy as np

from .. import _core
from .._util import as_points


def convex_hull_indices(points) -> np.ndarray:
    """Indices (ascending, int64) of the vertices ``S'`` of the convex hull of ``points``.

    ``CH(S) = CH(S')`` (Eq. 5.21): every input point lies in the hull of the
    returned subset, and every returned point is an extreme point (points inside
    the hull or in the relative interior of a hull edge or face are dropped). All
    orientation decisions use exact predicates, so this holds without tolerance.
    Among duplicate points the lowest index is returned.

    Degenerate sets are handled: no points give an empty array, collinear points
    their two end points, exactly coplanar points the vertices of their 2-D hull.
    A nearly planar scanned face gets its true 3-D hull (Table 5.2: 20,664 points
    of a flange face reduce to 87).

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Coordinates in mm.

    Raises
    ------
    InvalidInputError
        Wrong shape, non-numeric values, a NaN/inf coordinate, or a magnitude
        beyond 1e100 or below 1e-60 other than 0 (the exact predicates need
        products of coordinates in the normal floating-point range). The message
        names the point.

    References
    ----------
    Dissertation Sec. 5.4.1, Eqs. 5.20-5.21.
    """
    pts = as_points(points)
    return _core.geometry.hull_indices(pts)
