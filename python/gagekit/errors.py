"""The gagekit exception hierarchy.

Every error gagekit raises on purpose is a :class:`GagekitError`; the Rust
kernels' errors arrive as the same classes (the binding crate looks them up
here), and a panic inside a kernel arrives as :class:`InternalError`, never as
an abort of the Python process.
"""

from __future__ import annotations


class GagekitError(Exception):
    """Root of every gagekit exception."""


class InvalidInputError(GagekitError, ValueError):
    """Bad numbers, shapes or dtypes: NaN, infinities, empty input, wrong sizes."""


class FileFormatError(InvalidInputError):
    """A file that cannot be read: unknown format, malformed line, empty file."""


class FileAccessError(FileFormatError, OSError):
    """A file or folder that cannot be opened, read or written: missing, a folder where a
    file was expected, a FIFO or device, permission denied, read-only, disk full, a locked
    database. Raised by :mod:`gagekit._files`, the one place that maps OS errors."""


class DegenerateGeometryError(GagekitError, ValueError):
    """Too few points or a configuration too degenerate for the computation."""


class InfeasibleError(GagekitError):
    """An optimisation problem without a feasible solution."""


class ConfigError(GagekitError, ValueError):
    """An inconsistent configuration: machine file, gage file, region."""


class ConfigFileError(FileFormatError, ConfigError):
    """A configuration file (TOML: machine, gage, regions, zones, exclusions) that cannot be
    read or is not valid TOML; both a file-format and a configuration error."""


class NumericalError(GagekitError, ArithmeticError):
    """A numerical method failed to converge or lost accuracy."""


class InternalError(GagekitError, RuntimeError):
    """A bug inside gagekit (a caught panic of a Rust kernel). Please report it."""


class StoreError(GagekitError):
    """The results database cannot be reached, opened or written (the message names its URL,
    password hidden)."""


class SchemaVersionError(StoreError):
    """The results database has a schema this gagekit cannot use: newer than it knows
    (upgrade gagekit) or older (run ``gagekit db upgrade URL``)."""


class ClusterError(GagekitError):
    """The Dask scheduler cannot be reached, or the cluster cannot run the batch."""


__all__ = [
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
