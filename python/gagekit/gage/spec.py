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

The reader (:func:`parse_gage_spec`, below the types): every mistake raises
:class:`~gagekit.errors.ConfigError` whose message starts with the file name and names the
table and key.
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

MOTIONS = ("alpha", "beta", "gamma", "dx", "dy", "dz")
"""The six motions of Eq. 5.2: alpha about z, beta about y, gamma about x, then shifts."""

DEFAULT_MAX_ANGLE = 0.05
DEFAULT_MAX_SHIFT = 20.0


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

_TOP_KEYS = {"length_unit", "angle_unit", "motion", "alignment", "region", "gage", "description"}
_MOTION_KEYS = {"free", "max_angle", "max_shift"}
_ALIGN_KEYS = {"primary", "secondary", "tertiary"}
_REGION_KEYS = {"name", "frame", "center", "size", "rotation"}
_GAGE_KEYS = {"name", "region", "plane", "weight", "slack_weight"}



def _scaled_rotation(raw: Any, ang: float) -> Any:
    """A region's rotation in degrees, to radians (left as given when malformed: the box
    check then names the region and the key)."""
    if isinstance(raw, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in raw):
        return [float(v) * ang for v in raw]
    return raw

def _unknown(keys, allowed, where: str, source: str) -> None:
    extra = sorted(set(keys) - allowed)
    if extra:
        raise ConfigError(f"{source}: {where}: unknown key(s) {', '.join(map(repr, extra))}; "
                          f"allowed: {', '.join(sorted(allowed))}")


