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

The reader is :mod:`gagekit.gage.spec_file`: every mistake raises
:class:`~gagekit.errors.ConfigError` whose message starts with the file name and names the
table and key.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Optional, Union

from ..cloud.regions import Box
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
        from .spec_file import parse_gage_spec

        return parse_gage_spec(doc, source)


def load_gage_spec(path: Union[str, Path]) -> GageSpec:
    """Read a gage file (TOML); see the module docstring for the format."""
    return GageSpec.load(path)
