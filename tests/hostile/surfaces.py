"""Hostile cases of the surfaces added since issue 12 (issue 22, "Done when"): GD&T
inspection, controller-table export, NC-program compensation, batches, SPC, the results
database commands and the studio's HTTP API. Shared by ``tests/hostile/test_surfaces.py``
(a sample) and ``benches/hostile_census.py`` (all of them).

Each command case is ``(group, label, argv, mode)``: ``mode`` "inproc" runs through
``gagekit.cli.main`` in the calling process, "sub" as a child process (batches start
workers; a FIFO must not be opened). A case's files are written when the case is yielded,
so consume them one at a time. Studio cases are ``(group, label, method, path, body)``,
sent to one real server."""

from __future__ import annotations

import copy
import json
import os
import sqlite3
from pathlib import Path
from typing import Any, Iterator

from .mutants import HOSTILE_VALUES, _paths, _set, damaged, mutants

#: what a client may put anywhere in a JSON document: the types of issue 22's studio cases
HOSTILE_JSON: list[Any] = [v for v in HOSTILE_VALUES if not (isinstance(v, float) and v != v)] + [
    None, ["x", None, {}], 2 ** 70, -(2 ** 63), 10 ** 9, "\ud800", [1e308, 1e308, 1e308], [0, 0], [0, 0, 0, 0],
    {"center": [0, 0, 0]}, "../../etc/passwd", 0.5,
]

NC_PROGRAM = b"""%
O1000 (TEST PART)
N10 G21 G90 G17
N20 G0 B0 X-1000 Y400 Z1000 W-500 S1200 M3
N30 G1 X-900 F500 ; first cut
N40 Y450
N50 G91 X10 Z5
N60 G90 G1 X1000 (long move)
N70 G2 X1010 Y460 I5 J5
N80 M5
N90 M30
%
"""

#: words put in place of each word of the program, and whole lines inserted
NC_WORDS = [b"X5000", b"X-1e308", b"X1e400", b"Xnan", b"X", b"X1.2.3", b"Q7", b"G91", b"G2", b"G3 R0", b"G81",
            b"#1=5", b"B720", b"F0", b"F-5", b"G1 X1e9", b"(", b"N", b"G0 X", b"\x00", b"\xff\xfe", b"X" + b"9" * 400]
NC_LINES = [b"G91 G1 X100000", b"G91" + b" G1 X1000" * 200, b"G2 X0 Y0 I0 J0", b"G3 X1 Y1 R-1", b"M98 P1000",
            b"G65 P9000", b"IF [#1 GT 0] GOTO 10", b"G1 X1 Y1 Z1 B1 W1 A1", b"%", b";" * 10000, b"G0 B1e300"]


def nc_mutants(program: bytes = NC_PROGRAM) -> Iterator[tuple[str, bytes]]:
    """(label, program) with one word replaced, one line inserted, or whole-file damage."""
    lines = program.split(b"\n")
    for i, line in enumerate(lines):
        words = line.split(b" ")
        for j, _ in enumerate(words[:4]):
            for w in NC_WORDS:
                new = words[:j] + [w] + words[j + 1:]
                yield f"line {i + 1} word {j + 1}={w[:20]!r}", b"\n".join(lines[:i] + [b" ".join(new)] + lines[i + 1:])
    for k, extra in enumerate(NC_LINES):
        yield f"insert {extra[:20]!r}", b"\n".join(lines[:6] + [extra] + lines[6:])
    yield "empty", b""
    yield "binary", bytes(range(256)) * 8
    yield "utf-16", program.decode().encode("utf-16")
    yield "no newline", program.replace(b"\n", b" ")
    yield "CR only", program.replace(b"\n", b"\r")
    yield "one long line", b"G1 " + b"X1 " * 200000


def json_mutants(doc: Any) -> Iterator[tuple[str, Any]]:
    """(label, document) for each single-key mutation of ``doc`` and each deletion."""
    for path in _paths(doc):
        label = ".".join(map(str, path))
        yield f"del {label}", _set(doc, path, None, delete=True)
        for v in HOSTILE_JSON:
            yield f"{label}={v!r}"[:120], _set(doc, path, copy.deepcopy(v))


def _write(p: Path, data: bytes) -> Path:
    p.write_bytes(data)
    return p


def _fifo(p: Path) -> Path:
    if not p.exists():
        os.mkfifo(p)
    return p