def _number(v: Any, where: str, source: str, minimum: Optional[float] = None, positive: bool = False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ConfigError(f"{source}: {where} must be a number, got {v!r}")
    x = float(v)
    if not math.isfinite(x):
        raise ConfigError(f"{source}: {where} must be finite, got {v!r}")
    if positive and x <= 0:
        raise ConfigError(f"{source}: {where} must be positive, got {v!r}")
    if minimum is not None and x < minimum:
        raise ConfigError(f"{source}: {where} must be at least {minimum}, got {v!r}")
    return x


def _names(v: Any, where: str, source: str) -> tuple[str, ...]:
    if isinstance(v, str):
        v = [v]
    if not isinstance(v, list) or not v or not all(isinstance(s, str) and s for s in v):
        raise ConfigError(f"{source}: {where} must be a non-empty list of names, got {v!r}")
    if len(set(v)) != len(v):
        raise ConfigError(f"{source}: {where} lists a name twice: {v!r}")
    return tuple(v)


def parse_gage_spec(doc: Mapping[str, Any], source: str) -> GageSpec:
    """Validate a parsed gage file ``doc`` (see :mod:`gagekit.gage.spec` for the format)."""
    if not isinstance(doc, Mapping):
        raise ConfigError(f"{source}: expected a table at the top level")
    _unknown(doc.keys(), _TOP_KEYS, "top level", source)
    ang = _angle_factor(doc, source)
    motion = _parse_motion(doc, source, ang)
    regions = _parse_regions(doc, source, ang)
    gages = _parse_gages(doc, source, {r.name for r in regions})
    alignment = _parse_alignment(doc, source, regions)
    return GageSpec(regions, tuple(gages), motion, alignment, source)


def parse_region_spec(doc: Mapping[str, Any], source: str) -> GageSpec:
    """The ``[[region]]`` tables and the ``[alignment]`` of a gage or regions file, without
    gages or motions (``cloud regions``): the regions placed as ``gage check`` places them."""
    if not isinstance(doc, Mapping):
        raise ConfigError(f"{source}: expected a table at the top level")
    _unknown(doc.keys(), _TOP_KEYS, "top level", source)
    regions = _parse_regions(doc, source, _angle_factor(doc, source))
    return GageSpec(regions, (), alignment=_parse_alignment(doc, source, regions), source=source)


def _angle_factor(doc: Mapping[str, Any], source: str) -> float:
    """Radians per angle unit of the file (``length_unit`` must be mm)."""
    unit = doc.get("length_unit", "mm")
    if unit != "mm":
        raise ConfigError(f"{source}: length_unit must be \"mm\" (gage files are in millimetres), got {unit!r}")
    angle_unit = doc.get("angle_unit", "rad")
    if angle_unit not in ("rad", "deg"):
        raise ConfigError(f"{source}: angle_unit must be \"rad\" or \"deg\", got {angle_unit!r}")
    return math.pi / 180.0 if angle_unit == "deg" else 1.0


def _parse_motion(doc: Mapping[str, Any], source: str, ang: float) -> MotionSet:
    """[motion]: the free motions and their bounds (the set Omega of Eq. 5.2)."""
    mt = doc.get("motion", {})
    if not isinstance(mt, Mapping):
        raise ConfigError(f"{source}: [motion] must be a table")
    _unknown(mt.keys(), _MOTION_KEYS, "[motion]", source)
    raw_free = mt.get("free", list(MOTIONS))
    free = () if raw_free == [] else _names(raw_free, "[motion] free", source)  # [] = check as placed
    bad = [m for m in free if m not in MOTIONS]
    if bad:
        raise ConfigError(f"{source}: [motion] free: unknown motion(s) {', '.join(map(repr, bad))}; "
                          f"choose from {', '.join(MOTIONS)} (alpha about z, beta about y, gamma about x)")
    free = tuple(m for m in MOTIONS if m in free)
    max_angle = _number(mt.get("max_angle", DEFAULT_MAX_ANGLE / ang), "[motion] max_angle", source, minimum=0.0) * ang
    max_shift = _number(mt.get("max_shift", DEFAULT_MAX_SHIFT), "[motion] max_shift", source, minimum=0.0)
    if max_angle > 0.5:
        raise ConfigError(f"{source}: [motion] max_angle = {max_angle:.4g} rad is too large for a set-up "
                          "correction (at most 0.5 rad)")
    return MotionSet(free, max_angle, max_shift)


def _parse_regions(doc: Mapping[str, Any], source: str, ang: float) -> tuple[Region, ...]:
    """[[region]]: the sampling volumes (Sec. 5.4.1) and their frames."""
    tables = doc.get("region", [])
    if not isinstance(tables, list):
        raise ConfigError(f"{source}: regions must be given as [[region]] tables")
    frames = []
    for k, t in enumerate(tables):
        if not isinstance(t, Mapping):
            raise ConfigError(f"{source}: region #{k + 1} must be a table")
        label = f"region '{t.get('name')}'" if isinstance(t.get("name"), str) else f"region #{k + 1}"
        _unknown(t.keys(), _REGION_KEYS, label, source)
        frame = t.get("frame", "part")
        if frame not in ("part", "scanner"):
            raise ConfigError(f"{source}: {label}: frame must be \"part\" or \"scanner\", got {frame!r}")
        frames.append(frame)
    if ang != 1.0:
        tables = [dict(t, rotation=_scaled_rotation(t["rotation"], ang)) if "rotation" in t else t for t in tables]
    try:
        boxes = regions_from_tables(tables, source)
    except ConfigError as exc:
        msg = str(exc)
        raise ConfigError(msg if msg.startswith(source) else f"{source}: {msg}") from None
    return tuple(Region(b, f) for b, f in zip(boxes, frames))


def _parse_gages(doc: Mapping[str, Any], source: str, names: set) -> list[Gage]:
    """[[gage]]: the gage planes (Table 5.1), normalized, on regions of ``names``."""
    gtables = doc.get("gage", [])
    if not isinstance(gtables, list) or not gtables:
        raise ConfigError(f"{source}: no gages: add at least one [[gage]] table")
    gages: list[Gage] = []
    for name, t in named_tables(gtables, "gage", source):
        label = f"gage '{name}'"
        _unknown(t.keys(), _GAGE_KEYS, label, source)
        region = t.get("region")
        if region is None:
            raise ConfigError(f"{source}: {label} has no region (add region = \"<name of a [[region]]>\")")
        if not isinstance(region, str) or region not in names:
            raise ConfigError(f"{source}: {label}: unknown region {region!r}; defined regions: "
                              f"{', '.join(sorted(names)) or '(none)'}")
        plane = t.get("plane")
        if not isinstance(plane, list) or len(plane) != 4:
            raise ConfigError(f"{source}: {label}: plane must be four numbers [a, b, c, d], got {plane!r}")
        a, b, c, d = (_number(v, f"{label}: plane", source) for v in plane)
        nn = math.sqrt(a * a + b * b + c * c)
        if nn < 1e-12:
            raise ConfigError(f"{source}: {label}: plane normal (a, b, c) is zero")
        if abs(nn - 1.0) > 1e-6:
            warnings.warn(f"{source}: {label}: plane normal had length {nn:.6g}; normalized "
                          "(d scaled by the same factor)", GageFileWarning, stacklevel=4)
        weight = _number(t.get("weight", 1.0), f"{label}: weight", source, minimum=0.0)
        slack_weight = _number(t.get("slack_weight", 10.0), f"{label}: slack_weight", source, minimum=0.0)
        gages.append(Gage(name, region, (a / nn, b / nn, c / nn, d / nn), weight, slack_weight))
    return gages


def _parse_alignment(doc: Mapping[str, Any], source: str, regions: tuple[Region, ...]) -> Optional[AlignmentSpec]:
    """[alignment]: the 3-2-1 datums (Eqs. 5.13-5.19), regions in the scanner frame."""
    names = {r.name for r in regions}
    al = doc.get("alignment")
    if al is not None:
        if not isinstance(al, Mapping):
            raise ConfigError(f"{source}: [alignment] must be a table")
        _unknown(al.keys(), _ALIGN_KEYS, "[alignment]", source)
        for key in ("primary", "secondary", "tertiary"):
            if key not in al:
                raise ConfigError(f"{source}: [alignment] needs '{key}' (a list of region names); "
                                  "a 3-2-1 frame takes primary, secondary and tertiary datums")
        lists = []
        for key in ("primary", "secondary", "tertiary"):
            lst = _names(al[key], f"[alignment] {key}", source)
            for n in lst:
                if n not in names:
                    raise ConfigError(f"{source}: [alignment] {key}: unknown region {n!r}")
                frame = next(r.frame for r in regions if r.name == n)
                if frame != "scanner":
                    raise ConfigError(f"{source}: [alignment] {key}: region {n!r} must have frame = \"scanner\" "
                                      "(datums are found before the part frame exists)")
            lists.append(lst)
        return AlignmentSpec(*lists)
    return None
