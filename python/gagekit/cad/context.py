"""The CAD model of a drawing's ``[part] cad`` as the inspection uses it: every scan point's
signed distance to the model and its nearest face, and a feature's points by ``faces``
within ``band`` (see :mod:`.features` for the rule)."""

from __future__ import annotations

from functools import lru_cache
from typing import Optional

import numpy as np

__all__ = ["BAND_REACH", "CadContext", "cad_model"]

#: Points farther than this from the faces never count for the default band.
BAND_REACH = 1.0


@lru_cache(maxsize=4)
def cad_model(path: str):
    """The CAD model of a drawing's ``[part] cad`` (read once per path: a STEP model's
    tessellation takes seconds; the inspection and the studio share it)."""
    from . import read_cad

    return read_cad(path)


class CadContext:
    """The CAD model and every scan point's signed distance, nearest face and triangle."""

    def __init__(self, model, distance: np.ndarray, face: np.ndarray, triangle: Optional[np.ndarray] = None) -> None:
        self.model = model
        self.distance = distance
        self.face = face
        self.triangle = triangle

    @classmethod
    def of_scan(cls, path: str, points: np.ndarray) -> "CadContext":
        model = cad_model(str(path))
        d = model.distances(points)
        return cls(model, d.distance, d.face, d.triangle)

    def face_set(self, feature, where: str) -> list[int]:
        return sorted({self.model.face_index(k, f"{where}: 'faces'") for k in feature.faces})

    def indices(self, feature, where: str) -> np.ndarray:
        on = np.isin(self.face, self.face_set(feature, where))
        d = self.distance
        band = feature.band
        if band is None:
            near = d[on & (np.abs(d) <= BAND_REACH)]
            band = max(3.0 * float(np.sqrt(np.mean(near * near))) if len(near) else 0.0, 1e-9)
        return np.flatnonzero(on & (np.abs(d) <= band))