def _databases(tmp: Path, good: str) -> dict:
    """Database URLs that are not usable gagekit results databases, and one that is."""
    d = tmp / "dbs"
    d.mkdir(exist_ok=True)
    foreign = d / "foreign.db"
    if not foreign.exists():
        with sqlite3.connect(foreign) as c:
            c.execute("CREATE TABLE invoices (id INTEGER)")
    newer = d / "newer.db"
    if not newer.exists():
        with sqlite3.connect(newer) as c:
            c.execute("CREATE TABLE alembic_version (version_num VARCHAR(32) NOT NULL)")
            c.execute("INSERT INTO alembic_version VALUES ('9999')")
    (d / "folder.db").mkdir(exist_ok=True)
    return {
        "good": good,
        "garbage file": f"sqlite:///{_write(d / 'garbage.db', b'not a database' * 500)}",
        "empty file": f"sqlite:///{_write(d / 'empty.db', b'')}",
        "foreign tables": f"sqlite:///{foreign}",
        "newer schema": f"sqlite:///{newer}",
        "a folder": f"sqlite:///{d / 'folder.db'}",
        "missing folder": f"sqlite:///{d / 'nowhere' / 'x.db'}",
        "missing file": f"sqlite:///{d / 'missing.db'}",
        "FIFO": f"sqlite:///{_fifo(d / 'fifo.db')}",
        "in memory": "sqlite://",
        "bad URL": "mysql://user@host/db",
        "not a URL": "postgresql://[::1",
        "unreachable server": "postgresql://nobody@127.0.0.1:9/none?connect_timeout=2",
        "NUL": "sqlite:///x\x00y.db",
    }


