"""Sampling regions (Sec. 5.4.1): oriented boxes classified in parallel in Rust."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from .. import _core
from .._util import as_points, named_tables
from ..errors import ConfigError


@dataclass(frozen=True)
class Box:
    """An oriented box: ``center`` and full ``size`` along its own axes (mm), and
    ``rotation``, the rotation vector (axis times angle, rad) that turns the cloud
    axes onto the box axes. Points on the boundary are inside.
    """

    center: tuple[float, float, float]
    size: tuple[float, float, float]
    rotation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    name: str = field(default="region")

    def __post_init__(self) -> None:
        for attr in ("center", "size", "rotation"):
            raw = getattr(self, attr)
            if isinstance(raw, (str, bytes, dict)) or any(isinstance(v, (bool, str)) for v in _iter_or_empty(raw)):
                raise ConfigError(f"region '{self.name}': {attr} must be three numbers, got {raw!r}")
            try:
                vals = tuple(float(v) for v in raw)
            except (TypeError, ValueError):
                raise ConfigError(f"region '{self.name}': {attr} must be three numbers, got {raw!r}") from None
            if len(vals) != 3:
                raise ConfigError(f"region '{self.name}': {attr} must be three numbers, got {len(vals)}")
            object.__setattr__(self, attr, vals)
        _core.geometry.validate_box(self.name, self.center, self.size, self.rotation)  # finite, positive size (Rust)

    def row(self) -> list[float]:
        return [*self.center, *self.size, *self.rotation]

    def to_dict(self) -> dict:
        return {"name": self.name, "center": list(self.center), "size": list(self.size), "rotation": list(self.rotation)}


def _iter_or_empty(raw) -> tuple:
    try:
        return tuple(raw)
    except TypeError:
        return ()


def classify(points, regions: Sequence[Box]) -> list[np.ndarray]:
    """Indices (ascending, int64) of the points inside each region, one pass in Rust.

    A point may belong to several regions.
    """
    pts = as_points(points)
    boxes = np.array([r.row() for r in regions], dtype=np.float64).reshape(-1, 9)
    return list(_core.geometry.classify_boxes(pts, boxes))


def select(points, region: Box) -> np.ndarray:
    """Indices (ascending, int64) of the points inside ``region``."""
    return classify(points, [region])[0]


def regions_from_tables(tables: Sequence[dict], source: str = "regions", angle_scale: float = 1.0) -> list[Box]:
    """Boxes from ``[[region]]`` tables (``name``, ``center``, ``size``, optional
    ``rotation``, multiplied by ``angle_scale`` to radians; other keys such as ``frame`` are
    left to the caller).

    Raises :class:`ConfigError` naming the file and the region for a missing or
    malformed key, a non-positive size or a repeated name.
    """
    boxes: list[Box] = []
    for name, t in named_tables(tables, "region", source):
        for key in ("center", "size"):
            if key not in t:
                raise ConfigError(f"{source}: region '{name}' has no '{key}'")
        rotation = t.get("rotation", (0.0, 0.0, 0.0))
        if angle_scale != 1.0:
            rotation = [float(v) * angle_scale for v in rotation]
        boxes.append(Box(t["center"], t["size"], rotation, name=name))
    return boxes


def load_regions(path) -> list[Box]:
    """Read the ``[[region]]`` tables of a TOML file (a gage file or a regions file), validated
    against the regions schema (:mod:`gagekit.schema.gages`, ``gagekit schema regions``)."""
    from .._util import load_toml
    from ..schema import validate_document

    doc = load_toml(path, "regions")
    f = validate_document("regions", doc, str(path))
    # rotations in the file's angle unit, as the gage reader takes them
    return regions_from_tables(doc["region"], str(path), math.pi / 180.0 if f.angle_unit == "deg" else 1.0)
