"""Fits of point files: what ``gagekit form fit SHAPE FILE`` and ``gagekit form batch`` compute.

One place reads the file the way each shape needs it (2-D circles drop a constant coordinate,
two-column ASCII files are 2-D points) and dispatches on the shape name, so a batch result is
the single-file result (Ch. 6; the fits cite their equations in :mod:`gagekit.form`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Optional, Union

import numpy as np

from .. import _core
from ..errors import ConfigError, FileAccessError, FileFormatError, InvalidInputError

SHAPES_3D = ("line", "plane", "sphere", "circle3d", "cylinder", "cone")
SHAPES = ("circle", *SHAPES_3D)

__all__ = ["SHAPES", "SHAPES_3D", "fit_file", "load_points", "normalize_shape", "read_xy", "text_columns"]


def text_columns(path: Union[str, Path]) -> int:
    """Number of values on the first data line of a text file (0 if none), read as the
    cloud readers read it: ``1,5;2,5`` (decimal commas) has 2 values, ``1,5,2`` has 3."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(1 << 20)
    except OSError:
        return 0
    return int(_core.cloud.ascii_columns(head))


def read_xy(path: Union[str, Path], units: Optional[str] = None) -> np.ndarray:
    """Circle points from any file ``read_points`` reads: ASCII files of 2 columns as 2-D
    points; 3-D points in a plane parallel to a coordinate plane (as NIST's 2-D sets) as
    2-D points without the constant coordinate; any other 3-D points as (n, 3), fitted in
    their least-squares plane (circles in any pose)."""
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
        return arr
    return np.ascontiguousarray(np.delete(arr, const[-1], axis=1))


def load_points(path: Union[str, Path], units: Optional[str] = None) -> np.ndarray:
    """Points from any file ``read_points`` reads (in mm; ``units`` overrides the file's unit);
    ASCII files of 2 columns as 2-D points."""
    from ..cloud import read_points

    return read_points(path, units=units, dim=2 if text_columns(path) == 2 else 3)


def normalize_shape(shape: str) -> str:
    """The canonical shape name (``circle3d`` is an alias of ``circle``: circles in any
    pose); ConfigError for an unknown one."""
    name = shape.strip().lower().replace("-", "").replace("_", "")
    if name in ("circle3", "circle3d"):
        name = "circle"
    if name not in SHAPES:
        raise ConfigError(f"unknown shape {shape!r}; choose one of circle, {', '.join(SHAPES_3D)}")
    return name


def fit_file(shape: str, path: Union[str, Path], criterion: str = "least-squares", seed: int = 0,
             points: Optional[np.ndarray] = None, units: Optional[str] = None,
             axis: Optional[Any] = None, max_tilt: float = 10.0, angle: Optional[float] = None) -> Any:
    """Fit ``shape`` to the points of ``path`` with ``criterion`` (seeded swarm for cylinders
    and 3-D lines, searched within ``max_tilt`` degrees of ``axis`` or the least-squares axis).

    ``points`` skips the reading (already read the way :func:`read_xy` / :func:`load_points` do);
    ``units`` overrides the unit of the file (see :func:`gagekit.read_points`); ``angle``
    fixes a cone's half angle (degrees).
    """
    from .. import form

    name = normalize_shape(shape)
    if angle is not None and name != "cone":
        raise ConfigError(f"--angle (a fixed half angle) applies to cones only, not to a {name}")
    if name == "circle":  # the circle reader drops a constant coordinate; else any pose
        return form.fit_circle(read_xy(path, units) if points is None else points, criterion)
    pts = load_points(path, units) if points is None else points
    if name == "line":
        return form.fit_line(pts, criterion, seed=seed, axis=axis, max_tilt=max_tilt)
    if name == "plane":
        return form.fit_plane(pts, criterion)
    if name == "sphere":
        return form.fit_sphere(pts, criterion)
    if name == "cylinder":
        return form.fit_cylinder(pts, criterion, seed=seed, axis=axis, max_tilt=max_tilt)
    return form.fit_cone(pts, criterion, angle=angle)
