"""gagekit: machining accuracy for multi-axis CNC machine tools and scanned parts.

See README.md for the command line; the public Python API is listed in ``__all__``.
"""

from __future__ import annotations


def _quiet_ctrl_c_while_the_cli_starts() -> None:
    """Run as the `gagekit` command (or ``python -m gagekit``), Ctrl-C during the imports
    that follow ends with the CLI's one line ``gagekit: error: interrupted`` (exit 130)
    instead of a traceback; :func:`gagekit.cli.main` restores Python's handler. A library
    import changes nothing."""
    import os
    import signal
    import sys

    argv = list(getattr(sys, "orig_argv", sys.argv))
    as_cli = (sys.argv and os.path.basename(sys.argv[0]) == "gagekit") or argv[1:3] == ["-m", "gagekit"]
    if not as_cli or signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        return

    def _stop(signum, frame):  # pragma: no cover - exercised by the interrupt tests
        os.write(2, b"gagekit: error: interrupted\n")
        os._exit(130)

    try:
        signal.signal(signal.SIGINT, _stop)
    except ValueError:  # pragma: no cover - not the main thread
        pass


_quiet_ctrl_c_while_the_cli_starts()  # first: before any slow import

from importlib.metadata import PackageNotFoundError, version as _version  # noqa: E402

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
