"""The one validation engine of gagekit's TOML files.

Every file type (gage file, PART.toml, machine file, regions file, observer zones) is one
declarative schema: pydantic v2 models derived from :class:`Table` (unknown keys refused,
no coercion: a string is not a number, ``true`` is not 1, no inf or NaN). A reader calls
:func:`validate` once on the parsed document, then makes the cross-field checks a schema
cannot express (a datum letter naming a feature, a gage naming a region...) in one place.

**Why pydantic v2 and not msgspec.** Speed does not decide: both validate a document of a
few kB far faster than it is parsed (the schema pass over the bundled bracket drawing takes
about a tenth of the time tomllib takes to parse it, and nothing next to reading a scan). The
error does: pydantic reports every error as data (``loc``, ``type``, ``input``, ``ctx``), so
one renderer (:class:`Style`) writes each file type's own one-line message naming the file,
the table and the key, as the hand-written readers did; msgspec raises one formatted string
(``Expected `float`, got `str` - at `$.feature[0].band```) that would have to be parsed back,
and stops at the first error. pydantic also writes the JSON Schema (draft 2020-12,
``additionalProperties: false`` from ``extra="forbid"``, titles and descriptions from the
fields' docstrings), so the schema editors see is generated from the models the readers
validate with and cannot drift. It is a core dependency (recent Typer releases need it too).

A :class:`Style` maps a pydantic error to a message: it splits the error's location into
the table (``[[feature]] #3 ('top')``, ``[motion]``, ``joints.B``...) and the key, and
phrases the problem the way that file type always has (``'shape' = 'torus' is unknown;
choose one of ...``, ``max_shift must be at least 0.0, got -1.0``, ``joints.B.type must be
"prismatic" or "rotary", got 'linear'``).
"""

from __future__ import annotations

import json
import typing
from typing import Any, Callable, Mapping, Optional, Sequence, TypeVar, Union

from pydantic import BaseModel, ConfigDict, ValidationError
from pydantic.json_schema import GenerateJsonSchema

from ..errors import ConfigError

__all__ = ["Table", "Style", "validate", "json_schema", "DRAFT"]

DRAFT = "https://json-schema.org/draft/2020-12/schema"

M = TypeVar("M", bound=BaseModel)


class Table(BaseModel):
    """A TOML table: every key declared, unknown keys refused, no coercion, finite numbers."""

    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False, frozen=True,
                              use_attribute_docstrings=True, populate_by_name=True)


# -- walking a location through the document and the models ---------------------------------

_MISSING = object()


def _child(value: Any, key: Any) -> Any:
    if isinstance(key, int) and isinstance(value, list) and 0 <= key < len(value):
        return value[key]
    if isinstance(key, str) and isinstance(value, Mapping) and key in value:
        return value[key]
    return _MISSING


def doc_path(doc: Any, loc: Sequence[Any], keep_last: bool = False) -> tuple:
    """The part of a pydantic location that indexes the document: union member tags
    (``'str'``, ``'list[...]'``, model names) dropped; with ``keep_last`` the last element is
    kept even where the document has no such key (a missing key)."""
    out: list = []
    value = doc
    for n, key in enumerate(loc):
        nxt = _child(value, key)
        if nxt is _MISSING:
            if keep_last and n == len(loc) - 1:
                out.append(key)
            continue
        out.append(key)
        value = nxt
    return tuple(out)


def doc_value(doc: Any, path: Sequence[Any]) -> Any:
    value = doc
    for key in path:
        value = _child(value, key)
        if value is _MISSING:
            return None
    return value


def _members(tp: Any) -> list:
    """The alternatives of a type: Annotated and Optional/Union unwrapped."""
    origin = typing.get_origin(tp)
    if origin is typing.Annotated:
        return _members(typing.get_args(tp)[0])
    if origin is Union or type(tp).__name__ == "UnionType":
        return [m for a in typing.get_args(tp) for m in _members(a)]
    return [tp]


