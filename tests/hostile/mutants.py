"""Generated malformed inputs: every spec type (TOML) mutated key by key, plus whole-file
damage (empty, binary, Latin-1, truncated, a folder, a FIFO, missing); and the CPU clock of
a child process for the interrupt cases. Shared by the tests and by
``benches/hostile_census.py``."""

from __future__ import annotations

import math
import os
import sys
from pathlib import Path
from typing import Any, Iterator

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

import tomli_w

#: values put in place of every scalar, list and table of a valid file
HOSTILE_VALUES: list[Any] = [
    5, -1, 0, 1e308, -1e308, float("nan"), float("inf"), "x", "", True, [], [1], ["a", "b"],
    [float("nan"), 1.0], [[1, 2], [3]], {}, {"k": 1}, 10**30,
]


def _paths(doc: Any, prefix: tuple = ()) -> Iterator[tuple]:
    """Every key path of a TOML document (tables, arrays of tables, values)."""
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield prefix + (k,)
            yield from _paths(v, prefix + (k,))
    elif isinstance(doc, list) and doc and all(isinstance(t, dict) for t in doc):
        for i, t in enumerate(doc[:2]):  # the first two tables of an array are enough
            yield from _paths(t, prefix + (i,))


def _set(doc: Any, path: tuple, value: Any, delete: bool = False) -> Any:
    import copy

    d = copy.deepcopy(doc)
    node = d
    for k in path[:-1]:
        node = node[k]
    if delete:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return d


def mutants(valid: Path) -> Iterator[tuple[str, bytes]]:
    """(label, file bytes) for each single-key mutation of ``valid`` and each deletion."""
    doc = tomllib.loads(valid.read_text(encoding="utf-8"))
    for path in _paths(doc):
        label = ".".join(map(str, path))
        yield f"del {label}", tomli_w.dumps(_set(doc, path, None, delete=True)).encode()
        for v in HOSTILE_VALUES:
            try:
                text = tomli_w.dumps(_set(doc, path, v))
            except (TypeError, ValueError):  # tomli_w cannot write it (a table in an array of scalars...)
                continue
            yield f"{label}={v!r}", text.encode()


def damaged(valid: Path) -> Iterator[tuple[str, bytes]]:
    """Whole-file damage of ``valid``."""
    raw = valid.read_bytes()
    yield "empty", b""
    yield "binary", bytes(range(256)) * 4
    yield "latin-1", raw.replace(b"#", "\xe9".encode("latin-1"), 3) + "\n# caf\xe9\n".encode("latin-1")
    yield "utf-16", raw.decode("utf-8").encode("utf-16")
    yield "bom", b"\xef\xbb\xbf" + raw
    yield "nul bytes", raw[: len(raw) // 2] + b"\x00\x00" + raw[len(raw) // 2:]
    for frac in (0.1, 0.33, 0.5, 0.77, 0.95):
        yield f"truncated {frac}", raw[: int(len(raw) * frac)]
    yield "not toml", b"[[[ this is = not toml"
    yield "duplicate key", raw + b"\n" + raw
    yield "deep nesting", b"a = " + b"[" * 5000 + b"]" * 5000
    yield "huge line", b"name = '" + b"x" * 2_000_000 + b"'\n"


def special_paths(folder: Path) -> Iterator[tuple[str, Path]]:
    """Paths that are not regular files: missing, a folder, a FIFO."""
    yield "missing", folder / "no-such-file.toml"
    d = folder / "a-folder.toml"
    d.mkdir(exist_ok=True)
    yield "folder", d
    fifo = folder / "fifo.toml"
    if not fifo.exists():
        os.mkfifo(fifo)
    yield "fifo", fifo


def is_finite_json(obj: Any) -> bool:
    """No NaN or infinity anywhere (a JSON null is an absent optional value, e.g. "out": null:
    the CLI refuses to print a non-finite number, so a null never stands for one)."""
    if isinstance(obj, float):
        return math.isfinite(obj)
    if isinstance(obj, dict):
        return all(is_finite_json(v) for v in obj.values())
    if isinstance(obj, list):
        return all(is_finite_json(v) for v in obj)
    return True


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
commands = [[0.0, 0.0, 1000.0, 400.0, -500.0]]

[[box]]
X = [-100.0, 100.0]
Y = [350.0, 600.0]
"""


def spec_commands(tmp: Path, machine: Path, gage_toml: Path, cloud: Path) -> dict:
    """Spec type -> (a valid file, the command that reads it with ``SPEC`` standing for the
    file): machine, gage, regions, zones and exclusions files."""
    (tmp / "zones.toml").write_text(ZONES)
    (tmp / "excl.toml").write_text(EXCLUSIONS)
    design = ["machine", "design", machine, "--points", 40, "--candidates", 300, "--starts", 1,
              "--out", tmp / "plan.csv", "--json"]
    return {
        "machine": (machine, ["machine", "check", "SPEC", "--commands", 200, "--json"]),
        "gage": (gage_toml, ["gage", "check", cloud, "SPEC", "--no-groups", "--json"]),
        "regions": (gage_toml, ["cloud", "regions", cloud, "SPEC", "--json"]),
        "zones": (tmp / "zones.toml", [*design, "--zones", "SPEC"]),
        "exclusions": (tmp / "excl.toml", [*design, "--exclude", "SPEC"]),
    }


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a running process, all its threads (Linux /proc); 0 once
    it has exited. The interrupt cases measure the answer to Ctrl-C in CPU time: on a
    loaded, shared machine wall time measures the scheduler rather than the program."""
    try:
        fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
