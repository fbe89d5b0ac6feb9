"""Rotations: Rodrigues' formula and its inverse, the one copy in the Python package.

The rotation vector ``v`` is the axis times the angle (rad). The Rust kernels keep their own
(``gagekit_core::rotation_from_vector``) for the region tests they run on the points; every
Python module uses the functions below (boxes of Sec. 5.4.1, the measurement frame of
Eq. 3.10, the error motions of ISO 230-1, the inspection regions).
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

__all__ = ["rotation_from_vector", "rotations_about", "rotation_vector"]


def rotation_from_vector(v: Sequence[float] | np.ndarray) -> np.ndarray:
    """Exact rotation matrix of the rotation vector ``v`` (Rodrigues:
    R = I + sin(t)/t K + (1 - cos(t))/t^2 K^2, with K the cross-product matrix of v and
    t = |v|; the second-order series below t = 1e-12)."""
    v = np.asarray(v, dtype=np.float64)
    th = float(np.linalg.norm(v))
    k = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    if th < 1e-12:
        return np.eye(3) + k + 0.5 * k @ k
    return np.eye(3) + math.sin(th) / th * k + (1.0 - math.cos(th)) / th**2 * k @ k


def rotations_about(axis: Any, angles: Any) -> np.ndarray:
    """(n, 3, 3) rotations about the unit ``axis`` by each of ``angles`` (rad), Rodrigues'
    formula vectorised over the angles."""
    a = np.asarray(axis, dtype=np.float64)
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    s = np.sin(angles)[:, None, None]
    c = np.cos(angles)[:, None, None]
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


def rotation_vector(R: Any) -> np.ndarray:
    """The rotation vector of a rotation matrix, through the unit quaternion (Shepperd's
    method: the largest of the four candidates is taken first, stable for every angle up
    to pi); the zero vector for the identity."""
    R = np.asarray(R, dtype=np.float64)
    t = float(np.trace(R))
    k = int(np.argmax([t, R[0, 0], R[1, 1], R[2, 2]]))
    if k == 0:
        w = 0.5 * math.sqrt(1.0 + t)
        x, y, z = (R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w), (R[1, 0] - R[0, 1]) / (4 * w)
    elif k == 1:
        x = 0.5 * math.sqrt(1.0 + 2 * R[0, 0] - t)
        w, y, z = (R[2, 1] - R[1, 2]) / (4 * x), (R[0, 1] + R[1, 0]) / (4 * x), (R[0, 2] + R[2, 0]) / (4 * x)
    elif k == 2:
        y = 0.5 * math.sqrt(1.0 + 2 * R[1, 1] - t)
        w, x, z = (R[0, 2] - R[2, 0]) / (4 * y), (R[0, 1] + R[1, 0]) / (4 * y), (R[1, 2] + R[2, 1]) / (4 * y)
    else:
        z = 0.5 * math.sqrt(1.0 + 2 * R[2, 2] - t)
        w, x, y = (R[1, 0] - R[0, 1]) / (4 * z), (R[0, 2] + R[2, 0]) / (4 * z), (R[1, 2] + R[2, 1]) / (4 * z)
    if w < 0:
        w, x, y, z = -w, -x, -y, -z
    s = math.sqrt(x * x + y * y + z * z)
    if s < 1e-300:
        return np.zeros(3)
    return np.array([x, y, z]) / s * (2 * math.atan2(s, w))
