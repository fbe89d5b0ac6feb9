"""One declarative schema per TOML file type (issue 23, item 6): the JSON Schemas `gagekit schema`
prints accept every bundled file, as the readers do, and both refuse unknown keys; random valid
documents generated from the models survive the schema, TOML and the models unchanged."""

from __future__ import annotations

import copy
import functools
import json
import re
import subprocess
import sys
import tomllib
import typing
from pathlib import Path

import jsonschema
import pytest
import tomli_w
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pydantic import BaseModel

import gagekit
from gagekit.cloud import load_regions
from gagekit.errors import ConfigError
from gagekit.gage.spec import parse_gage_spec
from gagekit.inspect import part_spec_from_dict
from gagekit.machine.observer import ObserverSpace, read_exclusions, read_zones
from gagekit.schema import SCHEMA_KINDS, json_schema, validate_document
from gagekit.schema.exclusions import ExclusionsFile
from gagekit.schema.gages import GageFile, RegionsFile
from gagekit.schema.machine import MachineFile
from gagekit.schema.measurement import MeasurementTable
from gagekit.schema.part import PartFile
from gagekit.schema.zones import Interval, ZonesFile
from gagekit.uncertainty.model import MODEL_KEYS

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(gagekit.__file__).parent / "data"
MACHINE = gagekit.machine.example_machine_path()
ZONES = """
[[zone]]
count = 20
X = [-1250.0, 0.0]

[[zone]]
count = 20
X = [0.0, 1250.0]
Y = [350.0, 1400.0]
"""
EXCLUSIONS = """
tolerance = 0.02
commands = [[0.0, -1000.0, 1000.0, 400.0, -500.0]]

[[box]]
X = [-1250.0, -1000.0]
"Z+W" = [300.0, 600.0]
"""
MODELS = {"gages": GageFile, "part": PartFile, "machine": MachineFile, "regions": RegionsFile, "zones": ZonesFile,
          "exclusions": ExclusionsFile}


def _kind(doc: dict) -> str:
    return "part" if "feature" in doc else "gages"


def _validator(kind: str) -> jsonschema.Draft202012Validator:
    return jsonschema.Draft202012Validator(json_schema(kind))


def _bundled() -> list[tuple[str, Path]]:
    drawings = [*sorted(DATA.glob("*.toml")), *sorted((ROOT / "tests" / "golden").glob("*.toml"))]
    files = [(_kind(tomllib.loads(p.read_text())), p) for p in drawings]
    return files + [("machine", MACHINE)]


@functools.lru_cache(maxsize=1)
def _space() -> ObserverSpace:
    return ObserverSpace.of(gagekit.load_machine(MACHINE))


def _read(kind: str, path: Path, text: str = None):
    """The reader of each file type on the file at ``path`` (``text`` written there first)."""
    if text is not None:
        path.write_text(text)
    doc = tomllib.loads(path.read_text())
    if kind == "gages":
        return parse_gage_spec(doc, str(path))
    if kind == "part":
        return part_spec_from_dict(doc, str(path))
    if kind == "machine":
        return gagekit.parse_machine(path.read_text(), str(path))
    if kind == "regions":
        return load_regions(path)
    if kind == "exclusions":
        return read_exclusions(path, _space())
    return read_zones(path, _space())


@pytest.mark.parametrize("kind", SCHEMA_KINDS)
def test_the_schemas_are_draft_2020_12_and_closed(kind):
    schema = json_schema(kind)
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    jsonschema.Draft202012Validator.check_schema(schema)
    opened = []

    def walk(node, where):
        if isinstance(node, dict):
            if node.get("type") == "object" and node.get("additionalProperties") is not False and node is not schema:
                # named tables ([joints.X], [datums] A = ...) and zone variables are maps of one schema
                if not isinstance(node.get("additionalProperties"), dict):
                    opened.append(where)
            for k, v in node.items():
                walk(v, f"{where}/{k}")
        elif isinstance(node, list):
            for k, v in enumerate(node):
                walk(v, f"{where}/{k}")

    walk(schema, "#")
    assert schema["additionalProperties"] is False and not opened
    # every property documented (from the fields' docstrings)
    props = [p for d in [schema, *schema.get("$defs", {}).values()] for p in d.get("properties", {}).values()]
    assert props and all(p.get("description") for p in props)


