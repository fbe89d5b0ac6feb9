"""The schema of an observer exclusions file (``gagekit machine design --exclude``, Sec. 4.2).

``[[box]]`` tables of ``NAME = [lower, upper]`` per variable (a joint of the machine file or the
redundant sum, e.g. ``"Z+W"``) and/or ``commands = [[...], ...]`` (rows in the machine file's
joint order) that a plan must avoid, each with a margin of ``tolerance`` (a fraction of every
joint range). Which names exist and how long a command row is depend on the machine:
:func:`gagekit.machine.observer.zones.read_exclusions` checks them after this schema.
"""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import ConfigDict, Field

from ._engine import Style, Table
from .zones import Interval

__all__ = ["ExclusionsFile", "ExclusionsStyle"]


class BoxTable(Table):
    """``[[box]]``: a box of the observer space no design point may fall in. Every key is a
    variable (a joint name or a redundant sum such as "Z+W") = [lower, upper] (mm, or the machine
    file's angle_unit for rotary joints); variables not named span their range."""

    model_config = ConfigDict(extra="allow")
    __pydantic_extra__: dict[str, Interval] = Field(init=False)  # type: ignore[assignment]


class ExclusionsFile(Table):
    """An observer exclusions file: boxes and single commands a plan must avoid (Sec. 4.2)."""

    description: str = ""
    """Free text."""
    box: list[BoxTable] = []
    """The excluded boxes."""
    commands: list[list[float]] = []
    """Excluded commands, one row per command in the machine file's joint order."""
    tolerance: Annotated[float, Field(ge=0, lt=0.5)] = 0.01
    """The margin around each excluded command, as a fraction of every joint range."""


class ExclusionsStyle(Style):
    """The wording of the exclusions reader: ``excl.toml: box 2: 'X' must be [lower, upper], got
    [0]``, ``excl.toml: 'tolerance' must be a fraction of the joint ranges in [0, 0.5), got 0.7``."""

    tables = ((), ("box", int))
    phrases = {"commands": "a list of rows of numbers", "tolerance": "a fraction of the joint ranges in [0, 0.5)"}

    def label(self, table: tuple) -> str:
        return self.source if not table else f"{self.source}: box {table[1] + 1}"

    def phrase(self, kind: str, name: str) -> str:
        if name in self.phrases:
            return self.phrases[name]
        return super().phrase(kind, name) if name == "description" else "[lower, upper]"

    def bound(self, subject: str, name: str, kind: str, limit: Any, value: Any) -> str:
        if name == "tolerance":
            return self.must(subject, self.phrases["tolerance"], value)
        return super().bound(subject, name, kind, limit, value)
