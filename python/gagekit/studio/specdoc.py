"""The gage file (or PART.toml drawing) as the studio edits it: the original text, its
plain document, and the edits written back with formatting kept.

Two kinds of document: a gage file (``[[region]]``, ``[[gage]]``, ``[alignment]``: the
reader of ``gagekit gage check``) and a drawing (``[[feature]]``, ``[datums]``,
``[[tolerance]]``: the reader of ``gagekit inspect``, :mod:`gagekit.inspect.spec`).
:func:`kind_of` tells them apart; validation uses the matching reader.

The studio's client works on the plain document (the TOML tables as JSON: the
``[motion]`` and ``[alignment]`` tables, the ``[[region]]`` and ``[[gage]]`` lists).
:func:`render` turns an edited document back into text in exactly the format
``gagekit gage check`` reads (:mod:`gagekit.gage.spec`): when nothing changed it
returns the original text byte for byte; otherwise the edits are applied to the
parsed file with tomlkit (a style-preserving TOML library), so comments, key
order and number formatting of everything untouched stay as they were.

:func:`locate` maps a :class:`~gagekit.errors.ConfigError` of the spec reader to
the table it comes from, so the client can show it next to that table.
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass, field
from typing import Any, Optional

import tomlkit
from tomlkit.items import AoT, InlineTable, Table

from ..errors import ConfigError
from ..gage.spec import GageFileWarning, GageSpec

FLOAT_KEYS = {"center", "size", "rotation", "plane", "max_angle", "max_shift", "weight", "slack_weight",
              "outward", "direction", "tolerance", "point", "angle"}
"""Keys whose numbers the readers take as floats: new values are written as floats (``50.0``)."""

INLINE_KEYS = {"region", "nominal"}
"""Tables written inline (``region = { center = [...], size = [...] }``), as a drawing has them."""

TOP_ORDER = ("description", "length_unit", "angle_unit", "motion", "alignment", "part", "region", "gage", "feature",
             "datums", "tolerance")

PART_KEYS = {"part", "feature", "datums", "tolerance"}


def kind_of(doc: Any) -> str:
    """``"part"`` for a drawing (any of [part], [[feature]], [datums], [[tolerance]]), else ``"gage"``."""
    return "part" if isinstance(doc, dict) and PART_KEYS & set(doc) else "gage"

_LOCATORS = [
    (re.compile(r"^(?P<table>region|gage) '(?P<name>[^']*)'"), None),
    (re.compile(r"^(?P<table>region|gage) #(?P<num>\d+)"), None),
    (re.compile(r"^\[(?P<table>motion|alignment)\]"), None),
    (re.compile(r"^no gages"), "gage"),
    (re.compile(r"^regions must"), "region"),
    (re.compile(r"^(?:region|size along|\w+ must be three)"), "region"),
    (re.compile(r"^\[\[(?P<table>feature|tolerance)\]\] #(?P<num>\d+)"), None),
    (re.compile(r"^\[(?P<table>datums|part)\]"), None),
    (re.compile(r"^no \[\[(?P<table>feature|tolerance)\]\]"), None),
]


def parse_text(text: str, source: str) -> dict:
    """The plain document of a gage file's text; ConfigError when it is not TOML."""
    try:
        return tomlkit.parse(text).unwrap()
    except tomlkit.exceptions.ParseError as exc:
        raise ConfigError(f"{source}: not valid TOML ({exc})") from None


def locate(message: str, source: str) -> dict:
    """``{"table", "name", "index", "message"}`` for a spec-reader error message.

    ``table`` is ``region``, ``gage``, ``motion``, ``alignment`` (gage files),
    ``feature``, ``tolerance``, ``datums``, ``part`` (drawings) or ``top``; ``name``
    or ``index`` (1-based) names the entry when the message does.
    """
    text = message[len(source) + 2:] if message.startswith(source + ": ") else message
    out: dict[str, Any] = {"table": "top", "name": None, "index": None, "message": text}
    for rx, table in _LOCATORS:
        m = rx.match(text)
        if m:
            groups = m.groupdict()
            out["table"] = table or groups["table"]
            out["name"] = groups.get("name")
            out["index"] = int(groups["num"]) if groups.get("num") else None
            break
    return out


@dataclass
class Validation:
    """What the spec reader says of a document: the parsed spec or the error, and warnings."""

    spec: Optional[GageSpec]
    errors: list = field(default_factory=list)
    warnings: list = field(default_factory=list)

    def to_dict(self) -> dict:
        return {"valid": self.spec is not None, "errors": self.errors, "warnings": self.warnings}


def validate(doc: Any, source: str) -> Validation:
    """Read ``doc`` with the reader of ``gage check`` (:meth:`GageSpec.from_dict`) or, for a
    drawing, of ``gagekit inspect`` (:func:`gagekit.inspect.part_spec_from_dict`)."""
    from ..inspect import part_spec_from_dict

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", GageFileWarning)
        try:
            spec: Any = part_spec_from_dict(doc, source) if kind_of(doc) == "part" else GageSpec.from_dict(doc, source)
            errors: list = []
        except ConfigError as exc:
            spec, errors = None, [locate(str(exc), source)]
    warns = [locate(str(w.message), source) for w in caught if issubclass(w.category, GageFileWarning)]
    return Validation(spec, errors, warns)


