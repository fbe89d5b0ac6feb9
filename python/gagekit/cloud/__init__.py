"""Point clouds: reading and writing, sampling regions, the convex-hull filter."""

from .regions import Box, classify, select

__all__ = ["Box", "classify", "select"]
