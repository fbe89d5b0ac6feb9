"""The gage file (TOML): motions, the 3-2-1 alignment, sampling regions and gages.

Example (lengths in mm, angles in rad unless ``angle_unit = "deg"``)::

    length_unit = "mm"

    [motion]                      # the set Omega of Eq. 5.2
    free = ["beta", "dx", "dy", "dz"]
    max_angle = 0.05              # delta_r
    max_shift = 20.0              # delta_t

    [alignment]                   # optional 3-2-1 datum fit (Eqs. 5.13-5.19)
    primary = ["Z1", "Z2", "Z3"]
    secondary = ["Y1", "Y2"]
    tertiary = ["X1"]

    [[region]]                    # a sampling volume (Sec. 5.4.1)
    name = "flange_top"
    frame = "part"                # or "scanner"
    center = [45.0, 63.0, 111.4]
    size = [88.0, 112.0, 8.0]
    rotation = [0.0, 0.0, 0.0]

    [[gage]]
    name = "flange top min"
    region = "flange_top"
    plane = [0.0, 0.0, 1.0, -109.30]   # a x + b y + c z + d >= 0 on the material side
    weight = 1.0                       # f_i
    slack_weight = 10.0                # g_i

The reader (:func:`parse_gage_spec`, below the types) validates the file against its schema
(:mod:`gagekit.schema.gages`, ``gagekit schema gages``), then checks the rules between keys:
every mistake raises :class:`~gagekit.errors.ConfigError` whose message starts with the file
name and names the table and key.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Optional, Union

from .._util import named_tables
from ..cloud.regions import Box, regions_from_tables
from ..errors import ConfigError
from ..schema import validate_document
from ..schema.gages import DEFAULT_MAX_ANGLE, DEFAULT_MAX_SHIFT, MOTIONS


class GageFileWarning(UserWarning):
    """A gage file was read with an adjustment (e.g. a plane normal normalized)."""


@dataclass(frozen=True)
class MotionSet:
    """The set Omega of Eq. 5.2: the free motions and their bounds (rad, mm)."""

    free: tuple[str, ...] = MOTIONS
    max_angle: float = DEFAULT_MAX_ANGLE
    max_shift: float = DEFAULT_MAX_SHIFT

    def flags(self) -> list[bool]:
        return [m in self.free for m in MOTIONS]

    def to_dict(self) -> dict:
        return {"free": list(self.free), "max_angle": self.max_angle, "max_shift": self.max_shift}


@dataclass(frozen=True)
class Region:
    """A sampling volume and the frame its box is given in (``part`` or ``scanner``)."""

    box: Box
    frame: str = "part"

    @property
    def name(self) -> str:
        return self.box.name

    def to_dict(self) -> dict:
        return {**self.box.to_dict(), "frame": self.frame}


@dataclass(frozen=True)
class Gage:
    """A virtual gage: plane (a, b, c, d), unit normal, a x + b y + c z + d >= 0 on
    the material side (Table 5.1), checked on the points of ``region``."""

    name: str
    region: str
    plane: tuple[float, float, float, float]
    weight: float = 1.0
    slack_weight: float = 10.0

    def to_dict(self) -> dict:
        return {"name": self.name, "region": self.region, "plane": list(self.plane),
                "weight": self.weight, "slack_weight": self.slack_weight}


@dataclass(frozen=True)
class AlignmentSpec:
    """Region names of the primary, secondary and tertiary datums (scanner frame)."""

    primary: tuple[str, ...]
    secondary: tuple[str, ...]
    tertiary: tuple[str, ...]

    def to_dict(self) -> dict:
        return {"primary": list(self.primary), "secondary": list(self.secondary), "tertiary": list(self.tertiary)}


@dataclass(frozen=True)
class GageSpec:
    """A parsed gage file."""

    regions: tuple[Region, ...]
    gages: tuple[Gage, ...]
    motion: MotionSet = MotionSet()
    alignment: Optional[AlignmentSpec] = None
    source: str = "gage spec"

    def region(self, name: str) -> Region:
        for r in self.regions:
            if r.name == name:
                return r
        raise ConfigError(f"{self.source}: unknown region '{name}'")

    def to_dict(self) -> dict:
        return {
            "motion": self.motion.to_dict(),
            "alignment": None if self.alignment is None else self.alignment.to_dict(),
            "regions": [r.to_dict() for r in self.regions],
            "gages": [g.to_dict() for g in self.gages],
        }

    @classmethod
    def load(cls, path: Union[str, Path]) -> "GageSpec":
        """Read a gage file (TOML)."""
        from .._util import load_toml

        return cls.from_dict(load_toml(path, "gage"), str(path))

    @classmethod
    def from_dict(cls, doc: Mapping[str, Any], source: str = "gage spec") -> "GageSpec":
        """Build a spec from the parsed TOML document ``doc``."""
        return parse_gage_spec(doc, source)


def load_gage_spec(path: Union[str, Path]) -> GageSpec:
    """Read a gage file (TOML); see the module docstring for the format."""
    return GageSpec.load(path)


# -- the reader of gage files ------------------------------------------------------------
# The schema (gagekit.schema.gages) checks every key's type, range and choice and refuses
# unknown keys; what follows are the rules between keys, in one place.


def _unique(names: Union[str, list], where: str, source: str) -> tuple[str, ...]:
    v = [names] if isinstance(names, str) else list(names)
    if len(set(v)) != len(v):
        raise ConfigError(f"{source}: {where} lists a name twice: {v!r}")
    return tuple(v)


def parse_gage_spec(doc: Mapping[str, Any], source: str) -> GageSpec:
    """Validate a parsed gage file ``doc`` (see :mod:`gagekit.gage.spec` for the format)."""
    f = validate_document("gages", doc, source)
    ang = math.pi / 180.0 if f.angle_unit == "deg" else 1.0
    regions = _parse_regions(doc, source, ang)
    gages = _parse_gages(f.gage, doc["gage"], source, {r.name for r in regions})
    return GageSpec(regions, tuple(gages), _parse_motion(f.motion, source, ang), _parse_alignment(f.alignment, source, regions),
                    source)


def parse_region_spec(doc: Mapping[str, Any], source: str) -> GageSpec:
    """The ``[[region]]`` tables and the ``[alignment]`` of a gage or regions file, without
    gages or motions (``cloud regions``): the regions placed as ``gage check`` places them."""
    f = validate_document("regions", doc, source)
    regions = _parse_regions(doc, source, math.pi / 180.0 if f.angle_unit == "deg" else 1.0)
    return GageSpec(regions, (), alignment=_parse_alignment(f.alignment, source, regions), source=source)


def _parse_motion(mt: Any, source: str, ang: float) -> MotionSet:
    """[motion]: the free motions and their bounds (the set Omega of Eq. 5.2)."""
    free = () if mt.free == [] else _unique(mt.free, "[motion] free", source)  # [] = check as placed
    free = tuple(m for m in MOTIONS if m in free)
    max_angle = mt.max_angle * ang if "max_angle" in mt.model_fields_set else DEFAULT_MAX_ANGLE
    if max_angle > 0.5:
        raise ConfigError(f"{source}: [motion] max_angle = {max_angle:.4g} rad is too large for a set-up "
                          "correction (at most 0.5 rad)")
    return MotionSet(free, max_angle, mt.max_shift)


def _parse_regions(doc: Mapping[str, Any], source: str, ang: float) -> tuple[Region, ...]:
    """[[region]]: the sampling volumes (Sec. 5.4.1) and their frames."""
    tables = doc.get("region", [])
    try:
        boxes = regions_from_tables(tables, source, ang)
    except ConfigError as exc:
        msg = str(exc)
        raise ConfigError(msg if msg.startswith(source) else f"{source}: {msg}") from None
    return tuple(Region(b, t.get("frame", "part")) for b, t in zip(boxes, tables))


def _parse_gages(models: list, tables: list, source: str, names: set) -> list[Gage]:
    """[[gage]]: the gage planes (Table 5.1), normalized, on regions of ``names``."""
    gages: list[Gage] = []
    for (name, _), g in zip(named_tables(tables, "gage", source), models):
        label = f"gage '{name}'"
        if g.region not in names:
            raise ConfigError(f"{source}: {label}: unknown region {g.region!r}; defined regions: "
                              f"{', '.join(sorted(names)) or '(none)'}")
        a, b, c, d = g.plane
        nn = math.sqrt(a * a + b * b + c * c)
        if nn < 1e-12:
            raise ConfigError(f"{source}: {label}: plane normal (a, b, c) is zero")
        if abs(nn - 1.0) > 1e-6:
            warnings.warn(f"{source}: {label}: plane normal had length {nn:.6g}; normalized "
                          "(d scaled by the same factor)", GageFileWarning, stacklevel=4)
        gages.append(Gage(name, g.region, (a / nn, b / nn, c / nn, d / nn), g.weight, g.slack_weight))
    return gages


def _parse_alignment(al: Any, source: str, regions: tuple[Region, ...]) -> Optional[AlignmentSpec]:
    """[alignment]: the 3-2-1 datums (Eqs. 5.13-5.19), regions in the scanner frame."""
    if al is None:
        return None
    frames = {r.name: r.frame for r in regions}
    lists = []
    for key in ("primary", "secondary", "tertiary"):
        lst = _unique(getattr(al, key), f"[alignment] {key}", source)
        for n in lst:
            if n not in frames:
                raise ConfigError(f"{source}: [alignment] {key}: unknown region {n!r}")
            if frames[n] != "scanner":
                raise ConfigError(f"{source}: [alignment] {key}: region {n!r} must have frame = \"scanner\" "
                                  "(datums are found before the part frame exists)")
        lists.append(lst)
    return AlignmentSpec(*lists)
