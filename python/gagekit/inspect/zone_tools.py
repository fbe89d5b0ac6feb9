"""The small exact tools the callouts share (zones, sizes, material conditions): the
measured value of a callout (:class:`Measurement`), the projection of points normal to a
direction and the element (surface, derived axis or median line) a callout
measures (ISO 1101, ISO 5459 as in :mod:`.zones`). The searches over a turn angle live in
the kernel (``gagekit_gdt::turn``)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

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


def _element(fd: FeatureData) -> tuple[np.ndarray, str]:
    if fd.shape == "plane":
        return fd.points, "surface"
    pts = fd.axis_points()
    return pts, ("derived axis" if fd.spec.axis == "least-squares" else f"median line ({len(pts)} section centres)")
