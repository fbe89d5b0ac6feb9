"""Minimum-zone fits on an active set, exact by verification.

A minimum-zone zone is decided by a few extreme points. When a nearby zone is known (the
zone of the unperturbed scan, when a Monte Carlo trial re-fits a perturbed copy), the fit
runs on the points within ``band`` x the zone width of its two boundaries, and the result
is verified on every point: a zone of the subset that contains all points is optimal for
all points (the full set's minimum cannot be smaller than the subset's), so it is the
minimum zone; otherwise the points outside join the subset and the fit runs again. The
answer equals the fit of every point up to :data:`gagekit._util.LENGTH_RESOLUTION_MM`
(1 pm, the containment test's tolerance), and to the fits' own global search.

Used for spheres (the certified branch and bound's cost grows with the points: 10-20x
faster on the bracket's ball). Not for cylinders: the swarm's 2-D exact fits already work
on the projected convex hulls, and a band of extreme points is all hull (slower, measured).
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from .._util import LENGTH_RESOLUTION_MM

__all__ = ["minimum_zone_sphere_near", "active_fit"]

#: Points within this fraction of the zone width of either boundary of the nearby zone start the active set.
BAND = 0.2


def active_fit(points: np.ndarray, start: np.ndarray, fit: Callable[[np.ndarray], Any],
               bounds: Callable[[Any, np.ndarray], tuple[np.ndarray, float, float]]) -> Any:
    """The fit of ``points`` by fitting the subset ``start`` (a boolean mask) and growing
    it by the points outside the subset's zone until none is: ``bounds(fit, points)``
    gives (every point's radial distance, inner, outer) of a fit."""
    sel = np.asarray(start, dtype=bool).copy()
    while True:
        f = fit(np.ascontiguousarray(points[sel]))
        r, lo, hi = bounds(f, points)
        out = (r < lo - LENGTH_RESOLUTION_MM) | (r > hi + LENGTH_RESOLUTION_MM)
        if not out.any():
            return f
        sel |= out


def _band(r: np.ndarray) -> np.ndarray:
    lo, hi = float(r.min()), float(r.max())
    w = BAND * (hi - lo)
    return (r <= lo + w) | (r >= hi - w)


def minimum_zone_sphere_near(points: np.ndarray, near_center: Any) -> Any:
    """:func:`gagekit.form.fit_sphere` ``(points, "minimum-zone")`` on an active set started
    from the centre of a nearby minimum zone (module docstring)."""
    from .fits import fit_sphere

    start = _band(np.linalg.norm(points - np.asarray(near_center, dtype=float), axis=1))
    return active_fit(points, start, lambda p: fit_sphere(p, "minimum-zone"),
                      lambda f, p: (np.linalg.norm(p - np.asarray(f.center), axis=1), f.inner_radius, f.outer_radius))
