"""One declarative schema per TOML file type, one validation engine (pydantic v2).

==========  ========================================  ======================================================
kind        file                                      reader (schema pass, then cross-field rules)
==========  ========================================  ======================================================
gages       gage file (``gage check``)                :func:`gagekit.gage.spec.parse_gage_spec`
part        PART.toml (``inspect``)                   :func:`gagekit.inspect.spec.part_spec_from_dict`
machine     machine file (``machine ...``)            :func:`gagekit.machine.model.parse_machine`
regions     regions file (``cloud regions``)          :func:`gagekit.cloud.regions.load_regions`
zones       observer zones (``machine design``)       :func:`gagekit.machine.observer.zones.read_zones`
exclusions  observer exclusions (``machine design``)  :func:`gagekit.machine.observer.zones.read_exclusions`
==========  ========================================  ======================================================

:func:`json_schema` gives a kind's JSON Schema (draft 2020-12, unknown keys refused), generated
from the same models the readers validate with; ``gagekit schema KIND`` prints it, and a
``#:schema FILE`` first line lets Even Better TOML / taplo complete and check a file as it is
typed. Why pydantic: see :mod:`gagekit.schema._engine`.
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel

from ..errors import ConfigError
from ._engine import Style, Table, validate
from .gages import GageFile, GageStyle, RegionsFile
from .machine import MachineFile, MachineStyle
from .part import PartFile, PartStyle
from .exclusions import ExclusionsFile, ExclusionsStyle
from .zones import ZonesFile, ZonesStyle

__all__ = ["SCHEMA_KINDS", "json_schema", "validate_document", "Table", "Style"]

#: kind -> (root model, message style)
_KINDS: dict[str, tuple[type[BaseModel], type[Style]]] = {
    "gages": (GageFile, GageStyle),
    "part": (PartFile, PartStyle),
    "machine": (MachineFile, MachineStyle),
    "regions": (RegionsFile, GageStyle),
    "zones": (ZonesFile, ZonesStyle),
    "exclusions": (ExclusionsFile, ExclusionsStyle),
}

SCHEMA_KINDS = tuple(_KINDS)
"""The file types with a schema: gages, part, machine, regions, zones, exclusions."""


def _kind(kind: str) -> tuple[type[BaseModel], type[Style]]:
    if kind not in _KINDS:
        raise ConfigError(f"unknown file type {kind!r}; choose one of {', '.join(_KINDS)}")
    return _KINDS[kind]


def json_schema(kind: str) -> dict:
    """The JSON Schema (draft 2020-12) of the file type ``kind`` (one of :data:`SCHEMA_KINDS`)."""
    from ._engine import json_schema as _json_schema

    return _json_schema(_kind(kind)[0], f"urn:gagekit:schema:{kind}")


def validate_document(kind: str, doc: Any, source: str) -> Any:
    """``doc`` (a parsed TOML document) validated against the schema of ``kind``: the model,
    or :class:`~gagekit.errors.ConfigError` naming ``source``, the table and the key."""
    model, style = _kind(kind)
    return validate(model, doc, source, style)

