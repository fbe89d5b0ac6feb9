"""ASTM E2807 (E57) scans, read by the Rust reader of ``gagekit-cloudio`` (the pure-Rust
``e57`` crate: no C++ library, nothing printed on stderr, page checksums verified):
every scan with its pose, Cartesian or spherical coordinates, scaled-integer or float
fields; points whose invalid state is not 0 dropped and counted. Unit: metres, by the
standard.

A file whose points are all at one place (every spherical range 0, or every Cartesian
coordinate the same: what a failed or invalid acquisition leaves) is refused, not read as a
cloud of coincident points. The check is on the whole file: a multi-scan file with one such
scan among good ones is read (its points then sit at that scan's origin)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ... import _core
from ...errors import FileFormatError
from . import Raw


def at_one_place(p: Path, n: int, point) -> FileFormatError:
    """The error for a file whose ``n`` points are all at ``point`` (metres)."""
    x, y, z = (float(v) for v in point)
    return FileFormatError(f"{p}: all {n} points are at one place ({x:g}, {y:g}, {z:g} m; every range 0?): "
                           "an invalid acquisition, not a scan")


def _check_spread(p: Path, pts: np.ndarray) -> None:
    # a scan almost always differs within its first points: the full pass only when it does not
    if len(pts) > 1 and not (pts[:4096] != pts[0]).any() and np.array_equal(pts.min(axis=0), pts.max(axis=0)):
        raise at_one_place(p, len(pts), pts[0])


def read(p: Path, dim: int) -> Raw:
    cloud = _core.cloud.read_e57(str(p))  # FileFormatError / FileAccessError from the kernel
    pts, scans, dropped = cloud.points, cloud.scans, cloud.invalid_dropped
    if scans == 0:
        raise FileFormatError(f"{p}: the E57 file holds no scans")
    _check_spread(p, pts)
    return Raw(pts, "e57", unit="m", unit_basis="E57 standard (ASTM E2807): metres",
               scans=scans, invalid_dropped=dropped, finite_checked=True)
