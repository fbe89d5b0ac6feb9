"""ASTM E2807 (E57) scans, read by the Rust reader of ``gagekit-cloudio`` (the pure-Rust
``e57`` crate: no C++ library, nothing printed on stderr, page checksums verified):
every scan with its pose, Cartesian or spherical coordinates, scaled-integer or float
fields; points whose invalid state is not 0 dropped and counted. Unit: metres, by the
standard."""

from __future__ import annotations

from pathlib import Path

from ... import _core
from ...errors import FileFormatError, InvalidInputError
from . import Raw


def read(p: Path, dim: int) -> Raw:
    try:
        cloud = _core.cloud_read_e57(str(p))
    except InvalidInputError as exc:
        raise FileFormatError(str(exc)) from None
    pts, scans, dropped = cloud.points, cloud.scans, cloud.invalid_dropped
    if scans == 0:
        raise FileFormatError(f"{p}: the E57 file holds no scans")
    return Raw(pts, "e57", unit="m", unit_basis="E57 standard (ASTM E2807): metres",
               scans=scans, invalid_dropped=dropped, finite_checked=True)
