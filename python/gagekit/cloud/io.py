"""Reading and writing point clouds.

Formats, chosen by the file's extension (or, for an unknown extension, by its
first bytes):

========================  =====================================================
``.xyz .csv .txt .asc``   ASCII, values separated by commas, semicolons, spaces
``.pts``                  or tabs; optional header lines (a header naming
                          ``x``, ``y``, ``z`` columns selects them, otherwise the
                          first columns are used); extra columns ignored; ``#``
                          comment lines skipped. Parsed in parallel in Rust.
``.ds``                   NIST Algorithm Testing System: a count line, then
                          ``x y z`` per line (the count is checked).
``.ply``                  ASCII or binary PLY (float32 or float64 ``x y z``
                          vertex properties), read with ``plyfile``.
``.npy``                  NumPy array of shape (n, 3) or wider.
``.las .laz``             with the optional ``laspy`` extra (``pip install gagekit[las]``).
``.e57``                  with the optional ``pye57`` extra (``pip install gagekit[e57]``).
========================  =====================================================

Every reader returns a C-contiguous float64 array of shape (n, 3) (or (n, 2)
with ``dim=2`` for ASCII files of 2-D points) and raises
:class:`~gagekit.errors.FileFormatError` naming the file (and line, for text)
for anything it cannot read, and :class:`~gagekit.errors.InvalidInputError`
for NaN or infinite coordinates.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Union

import numpy as np

from .. import _core, _progress
from .._util import as_points
from ..errors import FileFormatError, InvalidInputError

PathLike = Union[str, os.PathLike]

ASCII_SUFFIXES = {".xyz", ".csv", ".txt", ".asc", ".pts", ".ds"}
SUPPORTED = "XYZ/CSV/TXT/ASC/PTS, NIST .ds, PLY, .npy, LAS/LAZ (laspy), E57 (pye57)"


def read_points(path: PathLike, dim: int = 3) -> np.ndarray:
    """Read a point cloud file into a float64 array of shape (n, ``dim``).

    ``dim=2`` is accepted for ASCII files of 2-D points (x y per line).
    """
    from .._files import input_file

    p = input_file(path, "point cloud file")  # typed errors: missing, folder, FIFO, permissions
    if dim not in (2, 3):
        raise InvalidInputError(f"dim must be 2 or 3, got {dim}")
    suffix = p.suffix.lower()
    if suffix not in ASCII_SUFFIXES | {".ply", ".npy", ".las", ".laz", ".e57"}:
        suffix = _sniff(p)
    with _progress.status(f"reading {p.name} ({p.stat().st_size / 1e6:.0f} MB)"):
        if suffix in ASCII_SUFFIXES:
            pts = _read_ascii(p, dim, nist=suffix == ".ds")
        else:
            if dim != 3:
                raise InvalidInputError(f"{p}: dim=2 is only for ASCII files")
            reader = {".ply": _read_ply, ".npy": _read_npy, ".las": _read_las, ".laz": _read_las, ".e57": _read_e57}
            pts = reader[suffix](p)
            _check_finite(pts, p)
    if len(pts) == 0:
        raise FileFormatError(f"{p}: the file holds no points")
    return pts


def write_points(path: PathLike, points, *, binary: bool = True) -> None:
    """Write an (n, 3) array as PLY (binary little-endian float64 unless
    ``binary=False``), CSV (``x,y,z`` header), XYZ/TXT (space separated) or .npy,
    by the extension of ``path``."""
    p = Path(path)
    pts = as_points(points, dim=np.asarray(points).shape[-1] if np.ndim(points) == 2 else 3)
    _check_finite(pts, p)
    suffix = p.suffix.lower()
    if suffix not in (".ply", ".npy", ".csv", ".xyz", ".txt", ".asc"):
        raise FileFormatError(f"{p}: cannot write '{suffix}' files; use .ply, .csv, .xyz, .txt or .npy")
    from .._files import atomic_path

    with atomic_path(p) as tmp:  # temp file in the same folder, then rename: never half-written
        if suffix == ".ply":
            _write_ply(tmp, pts, binary)
        elif suffix == ".npy":
            np.save(tmp, pts)
        else:
            header = ",".join("xyz"[: pts.shape[1]]) if suffix == ".csv" else None
            _core.cloud_write_ascii(str(tmp), pts, "," if suffix == ".csv" else " ", header)


def _sniff(p: Path) -> str:
    with open(p, "rb") as fh:
        head = fh.read(8)
    if head.startswith(b"ply"):
        return ".ply"
    if head.startswith(b"\x93NUMPY"):
        return ".npy"
    if head.startswith(b"LASF"):
        return ".las"
    if head.startswith(b"ASTM-E57"):
        return ".e57"
    if b"\x00" in head:
        raise FileFormatError(f"{p}: unknown binary format; gagekit reads {SUPPORTED}")
    return ".xyz"


def _check_finite(pts: np.ndarray, p: Path) -> None:
    bad = ~np.isfinite(pts).all(axis=1)
    if bad.any():
        i = int(np.argmax(bad))
        raise InvalidInputError(f"{p}: point {i} has a non-finite coordinate {pts[i].tolist()}")


def _read_ascii(p: Path, dim: int, nist: bool) -> np.ndarray:
    try:
        pts, _header_lines, _cols = _core.cloud_read_ascii(str(p), dim, 1 if nist else 0)
    except InvalidInputError as exc:
        raise FileFormatError(str(exc)) from None
    if nist:
        first = p.open("rb").readline().split()
        try:
            count = int(first[0])
        except (IndexError, ValueError):
            raise FileFormatError(f"{p}: line 1: a NIST .ds file starts with the point count") from None
        if count != len(pts):
            raise FileFormatError(f"{p}: line 1 announces {count} points but the file holds {len(pts)}")
    return pts


def _read_ply(p: Path) -> np.ndarray:
    from plyfile import PlyData  # maintained PLY reader (ASCII and binary)

    try:
        ply = PlyData.read(str(p))
        vertex = ply["vertex"].data
        pts = np.column_stack([np.asarray(vertex[c], dtype=np.float64) for c in ("x", "y", "z")])
    except KeyError as exc:
        raise FileFormatError(f"{p}: PLY file without vertex x, y, z properties ({exc})") from None
    except Exception as exc:  # plyfile raises several exception types for malformed files
        raise FileFormatError(f"{p}: not a readable PLY file ({exc})") from None
    return np.ascontiguousarray(pts)


def _write_ply(p: Path, pts: np.ndarray, binary: bool) -> None:
    from plyfile import PlyData, PlyElement

    if pts.shape[1] != 3:
        raise InvalidInputError(f"{p}: PLY needs (n, 3) points, got {pts.shape}")
    vertex = np.empty(len(pts), dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8")])
    vertex["x"], vertex["y"], vertex["z"] = pts.T
    PlyData([PlyElement.describe(vertex, "vertex")], text=not binary).write(str(p))


def _read_npy(p: Path) -> np.ndarray:
    try:
        arr = np.load(p, allow_pickle=False)
    except Exception as exc:
        raise FileFormatError(f"{p}: not a readable .npy file ({exc})") from None
    if arr.ndim != 2 or arr.shape[1] < 3 or not np.issubdtype(arr.dtype, np.number):
        raise FileFormatError(f"{p}: expected a numeric (n, 3) array, got {arr.dtype} {arr.shape}")
    return np.ascontiguousarray(arr[:, :3], dtype=np.float64)


def _read_las(p: Path) -> np.ndarray:
    try:
        import laspy
    except ImportError:
        raise FileFormatError(f"{p}: LAS/LAZ needs the optional extra: pip install 'gagekit[las]'") from None
    try:
        las = laspy.read(str(p))
    except Exception as exc:
        raise FileFormatError(f"{p}: not a readable LAS/LAZ file ({exc})") from None
    return np.ascontiguousarray(np.column_stack([las.x, las.y, las.z]), dtype=np.float64)


def _read_e57(p: Path) -> np.ndarray:
    try:
        import pye57
    except ImportError:
        raise FileFormatError(f"{p}: E57 needs the optional extra: pip install 'gagekit[e57]'") from None
    try:
        e57 = pye57.E57(str(p))
        scans = [e57.read_scan(i, ignore_missing_fields=True, transform=True) for i in range(e57.scan_count)]
    except Exception as exc:
        raise FileFormatError(f"{p}: not a readable E57 file ({exc})") from None
    if not scans:
        raise FileFormatError(f"{p}: the E57 file holds no scans")
    return np.ascontiguousarray(
        np.vstack([np.column_stack([s["cartesianX"], s["cartesianY"], s["cartesianZ"]]) for s in scans]),
        dtype=np.float64,
    )
