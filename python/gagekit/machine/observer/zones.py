"""Zones and exclusions of an observer plan (Sec. 4.2, Fig. 4.3): the ``dissertation-8``
zones, zones files and exclusions files (TOML).

The ``dissertation-8`` zones cut the box of commanded (X, Y, Z+W) into 4 equal slices along Y
and each slice into a central block (the middle 1/sqrt(2) of the X and Z+W ranges, half the
slice's volume) and the annulus around it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Union

import numpy as np

from ..._util import load_toml
from ...errors import ConfigError
from .space import ObserverSpace

__all__ = ["Zone", "Exclusions", "dissertation_zones", "read_zones", "read_exclusions"]


Zone = tuple  # (lower (d,), upper (d,), count, hole or None)


def _interval(val: Any, what: str) -> tuple[float, float]:
    """``[lower, upper]``: two finite numbers, lower <= upper (a reversed or NaN box would
    silently select nothing)."""
    if not isinstance(val, (list, tuple)) or len(val) != 2 or any(isinstance(v, (bool, str)) for v in val):
        raise ConfigError(f"{what} must be [lower, upper], got {val!r}")
    try:
        a, z = (float(v) for v in val)
    except (TypeError, ValueError):
        raise ConfigError(f"{what} must be [lower, upper], got {val!r}") from None
    if not (math.isfinite(a) and math.isfinite(z)):
        raise ConfigError(f"{what} = {val!r}: the bounds must be finite numbers")
    if a > z:
        raise ConfigError(f"{what} = {val!r} is reversed: give [lower, upper]")
    return a, z


def _named_box(space: ObserverSpace, spec: dict, what: str) -> tuple[np.ndarray, np.ndarray]:
    b = space.bounds
    lo, hi = b[:, 0].copy(), b[:, 1].copy()
    for key, val in spec.items():
        if key in ("count",):
            continue
        if key not in space.names:
            raise ConfigError(f"{what}: unknown variable '{key}' (use {', '.join(space.names)})")
        a, z = _interval(val, f"{what}: '{key}'")
        j = space.names.index(key)
        lo[j], hi[j] = a, z
    return lo, hi


def dissertation_zones(space: ObserverSpace, points: int) -> list[Zone]:
    """The 8 equal-volume zones of Fig. 4.3, ``points / 8`` each (the remainder to the first)."""
    names = space.names
    ys = [n for n in names if n == "Y"]
    if not ys or space.pair is None or "X" not in names:
        raise ConfigError(
            "dissertation-8 zones need joints X and Y and a redundant pair (Z and W): "
            f"this machine has {', '.join(space.machine.joint_names)}; give a zones file instead"
        )
    iy, ix, iz = names.index("Y"), names.index("X"), space.pair[0]
    b = space.bounds
    counts = [points // 8 + (1 if k < points % 8 else 0) for k in range(8)]
    zones = []
    edges = np.linspace(b[iy, 0], b[iy, 1], 5)
    for s in range(4):
        lo, hi = b[:, 0].copy(), b[:, 1].copy()
        lo[iy], hi[iy] = edges[s], edges[s + 1]
        clo, chi = lo.copy(), hi.copy()
        for j in (ix, iz):
            mid, half = 0.5 * (b[j, 0] + b[j, 1]), 0.5 * (b[j, 1] - b[j, 0]) / math.sqrt(2.0)
            clo[j], chi[j] = mid - half, mid + half
        hole_lo = np.full(len(names), -np.inf)
        hole_hi = np.full(len(names), np.inf)
        hole_lo[[ix, iz]], hole_hi[[ix, iz]] = clo[[ix, iz]], chi[[ix, iz]]
        zones.append((clo, chi, counts[2 * s], None))
        zones.append((lo, hi, counts[2 * s + 1], (hole_lo, hole_hi)))
    return zones


def read_zones(path: Union[str, Path], space: ObserverSpace) -> list[Zone]:
    """Zones file: ``[[zone]]`` tables with ``count`` and ``NAME = [lower, upper]`` per variable
    (joint names or the redundant sum, e.g. ``"Z+W"``); unnamed variables span their range."""
    from ...schema import validate_document

    doc = load_toml(path, "zones")
    validate_document("zones", doc, str(path))  # count, intervals, unknown top-level keys
    zones = []
    for k, z in enumerate(doc["zone"]):
        lo, hi = _named_box(space, z, f"{path}: zone {k + 1}")
        zones.append((lo, hi, z["count"], None))
    return zones


@dataclass(frozen=True)
class Exclusions:
    """Boxes (over joints or the redundant sum) and single commands a plan must avoid."""

    boxes: tuple = ()
    commands: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    tolerance: float = 0.01

    def mask(self, space: ObserverSpace, u: np.ndarray) -> np.ndarray:
        """True where a design point is usable (not excluded)."""
        ok = np.ones(len(u), bool)
        cols = space.columns(u)
        for box in self.boxes:
            inside = np.ones(len(u), bool)
            for name, (a, z) in box.items():
                inside &= (cols[name] >= a) & (cols[name] <= z)
            ok &= ~inside
        if len(self.commands):
            c = space.to_commands(u)
            r = space.machine.ranges
            half = self.tolerance * (r[:, 1] - r[:, 0])
            for cmd in self.commands:
                ok &= ~(np.abs(c - cmd) <= half).all(axis=1)
        return ok


def read_exclusions(path: Union[str, Path], space: ObserverSpace) -> Exclusions:
    """Exclusions file: ``[[box]]`` tables of ``NAME = [lower, upper]``; and/or
    ``commands = [[...], ...]`` (joint order of the machine file) to avoid, each with a
    margin of ``tolerance`` (fraction of every joint range, default 0.01)."""
    from ...schema import validate_document

    doc = load_toml(path, "exclusions")
    if isinstance(doc.get("box"), dict):  # a single [box] table
        doc["box"] = [doc["box"]]
    validate_document("exclusions", doc, str(path))  # intervals, rows of numbers, tolerance, unknown keys
    valid = set(space.names) | set(space.machine.joint_names)
    boxes = []
    for k, bx in enumerate(doc.get("box", [])):
        if not bx:
            raise ConfigError(f"{path}: box {k + 1} is empty")
        for key in bx:
            if key not in valid:
                raise ConfigError(f"{path}: box {k + 1}: unknown variable '{key}' (use {', '.join(sorted(valid))})")
        boxes.append({key: _interval(val, f"{path}: box {k + 1}: '{key}'") for key, val in bx.items()})
    cmds = doc.get("commands", [])
    nj = len(space.machine.joint_names)
    if any(len(r) != nj for r in cmds):
        raise ConfigError(f"{path}: commands must be a list of [{', '.join(space.machine.joint_names)}] rows")
    cmd_arr = np.asarray(cmds, dtype=np.float64).reshape(-1, nj) if cmds else np.empty((0, nj))
    tol = doc.get("tolerance", 0.01)
    if not boxes and not len(cmd_arr):
        raise ConfigError(f"{path}: no [[box]] tables and no commands to exclude")
    return Exclusions(tuple(boxes), cmd_arr, float(tol))

