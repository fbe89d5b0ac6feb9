"""PLY (ASCII, binary little- and big-endian), read by the Rust reader of
``gagekit-cloudio``: the file is memory-mapped and the vertex ``x y z`` decoded in one
parallel pass straight into the result; the header's element counts are checked against
the file (more or less data than declared is an error). A file in gagekit's own layout
(binary little-endian ``double x, y, z`` only, as :func:`gagekit.write_points` writes it)
is not decoded at all: the result is a copy-on-write memory map of the file (changing the
array never changes the file). No unit: mm."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ... import _core
from . import Raw


def read(p: Path, dim: int) -> Raw:
    layout = _core.cloud.ply_layout(str(p))  # FileFormatError / FileAccessError from the kernel
    n, offset = layout.vertices, layout.direct_offset
    if offset is not None and offset % 8 == 0:  # numpy and the kernels need aligned float64
        pts = np.asarray(np.memmap(p, dtype="<f8", mode="c", offset=offset, shape=(n, 3))) if n else np.empty((0, 3))
        return Raw(pts, "ply binary_little_endian", finite_checked=True)
    cloud = _core.cloud.read_ply(str(p))
    return Raw(cloud.points, f"ply {cloud.format}", finite_checked=True)
