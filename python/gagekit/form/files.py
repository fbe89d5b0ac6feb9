"""Fits of point files: what ``gagekit form fit SHAPE FILE`` and ``gagekit form batch`` compute.

One place reads the file the way each shape needs it (2-D circles drop a constant coordinate,
two-column ASCII files are 2-D points) and dispatches on the shape name, so a batch result is
the single-file result (Ch. 6; the fits cite their equations in :mod:`gagekit.form`).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Optional, Union

import numpy as np

from ..errors import ConfigError, FileAccessError, FileFormatError, InvalidInputError

SHAPES_3D = ("line", "plane", "sphere", "circle3d", "cylinder", "cone")
SHAPES = ("circle", *SHAPES_3D)

__all__ = ["SHAPES", "SHAPES_3D", "fit_file", "load_points", "normalize_shape", "read_xy", "text_columns"]


def text_columns(path: Union[str, Path]) -> int:
    """Number of numeric fields on the first data line of a text file (0 if none)."""
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            for _, line in zip(range(1000), fh):
                fields = [f for f in re.split(r"[,;\s]+", line.strip()) if f]
                if not fields or fields[0].startswith("#"):
                    continue
                try:
                    [float(f) for f in fields]
                except ValueError:
                    continue  # a header line
                return len(fields)
    except OSError:
        return 0
    return 0


def read_xy(path: Union[str, Path], units: Optional[str] = None) -> np.ndarray:
    """(n, 2) points from any file ``read_points`` reads: 3-D points must lie in a plane
    parallel to a coordinate plane (as NIST's 2-D sets do); the constant coordinate is
    dropped. ASCII files of 2 columns are read as 2-D points."""
    from ..cloud import read_points

    try:
        arr = read_points(path, units=units, dim=3)
    except FileFormatError as exc3:
        if isinstance(exc3, FileAccessError) or text_columns(path) != 2:  # never reopen a FIFO
            raise
        try:
            return read_points(path, units=units, dim=2)
        except (FileFormatError, InvalidInputError):
            raise exc3 from None
    const = [k for k in range(3) if np.ptp(arr[:, k]) == 0.0]
    if not const:
        raise InvalidInputError(
            f"{path}: 3-D points do not lie in a plane parallel to a coordinate plane; "
            "a 2-D circle fit needs planar points"
        )
    return np.ascontiguousarray(np.delete(arr, const[-1], axis=1))


def load_points(path: Union[str, Path], units: Optional[str] = None) -> np.ndarray:
    """Points from any file ``read_points`` reads (in mm; ``units`` overrides the file's unit);
    ASCII files of 2 columns as 2-D points."""
    from ..cloud import read_points

    return read_points(path, units=units, dim=2 if text_columns(path) == 2 else 3)


def normalize_shape(shape: str) -> str:
    """The canonical shape name (``circle-3d`` -> ``circle3d``); ConfigError for an unknown one."""
    name = shape.strip().lower().replace("-", "").replace("_", "")
    if name == "circle3":
        name = "circle3d"
    if name not in SHAPES:
        raise ConfigError(f"unknown shape {shape!r}; choose one of circle, {', '.join(SHAPES_3D)}")
    return name


def fit_file(shape: str, path: Union[str, Path], criterion: str = "least-squares", seed: int = 0,
             points: Optional[np.ndarray] = None, units: Optional[str] = None) -> Any:
    """Fit ``shape`` to the points of ``path`` with ``criterion`` (seeded swarm for cylinders).

    ``points`` skips the reading (already read the way :func:`read_xy` / :func:`load_points` do);
    ``units`` overrides the unit of the file (see :func:`gagekit.read_points`).
    """
    from .. import form

    name = normalize_shape(shape)
    if name == "circle":  # 2-D circles: the circle reader drops a constant coordinate
        return form.fit_circle(read_xy(path, units) if points is None else points, criterion)
    pts = load_points(path, units) if points is None else points
    if name == "line":
        return form.fit_line(pts, criterion)
    if name == "plane":
        return form.fit_plane(pts, criterion)
    if name == "sphere":
        return form.fit_sphere(pts, criterion)
    if name == "circle3d":
        return form.fit_circle_3d(pts, criterion)
    if name == "cylinder":
        return form.fit_cylinder(pts, criterion, seed=seed)
    return form.fit_cone(pts, criterion)
