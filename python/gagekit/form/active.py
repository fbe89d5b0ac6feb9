"""Minimum-zone fits on an active set, exact by verification.

A minimum-zone zone is decided by a few extreme points. When a nearby zone is known (the
zone of the unperturbed scan, when a Monte Carlo trial re-fits a perturbed copy), the fit
runs on the points within ``band`` x the zone width of its two boundaries, and the result
is verified on every point (the kernel ``gagekit_gdt::plan::active``, which the compiled Monte Carlo
trials use too): a zone of the subset that contains all points is optimal for
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

from typing import Any

import numpy as np

from .. import _core

__all__ = ["minimum_zone_sphere_near", "minimum_zone_circle_near", "thinnest_slab_near"]


def minimum_zone_sphere_near(points: np.ndarray, near_center: Any) -> Any:
    """:func:`gagekit.form.fit_sphere` ``(points, "minimum-zone")`` on an active set started
    from the centre of a nearby minimum zone (module docstring)."""
    p = np.ascontiguousarray(points, dtype=float)
    c = tuple(float(x) for x in np.asarray(near_center, dtype=float).reshape(3))
    return _core.form.fit_sphere_near(p, c)


def minimum_zone_circle_near(xy: np.ndarray, near_center: Any) -> Any:
    """:func:`gagekit.form.fit_circle` ``(xy, "mz")`` of (n, 2) points on an active set
    started from a nearby centre (e.g. the least-squares centre): exact by verification
    (module docstring)."""
    p = np.ascontiguousarray(xy, dtype=float)
    c = tuple(float(x) for x in np.asarray(near_center, dtype=float).reshape(2))
    return _core.form.fit_circle_near(p, c)


def thinnest_slab_near(points: np.ndarray, near_normal: Any) -> tuple[float, np.ndarray]:
    """(width, normal) of the thinnest slab of (n, 3) points (the flatness zone: the
    kernel's exact minimum width) on an active set started from the points near the two
    planes of a nearby zone of normal ``near_normal``: a slab of the subset that holds
    every point is the thinnest of all points (the subset's cannot be wider)."""
    p = np.ascontiguousarray(points, dtype=float)
    n = tuple(float(x) for x in np.asarray(near_normal, dtype=float).reshape(3))
    normal, _, _, width = _core.gdt.slab_near(p, n)
    return float(width), np.array(normal)
