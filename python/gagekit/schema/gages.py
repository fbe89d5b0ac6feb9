"""The schema of the gage file (``gage check``) and of the regions file (``cloud regions``).

The gage file holds the motions Omega (Eq. 5.2), the 3-2-1 alignment (Eqs. 5.13-5.19), the
sampling regions (Sec. 5.4.1) and the gages (Table 5.1); a regions file is the same file
without gages. Cross-field rules (a gage's region exists, datum regions are in the scanner
frame, a plane normal is not zero) are checked by :mod:`gagekit.gage.spec`.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, Optional, Union

from pydantic import Field

from ._engine import Style, Table
from ._types import Name, NonNegative, Vec3
from .measurement import MeasurementTable

__all__ = ["MOTIONS", "DEFAULT_MAX_ANGLE", "DEFAULT_MAX_SHIFT", "GageFile", "RegionsFile", "RegionTable",
           "GageStyle"]

MOTIONS = ("alpha", "beta", "gamma", "dx", "dy", "dz")
"""The six motions of Eq. 5.2: alpha about z, beta about y, gamma about x, then shifts."""

DEFAULT_MAX_ANGLE = 0.05
DEFAULT_MAX_SHIFT = 20.0

Motion = Literal[MOTIONS]  # type: ignore[valid-type]
Names = Union[Name, Annotated[list[Name], Field(min_length=1)]]


class RegionTable(Table):
    """``[[region]]``: a sampling volume (Sec. 5.4.1), an oriented box."""

    name: Name
    """The region's name: gages and datums refer to it."""
    center: Vec3
    """Centre of the box (mm)."""
    size: Vec3
    """Full edge lengths along the box's own axes (mm, positive)."""
    rotation: Vec3 = [0.0, 0.0, 0.0]
    """Rotation vector (axis times angle, in the file's angle_unit) turning the file's axes onto the box axes."""


class GageRegion(RegionTable):
    """``[[region]]``: a sampling volume (Sec. 5.4.1) and the frame its box is given in."""

    frame: Literal["part", "scanner"] = "part"
    """The frame of the box: the part (after the alignment) or the scanner (datum regions)."""


class MotionTable(Table):
    """``[motion]``: the set Omega of Eq. 5.2, the free motions and their bounds."""

    free: Union[Motion, list[Motion]] = list(MOTIONS)
    """The free motions (alpha about z, beta about y, gamma about x, dx, dy, dz); [] checks the part as placed."""
    max_angle: NonNegative = DEFAULT_MAX_ANGLE
    """delta_r: the largest rotation (in the file's angle_unit; at most 0.5 rad)."""
    max_shift: NonNegative = DEFAULT_MAX_SHIFT
    """delta_t: the largest shift (mm)."""


class AlignmentTable(Table):
    """``[alignment]``: the 3-2-1 datums (Eqs. 5.13-5.19), regions in the scanner frame."""

    primary: Names
    """The regions of the primary datum (a plane)."""
    secondary: Names
    """The regions of the secondary datum."""
    tertiary: Names
    """The regions of the tertiary datum."""


class GageTable(Table):
    """``[[gage]]``: a virtual gage, the plane a x + b y + c z + d >= 0 on the material side (Table 5.1)."""

    name: Name
    """The gage's name."""
    region: str
    """The [[region]] whose points the gage checks."""
    plane: Annotated[list[float], Field(min_length=4, max_length=4)]
    """[a, b, c, d] with (a, b, c) the unit normal into the material (mm for d; normalized when not unit)."""
    weight: NonNegative = 1.0
    """f_i: the weight of the gage's allowance in the objective."""
    slack_weight: NonNegative = 10.0
    """g_i: the weight of its slack (violation)."""


class _GageBase(Table):
    description: str = ""
    """Free text."""
    length_unit: Literal["mm"] = "mm"
    """Lengths are millimetres."""
    angle_unit: Literal["rad", "deg"] = "rad"
    """The unit of max_angle and of the regions' rotations."""
    motion: MotionTable = MotionTable()
    """The free motions and their bounds."""
    alignment: Optional[AlignmentTable] = None
    """The 3-2-1 alignment of the scan before the gage check (optional)."""
    measurement: Optional[MeasurementTable] = None
    """The measurement model of the instrument (``--measurement GAGES.toml``)."""