def table_keys(model: type, path: Sequence[Any]) -> Optional[list]:
    """The keys the schema allows in the table at ``path`` (aliases), or None."""
    types = [model]
    for key in path:
        nxt = []
        for tp in (m for t in types for m in _members(t)):
            origin = typing.get_origin(tp)
            if isinstance(tp, type) and issubclass(tp, BaseModel) and isinstance(key, str):
                for name, f in tp.model_fields.items():
                    if (f.alias or name) == key:
                        nxt.append(f.annotation)
            elif origin in (list, tuple) and isinstance(key, int):
                nxt.append(typing.get_args(tp)[0])
            elif origin is dict and isinstance(key, str):
                nxt.append(typing.get_args(tp)[1])
        types = nxt
    for tp in (m for t in types for m in _members(t)):
        if isinstance(tp, type) and issubclass(tp, BaseModel):
            return sorted(f.alias or n for n, f in tp.model_fields.items())
    return None


# -- the messages ----------------------------------------------------------------------------


def _quoted_choices(expected: str) -> list[str]:
    """``"'a', 'b' or 'c'"`` (pydantic's literal_error context) as ``['a', 'b', 'c']``."""
    parts = expected.replace(" or ", ", ").split(", ")
    return [p.strip().strip("'\"") for p in parts]


class Style:
    """How one file type names its tables and phrases its problems.

    ``tables`` lists the locations of tables (tuples of keys; ``int`` stands for any index of
    an array of tables, ``str`` for any name of a named table): a location is split into the
    innermost table and the key inside it. ``phrases`` says what a key must be (``"three
    finite numbers"``) where the generic words would be vague.
    """

    tables: tuple = ((),)
    phrases: Mapping[str, str] = {}

    def __init__(self, source: str, doc: Any, model: type):
        self.source = source
        self.doc = doc
        self.model = model

    # locating
    def split(self, path: tuple) -> tuple[tuple, tuple]:
        best: tuple = ()
        for pattern in self.tables:
            n = len(pattern)
            if n <= len(path) and n >= len(best) and all(
                    (p is int and isinstance(k, int)) or (p is str and isinstance(k, str)) or p == k
                    for p, k in zip(pattern, path)):
                best = path[:n]
        return best, path[len(best):]

    def label(self, table: tuple) -> str:
        """The table's name as the messages write it (with the file name)."""
        return self.source if not table else f"{self.source}: [{'.'.join(map(str, table))}]"

    def subject(self, table: tuple, key: tuple) -> str:
        return f"{self.label(table)}: '{'.'.join(str(k) for k in key if not isinstance(k, int))}'"

    # phrasing
    def unknown(self, table: tuple, inline: tuple, extra: list, allowed: list) -> str:
        where = self.label(table) + "".join(f", {k}" for k in inline)
        return f"{where}: unknown key(s) {', '.join(map(repr, extra))}; allowed: {', '.join(allowed)}"

    def missing(self, table: tuple, key: tuple) -> str:
        return f"{self.subject(table, key)} is missing"

    def choice(self, subject: str, value: Any, choices: list[str]) -> str:
        return f"{subject} = {value!r} is unknown; choose one of {', '.join(choices)}"

    def must(self, subject: str, phrase: str, value: Any) -> str:
        return f"{subject} must be {phrase}, got {value!r}"

    def bound(self, subject: str, name: str, kind: str, limit: Any, value: Any) -> str:
        words = {"greater_than": "greater than", "greater_than_equal": "at least", "less_than": "less than",
                 "less_than_equal": "at most"}[kind]
        if kind == "greater_than" and limit == 0:
            return f"{subject} must be positive, got {value!r}"
        return f"{subject} must be {words} {limit}, got {value!r}"

    def not_table(self, path: tuple, value: Any) -> str:
        """A table (or an array of tables) given as something else."""
        if path and self._is_array_of_tables(path):
            return f"{self.source}: {path[-1]} must be given as [[{path[-1]}]] tables, got {value!r}"
        table, key = self.split(path)
        if not key:
            return f"{self.label(table)} must be a table"
        return self.must(self.subject(table, key), "a table", value)

    def _is_array_of_tables(self, path: tuple) -> bool:
        probe = tuple(path) + (0,)
        return self.split(probe)[0] == probe

    def generic(self, kind: str) -> str:
        return {"float_type": "a number", "int_type": "an integer", "string_type": "a string",
                "bool_type": "true or false", "list_type": "a list", "finite_number": "a finite number",
                "too_short": "longer", "too_long": "shorter", "string_too_short": "a non-empty string"}.get(kind, "valid")

    # the one entry
    def message(self, err: Mapping[str, Any]) -> str:
        kind = err["type"]
        if kind == "extra_forbidden":
            path = doc_path(self.doc, err["loc"])
            parent, extra_key = path[:-1], path[-1]
            table, inline = self.split(parent)
            extras = sorted(k for k in (doc_value(self.doc, parent) or {}) if k == extra_key or self._is_extra(parent, k))
            return self.unknown(table, inline, extras, table_keys(self.model, parent) or [])
        if kind == "missing":
            path = doc_path(self.doc, err["loc"], keep_last=True)
            table, key = self.split(path[:-1])  # the table holding the missing key (or table)
            return self.missing(table, key + path[-1:])
        path = doc_path(self.doc, err["loc"])
        while path and isinstance(path[-1], int) and self.split(path)[0] != path:
            path = path[:-1]  # an item of a list: the key names the list
        value = doc_value(self.doc, path)
        table, key = self.split(path)
        if self._is_array_of_tables(path):  # [[feature]] tables: none, or not an array of tables
            return self.missing(table, key) if kind == "too_short" else self.not_table(path, value)
        if kind in ("model_type", "dict_type", "model_attributes_type") or (not key and kind != "literal_error"):
            return self.not_table(path, value)
        subject = self.subject(table, key)
        name = next((k for k in reversed(key) if isinstance(k, str)), "")
        if kind == "literal_error" and name not in self.phrases:
            return self.choice(subject, err.get("input", value), _quoted_choices(err.get("ctx", {}).get("expected", "")))
        if kind in _BOUNDS:
            ctx = err.get("ctx", {})
            return self.bound(subject, name, kind, next(iter(ctx.values())) if ctx else "?", value)
        return self.must(subject, self.phrase(kind, name), value)

    def phrase(self, kind: str, name: str) -> str:
        """What the key ``name`` must be, after an error of type ``kind``."""
        if kind in _TYPE_KINDS and name in self.phrases:
            return self.phrases[name]
        return self.generic(kind)

    def _is_extra(self, parent: tuple, key: str) -> bool:
        allowed = table_keys(self.model, parent)
        return allowed is not None and key not in allowed


