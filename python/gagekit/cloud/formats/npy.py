"""NumPy ``.npy`` arrays of shape (n, 3) or wider (extra columns ignored). No unit: mm.
Only real numbers: a complex array is refused (its imaginary part would be lost)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import FileFormatError
from . import Raw


def read(p: Path, dim: int) -> Raw:
    try:
        arr = np.load(p, allow_pickle=False, mmap_mode="r")
    except Exception as exc:  # numpy raises ValueError, OSError, EOFError... for bad headers
        raise FileFormatError(f"{p}: not a readable .npy file ({exc})") from None
    if arr.dtype.kind == "c":
        raise FileFormatError(f"{p}: complex array ({arr.dtype}); point coordinates must be real numbers")
    if arr.dtype.kind not in "fiu" or arr.ndim != 2 or arr.shape[1] < dim:
        raise FileFormatError(f"{p}: expected a real numeric (n, {dim}) array, got {arr.dtype} {arr.shape}")
    try:
        pts = np.ascontiguousarray(arr[:, :dim], dtype=np.float64)
    except (OSError, ValueError) as exc:  # a truncated memory map
        raise FileFormatError(f"{p}: not a readable .npy file ({exc})") from None
    return Raw(pts, "npy")
