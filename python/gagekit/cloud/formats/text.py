"""ASCII point lists (XYZ/CSV/TXT/ASC/PTS) and NIST ``.ds`` files, parsed in parallel by
the Rust reader (``gagekit-cloudio``): separators, header lines naming x/y/z columns,
decimal commas in semicolon-separated files, a UTF-8 byte-order mark. No unit: mm."""

from __future__ import annotations

from pathlib import Path

from ... import _core
from ...errors import FileFormatError
from . import Raw


def read(p: Path, dim: int, nist: bool = False) -> Raw:
    pts = _core.cloud.read_ascii(str(p), dim, 1 if nist else 0).points  # FileFormatError from the kernel
    if nist:
        with p.open("rb") as fh:
            first = fh.readline().split()
        try:
            count = int(first[0])
        except (IndexError, ValueError):
            raise FileFormatError(f"{p}: line 1: a NIST .ds file starts with the point count") from None
        if count != len(pts):
            raise FileFormatError(f"{p}: line 1 announces {count} points but the file holds {len(pts)}")
    return Raw(pts, "nist-ds" if nist else "ascii", finite_checked=True)