@pytest.mark.parametrize("kind, path", _bundled(), ids=lambda v: getattr(v, "name", v))
def test_every_bundled_file_validates_both_ways(kind, path):
    doc = tomllib.loads(path.read_text())
    assert not list(_validator(kind).iter_errors(doc))
    _read(kind, path)
    if kind == "gages":  # a gage file is a regions file too (`cloud regions`)
        assert not list(_validator("regions").iter_errors(doc))
        assert load_regions(path)


def test_the_zones_example_validates_both_ways(tmp_path):
    assert not list(_validator("zones").iter_errors(tomllib.loads(ZONES)))
    assert len(_read("zones", tmp_path / "z.toml", ZONES)) == 2


def test_the_exclusions_example_validates_both_ways(tmp_path):
    assert not list(_validator("exclusions").iter_errors(tomllib.loads(EXCLUSIONS)))
    ex = _read("exclusions", tmp_path / "e.toml", EXCLUSIONS)
    assert ex.tolerance == 0.02 and ex.commands.shape == (1, 5) and ex.boxes == ({"X": (-1250.0, -1000.0), "Z+W": (300.0, 600.0)},)


@pytest.mark.parametrize("text, message", [
    ("tolerence = 0.1\ncommands = [[0, 0, 0, 0, 0]]\n", "e.toml: unknown key(s) 'tolerence'; allowed: box, commands, description, tolerance"),
    ("tolerance = 0.7\ncommands = [[0, 0, 0, 0, 0]]\n", "e.toml: 'tolerance' must be a fraction of the joint ranges in [0, 0.5), got 0.7"),
    ("commands = [[0, 0]]\n", "e.toml: commands must be a list of [B, X, Z, Y, W] rows"),
    ("commands = [['a', 0, 0, 0, 0]]\n", "e.toml: 'commands' must be a list of rows of numbers, got [['a', 0, 0, 0, 0]]"),
    ("commands = [[nan, 0, 0, 0, 0]]\n", "e.toml: 'commands' must be a list of rows of numbers, got [[nan, 0, 0, 0, 0]]"),
    ("[[box]]\nX = [0]\n", "e.toml: box 1: 'X' must be [lower, upper], got [0]"),
    ("[[box]]\nX = [2, 1]\n", "e.toml: box 1: 'X' = [2, 1] is reversed: give [lower, upper]"),
    ("[[box]]\nQ = [0, 1]\n", "e.toml: box 1: unknown variable 'Q' (use B, W, X, Y, Z, Z+W)"),
    ("box = 3\n", "e.toml: box must be given as [[box]] tables, got 3"),
    ("[[box]]\n", "e.toml: box 1 is empty"),
    ("description = 'nothing'\n", "e.toml: no [[box]] tables and no commands to exclude"),
])
def test_exclusions_mistakes_are_one_line_naming_file_table_and_key(tmp_path, monkeypatch, text, message):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ConfigError) as err:
        read_exclusions(Path("e.toml"), _space()) if Path("e.toml").write_text(text) else None
    assert str(err.value) == message


def _doc_fragments() -> list[tuple[str, dict]]:
    """The TOML examples of README.md and docs/*.md: (file, document)."""
    out = []
    for md in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        for block in re.findall(r"```toml\n(.*?)```", md.read_text(), flags=re.S):
            out.append((md.name, tomllib.loads(block)))
    return out


def _table_model(tp) -> type[BaseModel]:
    """The model of a table (or of the items of an array of tables) in a field's type."""
    for t in typing.get_args(tp) or (tp,):
        inner = typing.get_args(t)
        if typing.get_origin(t) is typing.Annotated or typing.get_origin(t) is list:
            return _table_model(inner[0])
        if isinstance(t, type) and issubclass(t, BaseModel):
            return t
    raise AssertionError(f"no table in {tp!r}")


