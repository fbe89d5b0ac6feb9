"""Reading and writing point clouds, in millimetres.

Formats, chosen by the file's extension (or, for an unknown extension, by its
first bytes); one reader module per format in :mod:`gagekit.cloud.formats`:

========================  ===========  ===============================================
extension                 file unit    reader
========================  ===========  ===============================================
``.xyz .csv .txt .asc``   mm           ASCII, values separated by commas, semicolons,
``.pts``                               spaces or tabs (decimal commas in semicolon
                                       files); header lines naming ``x``, ``y``, ``z``
                                       select columns; ``#`` comments; UTF-8 BOM.
                                       Parsed in parallel in Rust (``gagekit-cloudio``).
``.ds``                   mm           NIST Algorithm Testing System: a count line,
                                       then ``x y z`` per line (the count is checked).
``.ply``                  mm           ASCII or binary PLY; the element counts of the
                                       header are checked against the file's size.
``.npy``                  mm           NumPy array (n, 3) or wider, real numbers.
``.las .laz``             CRS unit     ``laspy`` (``pip install gagekit[las]``); the
                                       unit of the header's CRS, metres without one.
``.e57``                  m            every scan, pose applied, spherical converted,
                                       invalid points dropped and counted.
========================  ===========  ===============================================

Units (see :mod:`gagekit.cloud.units`): every reader returns millimetres. The file's own
unit is used unless ``units`` is given (``"mm", "cm", "m", "um", "in", "ft"``), which
overrides it. :func:`read_cloud` returns a :class:`Cloud` with the points and what was
done (``source_unit``, ``scale_to_mm``, dropped invalid points, warnings);
:func:`read_points` returns the points alone and issues the warnings with
:func:`warnings.warn`.

For command-line commands that read a cloud (use this in every new command)::

    from ._common import UNITS_OPTION, read_cloud_cli
    def cmd(file: Path = ..., units: Optional[str] = UNITS_OPTION):
        pts = read_cloud_cli(file, units).points   # warnings -> "gagekit: warning: ..." lines

Errors: :class:`~gagekit.errors.FileFormatError` naming the file (and line, for text)
for anything a reader cannot read; :class:`~gagekit.errors.InvalidInputError` for NaN or
infinite coordinates and unknown unit names.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Union

import numpy as np

from .. import _core, _progress
from .._util import as_points, check_finite
from ..errors import FileFormatError, InvalidInputError
from . import units as _units
from .formats import Raw, e57, las, npy, ply, text

PathLike = Union[str, os.PathLike]

ASCII_SUFFIXES = {".xyz", ".csv", ".txt", ".asc", ".pts", ".ds"}
SUPPORTED = "XYZ/CSV/TXT/ASC/PTS, NIST .ds, PLY, .npy, LAS/LAZ (laspy), E57"
_BINARY = {".ply": ply.read, ".npy": npy.read, ".las": las.read, ".laz": las.read, ".e57": e57.read}

__all__ = ["Cloud", "read_cloud", "read_points", "write_points", "SUPPORTED"]


@dataclass(frozen=True, eq=False)
class Cloud:
    """A point cloud read from a file, in millimetres, and how it was read.

    ``source_unit``: the unit the file's coordinates were taken to be in; ``scale_to_mm``:
    the factor applied (``z_scale_to_mm`` differs only for a LAS file whose vertical CRS
    unit differs from its horizontal one); ``unit_basis``: why that unit (the format's
    standard, the LAS CRS, an assumption, or ``units=``); ``invalid_dropped``: E57 points
    whose invalid state was not 0; ``warnings``: what the reader assumed.
    """

    points: np.ndarray
    path: str
    format: str
    source_unit: str
    scale_to_mm: float
    unit_basis: str
    z_scale_to_mm: float
    scans: int = 1
    invalid_dropped: int = 0
    warnings: tuple = field(default_factory=tuple)

    def to_dict(self) -> dict:
        """The description without the points (for ``--json``)."""
        return {
            "file": self.path,
            "format": self.format,
            "count": int(len(self.points)),
            "source_unit": self.source_unit,
            "scale_to_mm": self.scale_to_mm,
            "z_scale_to_mm": self.z_scale_to_mm,
            "unit_basis": self.unit_basis,
            "scans": self.scans,
            "invalid_dropped": self.invalid_dropped,
            "warnings": list(self.warnings),
        }


def read_cloud(path: PathLike, units: Optional[str] = None, dim: int = 3) -> Cloud:
    """Read a point-cloud file and convert it to millimetres (see the module docstring).

    ``units`` overrides the file's unit (``mm``, ``cm``, ``m``, ``um``, ``in``, ``ft``);
    ``dim=2`` is accepted for ASCII files of 2-D points (x y per line).
    """
    from .._files import input_file

    override = _units.check_units(units)
    if dim not in (2, 3):
        raise InvalidInputError(f"dim must be 2 or 3, got {dim}")
    p = input_file(path, "point cloud file")  # typed errors: missing, folder, FIFO, permissions
    suffix = p.suffix.lower()
    if suffix not in ASCII_SUFFIXES and suffix not in _BINARY:
        suffix = _sniff(p)
    try:
        size = p.stat().st_size
    except OSError as exc:
        raise FileFormatError(f"{p}: cannot be read ({exc.strerror or exc})") from None
    with _progress.status(f"reading {p.name} ({size / 1e6:.0f} MB)"):
        if suffix in ASCII_SUFFIXES:
            raw = text.read(p, dim, nist=suffix == ".ds")
        else:
            if dim != 3:
                raise InvalidInputError(f"{p}: dim=2 is only for ASCII files")
            try:
                raw = _BINARY[suffix](p, dim)
            except OSError as exc:
                raise FileFormatError(f"{p}: cannot be read ({exc.strerror or exc})") from None
    return _to_mm(raw, p, override)


def read_points(path: PathLike, units: Optional[str] = None, dim: int = 3) -> np.ndarray:
    """Read a point cloud file into a float64 array of shape (n, ``dim``), in millimetres.

    ``units`` overrides the unit of the file (E57: metres, LAS/LAZ: its CRS unit, the
    other formats: millimetres). Warnings of the reader are issued with
    :func:`warnings.warn`; :func:`read_cloud` returns them with the points.
    """
    cloud = read_cloud(path, units=units, dim=dim)
    for w in cloud.warnings:
        warnings.warn(w, stacklevel=2)
    return cloud.points


def _unit_of(raw: Raw, p: Path, override: Optional[str]) -> tuple[str, str, str, list]:
    """(unit, z unit, why that unit, the reader's warnings that still apply) of a read,
    shared by the whole read and the streamed one (:mod:`gagekit.cloud.stream`)."""
    warns = list(raw.warnings)
    if override is not None:
        unit, z_unit, basis = override, override, "given (units=/--units)"
        warns = [w for w in warns if "unit" not in w]  # the reader's unit assumption no longer applies
    elif raw.unit is None:
        raise FileFormatError(raw.unit_basis)
    else:
        unit, z_unit, basis = raw.unit, raw.z_unit or raw.unit, raw.unit_basis
    return unit, z_unit, basis, warns


def _to_mm(raw: Raw, p: Path, override: Optional[str]) -> Cloud:
    pts = raw.points
    unit, z_unit, basis, warns = _unit_of(raw, p, override)
    s, sz = _units.scale_to_mm(unit), _units.scale_to_mm(z_unit)
    if len(pts) == 0:
        raise FileFormatError(f"{p}: the file holds no points")
    if not raw.finite_checked:
        check_finite(pts, str(p))
    if s != 1.0 or sz != 1.0:
        # in place (the reader's own fresh array): one parallel pass, no second array;
        # an overflow to infinity is an error naming the point
        pts = np.require(pts, np.float64, ["C_CONTIGUOUS", "WRITEABLE"])
        _core.cloud.scale_in_place(pts, [s, s, sz][: pts.shape[1]], str(p))
    return Cloud(np.ascontiguousarray(pts), str(p), raw.format, unit, s, basis, sz,
                 raw.scans, raw.invalid_dropped, tuple(warns))


def write_points(path: PathLike, points, *, binary: bool = True) -> None:
    """Write an (n, 3) array (millimetres) as PLY (binary little-endian float64 unless
    ``binary=False``), CSV (``x,y,z`` header), XYZ/TXT (space separated) or .npy,
    by the extension of ``path``."""
    p = Path(path)
    pts = as_points(points, dim=np.asarray(points).shape[-1] if np.ndim(points) == 2 else 3)
    check_finite(pts, str(p))
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
            _core.cloud.write_ascii(str(tmp), pts, "," if suffix == ".csv" else " ", header)


def _sniff(p: Path) -> str:
    try:
        with open(p, "rb") as fh:
            head = fh.read(8)
    except OSError as exc:
        raise FileFormatError(f"{p}: cannot be read ({exc.strerror or exc})") from None
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


def _write_ply(p: Path, pts: np.ndarray, binary: bool) -> None:
    """Binary: little-endian ``double x, y, z`` with the body at an offset that is a
    multiple of 8 (the header padded by its comment line), so that reading the file back
    maps it as the array, with no copy (see :mod:`gagekit.cloud.formats.ply`)."""
    if pts.shape[1] != 3:
        raise InvalidInputError(f"{p}: PLY needs (n, 3) points, got {pts.shape}")
    if not binary:
        from plyfile import PlyData, PlyElement

        vertex = np.empty(len(pts), dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8")])
        vertex["x"], vertex["y"], vertex["z"] = pts.T
        PlyData([PlyElement.describe(vertex, "vertex")], text=True).write(str(p))
        return
    rest = (f"element vertex {len(pts)}\nproperty double x\nproperty double y\nproperty double z\n"
            "end_header\n")
    head = "ply\nformat binary_little_endian 1.0\ncomment gagekit"
    pad = -(len(head) + 1 + len(rest)) % 8
    header = (head + " " * pad + "\n" + rest).encode("ascii")
    with open(p, "wb") as fh:
        fh.write(header)
        np.ascontiguousarray(pts, dtype="<f8").tofile(fh)
