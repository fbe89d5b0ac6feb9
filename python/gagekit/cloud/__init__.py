"""Point clouds: reading and writing, sampling regions, the convex-hull filter."""

from .io import read_points, write_points
from .regions import Box, classify, load_regions, regions_from_tables, select

__all__ = [
    "Box",
    "classify",
    "load_regions",
    "read_points",
    "regions_from_tables",
    "select",
    "write_points",
]