def command_cases(tmp: Path, machine: Path, cal: Path, good_db: str, quick: bool) -> Iterator[tuple[str, str, list, str]]:
    """Every command case of the new surfaces (see the module doc)."""
    import numpy as np

    from gagekit.cloud import read_points, write_points
    from gagekit.samples import data_path

    step = 5 if quick else 1
    bracket_toml = data_path("bracket.toml")
    bracket = tmp / "bracket.npy"
    if not bracket.exists():
        write_points(bracket, read_points(data_path("bracket.ply"))[::3])
    # inspect: the drawing damaged and mutated key by key; degenerate clouds
    spec = tmp / "part.toml"
    cases = list(damaged(bracket_toml)) + list(mutants(bracket_toml))[:: 12 * step]
    for label, data in cases:
        _write(spec, data)
        yield "inspect: drawing", label, ["inspect", bracket, spec, "--json"], "inproc"
    rng = np.random.default_rng(22)
    shapes = {"one point": np.zeros((1, 3)), "identical": np.ones((50, 3)), "collinear": np.outer(np.linspace(0, 9, 60), [1, 2, 3]),
              "tiny": rng.random((200, 3)) * 1e-300, "huge": rng.random((200, 3)) * 1e200,
              "far clutter": np.vstack([read_points(bracket), rng.random((1000, 3)) * 1e3 + 5e4])}
    for name, pts in shapes.items():
        f = tmp / f"deg-{name.replace(' ', '_')}.npy"
        np.save(f, pts)
        yield "inspect: scan", name, ["inspect", f, bracket_toml, "--json"], "inproc"
    for label, p in (("missing", tmp / "none.toml"), ("folder", tmp), ("FIFO", _fifo(tmp / "fifo.toml"))):
        yield "inspect: drawing", label, ["inspect", bracket, p, "--json"], "sub"

    # export: the calibration file mutated; the options at their edges
    cal_doc = json.loads(cal.read_text())
    calf = tmp / "cal-mut.json"
    out = tmp / "table.csv"
    for label, data in list(damaged(cal))[::step]:
        _write(calf, data)
        yield "export", f"calibration {label}", ["machine", "export", machine, calf, "--format", "grid-csv", "--out", out,
                                                  "--step", "200"], "inproc"
    for label, doc in list(json_mutants(cal_doc))[:: 4 * step]:
        calf.write_text(json.dumps(doc))
        yield "export", f"calibration {label}", ["machine", "export", machine, calf, "--format", "grid-csv", "--out", out,
                                                  "--step", "200"], "inproc"
    for fmt in ("grid-csv", "isg-csv", "fanuc-3d", "linuxcnc", "bogus", ""):
        for opts in ([], ["--step", "0"], ["--step", "-5"], ["--step", "nan"], ["--step", "1e-9"], ["--points", "1"],
                     ["--points", "10000000"], ["--axes", "Q"], ["--axes", "X,X"], ["--at", "B=nan"], ["--at", "=,"],
                     ["--limits", "X=5:-5"], ["--limits", "X=-1e300:1e300"], ["--increment", "0"], ["--seed", "-1"])[::step]:
            yield "export", f"{fmt} {' '.join(opts)}", ["machine", "export", machine, cal, "--format", fmt, "--out", out,
                                                         "--step", "200", *opts], "inproc"

    # compensate-nc: the program damaged word by word; the options at their edges
    nc, nc_out = tmp / "prog.nc", tmp / "prog-out.nc"
    for label, data in list(nc_mutants())[:: 3 * step]:
        _write(nc, data)
        yield "compensate-nc", label, ["machine", "compensate-nc", machine, cal, nc, "--out", nc_out,
                                       "--linearize-arcs", "0.01", "--json"], "inproc"
    _write(nc, NC_PROGRAM)
    for opts in (["--max-step", "1e-9"], ["--max-step", "0"], ["--max-step", "-1"], ["--max-step", "nan"],
                 ["--max-step", "1e300"], ["--linearize-arcs", "0"], ["--linearize-arcs", "-1"], ["--linearize-arcs", "inf"],
                 ["--linearize-arcs", "1e-12"], ["--decimals", "-1"], ["--decimals", "400"], ["--axes", "Q"],
                 ["--start", "B=1e308"], ["--start", "W"]):
        yield "compensate-nc", " ".join(opts), ["machine", "compensate-nc", machine, cal, nc, "--out", nc_out,
                                                "--linearize-arcs", "0.01", *opts, "--json"], "inproc"
    yield "compensate-nc", "FIFO program", ["machine", "compensate-nc", machine, cal, _fifo(tmp / "fifo.nc"), "--out",
                                            nc_out, "--json"], "sub"

    # batches: scan sets with every kind of bad file, bad options, bad databases
    scans = tmp / "scans"
    scans.mkdir(exist_ok=True)
    write_points(scans / "good.ply", read_points(data_path("casting_ok.ply"))[::4])
    _write(scans / "empty.ply", b"")
    _write(scans / "random.xyz", bytes(rng.integers(0, 256, 3000, dtype=np.uint8)))
    _write(scans / "nan.xyz", b"1 2 3\nnan 1 2\n")
    (scans / "folder.ply").mkdir(exist_ok=True)
    _fifo(scans / "pipe.xyz")
    casting_toml = data_path("casting_ok.toml")
    dbs = _databases(tmp, good_db)
    batch_db = f"sqlite:///{tmp / 'batch.db'}"
    every = str(scans / "*")
    yield "batch", "gage: every bad file", ["gage", "batch", casting_toml, every, "--db", batch_db, "--json", "-w", "1"], "sub"
    yield "batch", "gage: again (stored)", ["gage", "batch", casting_toml, every, "--db", batch_db, "--json", "-w", "1"], "sub"
    yield "batch", "form: every bad file", ["form", "batch", "plane", every, "--db", batch_db, "--json", "-w", "1"], "sub"
    yield "batch", "inspect: every bad file", ["inspect", "batch", bracket_toml, every, "--db", batch_db, "--json", "-w", "1"], "sub"
    for label, extra in (("no match", [str(tmp / "none*.ply")]), ("workers 0", [every, "-w", "0"]),
                         ("workers -1", [every, "-w", "-1"]), ("workers 10**9", [every, "-w", str(10 ** 9)]),
                         ("bad scheduler", [every, "--scheduler", "tcp://127.0.0.1:9"]),
                         ("scheduler garbage", [every, "--scheduler", "::::"])):
        yield "batch", f"gage: {label}", ["gage", "batch", casting_toml, *extra, "--db", batch_db, "--json"], "sub"
    yield "batch", "form: criterion bogus", ["form", "batch", "plane", every, "-c", "bogus", "--db", batch_db], "sub"
    yield "batch", "form: shape bogus", ["form", "batch", "torus", every, "--db", batch_db], "sub"
    for label, url in dbs.items():
        if label not in ("good", "NUL"):  # a NUL cannot be passed to a child process
            yield "batch", f"gage: db {label}", ["gage", "batch", casting_toml, str(scans / "good.ply"), "--db", url], "sub"

    # stats and db: every database, every option
    for label, url in dbs.items():
        yield "stats", f"db {label}", ["stats", "--db", url, "--json"], "sub" if "FIFO" in label else "inproc"
        yield "db", f"upgrade {label}", ["db", "upgrade", url], "sub" if "FIFO" in label else "inproc"
        yield "db", f"export {label}", ["db", "export", url, "--format", "csv", "--out", tmp / f"exp-{len(label)}"], \
            "sub" if "FIFO" in label else "inproc"
    for opts in (["--tolerance", "-1"], ["--tolerance", "0"], ["--tolerance", "nan"], ["--tolerance", "inf"],
                 ["--tolerance", "1e-300"], ["--resolution", "0"], ["--resolution", "-1e-9"], ["--resolution", "nan"],
                 ["--resolution", "5"], ["--spec", casting_toml], ["--spec", bracket_toml], ["--spec", tmp / "none.toml"],
                 ["--spec", _fifo(tmp / "fifo-spec.toml")], ["--spec", _write(tmp / "bad.toml", b"[[[")],
                 ["--report", tmp / "nowhere" / "r"], ["--report", casting_toml]):
        yield "stats", " ".join(map(str, opts))[-60:], ["stats", "--db", good_db, *opts, "--json"], "sub"
    for fmt in ("parquet", "csv", "xlsx", ""):
        yield "db", f"export --format {fmt!r}", ["db", "export", good_db, "--format", fmt, "--out", tmp / f"e-{fmt}"], "inproc"
    yield "db", "export --out a file", ["db", "export", good_db, "--format", "csv", "--out", casting_toml], "inproc"


