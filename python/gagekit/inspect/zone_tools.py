"""The small exact tools the callouts share (zones, sizes, material conditions): the
measured value of a callout (:class:`Measurement`), the minimum enclosing circle of 2-D
points (Welzl, exact), the exact minimum of an upper envelope of sinusoids, the search over
a turn angle, a rotation about a frame's z axis, and the element (surface, derived axis or
median line) a callout measures (ISO 1101, ISO 5459 as in :mod:`.zones`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np

from .. import _core
from .features import FeatureData, _basis, golden_min

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
    c = _core.form.circle_fit(np.ascontiguousarray(xy), "min-circumscribed").center
    r = float(np.linalg.norm(xy - np.array(c), axis=1).max())
    return r, np.array(c)


def _min_max_sinusoids(a: np.ndarray, b: np.ndarray, phi: np.ndarray) -> tuple[float, float]:
    """Exact (value, psi) of min over psi of max_i f_i(psi), f_i = a_i - b_i cos(psi - phi_i):
    the minimum of the upper envelope lies at the minimum of one sinusoid or where two
    cross, (a_i - a_j) = r cos(psi - d); every candidate is scored on every f_i."""
    cand = [phi]
    i, j = np.triu_indices(len(a), 1)
    if len(i):
        c1 = b[i] * np.cos(phi[i]) - b[j] * np.cos(phi[j])
        s1 = b[i] * np.sin(phi[i]) - b[j] * np.sin(phi[j])
        r, d, rhs = np.hypot(c1, s1), np.arctan2(s1, c1), a[i] - a[j]
        ok = (r > 0) & (np.abs(rhs) <= r)
        t = np.arccos(np.clip(rhs[ok] / r[ok], -1.0, 1.0))
        cand += [d[ok] + t, d[ok] - t]
    psi = np.concatenate(cand)
    env = (a[None, :] - b[None, :] * np.cos(psi[:, None] - phi[None, :])).max(axis=1)
    k = int(np.argmin(env))
    return float(env[k]), float(psi[k])


def _min_over_turn(f: Callable[[float], float], grid: int = 720) -> tuple[float, float]:
    """Minimum of a continuous function of a turn angle: grid, then golden-section search
    in the best three cells (deterministic)."""
    step = 2 * math.pi / grid
    vals = [f(k * step) for k in range(grid)]
    cells = sorted(range(grid), key=lambda k: (vals[k], k))[:3]
    best = (vals[cells[0]], cells[0] * step)
    for k in cells:
        fx, x = golden_min(f, (k - 1) * step, (k + 1) * step)
        if fx < best[0]:
            best = (fx, x)
    return best


def _rot_z(frame, psi: float) -> tuple[Callable, Callable]:
    """Maps rotating nominal points / directions by psi about the frame's z axis."""
    z = frame.axes[2]
    c, s = math.cos(psi), math.sin(psi)
    K = np.array([[0, -z[2], z[1]], [z[2], 0, -z[0]], [-z[1], z[0], 0]])
    R = np.eye(3) + s * K + (1 - c) * (K @ K)
    return (lambda p: frame.origin + R @ (p - frame.origin)), (lambda d: R @ d)


def _element(fd: FeatureData) -> tuple[np.ndarray, str]:
    if fd.shape == "plane":
        return fd.points, "surface"
    pts = fd.axis_points()
    return pts, ("derived axis" if fd.spec.axis == "least-squares" else f"median line ({len(pts)} section centres)")