_BOUNDS = ("greater_than", "greater_than_equal", "less_than", "less_than_equal")
_TYPE_KINDS = ("float_type", "int_type", "string_type", "bool_type", "list_type", "too_short", "too_long",
               "literal_error", "string_too_short")


def _order(doc: Any) -> Callable[[Mapping[str, Any]], tuple]:
    """An unknown key first (a misspelt key also makes the right one missing), then the error
    deepest in the document (of a key that may be a string or a table, the table's own error),
    then in the order of the schema."""
    def key(err: Mapping[str, Any]) -> tuple:
        depth = len(doc_path(doc, err["loc"], keep_last=err["type"] == "missing"))
        return (err["type"] != "extra_forbidden", -depth)
    return key


def validate(model: type[M], doc: Any, source: str, style: Callable[..., Style] = Style) -> M:
    """``doc`` validated by ``model``: the model, or ConfigError with one line naming the file,
    the table and the key (worded by ``style``)."""
    if not isinstance(doc, Mapping):
        raise ConfigError(f"{source}: expected a table at the top level")
    try:
        return model.model_validate(doc)
    except ValidationError as exc:
        errors = sorted(exc.errors(include_url=False), key=_order(doc))
        try:
            message = style(source, doc, model).message(errors[0])
        except Exception:  # pragma: no cover - a wording this style lacks: still one line, file and key
            loc = ".".join(str(k) for k in doc_path(doc, errors[0]["loc"], keep_last=True))
            message = f"{source}: {loc or 'top level'}: {errors[0]['msg']}"
        raise ConfigError(message) from None


class _Generator(GenerateJsonSchema):
    def generate(self, schema, mode="validation"):  # type: ignore[no-untyped-def]
        out = super().generate(schema, mode=mode)
        return {"$schema": DRAFT, **out}


def json_schema(model: type[BaseModel], schema_id: str) -> dict:
    """The JSON Schema (draft 2020-12) of a file type, generated from its models."""
    out = model.model_json_schema(schema_generator=_Generator, mode="validation")
    out = {"$schema": out.pop("$schema"), "$id": schema_id, **out}
    return json.loads(json.dumps(out).replace("``", "`"))  # docstrings' reST literals, as Markdown
