"""Point clouds: reading and writing, sampling regions, the convex-hull filter."""

from .io import read_points, write_points
from .regions import Box, classify, select

__all__ = [
    "Box",
    "classify",
    "read_points",
    "select",
    "write_points",
]
