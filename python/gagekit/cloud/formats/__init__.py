"""One reader per point-cloud format. Each ``read(path, dim)`` returns a :class:`Raw`:
coordinates in the file's own unit plus what the reader learned about that unit.
:func:`gagekit.cloud.io.read_cloud` picks the reader and converts to millimetres."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Raw:
    """What a format reader returns (before unit conversion)."""

    points: np.ndarray  # (n, dim) float64, C-contiguous, in ``unit`` (z possibly in ``z_unit``)
    format: str  # e.g. "ply (binary_little_endian)", "e57", "xyz"
    unit: "str | None" = "mm"  # a key of units.MM_PER_UNIT; None: not lengths (unit_basis says why)
    unit_basis: str = "the format carries no unit: millimetres"
    z_unit: str = ""  # LAS: the vertical CRS unit when it differs from the horizontal one
    scans: int = 1
    invalid_dropped: int = 0
    warnings: list = field(default_factory=list)
    finite_checked: bool = False  # the (Rust) reader has already refused NaN and inf
