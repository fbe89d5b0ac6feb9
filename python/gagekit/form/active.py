"""Minimum-zone fits on an active set, exact by verification.

A minimum-zone zone is decided by a few extreme points. When a nearby zone is known (the
zone of the unperturbed scan, when a Monte Carlo trial re-fits a perturbed copy), the fit
runs on the points within ``band`` x the zone width of its two boundaries, and the result
is verified on every point: a zone of the subset that contains all points is optimal for
all points (the full set's minimum cannot be smaller than the subset's), so it is the
minimum zone; otherwise the points outside join the subset and the fit runs again. The
answer equals the fit of every point up to :data:`gagekit._util.LENGTH_RESOLUTION_MM`
(1 pm, the containment test's tolerance), and to the fits' own global search.

Used in Monte Carlo trials for spheres (the certified branch and bound's cost grows with
the points: 10-20x faster on the bracket's ball), minimum-zone circles (a roundness
section: started from the least-squares centre) and the thinnest slab (flatness: started
from the measured zone's normal). Not for cylinders: those start the exact local method
from the measured axis instead (:func:`gagekit.form.fit_cylinder` ``warm=``), on the
kernel's own active subset.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from .._util import LENGTH_RESOLUTION_MM
from ..errors import GagekitError

__all__ = ["minimum_zone_sphere_near", "minimum_zone_circle_near", "thinnest_slab_near", "active_fit"]

#: Points within this fraction of the zone width of either boundary of the nearby zone start the active set.
BAND = 0.2


def active_fit(points: np.ndarray, start: np.ndarray, fit: Callable[[np.ndarray], Any],
               bounds: Callable[[Any, np.ndarray], tuple[np.ndarray, float, float]]) -> Any:
    """The fit of ``points`` by fitting the subset ``start`` (a boolean mask) and growing
    it by the points outside the subset's zone until none is: ``bounds(fit, points)``
    gives (every point's radial distance, inner, outer) of a fit."""
    sel = np.asarray(start, dtype=bool).copy()
    while True:
        if sel.all():
            return fit(points)
        try:
            f = fit(np.ascontiguousarray(points[sel]))
        except GagekitError:  # a subset too small or degenerate for the kernel: the fit of every point
            return fit(points)
        r, lo, hi = bounds(f, points)
        out = (r < lo - LENGTH_RESOLUTION_MM) | (r > hi + LENGTH_RESOLUTION_MM)
        if not out.any():
            return f
        sel |= out


#: ... and at least this many points of each extreme.
MIN_EXTREMES = 16


def _band(r: np.ndarray) -> np.ndarray:
    lo, hi = float(r.min()), float(r.max())
    w = BAND * (hi - lo)
    sel = (r <= lo + w) | (r >= hi - w)
    if len(r) > 2 * MIN_EXTREMES:
        order = np.argsort(r, kind="stable")
        sel[order[:MIN_EXTREMES]] = True
        sel[order[-MIN_EXTREMES:]] = True
    else:
        sel[:] = True
    return sel


def minimum_zone_sphere_near(points: np.ndarray, near_center: Any) -> Any:
    """:func:`gagekit.form.fit_sphere` ``(points, "minimum-zone")`` on an active set started
    from the centre of a nearby minimum zone (module docstring)."""
    from .fits import fit_sphere

    start = _band(np.linalg.norm(points - np.asarray(near_center, dtype=float), axis=1))
    return active_fit(points, start, lambda p: fit_sphere(p, "minimum-zone"),
                      lambda f, p: (np.linalg.norm(p - np.asarray(f.center), axis=1), f.inner_radius, f.outer_radius))


def minimum_zone_circle_near(xy: np.ndarray, near_center: Any) -> Any:
    """:func:`gagekit.form.fit_circle` ``(xy, "mz")`` of (n, 2) points on an active set
    started from a nearby centre (e.g. the least-squares centre): exact by verification
    (module docstring)."""
    from .circle import fit_circle

    start = _band(np.linalg.norm(xy - np.asarray(near_center, dtype=float), axis=1))
    return active_fit(xy, start, lambda p: fit_circle(p, "mz"),
                      lambda f, p: (np.linalg.norm(p - np.asarray(f.center), axis=1), f.r_in, f.r_out))


def thinnest_slab_near(points: np.ndarray, near_normal: Any) -> tuple[float, np.ndarray]:
    """(width, normal) of the thinnest slab of (n, 3) points (the flatness zone: the
    kernel's exact minimum width) on an active set started from the points near the two
    planes of a nearby zone of normal ``near_normal``: a slab of the subset that holds
    every point is the thinnest of all points (the subset's cannot be wider)."""
    from .. import _core

    start = _band(points @ np.asarray(near_normal, dtype=float))
    normal, _, _, width = active_fit(points, start, lambda p: _core.gdt_slab(p, "free", (0.0, 0.0, 1.0), 0.0),
                                     lambda f, p: (p @ np.asarray(f[0]), f[1], f[2]))
    return float(width), np.array(normal)
