"""Point clouds: reading and writing, sampling regions, the convex-hull filter."""

from .hull import convex_hull_indices
from .io import Cloud, read_cloud, read_points, write_points
from .units import UNIT_NAMES
from .regions import Box, classify, load_regions, regions_from_tables, select
from .workflow import CutResult, RegionCut, cut_and_filter

__all__ = [
    "Box",
    "Cloud",
    "UNIT_NAMES",
    "CutResult",
    "RegionCut",
    "classify",
    "convex_hull_indices",
    "cut_and_filter",
    "load_regions",
    "read_cloud",
    "read_points",
    "regions_from_tables",
    "select",
    "write_points",
]