class GageFile(_GageBase):
    """A gage file (``gagekit gage check``): motions, alignment, sampling regions and gages (Ch. 5)."""

    region: list[GageRegion] = []
    """The sampling volumes."""
    gage: Annotated[list[GageTable], Field(min_length=1)]
    """The virtual gages (at least one)."""


class RegionsFile(_GageBase):
    """A regions file (``gagekit cloud regions``): sampling regions and an optional 3-2-1 alignment; a gage file works too."""

    region: Annotated[list[GageRegion], Field(min_length=1)]
    """The sampling volumes."""
    gage: list[GageTable] = []
    """Gages (read, not used: a gage file is a regions file)."""


class GageStyle(Style):
    """The wording of the gage and regions readers: ``[motion] max_shift must be at least 0.0``,
    ``gage 'top min': unknown key(s) ...``, ``region 'top' has no 'size'``."""

    tables = ((), ("motion",), ("alignment",), ("measurement",), ("region", int), ("gage", int))
    phrases = {"plane": "four numbers [a, b, c, d]", "center": "three numbers", "size": "three numbers",
               "rotation": "three numbers", "primary": "a non-empty list of names",
               "secondary": "a non-empty list of names", "tertiary": "a non-empty list of names"}

    def label(self, table: tuple) -> str:
        if not table:
            return "top level"
        if len(table) == 1:
            return f"[{table[0]}]"
        name = (self.doc.get(table[0]) or [{}])[table[1]]
        name = name.get("name") if isinstance(name, dict) else None
        return f"{table[0]} '{name}'" if isinstance(name, str) and name else f"{table[0]} #{table[1] + 1}"

    def subject(self, table: tuple, key: tuple) -> str:
        words = " ".join(str(k) for k in key if not isinstance(k, int))
        if not table:
            return f"{self.source}: {words}"
        return f"{self.source}: {self.label(table)}{'' if len(table) == 1 else ':'} {words}"

    def unknown(self, table: tuple, inline: tuple, extra: list, allowed: list) -> str:
        return f"{self.source}: {self.label(table)}: unknown key(s) {', '.join(map(repr, extra))}; allowed: {', '.join(allowed)}"

    def missing(self, table: tuple, key: tuple) -> str:
        k = key[-1]
        if not table and k == "gage":
            return f"{self.source}: no gages: add at least one [[gage]] table"
        if not table and k == "region":
            return f"{self.source}: no regions: add at least one [[region]] table"
        if table == ("alignment",):
            return (f"{self.source}: [alignment] needs '{k}' (a list of region names); "
                    "a 3-2-1 frame takes primary, secondary and tertiary datums")
        if k == "name":
            return f"{self.source}: {table[0]} #{table[1] + 1} needs a name"
        if table[:1] == ("gage",) and k == "region":
            return f"{self.source}: {self.label(table)} has no region (add region = \"<name of a [[region]]>\")"
        return f"{self.source}: {self.label(table)} has no '{k}'"

    def choice(self, subject: str, value: Any, choices: list[str]) -> str:
        if subject.endswith("[motion] free"):
            bad = [m for m in (value if isinstance(value, list) else [value]) if m not in MOTIONS]
            return (f"{subject}: unknown motion(s) {', '.join(map(repr, bad))}; choose from {', '.join(MOTIONS)} "
                    "(alpha about z, beta about y, gamma about x)")
        extra = " (gage files are in millimetres)" if subject.endswith("length_unit") else ""
        return f"{subject} must be {' or '.join(f'{c!r}'.replace(chr(39), chr(34)) for c in choices)}{extra}, got {value!r}"

    def must(self, subject: str, phrase: str, value: Any) -> str:
        return f"{subject} must be {phrase}, got {value!r}"

    def generic(self, kind: str) -> str:
        return {"finite_number": "finite"}.get(kind) or super().generic(kind)

    def not_table(self, path: tuple, value: Any) -> str:
        if path == ("region",):
            return f"{self.source}: regions must be given as [[region]] tables"
        if path == ("gage",):
            return f"{self.source}: no gages: add at least one [[gage]] table"
        table, key = self.split(path)
        if not key:
            return f"{self.source}: {self.label(table)} must be a table"
        return self.must(self.subject(table, key), "a table", value)
