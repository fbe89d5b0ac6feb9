"""The tracker's measurement frame T0 (Eqs. 3.10-3.12): rigid transforms, the small frame
correction of Eq. 3.11 and the closed-form rigid fit (Kabsch/Horn)."""

from __future__ import annotations

from dataclasses import dataclass


import numpy as np

from .. import _core
from .._rotation import rotation_from_vector
from ..errors import FileFormatError, InvalidInputError

__all__ = ["Frame", "rotation_from_vector", "frame_columns", "rigid_fit"]


@dataclass(frozen=True)
class Frame:
    """The measurement frame T0: a tracker reading is q = rotation @ p + translation for a
    point p in the table frame (Eq. 3.10, 3.12), mm."""

    rotation: np.ndarray
    translation: np.ndarray

    def __post_init__(self) -> None:
        r = np.asarray(self.rotation, dtype=np.float64).reshape(3, 3)
        t = np.asarray(self.translation, dtype=np.float64).reshape(3)
        if not (np.isfinite(r).all() and np.isfinite(t).all()):
            raise InvalidInputError("frame: non-finite rotation or translation")
        if np.abs(r.T @ r - np.eye(3)).max() > 1e-6 or np.linalg.det(r) < 0:
            raise InvalidInputError("frame: rotation is not a proper rotation matrix")
        object.__setattr__(self, "rotation", r)
        object.__setattr__(self, "translation", t)

    @classmethod
    def identity(cls) -> "Frame":
        return cls(np.eye(3), np.zeros(3))

    def to_tracker(self, p: np.ndarray) -> np.ndarray:
        return np.asarray(p) @ self.rotation.T + self.translation

    def to_table(self, q: np.ndarray) -> np.ndarray:
        return (np.asarray(q) - self.translation) @ self.rotation

    def corrected(self, small: np.ndarray) -> "Frame":
        """This frame followed by the small table-frame motion ``small`` = (alpha0, beta0,
        gamma0, x0, y0, z0) of Eq. 3.11: rotations about z, y, x and a translation."""
        a, b, g, x, y, z = small
        return Frame(self.rotation @ rotation_from_vector([g, b, a]), self.translation + self.rotation @ [x, y, z])

    def to_dict(self) -> dict:
        return {"rotation": self.rotation.tolist(), "translation": self.translation.tolist()}

    @classmethod
    def from_dict(cls, d: dict) -> "Frame":
        try:
            return cls(np.array(d["rotation"], dtype=np.float64), np.array(d["translation"], dtype=np.float64))
        except (KeyError, TypeError, ValueError) as exc:
            raise FileFormatError(f"frame: expected rotation (3x3) and translation (3), {exc}") from None


def frame_columns(p: np.ndarray) -> np.ndarray:
    """(3n, 6) effect of a small table-frame motion (alpha0, beta0, gamma0, x0, y0, z0) on
    points p (n, 3): omega x p + tau."""
    p = np.asarray(p, dtype=np.float64)
    n = p.shape[0]
    out = np.zeros((n, 3, 6))
    for c, ax in enumerate((2, 1, 0)):
        e = np.zeros(3)
        e[ax] = 1.0
        out[:, :, c] = np.cross(e, p)
    out[:, :, 3:] = np.eye(3)
    return out.reshape(3 * n, 6)



def rigid_fit(src: np.ndarray, dst: np.ndarray) -> Frame:
    """The proper rigid motion taking ``src`` (n, 3) to ``dst`` best in least squares
    (Kabsch/Horn, closed form; the Rust kernel)."""
    fit = _core.kinematics.rigid_fit(np.ascontiguousarray(src), np.ascontiguousarray(dst))
    return Frame(fit.rotation, fit.translation)
