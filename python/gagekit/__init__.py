"""gagekit: machining accuracy for multi-axis CNC machine tools and scanned parts.

See README.md for the command line; the public Python API is listed in ``__all__``.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version as _version

from . import _core, cloud, design, form, gage, machine
from .cloud import *  # noqa: F401,F403  (each subpackage lists its public names in __all__)
from .design import *  # noqa: F401,F403
from .form import *  # noqa: F401,F403
from .gage import *  # noqa: F401,F403
from .machine import *  # noqa: F401,F403
from .inspect import InspectionResult, PartSpec, inspect, load_part_spec  # noqa: F401
from .errors import (
    ClusterError,
    ConfigError,
    DegenerateGeometryError,
    FileAccessError,
    FileFormatError,
    GagekitError,
    InfeasibleError,
    InternalError,
    InvalidInputError,
    NumericalError,
    SchemaVersionError,
    StoreError,
)

try:
    __version__ = _version("gagekit")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = _core.__version__

__all__ = [
    "__version__",
    *cloud.__all__,
    *design.__all__,
    *form.__all__,
    *gage.__all__,
    *machine.__all__,
    "inspect",
    "load_part_spec",
    "PartSpec",
    "InspectionResult",
    "GagekitError",
    "InvalidInputError",
    "FileFormatError",
    "FileAccessError",
    "DegenerateGeometryError",
    "InfeasibleError",
    "ConfigError",
    "NumericalError",
    "InternalError",
    "StoreError",
    "SchemaVersionError",
    "ClusterError",
]