@pytest.mark.parametrize("name, doc", _doc_fragments(), ids=lambda v: v if isinstance(v, str) else "")
def test_the_docs_examples_validate(name, doc):
    """The docs show single tables of a drawing ([[tolerance]], [measurement]): each table
    validates against its definition in the part schema, and through the reader's model."""
    schema = json_schema("part")
    for key, value in doc.items():
        sub = {**schema["properties"][key], "$defs": schema["$defs"]}
        assert not list(jsonschema.Draft202012Validator(sub).iter_errors(value)), (name, key)
        model = _table_model(PartFile.model_fields[key].annotation)  # a KeyError: not a table of a drawing
        for item in value if isinstance(value, list) else [value]:
            model.model_validate(item)
    assert doc


def test_a_drawing_with_a_docs_callout_reads(tmp_path):
    """The sizes example of docs/inspection.md in a whole drawing, through the reader."""
    frags = [d for n, d in _doc_fragments() if n == "inspection.md"]
    base = tomllib.loads((DATA / "bracket_sizes.toml").read_text())
    bore = next(f["name"] for f in base["feature"] if f["shape"] == "cylinder" and f.get("kind"))
    for frag in frags:
        doc = copy.deepcopy(base)
        for t in frag.get("tolerance", []):
            doc["tolerance"].append({**t, "feature": bore})
        part_spec_from_dict(doc, "PART.toml")


# -- unknown keys ----------------------------------------------------------------------------

UNKNOWN = [  # (kind, path of the table inside the file, words the reader's message holds)
    ("gages", [], ["top level", "'colour'"]),
    ("gages", ["motion"], ["[motion]", "'colour'"]),
    ("gages", ["region", 0], ["region 'Z1'", "'colour'"]),
    ("gages", ["gage", 0], ["gage '", "'colour'"]),
    ("regions", ["region", 0], ["region 'Z1'", "'colour'"]),
    ("part", [], ["unknown key(s) 'colour'"]),
    ("part", ["feature", 0], ["[[feature]] #1", "'colour'"]),
    ("part", ["feature", 0, "region"], ["[[feature]] #1", ", region", "'colour'"]),
    ("part", ["tolerance", 0], ["[[tolerance]] #1", "'colour'"]),
    ("part", ["part"], ["[part]", "'colour'"]),
    ("machine", [], ["unknown top-level key 'colour'"]),
    ("machine", ["joints", "X"], ["joints.X: unknown key 'colour'"]),
    ("machine", ["shapes", "T1"], ["shapes.T1: unknown key 'colour'"]),
    ("machine", ["tool"], ["tool: unknown key 'colour'"]),
    ("zones", [], ["unknown key(s) 'colour'"]),
]


def _source(kind: str) -> tuple[Path, dict]:
    path = {"gages": DATA / "casting_ok.toml", "regions": DATA / "casting_ok.toml", "part": DATA / "bracket.toml",
            "machine": MACHINE}.get(kind)
    return path, tomllib.loads(path.read_text() if path else ZONES)


@pytest.mark.parametrize("kind, where, words", UNKNOWN, ids=lambda v: "/".join(map(str, v)) if isinstance(v, list) else v)
def test_unknown_keys_are_refused_by_the_schema_and_the_reader(kind, where, words, tmp_path):
    _, doc = _source(kind)
    table = doc
    for key in where:
        table = table[key]
    table["colour"] = "red"
    assert list(_validator(kind).iter_errors(doc)), "the JSON Schema accepts an unknown key"
    f = tmp_path / "f.toml"
    with pytest.raises(ConfigError) as exc:
        _read(kind, f, tomli_w.dumps(doc))
    msg = str(exc.value)
    assert msg.startswith(str(f)) and "\n" not in msg
    for w in words:
        assert w in msg, (w, msg)


def test_a_zone_variable_the_machine_lacks_is_refused(tmp_path):
    text = ZONES + '\n[[zone]]\ncount = 1\ncolour = "red"\n'
    assert list(_validator("zones").iter_errors(tomllib.loads(text)))
    with pytest.raises(ConfigError, match=r"zone 3: 'colour' must be \[lower, upper\]"):
        _read("zones", tmp_path / "z.toml", text)


# -- the messages: one line, the file, the table, the key ------------------------------------

