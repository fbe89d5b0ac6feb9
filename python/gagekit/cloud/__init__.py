"""Point clouds: reading and writing, sampling regions, the convex-hull filter."""

from .hull import convex_hull_indices
from .regions import Box, classify, select

__all__ = ["Box", "classify", "convex_hull_indices", "select"]
