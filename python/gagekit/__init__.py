"""gagekit: machining accuracy for multi-axis CNC machine tools and scanned parts.

See README.md for the command line; the public Python API is listed in ``__all__``.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version as _version

from . import _core
from .cloud import Box, classify, select
from .errors import (
    ConfigError,
    DegenerateGeometryError,
    FileFormatError,
    GagekitError,
    InfeasibleError,
    InternalError,
    InvalidInputError,
    NumericalError,
)

try:
    __version__ = _version("gagekit")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = _core.__version__

__all__ = [
    "__version__",
    "Box",
    "classify",
    "select",
    "GagekitError",
    "InvalidInputError",
    "FileFormatError",
    "DegenerateGeometryError",
    "InfeasibleError",
    "ConfigError",
    "NumericalError",
    "InternalError",
]