BAD = [  # (kind, edit of the document, words)
    ("gages", lambda d: d["motion"].update(max_angle="big"), ["[motion] max_angle must be a number, got 'big'"]),
    ("gages", lambda d: d["gage"][0].update(weight=-1.0), ["gage '", "weight must be at least 0.0, got -1.0"]),
    ("gages", lambda d: d.update(angle_unit="grad"), ['angle_unit must be "rad" or "deg", got \'grad\'']),
    ("gages", lambda d: d["region"][0].update(center=[0, 0]), ["region 'Z1': center must be three numbers"]),
    ("gages", lambda d: d["region"][0].pop("size"), ["region 'Z1' has no 'size'"]),
    ("gages", lambda d: d.update(motion=3), ["[motion] must be a table"]),
    ("gages", lambda d: d.update(gage=[]), ["no gages"]),
    ("part", lambda d: d["feature"][0].update(sections=0), ["[[feature]] #1 ('", "'sections' must be a positive integer, got 0"]),
    ("part", lambda d: d["feature"][0].update(sections=20000), ["'sections' = 20000 is more than 10000"]),
    ("part", lambda d: d["feature"][0].update(outward=[0, 0, "up"]), ["'outward' must be three finite numbers"]),
    ("part", lambda d: d["tolerance"][0].update(tolerance=True), ["[[tolerance]] #1 (", "'tolerance' must be a finite number, got True"]),
    ("part", lambda d: d["part"].update(standard="din"), ["[part]: 'standard' = 'din' is unknown; choose one of iso, asme"]),
    ("part", lambda d: d["feature"][0]["region"].pop("center"), ["'region' has no 'center'"]),
    ("part", lambda d: d.update(tolerance=[]), ["no [[tolerance]] tables"]),
    ("part", lambda d: d["datums"].update(A=5), ["[datums] A: must name a [[feature]]"]),
    ("machine", lambda d: d["joints"]["B"].update(fourier_terms=65), ["joints.B.fourier_terms must be an integer from 1 to 64, got 65"]),
    ("machine", lambda d: d["joints"]["X"].update(range=[0]), ["joints.X.range must be two finite numbers [min, max]"]),
    ("machine", lambda d: d.pop("chain"), ['missing "chain"']),
    ("machine", lambda d: d["tool"].pop("offset"), ["missing [tool] offset"]),
    ("machine", lambda d: d.update(joints=[1]), ["[joints] must be tables such as [joints.NAME]"]),
    ("zones", lambda d: d["zone"][0].update(count=-1), ["zone 1: count must be a non-negative integer, got -1"]),
    ("zones", lambda d: d["zone"][1].pop("count"), ["zone 2 needs a count"]),
    ("zones", lambda d: d["zone"][0].update(X=[0.0]), ["zone 1: 'X' must be [lower, upper], got [0.0]"]),
]


@pytest.mark.parametrize("kind, edit, words", BAD, ids=[f"{k}-{n}" for n, (k, _, _) in enumerate(BAD)])
def test_each_mistake_is_one_line_naming_file_table_and_key(kind, edit, words, tmp_path):
    _, doc = _source(kind)
    edit(doc)
    assert list(_validator(kind).iter_errors(doc)), "the JSON Schema accepts it"
    f = tmp_path / "f.toml"
    with pytest.raises(ConfigError) as exc:
        _read(kind, f, tomli_w.dumps(doc))
    msg = str(exc.value)
    assert msg.startswith(f"{f}: ") and "\n" not in msg, msg
    for w in words:
        assert w in msg, (w, msg)


def test_the_measurement_table_is_the_measurement_models():
    assert set(MeasurementTable.model_fields) == set(MODEL_KEYS)
    doc = tomllib.loads((DATA / "bracket.toml").read_text())
    doc["measurement"] = {"sigma": 0.002, "origin": [0, 0, 800], "probing": 0.003}
    part_spec_from_dict(doc, "PART.toml")  # a drawing may hold its instrument's model
    assert not list(_validator("part").iter_errors(doc))


# -- the command -----------------------------------------------------------------------------


