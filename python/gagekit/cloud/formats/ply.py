"""PLY (ASCII, binary little- and big-endian), read with ``plyfile``. No unit: mm."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import FileFormatError
from . import Raw


def read(p: Path, dim: int) -> Raw:
    from plyfile import PlyData  # maintained PLY reader (ASCII and binary)

    try:
        ply = PlyData.read(str(p))
        vertex = ply["vertex"].data
        pts = np.column_stack([np.asarray(vertex[c], dtype=np.float64) for c in ("x", "y", "z")])
    except KeyError as exc:
        raise FileFormatError(f"{p}: PLY file without vertex x, y, z properties ({exc})") from None
    except Exception as exc:  # plyfile raises several exception types for malformed files
        raise FileFormatError(f"{p}: not a readable PLY file ({exc})") from None
    return Raw(np.ascontiguousarray(pts), "ply")