def render(original_text: str, new_doc: dict, source: str) -> str:
    """The text of ``new_doc``: ``original_text`` itself when the document is unchanged,
    else the original file with the changes applied (tomlkit keeps the rest as it was)."""
    if not isinstance(new_doc, dict):
        raise ConfigError(f"{source}: the spec document must be a table")
    old = tomlkit.parse(original_text) if original_text.strip() else tomlkit.document()
    if old.unwrap() == new_doc and original_text:
        return original_text
    _merge_table(old, new_doc)
    text = tomlkit.dumps(old)
    if parse_text(text, source) != _without_empty_lists(new_doc):
        raise ConfigError(f"{source}: internal error: the written file would not read back as edited")
    return text


def _without_empty_lists(doc: dict) -> dict:
    return {k: v for k, v in doc.items() if not (isinstance(v, list) and not v)}


def _floaty(key: str, value: Any) -> Any:
    if key in FLOAT_KEYS:
        if isinstance(value, list):
            return [float(v) if isinstance(v, int) and not isinstance(v, bool) else v for v in value]
        if isinstance(value, int) and not isinstance(value, bool):
            return float(value)
    return value


def _new_table(values: dict) -> Table:
    t = tomlkit.table()
    for k, v in values.items():
        t.add(k, _item(k, v))
    return t


def _item(key: str, value: Any):
    if isinstance(value, dict) and key in INLINE_KEYS:
        t = tomlkit.inline_table()
        for k, v in value.items():
            t.append(k, _item(k, v))
        return t
    if isinstance(value, dict):
        return _new_table(value)
    if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
        aot = tomlkit.aot()
        for v in value:
            aot.append(_new_table(v))
        return aot
    return tomlkit.item(_floaty(key, value))


def _merge_table(old, new: dict) -> None:
    """Make the tomlkit container ``old`` hold ``new``, touching only what differs
    (values equal to the old ones, ``1`` and ``1.0`` alike, keep their old text)."""
    old_plain = old.unwrap()
    for key in [k for k in list(old.keys()) if k not in new or (isinstance(new[k], list) and not new[k]
                                                                   and isinstance(old[k], AoT))]:
        del old[key]
    order = sorted(new, key=lambda k: TOP_ORDER.index(k) if k in TOP_ORDER else len(TOP_ORDER))
    for key in order:
        value = new[key]
        if key not in old:
            if not (isinstance(value, list) and not value and key in ("region", "gage")):
                old.append(key, _item(key, value))
        elif old_plain[key] == value:
            continue
        elif isinstance(value, dict) and isinstance(old[key], (Table, InlineTable)):
            _merge_table(old[key], value)
        elif isinstance(old[key], AoT) and isinstance(value, list) and all(isinstance(v, dict) for v in value):
            _merge_aot(old, key, value)
        else:
            old[key] = _item(key, value)


def _merge_aot(parent, key: str, new: list) -> None:
    """Edit an array of tables in place: tables are matched by name; removed ones are
    deleted, new ones inserted where they stand in ``new``, the others merged. A
    reordering (or unnamed tables) rewrites the array whole."""
    aot = parent[key]
    old_names = [t.get("name") for t in aot]
    new_names = [t.get("name") for t in new]
    named = all(isinstance(n, str) for n in old_names + new_names)
    if not named or len(set(old_names)) != len(old_names) or len(set(new_names)) != len(new_names):
        if len(new) >= len(aot):  # unnamed tables ([[tolerance]]): edited in place, new ones appended
            for i, values in enumerate(new):
                if i < len(aot):
                    _merge_table(aot[i], values)
                else:
                    if len(aot) and not aot[-1].as_string().endswith("\n\n"):
                        aot[-1].add(tomlkit.nl())
                    aot.append(_new_table(values))
            return
        parent[key] = _item(key, new)
        return
    for i in reversed(range(len(aot))):
        if old_names[i] not in new_names:
            del aot[i]
    kept = [n for n in old_names if n in new_names]
    if kept != [n for n in new_names if n in kept]:
        parent[key] = _item(key, new)
        return
    last_in_doc = list(parent.keys())[-1] == key if hasattr(parent, "keys") else True
    for i, values in enumerate(new):
        if i < len(aot) and aot[i].get("name") == values["name"]:
            _merge_table(aot[i], values)
            continue
        tbl = _new_table(values)
        if i < len(aot) or not last_in_doc:
            tbl.add(tomlkit.nl())
        elif len(aot) and not aot[-1].as_string().endswith("\n\n"):
            aot[-1].add(tomlkit.nl())
        aot.insert(i, tbl)