def test_gagekit_schema_prints_and_writes(tmp_path):
    run = [sys.executable, "-m", "gagekit", "schema"]
    out = subprocess.run([*run, "part"], capture_output=True, text=True, check=True).stdout
    assert json.loads(out) == json_schema("part")
    target = tmp_path / "machine.schema.json"
    subprocess.run([*run, "machine", "--out", str(target)], capture_output=True, text=True, check=True)
    assert json.loads(target.read_text()) == json_schema("machine")
    assert [p.name for p in tmp_path.iterdir()] == [target.name]  # no temporary file left
    bad = subprocess.run([*run, "gauges"], capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.startswith("gagekit: error: unknown file type 'gauges'")


def test_a_schema_comment_leaves_the_file_valid(tmp_path):
    """taplo / Even Better TOML read `#:schema FILE` as the file's schema; TOML reads a comment."""
    f = tmp_path / "PART.toml"
    f.write_text("#:schema ./part.schema.json\n" + (DATA / "bracket.toml").read_text())
    assert part_spec_from_dict(tomllib.loads(f.read_text()), str(f)).features


# -- random valid documents round-trip -------------------------------------------------------


def _bounds(meta) -> dict:
    out: dict = {}
    for m in [x for m in meta for x in (getattr(m, "metadata", None) or [m])]:
        for name in ("ge", "gt", "le", "lt", "min_length", "max_length"):
            if getattr(m, name, None) is not None:
                out[name] = getattr(m, name)
    return out


def _strategy(tp, meta=()) -> st.SearchStrategy:
    """Valid values of a field type of the schema models."""
    origin = typing.get_origin(tp)
    if origin is typing.Annotated:
        base, *extra = typing.get_args(tp)
        return _strategy(base, (*meta, *extra))
    b = _bounds(meta)
    if origin is typing.Union:
        return st.one_of([_strategy(a, meta) for a in typing.get_args(tp) if a is not type(None)])
    if origin is typing.Literal:
        return st.sampled_from(typing.get_args(tp))
    if origin is list:
        lo, hi = b.get("min_length", 0), b.get("max_length", min(b.get("min_length", 0) + 3, 4))
        return st.lists(_strategy(typing.get_args(tp)[0]), min_size=lo, max_size=hi)
    if origin is dict:
        return st.dictionaries(st.from_regex(r"[A-Z][a-z0-9_]{0,5}", fullmatch=True), _strategy(typing.get_args(tp)[1]), max_size=3)
    if tp is bool:
        return st.booleans()
    if tp is int:
        return st.integers(b.get("ge", b.get("gt", -1000 - 1) + 1), b.get("le", 1000))
    if tp is float:
        lo, hi = b.get("ge", b.get("gt", -1e6)), b.get("le", b.get("lt", 1e6))
        return st.floats(lo, hi, exclude_min="gt" in b, exclude_max="lt" in b, allow_nan=False)
    if tp is str:
        return st.text(st.characters(codec="utf-8", exclude_categories=("Cs", "Cc")), min_size=b.get("min_length", 0), max_size=8)
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return _model(tp)
    raise AssertionError(f"no strategy for {tp!r}")


def _model(model: type[BaseModel]) -> st.SearchStrategy:
    required = {n: _strategy(f.annotation, f.metadata) for n, f in model.model_fields.items() if f.is_required()}
    optional = {n: _strategy(f.annotation, f.metadata) for n, f in model.model_fields.items() if not f.is_required()}
    base = st.fixed_dictionaries(required, optional=optional)
    if model.model_config.get("extra") == "allow":  # zone variables
        variables = st.dictionaries(st.from_regex(r"[A-Z]{1,3}", fullmatch=True), _strategy(Interval), max_size=2)
        return st.tuples(base, variables).map(lambda t: {**t[1], **t[0]})
    return base


def _drop_none(v):
    if isinstance(v, dict):
        return {k: _drop_none(x) for k, x in v.items() if x is not None}
    if isinstance(v, list):
        return [_drop_none(x) for x in v]
    return v


@pytest.mark.parametrize("kind", SCHEMA_KINDS)
def test_random_valid_documents_round_trip(kind):
    model = MODELS[kind]
    validator = _validator(kind)

    @settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
    @given(_model(model).map(_drop_none))
    def check(doc):
        assert not list(validator.iter_errors(doc)), doc  # the JSON Schema agrees with the models
        text = tomli_w.dumps(doc)
        again = tomllib.loads(text)
        m = validate_document(kind, again, "doc.toml")
        dumped = _drop_none(m.model_dump(mode="json", exclude_unset=True))
        assert dumped == json.loads(json.dumps(doc)), (doc, dumped)
        assert validate_document(kind, dumped, "doc.toml") == m

    check()
