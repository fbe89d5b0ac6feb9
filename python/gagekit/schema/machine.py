"""The schema of the machine file (``gagekit machine ...``): the chain of Eq. 3.1.

Shape transforms ``[shapes.T*]`` with a nominal offset, joints ``[joints.*]`` with type, unit
axis, range and (rotary) Fourier terms (Eq. 3.6), ``[tool] offset`` the target r_t. The chain
rules (every element defined and listed once, a unit axis, min < max) are checked by
:mod:`gagekit.machine.model` after this schema.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field

from .._core import kinematics as _kinematics
from ._engine import Style, Table
from ._types import Vec3

__all__ = ["MachineFile", "MachineStyle", "MAX_TERMS"]

MAX_TERMS: int = _kinematics.MAX_FOURIER_TERMS  #: the kernel's limit (rust/kinematics chain.rs), defined once


class JointTable(Table):
    """``[joints.NAME]``: a prismatic or rotary axis of the machine."""

    type: Literal["prismatic", "rotary"]
    """Prismatic (a slide) or rotary (a table or head)."""
    axis: Vec3
    """The unit direction of motion (prismatic) or rotation (rotary), in the joint's frame."""
    range: Annotated[list[float], Field(min_length=2, max_length=2)]
    """[min, max] of the commands (mm; rotary: the file's angle_unit)."""
    fourier_terms: Annotated[int, Field(ge=1, le=MAX_TERMS)] = 1
    """Rotary joints: the terms n = 1..N of the Fourier series of each error (Eq. 3.6)."""
    description: str = ""
    """Free text."""


class ShapeTable(Table):
    """``[shapes.NAME]``: a fixed link between two joints."""

    offset: Vec3
    """The nominal translation of the link (mm)."""
    description: str = ""
    """Free text."""


class ToolTable(Table):
    """``[tool]``: the target r_t in the spindle frame."""

    offset: Vec3
    """The target's position in the spindle frame (mm)."""
    description: str = ""
    """Free text."""


class MachineFile(Table):
    """A machine file: the serial chain from the table to the spindle (Eq. 3.1), its joints, links and tool."""

    name: str = ""
    """The machine's name (default: the file's stem)."""
    description: str = ""
    """Free text."""
    length_unit: Literal["mm"] = "mm"
    """Lengths are millimetres."""
    angle_unit: Literal["deg", "rad"] = "deg"
    """The unit of rotary commands and ranges (here and in command and observation CSVs)."""
    chain: Annotated[list[str], Field(min_length=1)]
    """The joints and shapes from the table to the spindle."""
    joints: dict[str, JointTable] = {}
    """The joints by name."""
    shapes: dict[str, ShapeTable] = {}
    """The shape transforms by name."""
    tool: ToolTable
    """The tool target."""


class MachineStyle(Style):
    """The wording of the machine reader: ``m.toml: joints.B.type must be "prismatic" or
    "rotary", got 'linear'``, ``m.toml: joints.Z: unknown key 'axes' (allowed: ...)``."""

    tables = ((), ("joints",), ("joints", str), ("shapes",), ("shapes", str), ("tool",))
    phrases = {"axis": "three finite numbers", "offset": "three finite numbers",
               "range": "two finite numbers [min, max]", "chain": "a non-empty list of element names",
               "fourier_terms": f"an integer from 1 to {MAX_TERMS}", "name": "a string"}

    def dotted(self, path: tuple) -> str:
        return ".".join(str(k) for k in path if not isinstance(k, int))

    def subject(self, table: tuple, key: tuple) -> str:
        return f"{self.source}: {self.dotted(table + key)}"

    def unknown(self, table: tuple, inline: tuple, extra: list, allowed: list) -> str:
        if not table:
            return f"{self.source}: unknown top-level key '{extra[0]}' (allowed: {', '.join(allowed)})"
        shown = ", ".join(k for k in allowed if k != "description")
        return f"{self.source}: {self.dotted(table)}: unknown key '{extra[0]}' (allowed: {shown})"

    def missing(self, table: tuple, key: tuple) -> str:
        k = key[-1]
        if k == "chain":
            return f'{self.source}: missing "chain": list the joints and shapes from the table to the spindle'
        if k == "tool" or table == ("tool",):
            return f"{self.source}: missing [tool] offset: the target r_t in the spindle frame, e.g. offset = [0, 0, -312.035]"
        return f"{self.source}: {self.dotted(table)}: missing {k}"

    def choice(self, subject: str, value: Any, choices: list[str]) -> str:
        extra = " (gagekit works in millimetres)" if subject.endswith("length_unit") else ""
        quoted = " or ".join('"' + c + '"' for c in choices)
        return f"{subject} must be {quoted}{extra}, got {value!r}"

    def phrase(self, kind: str, name: str) -> str:
        return self.phrases.get(name) or super().phrase(kind, name)

    def bound(self, subject: str, name: str, kind: str, limit: Any, value: Any) -> str:
        if name in self.phrases:
            return self.must(subject, self.phrases[name], value)
        return super().bound(subject, name, kind, limit, value)

    def not_table(self, path: tuple, value: Any) -> str:
        if path and path[0] in ("joints", "shapes") and len(path) <= 2:
            return f"{self.source}: [{path[0]}] must be tables such as [{path[0]}.NAME]"
        if path == ("tool",):
            return self.missing((), ("tool",))
        return f"{self.source}: {self.dotted(path)} must be a table, got {value!r}"
