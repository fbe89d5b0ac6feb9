"""Point-set manipulation of Sec. 5.4.1: cut a cloud into its regions and keep,
in each region, only the vertices of its convex hull (the set S' of Eq. 5.21).

A linear constraint that holds at every hull vertex holds at every point of the
region (a linear function attains its extremes at vertices), so the LP of the
virtual gage needs the hull vertices only.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .hull import convex_hull_indices
from .regions import Box, classify


@dataclass(frozen=True)
class RegionCut:
    """One region: the indices of its points and of its hull vertices (into the cloud)."""

    name: str
    indices: np.ndarray
    hull: np.ndarray

    def to_dict(self) -> dict:
        n, h = len(self.indices), len(self.hull)
        return {"name": self.name, "points": n, "hull_vertices": h, "reduction": (n / h) if h else 0.0}


@dataclass(frozen=True)
class CutResult:
    points: int
    regions: tuple[RegionCut, ...]

    def __getitem__(self, name: str) -> RegionCut:
        for r in self.regions:
            if r.name == name:
                return r
        raise KeyError(name)

    def to_dict(self) -> dict:
        return {"points": self.points, "regions": [r.to_dict() for r in self.regions]}


def cut_and_filter(points, regions: Sequence[Box]) -> CutResult:
    """Classify ``points`` into ``regions`` (one parallel pass) and hull-filter each."""
    pts = np.ascontiguousarray(points, dtype=np.float64)
    cuts = []
    for box, idx in zip(regions, classify(pts, regions)):
        hull = idx[convex_hull_indices(pts[idx])] if len(idx) else idx
        cuts.append(RegionCut(box.name, idx, hull))
    return CutResult(len(pts), tuple(cuts))


def cut_and_filter_stream(chunks, regions: Sequence[Box]) -> CutResult:
    """:func:`cut_and_filter` of a streamed cloud (:mod:`gagekit.cloud.streamed`): every
    inside point's number is kept (8 bytes each), the points themselves only as the hull
    vertices of each chunk's part of a region; the result is the whole read's."""
    from .streamed import cut_stream

    p = cut_stream(chunks, regions, ["hull"] * len(regions), all_indices=True)
    cuts = tuple(RegionCut(r.name, np.concatenate(r.all_indices) if r.all_indices else np.zeros(0, dtype=np.int64),
                           r.index_array()) for r in p.regions)
    return CutResult(p.count, cuts)