def studio_cases(gage_doc: dict, part_doc: dict, quick: bool) -> Iterator[tuple[str, str, str, str, bytes]]:
    """(group, label, method, path, body) of hostile requests to a studio serving the
    casting and its gage file (in a folder with ``pipe.toml``, ``pipe.ply`` FIFOs and
    ``out.ply`` / ``outdir`` symlinks leading outside)."""
    step = 6 if quick else 2
    g = "studio HTTP: documents"
    for label, doc in list(json_mutants(gage_doc))[::step]:
        yield g, f"gage run {label}", "POST", "/api/run", json.dumps({"doc": doc, "groups": False}).encode()
    for label, doc in list(json_mutants(gage_doc))[1::step * 2]:
        yield g, f"gage regions {label}", "POST", "/api/regions", json.dumps({"doc": doc}).encode()
    for label, doc in list(json_mutants(part_doc))[::step * 3]:
        yield g, f"part run {label}", "POST", "/api/run", json.dumps({"doc": doc}).encode()
    region = {"center": [0, 0, 0], "size": [10, 10, 10], "rotation": [0, 0, 0]}
    for label, r in json_mutants(region):
        yield "studio HTTP: select", label, "POST", "/api/select", json.dumps({"region": r}).encode()
    g = "studio HTTP: bodies"
    deep = b"[" * 100_000 + b"]" * 100_000
    bodies = {"deep array": b'{"doc": ' + deep + b"}", "deep object": b'{"doc": ' + b'{"a":' * 50_000 + b"1" + b"}" * 50_001,
              "lone surrogate": b'{"path": "\\ud800.toml"}', "surrogate key": b'{"doc": {"\\udfff": 1}}',
              "not JSON": b"{{{", "array": b"[1, 2]", "string": b'"x"', "NaN": b'{"doc": NaN}',
              "huge number": b'{"doc": {"motion": {"max_shift": 1e999}}}', "huge integer": b'{"doc": {"x": ' + b"9" * 5000 + b"}}",
              "latin-1": '{"path": "caf\xe9.toml"}'.encode("latin-1"), "empty": b"", "BOM": b'\xef\xbb\xbf{"doc": {}}',
              "null doc": b'{"doc": null}', "groups string": b'{"doc": {}, "groups": "yes"}'}
    for path in ("/api/run", "/api/regions", "/api/select", "/api/save", "/api/spec", "/api/scan"):
        for label, body in bodies.items():
            yield g, f"{path} {label}", "POST", path, body
    g = "studio HTTP: paths"
    for path, key in (("/api/spec", "path"), ("/api/scan", "path"), ("/api/save", "path")):
        for name in ("pipe.toml", "pipe.ply", "out.ply", "outdir/secret.toml", "../x.toml", "/etc/passwd", "a\x00b.toml",
                     "x" * 5000 + ".toml", "\ud800.toml", "", 5, None, ["a"], ".", "sub/../../x.toml", "casting.ply",
                     "casting.toml", "new.toml"):
            body = {key: name}
            if path == "/api/save":
                body["doc"] = gage_doc
            try:
                data = json.dumps(body).encode()
            except (TypeError, ValueError):
                continue
            yield g, f"{path} {name!r}"[:80], "POST", path, data
    for method, path in (("GET", "/api/files"), ("GET", "/api/state"), ("GET", "/static/../app.py"), ("DELETE", "/api/run"),
                         ("GET", "/api/run"), ("POST", "/api/state"), ("GET", "/nowhere")):
        yield g, f"{method} {path}", method, path, None
