"""PLY (ASCII, binary little- and big-endian), read by the Rust reader of
``gagekit-cloudio``: the file is memory-mapped and the vertex ``x y z`` decoded in one
parallel pass; the header's element counts are checked against the file (more or less
data than declared is an error). No unit: mm."""

from __future__ import annotations

from pathlib import Path

from ... import _core
from ...errors import FileFormatError, InvalidInputError
from . import Raw


def read(p: Path, dim: int) -> Raw:
    try:
        pts, fmt = _core.cloud_read_ply(str(p))
    except InvalidInputError as exc:
        raise FileFormatError(str(exc)) from None
    return Raw(pts, f"ply {fmt}", finite_checked=True)
