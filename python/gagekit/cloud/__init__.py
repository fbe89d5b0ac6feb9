"""Point clouds: reading and writing, sampling regions, the convex-hull filter."""

from .hull import convex_hull_indices
from .io import read_points, write_points
from .regions import Box, classify, load_regions, regions_from_tables, select
from .workflow import CutResult, RegionCut, cut_and_filter

__all__ = [
    "Box",
    "CutResult",
    "RegionCut",
    "classify",
    "convex_hull_indices",
    "cut_and_filter",
    "load_regions",
    "read_points",
    "regions_from_tables",
    "select",
    "write_points",
]
