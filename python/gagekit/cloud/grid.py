"""A point cloud indexed by a uniform cell grid, for repeated region queries.

The sampling volumes of Sec. 5.4.1 are oriented boxes (:class:`~gagekit.cloud.regions.Box`).
:func:`~gagekit.cloud.regions.select` classifies every point for each box; an
interactive editor that recounts a box on every drag of a handle would pay a
full pass over a 14-million-point scan each time. :class:`IndexedCloud` sorts the
point numbers once into grid cells (Rust); a query then only tests the points of
the cells the box cuts, and returns exactly what ``select`` returns.
"""

from __future__ import annotations

import numpy as np

from .. import _core
from .._util import as_points
from .regions import Box

DEFAULT_PER_CELL = 64
"""Average points per cell: small enough that partial cells are cheap, large
enough that the offsets array stays small."""


class IndexedCloud:
    """A cloud and a grid over its points (the points themselves are not moved).

    Indices returned refer to the rows of :attr:`points`, as those of
    :func:`~gagekit.cloud.regions.select` do. :attr:`points` is read-only: the grid
    was built for these coordinates.

    Raises :class:`~gagekit.errors.InvalidInputError` for an empty cloud or a
    non-finite coordinate.
    """

    def __init__(self, points, per_cell: int = DEFAULT_PER_CELL) -> None:
        pts = as_points(points, 3, "cloud")
        if pts is points and pts.flags.writeable:
            pts = pts.view()
        pts.flags.writeable = False
        self._grid = _core.geometry.grid_build(pts, int(max(1, per_cell)))
        self.points: np.ndarray = pts

    def __len__(self) -> int:
        return len(self.points)

    @property
    def cell_size(self) -> float:
        """Edge length of a grid cell (mm)."""
        return float(self._grid.cell_size)

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Smallest and largest x, y, z of the points (found while indexing)."""
        lo, hi = self._grid.bounds
        return np.array(lo), np.array(hi)

    def select(self, region: Box) -> np.ndarray:
        """Ascending indices of the points inside ``region`` (boundary included)."""
        return self._grid.select(np.asarray(region.row(), dtype=np.float64))

    def count(self, region: Box) -> int:
        """Number of points inside ``region`` (boundary included)."""
        return int(self._grid.count(np.asarray(region.row(), dtype=np.float64)))


__all__ = ["IndexedCloud", "DEFAULT_PER_CELL"]
