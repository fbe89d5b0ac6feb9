"""The CAD model beside the scan: the mesh the browser draws and its colours after *Run*.

- The mesh is the model's triangles (a STEP model's tessellation, :mod:`gagekit.cad.step`),
  in millimetres, sent as float32 vertices relative to the model's centre and uint32
  triangles. Above :data:`MAX_CAD_TRIANGLES` it is decimated by vertex clustering
  (Rossignac and Borrel 1993): the vertices of each cubic cell of a grid merge into their
  mean, triangles whose corners fall into fewer than three cells drop; the cell grows
  until at most :data:`MAX_CAD_TRIANGLES` remain. Display only: every distance is
  computed on the full model.
- After *Run* each vertex is coloured as ``gagekit compare --report`` colours the model:
  the mean signed deviation of the scan points whose nearest triangle has it as a corner
  (:func:`gagekit.cad.compare.vertex_deviations`), on the report's colour scale
  (:func:`gagekit.report.compare.vertex_rgb`, grey: no point near); a decimated vertex
  takes the mean over the points of the vertices it merges.
"""

from __future__ import annotations

import base64
import itertools
from pathlib import Path
from typing import Any, Optional

import numpy as np

__all__ = ["CadView", "decimate", "MAX_CAD_TRIANGLES"]

#: The most triangles the studio sends to the browser (larger models are decimated).
MAX_CAD_TRIANGLES = 300_000

_KEYS = itertools.count(1)


def decimate(vertices: np.ndarray, triangles: np.ndarray, max_triangles: int) -> tuple[np.ndarray, np.ndarray, Optional[np.ndarray]]:
    """(vertices, triangles, cluster) of a mesh with at most ``max_triangles`` triangles:
    the mesh itself (cluster None) when it is small enough, else its vertex clustering
    (module docstring); ``cluster[i]`` is the vertex that original vertex ``i`` became."""
    v = np.asarray(vertices, dtype=np.float64)
    t = np.asarray(triangles, dtype=np.int64)
    if len(t) <= max_triangles:
        return v, t, None
    lo = v.min(axis=0)
    e = v[t]
    area = 0.5 * float(np.linalg.norm(np.cross(e[:, 1] - e[:, 0], e[:, 2] - e[:, 0]), axis=1).sum())
    span = float(np.max(v.max(axis=0) - lo)) or 1.0
    cell = max(np.sqrt(2.0 * area / max_triangles), span * 1e-6)  # a closed surface: about 2 triangles per cell
    while True:
        k = np.floor((v - lo) / cell).astype(np.int64)
        dims = k.max(axis=0) + 1
        _, cluster = np.unique((k[:, 0] * dims[1] + k[:, 1]) * dims[2] + k[:, 2], return_inverse=True)
        cluster = cluster.ravel()
        ct = cluster[t]
        ct = ct[(ct[:, 0] != ct[:, 1]) & (ct[:, 1] != ct[:, 2]) & (ct[:, 0] != ct[:, 2])]
        _, first = np.unique(np.sort(ct, axis=1), axis=0, return_index=True)
        ct = ct[np.sort(first)]  # one triangle per corner set, in the model's order
        if len(ct) <= max_triangles:
            break
        cell *= max(1.1, float(np.sqrt(len(ct) / max_triangles)))
    n = int(cluster.max()) + 1
    count = np.bincount(cluster, minlength=n)
    mean = np.column_stack([np.bincount(cluster, weights=v[:, j], minlength=n) for j in range(3)]) / count[:, None]
    used = np.unique(ct)  # cells without a triangle left (slivers) are not sent
    remap = np.full(n, -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return mean[used], remap[ct], remap[cluster]


class CadView:
    """One CAD model as the studio shows it (``name``: its path in the studio folder)."""

    def __init__(self, model: Any, name: str, max_distance: Optional[float] = None,
                 max_triangles: int = MAX_CAD_TRIANGLES) -> None:
        self.model = model
        self.name = name
        self.max_distance = max_distance
        self.key = next(_KEYS)
        self.vertices, self.triangles, self.cluster = decimate(model.vertices, model.triangles, max_triangles)
        self.origin = np.round((self.vertices.min(axis=0) + self.vertices.max(axis=0)) / 2.0, 3)
        self.max_triangles = max_triangles

    def info(self) -> dict[str, Any]:
        m = self.model
        return {"name": self.name, "key": self.key, "format": m.format, "unit": m.unit, "faces": len(m.faces),
                "triangles": int(len(m.triangles)), "shown_triangles": int(len(self.triangles)),
                "shown_vertices": int(len(self.vertices)), "decimated": self.cluster is not None,
                "max_triangles": self.max_triangles, "origin": self.origin.tolist(), "signed": bool(m.signed),
                "max_distance": self.max_distance, "warnings": list(m.warnings), "distance_method": m.method}

    def buffer(self) -> bytes:
        """float32 x, y, z of the shown vertices minus :attr:`origin`, then uint32 corner
        indices of the shown triangles (little-endian)."""
        v = np.ascontiguousarray(self.vertices - self.origin, dtype="<f4").tobytes()
        return v + np.ascontiguousarray(self.triangles, dtype="<u4").tobytes()

    def colours(self, triangle: np.ndarray, deviation: np.ndarray) -> dict[str, Any]:
        """The shown vertices' colours from every scan point's nearest triangle and signed
        deviation (NaN: not used), with the colour scale for the legend."""
        from ..cad.compare import vertex_deviations
        from ..report.compare import colour_limit, colour_stops, vertex_rgb

        d = np.asarray(deviation, dtype=np.float64)
        if self.max_distance is not None:
            d = np.where(np.abs(d) <= self.max_distance, d, np.nan)
        mean, count = vertex_deviations(self.model, triangle, d)
        if self.cluster is not None:
            n = len(self.vertices)
            total = np.bincount(self.cluster, weights=mean * count, minlength=n)
            count = np.bincount(self.cluster, weights=count, minlength=n)
            mean = np.where(count > 0, total / np.maximum(count, 1), 0.0)
        used = np.isfinite(d)
        lim = colour_limit(d)
        rgb = vertex_rgb(mean, count, lim)
        return {"key": self.key, "colours": base64.b64encode(np.ascontiguousarray(rgb, dtype=np.uint8).tobytes()).decode("ascii"),
                "limit": lim, "stops": colour_stops(), "coloured_vertices": int((count > 0).sum()),
                "n_points": int(used.sum()), "n_beyond": int(len(d) - used.sum()),
                "range": [float(d[used].min()), float(d[used].max())] if used.any() else None}


def ply_has_faces(path: Path) -> bool:
    """Whether a PLY file's header declares faces (a mesh, not a point cloud)."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(4096)
    except OSError:
        return False
    head = head.split(b"end_header")[0]
    for line in head.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[0] == b"element" and parts[1] == b"face":
            return parts[2].isdigit() and int(parts[2]) > 0
    return False
