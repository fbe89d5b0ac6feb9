"""The schema of an observer zones file (``gagekit machine design --zones``, Sec. 4.2).

``[[zone]]`` tables: ``count`` observations inside the box given by ``NAME = [lower, upper]``
per variable (a joint of the machine file or the redundant sum, e.g. ``"Z+W"``); variables not
named span their range. Which names exist depends on the machine: :mod:`gagekit.machine.observer.zones`
checks them, and that a bound pair is not reversed, after this schema.
"""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import ConfigDict, Field

from ._engine import Style, Table

__all__ = ["ZonesFile", "ZonesStyle", "Interval"]

Interval = Annotated[list[float], Field(min_length=2, max_length=2)]


class ZoneTable(Table):
    """``[[zone]]``: a box of the observer space and the observations inside it. Every other key
    is a variable (a joint name or a redundant sum such as "Z+W") = [lower, upper] (mm, or the
    machine file's angle_unit for rotary joints)."""

    model_config = ConfigDict(extra="allow")
    __pydantic_extra__: dict[str, Interval] = Field(init=False)  # type: ignore[assignment]

    count: Annotated[int, Field(ge=0)]
    """The number of observations in the zone."""


class ZonesFile(Table):
    """An observer zones file: the zones of an observer plan (Sec. 4.2, Fig. 4.3)."""

    description: str = ""
    """Free text."""
    zone: Annotated[list[ZoneTable], Field(min_length=1)]
    """The zones (at least one)."""


class ZonesStyle(Style):
    """The wording of the zones reader: ``zones.toml: zone 2: count must be a non-negative
    integer, got -1``, ``zones.toml: zone 1: 'X' must be [lower, upper], got [0]``."""

    tables = ((), ("zone", int))

    def label(self, table: tuple) -> str:
        return self.source if not table else f"{self.source}: zone {table[1] + 1}"

    def subject(self, table: tuple, key: tuple) -> str:
        name = str(key[0])
        return f"{self.label(table)}: {name if name == 'count' else repr(name)}"

    def missing(self, table: tuple, key: tuple) -> str:
        if not table:
            return f"{self.source}: expected one or more [[zone]] tables"
        return f"{self.label(table)} needs a count"

    def phrase(self, kind: str, name: str) -> str:
        return "a non-negative integer" if name == "count" else "[lower, upper]"

    def bound(self, subject: str, name: str, kind: str, limit: Any, value: Any) -> str:
        return self.must(subject, self.phrase(kind, name), value)

    def not_table(self, path: tuple, value: Any) -> str:
        if path == ("zone",):
            return self.missing((), path)
        return f"{self.label(path)} must be a table" if len(path) == 2 else f"{self.source}: {path[-1]} must be a table"
