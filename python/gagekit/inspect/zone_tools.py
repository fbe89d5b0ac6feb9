"""The small exact tools the callouts share (zones, sizes, material conditions): the
measured value of a callout (:class:`Measurement`), the minimum enclosing circle of 2-D
points (Welzl, exact) and the element (surface, derived axis or median line) a callout
measures (ISO 1101, ISO 5459 as in :mod:`.zones`). The searches over a turn angle live in
the kernel (``gagekit_gdt::turn``)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .. import _core
from .features import FeatureData, _basis

__all__ = ["Measurement"]


@dataclass(frozen=True)
class Measurement:
    value: float
    zone: str
    element: str
    n_points: int
    details: dict = field(default_factory=dict)
    #: two-sided callouts (sizes, distances, angles) and material conditions: the margin
    #: to the nearer limit / to the zone with its bonus; ``None``: ``tolerance - value``
    margin: Optional[float] = None
    #: top-level JSON keys of the callout (limits, local sizes, bonus, ...)
    extra: dict = field(default_factory=dict)


def _plane_2d(points: np.ndarray, d: np.ndarray) -> np.ndarray:
    u, v = _basis(d)
    return np.ascontiguousarray(np.column_stack([points @ u, points @ v]))


def _mec_radius(xy: np.ndarray) -> tuple[float, np.ndarray]:
    """Minimum circumscribed circle of 2-D points (Welzl, exact): (radius, centre)."""
    if len(xy) == 1:
        return 0.0, xy[0]
    if len(xy) == 2:
        return 0.5 * float(np.linalg.norm(xy[1] - xy[0])), 0.5 * (xy[0] + xy[1])
    if np.ptp(xy, axis=0).max() == 0.0:
        return 0.0, xy[0]
    c = _core.form_circle_fit(np.ascontiguousarray(xy), "min-circumscribed").center
    r = float(np.linalg.norm(xy - np.array(c), axis=1).max())
    return r, np.array(c)


def _element(fd: FeatureData) -> tuple[np.ndarray, str]:
    if fd.shape == "plane":
        return fd.points, "surface"
    pts = fd.axis_points()
    return pts, ("derived axis" if fd.spec.axis == "least-squares" else f"median line ({len(pts)} section centres)")
