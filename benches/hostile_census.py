"""The hostile-input census of issue 12: run every generated bad input through the
``gagekit`` command and count the outcomes.

    python benches/hostile_census.py [--quick] [--only machine,gage,...] [--show N]

Categories (one row per group of cases, and a total):

* tries       cases run
* clean       exit 2 with exactly one stderr line ``gagekit: error: ...``, nothing on stdout
* ok          exit 0 with a finite, correct result (where the input is valid)
* tracebacks  a Python exception escaped (or any other exit status / stderr shape)
* panics      a Rust panic (``panicked`` on stderr, or an InternalError line)
* hangs       no answer within the time bound
* wrong       exit 0 with a non-finite value (NaN, null, inf) or a result that disagrees
              with the known answer of that case

Spec files and point files run in this process through ``gagekit.cli.main`` (thousands of
cases); paths that are not regular files, kills and interrupts run as subprocesses. The
cases are those of ``tests/hostile`` (shared generators in ``tests/hostile/mutants.py``),
plus the reader cases of ``tests/hostile`` written by the readers' owner when present.

The surfaces of issue 22 (``tests/hostile/surfaces.py``): ``inspect`` (drawings mutated key
by key, degenerate scans), ``machine export`` (calibrations mutated, options at their
edges), ``machine compensate-nc`` (programs mutated word by word), batches (every kind of
bad file, option and database), ``stats`` and ``db`` (every kind of database), and the
studio's HTTP API (one real server: documents mutated key by key, hostile bodies and
paths; a 4xx JSON error is clean, a 2xx finite JSON ok, a 5xx a traceback, no answer in
the time bound a hang; after them all Ctrl-C must stop the server).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.hostile.mutants import cpu_seconds, damaged, is_finite_json, mutants, spec_commands, special_paths  # noqa: E402

CATS = ("tries", "clean", "ok", "tracebacks", "panics", "hangs", "wrong")
TIME_LIMIT = 60.0


class _Timeout(Exception):
    pass


def _alarm(signum, frame):  # pragma: no cover - only on a hang
    raise _Timeout()


def classify(code, out: str, err: str, expect=None) -> tuple[str, str]:
    """(category, detail) of one finished run."""
    lines = [ln for ln in err.splitlines() if ln.strip()]
    if "panicked" in err or any("internal error" in ln for ln in lines):
        return "panics", err.strip().splitlines()[-1] if err.strip() else "panic"
    if "Traceback" in err:
        return "tracebacks", err.strip().splitlines()[-1]
    if code == 0:
        if any(ln.startswith("gagekit: error") for ln in lines):
            return "tracebacks", "error line with exit 0"
        try:
            data = json.loads(out) if out.strip() else None
        except json.JSONDecodeError:
            data = out
        if data is not None and not isinstance(data, str) and not is_finite_json(data):
            return "wrong", "non-finite value in the result"
        if expect is not None:
            bad = expect(data)
            if bad:
                return "wrong", bad
        return "ok", ""
    if code == 2 and len(lines) == 1 and lines[0].startswith("gagekit: error: ") and out == "":
        return "clean", lines[0]
    return "tracebacks", f"exit {code}: {(lines or ['(no stderr)'])[-1][:200]}"


def run_inproc(argv, expect=None, limit=TIME_LIMIT) -> tuple[str, str]:
    from gagekit.cli import main

    out, err = io.StringIO(), io.StringIO()
    code = 0
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, limit)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                main([str(a) for a in argv])
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 1
            except _Timeout:
                return "hangs", f"no answer in {limit:.0f} s"
            except BaseException as exc:  # noqa: BLE001 - the census counts it
                return "tracebacks", f"{type(exc).__name__}: {exc}"[:300]
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    return classify(code, out.getvalue(), err.getvalue(), expect)


def run_sub(argv, expect=None, limit=TIME_LIMIT, **kw) -> tuple[str, str]:
    env = dict(os.environ, RUST_BACKTRACE="1")
    try:
        p = subprocess.run([sys.executable, "-m", "gagekit", *map(str, argv)], capture_output=True, text=True,
                           timeout=limit, env=env, **kw)
    except subprocess.TimeoutExpired:
        return "hangs", f"no answer in {limit:.0f} s"
    return classify(p.returncode, p.stdout, p.stderr, expect)


# --------------------------------------------------------------------------- the cases

def _data():
    import gagekit
    from gagekit.samples import data_path

    return gagekit.machine.example_machine_path(), data_path("casting_ok.ply"), data_path("casting_ok.toml")


class Census:
    def __init__(self, show: int):
        self.rows: dict[str, Counter] = defaultdict(Counter)
        self.examples: dict[tuple, list] = defaultdict(list)
        self.show = show
        self.ok_labels: set = set()

    def add(self, group: str, label: str, outcome: tuple[str, str]) -> None:
        cat, detail = outcome
        self.rows[group]["tries"] += 1
        self.rows[group][cat] += 1
        if cat not in ("clean", "ok") and len(self.examples[(group, cat)]) < self.show:
            self.examples[(group, cat)].append(f"{label}: {detail}")

    def table(self) -> str:
        head = f"{'group':<28}" + "".join(f"{c:>11}" for c in CATS)
        lines = [head, "-" * len(head)]
        total = Counter()
        for g, row in self.rows.items():
            total.update(row)
            lines.append(f"{g:<28}" + "".join(f"{row[c]:>11}" for c in CATS))
        lines.append("-" * len(head))
        lines.append(f"{'total':<28}" + "".join(f"{total[c]:>11}" for c in CATS))
        for (g, cat), ex in self.examples.items():
            lines.append(f"\n{g} / {cat}:")
            lines += [f"  {e}" for e in ex]
        return "\n".join(lines)


def spec_cases(tmp: Path, quick: bool):
    from gagekit.cloud import read_points, write_points

    machine, ply, toml = _data()
    cloud = tmp / "casting.npy"
    write_points(cloud, read_points(ply)[::10])
    return {f"spec: {k}": v for k, v in spec_commands(tmp, machine, toml, cloud).items()}


def run_specs(c: Census, tmp: Path, quick: bool) -> None:
    for group, (valid, argv) in spec_cases(tmp, quick).items():
        f = tmp / f"case{Path(valid).suffix}"
        allcases = list(damaged(Path(valid))) + list(mutants(Path(valid)))
        if quick:
            allcases = allcases[::5]
        for label, data in allcases:
            f.write_bytes(data)
            c.add(group, label, run_inproc([f if a == "SPEC" else a for a in argv]))
        for label, p in special_paths(tmp):
            c.add("paths: not regular files", f"{group} {label}", run_sub([p if a == "SPEC" else a for a in argv]))


def _obs_file(tmp: Path) -> tuple[Path, Path]:
    machine, _, _ = _data()
    obs, cal = tmp / "obs.csv", tmp / "cal.json"
    if not cal.exists():
        run_inproc(["machine", "simulate", machine, "--points", 120, "--out", obs, "--seed", 1])
        run_inproc(["machine", "identify", machine, obs, "--out", cal])
    return obs, cal


def csv_mutants(valid: Path):
    """Observation/command CSVs: damaged cells, columns, magnitudes."""
    lines = valid.read_text().splitlines()
    head, rows = lines[0], lines[1:]
    yield from damaged(valid)
    yield "header only", (head + "\n").encode()
    yield "no header", ("\n".join(rows) + "\n").encode()
    cols = head.split(",")
    for j, name in enumerate(cols):
        yield f"drop {name}", ("\n".join(",".join(c for k, c in enumerate(r.split(",")) if k != j)
                                         for r in lines) + "\n").encode()
        for v in ("nan", "inf", "-inf", "1e160", "1e308", "-1e308", "x", "", "1,5", "0x10", "1e400"):
            r0 = rows[3].split(",")
            r0[j] = v
            yield f"{name}={v}", "\n".join([head, *rows[:3], ",".join(r0), *rows[4:]]).encode() + b"\n"
        for v in ("1e160", "1e12", "-1e200"):
            yield f"all {name}={v}", "\n".join([head] + [",".join(v if k == j else c for k, c in enumerate(r.split(",")))
                                                          for r in rows]).encode() + b"\n"
    yield "duplicate column", (head + ",x\n" + "\n".join(r + ",1.0" for r in rows) + "\n").encode()
    yield "3 rows", ("\n".join(lines[:4]) + "\n").encode()
    yield "one row repeated", ("\n".join([head] + [rows[0]] * 80) + "\n").encode()


def run_csv(c: Census, tmp: Path, quick: bool) -> None:
    machine, _, _ = _data()
    obs, cal = _obs_file(tmp)
    f = tmp / "case.csv"
    cmds = [
        ("csv: identify", ["machine", "identify", machine, "CSV", "--json"]),
        ("csv: predict", ["machine", "predict", machine, cal, "CSV", "--out", tmp / "pred.csv", "--json"]),
        ("csv: compensate", ["machine", "compensate", machine, cal, "CSV", "--out", tmp / "comp.csv", "--json"]),
    ]
    cases = list(csv_mutants(obs))
    if quick:
        cases = cases[::5]
    for group, argv in cmds:
        for label, data in cases:
            f.write_bytes(data)
            c.add(group, label, run_inproc([f if a == "CSV" else a for a in argv]))


def run_numeric(c: Census, tmp: Path, quick: bool) -> None:
    """Arguments at the edges: seeds, counts, magnitudes, known answers."""
    machine, ply, toml = _data()
    obs, cal = _obs_file(tmp)
    out = tmp / "o.csv"
    g = "arguments"
    for seed in ("-1", "18446744073709551616", "18446744073709551615", "0", "abc", "1e3", "nan"):
        want_ok = seed in ("18446744073709551615", "0")
        res = run_inproc(["machine", "simulate", machine, "--points", 20, "--out", out, "--seed", seed, "--json"])
        c.add(g, f"simulate --seed {seed}", res if (res[0] == "ok") == want_ok else ("wrong", f"{res}"))
    for opt, val in (("--starts", -1), ("--starts", 0), ("--points", 0), ("--points", -5), ("--candidates", 0),
                     ("--candidates", 10**12)):
        c.add(g, f"design {opt} {val}", run_inproc(["machine", "design", machine, opt, val, "--out", tmp / "p.csv", "--json"]))
    for opt, val in (("--test-points", 0), ("--seeds", 0), ("--test-points", -1)):
        c.add(g, f"evaluate-plan {opt} {val}", run_inproc(["machine", "evaluate-plan", machine, obs, opt, val, "--json"]))
    for opt, val in (("--noise", "nan"), ("--noise", "-1"), ("--noise", "inf"), ("--scale", "nan"), ("--points", "1e3")):
        c.add(g, f"simulate {opt} {val}", run_inproc(["machine", "simulate", machine, "--points", 20, opt, val, "--out", out, "--json"]))
    c.add(g, "unknown option", run_inproc(["machine", "check", machine, "--bogus"]))
    c.add(g, "missing argument", run_inproc(["machine", "design"]))
    c.add(g, "unknown command", run_inproc(["machine", "frobnicate"]))
    # magnitudes: commands and coordinates beyond the documented limit (1e9)
    g = "magnitudes"
    lines = obs.read_text().splitlines()
    for v in ("1e10", "1e160", "1e200", "1e308", "-1e308"):
        for which in ("joint", "xyz"):
            rows = [lines[0]]
            for r in lines[1:]:
                cells = r.split(",")
                idx = 1 if which == "joint" else -2
                cells[idx] = v
                rows.append(",".join(cells))
            f = tmp / "big.csv"
            f.write_text("\n".join(rows) + "\n")
            for cmd in (["machine", "identify", machine, f, "--json"],
                        ["machine", "predict", machine, cal, f, "--out", tmp / "pr.csv", "--json"]):
                if cmd[1] == "predict" and which == "xyz":
                    continue
                c.add(g, f"{cmd[1]} {which}={v}", run_inproc(cmd))
    # the gage LP: the verdict must not depend on a loose bound (issue 12, item 2)
    g = "gage LP: max_shift sweep"
    text = toml.read_text()
    ref = None
    for e in (20,) + tuple(10.0 ** k for k in range(0, 301, 30 if quick else 10)):
        f = tmp / "sweep.toml"
        f.write_text(text.replace("max_shift = 20.0", f"max_shift = {e!r}"))
        res_holder = {}

        def expect(data, e=e):
            nonlocal ref
            verdict, objective = data["status"], data["objective"]
            if ref is None:
                ref = (verdict, objective)
                return ""
            if e < 20:  # a limiting bound may change the answer; only a looser one may not
                return ""
            if verdict != ref[0] or abs(objective - ref[1]) > 1e-6 * (1 + abs(ref[1])):
                return f"max_shift {e:g}: {verdict} {objective:.6f} vs {ref[0]} {ref[1]:.6f}"
            return ""

        c.add(g, f"max_shift={e:g}", run_inproc(["gage", "check", ply, f, "--no-groups", "--json"], expect=expect))


def run_outputs(c: Census, tmp: Path, quick: bool) -> None:
    machine, ply, toml = _data()
    obs, cal = _obs_file(tmp)
    writers = [
        ("simulate --out", ["machine", "simulate", machine, "--points", 30, "--out", "OUT"]),
        ("design --out", ["machine", "design", machine, "--points", 40, "--candidates", 400, "--starts", 1, "--out", "OUT"]),
        ("predict --out", ["machine", "predict", machine, cal, obs, "--out", "OUT"]),
        ("compensate --out", ["machine", "compensate", machine, cal, obs, "--out", "OUT"]),
        ("identify --out", ["machine", "identify", machine, obs, "--out", "OUT"]),
        ("identify --residuals", ["machine", "identify", machine, obs, "--residuals", "OUT"]),
        ("gage --out-cloud", ["gage", "check", ply, toml, "--no-groups", "--out-cloud", "OUT"]),
        ("gage --report", ["gage", "check", ply, toml, "--no-groups", "--report", "OUT"]),
        ("track --report", ["machine", "track", machine, "CYC", "--report", "OUT"]),
        ("cloud hull --out", ["cloud", "hull", ply, "--out", "OUT"]),
        ("demo --out", ["demo", "--quick", "--out", "OUT"]),
    ]
    base = tmp / "outs"
    base.mkdir()
    ro = base / "ro"
    ro.mkdir()
    (base / "adir.csv").mkdir()
    rofile = base / "rofile.csv"
    rofile.write_text("old")
    rofile.chmod(0o444)
    kinds = {"missing folder": base / "no" / "x.csv", "a folder": base / "adir.csv", "read-only folder": ro / "x.csv",
             "read-only file": rofile, "empty name": Path("")}
    ro.chmod(0o555)
    for name, argv in writers:
        for kind, p in kinds.items():
            if name == "demo --out" and kind not in ("missing folder", "read-only folder"):
                continue
            if name == "track --report":
                continue  # needs cycles: covered in the interrupt group
            target = p.with_suffix(".ply") if "cloud" in name and p.suffix == ".csv" else p
            c.add("outputs: bad paths", f"{name} / {kind}", run_sub([target if a == "OUT" else a for a in argv], limit=300))
    ro.chmod(0o755)


def census_ok(c: "Census", group: str, label: str) -> bool:
    return (group, label) in c.ok_labels


def run_history(c: Census, tmp: Path, quick: bool) -> None:
    import sqlite3

    machine, _, _ = _data()
    plan = tmp / "hplan.csv"
    cyc = tmp / "cycles.csv"
    run_inproc(["machine", "design", machine, "--points", 60, "--candidates", 2000, "--out", plan])
    run_inproc(["machine", "simulate-cycles", machine, plan, "--cycles", 3, "--out", cyc])
    g = "history file"
    h = tmp / "h.sqlite"
    c.add(g, "new history", run_inproc(["machine", "track", machine, cyc, "--history", h, "--json"]))
    c.add(g, "append", run_inproc(["machine", "track", machine, cyc, "--history", h, "--json"]))
    c.add(g, "read", run_inproc(["machine", "history", h, "--json"],
                                  expect=lambda d: "" if len(d["runs"]) == 2 else f"{len(d['runs'])} runs, expected 2"))
    foreign = tmp / "foreign.sqlite"
    con = sqlite3.connect(foreign)
    con.execute("CREATE TABLE parts (id INTEGER, name TEXT)")
    con.commit()
    con.close()
    before = foreign.read_bytes()
    c.add(g, "foreign db track", run_inproc(["machine", "track", machine, cyc, "--history", foreign, "--json"]))
    c.add(g, "foreign db history", run_inproc(["machine", "history", foreign, "--json"]))
    if foreign.read_bytes() != before:
        c.add(g, "foreign db unchanged", ("wrong", "the foreign database was modified"))
    for label, data in (("garbage", b"not sqlite at all" * 100), ("empty", b""), ("truncated", h.read_bytes()[:3000])):
        f = tmp / f"bad-{label}.sqlite"
        f.write_bytes(data)
        c.add(g, f"{label} history", run_inproc(["machine", "history", f, "--json"]))
        c.add(g, f"{label} track", run_inproc(["machine", "track", machine, cyc, "--history", f, "--json"]))
    rofile = tmp / "ro.sqlite"
    rofile.write_bytes(h.read_bytes())
    rofile.chmod(0o444)
    c.add(g, "read-only history: read", run_inproc(["machine", "history", rofile, "--json"]))
    c.add(g, "read-only history: track", run_inproc(["machine", "track", machine, cyc, "--history", rofile, "--json"]))
    # a lock held by another process for longer than the busy timeout
    locker = subprocess.Popen([sys.executable, "-c", (
        "import sqlite3, sys, time; c = sqlite3.connect(sys.argv[1]); c.execute('BEGIN EXCLUSIVE');"
        "print('locked', flush=True); time.sleep(float(sys.argv[2]))"), str(h), "12"], stdout=subprocess.PIPE, text=True)
    locker.stdout.readline()
    res = run_sub(["machine", "track", machine, cyc, "--history", h, "--json"], limit=60)
    c.add(g, "locked: track", res)
    c.ok_labels.add((g, "locked: track")) if res[0] == "ok" else None
    c.add(g, "locked: history", run_sub(["machine", "history", h, "--json"], limit=60))
    locker.kill()
    locker.wait()
    stored = 2 + sum(1 for label in ("locked: track",) if census_ok(c, g, label))
    c.add(g, "after lock", run_inproc(["machine", "history", h, "--json"],
                                        expect=lambda d: "" if len(d["runs"]) == stored else f"{len(d['runs'])} runs, expected {stored}"))


def _count_rows(p: Path) -> int:
    with open(p, "rb") as fh:
        return sum(1 for _ in fh) - 1


def run_interrupts(c: Census, tmp: Path, quick: bool) -> None:
    """SIGINT (Ctrl-C) and SIGKILL at several moments of long runs: the answer within a
    second, and the output file either the old one, absent, or complete.

    "Within a second" is measured as the CPU time the process uses after the signal (all
    its threads) against one second per core: what it would take on an idle machine. On a
    loaded, shared machine the wall time measures the scheduler rather than the program;
    it is shown with each answer (a run with no exit 30 s after the signal is a hang)."""
    machine, _, _ = _data()
    env = dict(os.environ, RUST_BACKTRACE="1")
    delays = (0.3, 1.0, 2.0, 4.0) if not quick else (1.0, 3.0)
    obs = tmp / "obs200k.csv"
    uniform = tmp / "uniform1m.npy"
    long_runs = [
        ("simulate 400000", ["machine", "simulate", machine, "--points", 400000, "--out", "OUT"], 400000),
        ("design 100000", ["machine", "design", machine, "--candidates", 100000, "--out", "OUT"], 80),
        ("evaluate-plan", ["machine", "evaluate-plan", machine, "PLAN", "--seeds", 40], None),
        ("identify 200000", ["machine", "identify", machine, obs, "--out", "OUT"], None),
        ("circle MI 1e6", ["form", "fit", "circle", uniform, "-c", "max-inscribed", "--json"], None),
    ]
    plan = tmp / "iplan.csv"
    run_inproc(["machine", "design", machine, "--points", 80, "--candidates", 3000, "--out", plan])
    run_inproc(["machine", "simulate", machine, "--points", 200000, "--out", obs])
    import numpy as np

    rng = np.random.default_rng(0)
    np.save(uniform, np.c_[rng.uniform(-1, 1, (10**6, 2)), np.zeros(10**6)])
    cores = float(os.cpu_count() or 1)
    for sig, sname in ((signal.SIGINT, "SIGINT"), (signal.SIGKILL, "SIGKILL")):
        for name, argv, rows in long_runs:
            for d in delays:
                out = tmp / f"int-{sname}-{name.split()[0]}-{d}.csv"
                args = [out if a == "OUT" else plan if a == "PLAN" else a for a in argv]
                so_f, se_f = tmp / "int.out", tmp / "int.err"
                with open(so_f, "w") as so_h, open(se_f, "w") as se_h:  # files, not pipes: nothing can block
                    p = subprocess.Popen([sys.executable, "-m", "gagekit", *map(str, args)], stdout=so_h,
                                         stderr=se_h, text=True, env=env)
                time.sleep(d)
                cpu0 = cpu_seconds(p.pid)
                t0 = time.perf_counter()
                p.send_signal(sig)
                # the CPU clock sampled every 5 ms until the exit (Popen.poll reaps the child)
                cpu = 0.0
                while p.poll() is None and time.perf_counter() - t0 < 30:
                    cpu = max(cpu, cpu_seconds(p.pid) - cpu0)
                    time.sleep(0.005)
                if p.returncode is None:
                    p.kill()
                    p.wait()
                    c.add(f"interrupts: {sname}", f"{name} after {d}s", ("hangs", "no exit 30 s after the signal"))
                    continue
                dt = time.perf_counter() - t0
                se = se_f.read_text()
                label = f"{name} after {d}s"
                group = f"interrupts: {sname}"
                if rows is not None and out.exists() and _count_rows(out) != rows:
                    c.add(group, label, ("wrong", f"half-written output: {_count_rows(out)} of {rows} rows"))
                    continue
                if sig == signal.SIGKILL:
                    c.add(group, label, ("ok", "") if p.returncode in (-9, 0) else ("tracebacks", se[-200:]))
                    continue
                if p.returncode == 0:
                    c.add(group, label, ("ok", "finished before the signal"))
                elif cpu > cores:
                    c.add(group, label, ("hangs", f"answered Ctrl-C after {cpu:.2f} s of CPU ({dt:.1f} s wall)"))
                else:
                    lines = [ln for ln in se.splitlines() if ln.strip()]
                    good = p.returncode == 130 and lines == ["gagekit: error: interrupted"]
                    c.add(group, label, ("clean", "") if good else ("tracebacks", f"exit {p.returncode}: {se[-300:]}"))
                leftovers = [x.name for x in tmp.iterdir() if ".gk-tmp" in x.name and sig == signal.SIGINT]
                if leftovers:
                    c.add(group, label + " temp files", ("wrong", f"left {leftovers}"))


def run_point_files(c: Census, tmp: Path, quick: bool) -> None:
    """Random bytes and degenerate geometry as point files (the readers' own hostile cases
    are in tests/hostile, by the readers' owner); the hull, regions and gage kernels."""
    import numpy as np

    _, ply, toml = _data()
    rng = np.random.default_rng(12)
    n = 60 if quick else 300
    for k in range(n):
        ext = (".xyz", ".csv", ".ply", ".npy", ".pts", ".ds", ".txt", ".las", ".e57", ".bin")[k % 10]
        f = tmp / f"rand{k}{ext}"
        size = int(rng.integers(0, 4000))
        data = rng.integers(0, 256, size, dtype=np.uint8).tobytes()
        if k % 3 == 0:  # printable noise: digits, separators, signs
            data = bytes(rng.choice(list(b"0123456789.,;eE+- \t\n#nainfNAN"), size).astype(np.uint8))
        if k % 5 == 0:  # a valid header followed by noise
            data = {".ply": b"ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
                    ".npy": b"\x93NUMPY\x01\x00v\x00{'descr': '<f8', 'fortran_order': False, 'shape': (5, 3), }" + b" " * 50 + b"\n"}.get(ext, b"x,y,z\n") + data
        f.write_bytes(data)
        c.add("point files: random bytes", f"{f.name}", run_inproc(["cloud", "info", f, "--json"]))
        c.add("point files: random bytes", f"hull {f.name}", run_inproc(["cloud", "hull", f, "--json"]))
    g = "degenerate geometry"
    shapes = {
        "one point": np.zeros((1, 3)),
        "two points": np.array([[0, 0, 0], [1, 1, 1.0]]),
        "identical": np.ones((50, 3)),
        "collinear": np.outer(np.linspace(0, 1, 50), [1, 2, 3]),
        "coplanar": np.column_stack([rng.random((200, 2)), np.zeros(200)]),
        "tiny": rng.random((100, 3)) * 1e-300,
        "huge": rng.random((100, 3)) * 1e200,
        "mixed scale": np.vstack([rng.random((100, 3)), [[1e12, 0, 0]]]),
        "nan row": np.vstack([rng.random((10, 3)), [[np.nan, 0, 0]]]),
        "inf row": np.vstack([rng.random((10, 3)), [[np.inf, 0, 0]]]),
        "integer grid": np.stack(np.meshgrid(np.arange(6), np.arange(6), np.arange(6)), -1).reshape(-1, 3).astype(float),
        "sphere": (lambda v: v / np.linalg.norm(v, axis=1, keepdims=True))(rng.normal(size=(500, 3))),
    }
    for name, pts in shapes.items():
        f = tmp / f"deg-{name.replace(' ', '_')}.npy"
        np.save(f, pts)
        c.add(g, f"hull {name}", run_inproc(["cloud", "hull", f, "--json"]))
        c.add(g, f"regions {name}", run_inproc(["cloud", "regions", f, toml, "--json"]))
        c.add(g, f"gage {name}", run_inproc(["gage", "check", f, toml, "--no-groups", "--json"]))


def _run_case(argv, mode, limit=TIME_LIMIT):
    return run_inproc(argv, limit=limit) if mode == "inproc" else run_sub(argv, limit=limit)


def _good_db(tmp: Path) -> str:
    """A results database with gage, form and inspection results (a small batch of each)."""
    from gagekit.cloud import read_points, write_points
    from gagekit.samples import data_path

    url = f"sqlite:///{tmp / 'good.db'}"
    d = tmp / "good-scans"
    d.mkdir()
    pts = read_points(data_path("casting_ok.ply"))
    for k in range(3):
        write_points(d / f"c{k}.ply", pts[k::6])
    write_points(d / "b.npy", read_points(data_path("bracket.ply"))[::3])
    run_sub(["gage", "batch", data_path("casting_ok.toml"), d / "c*.ply", "--db", url, "-w", "1"])
    run_sub(["form", "batch", "plane", d / "c*.ply", "--db", url, "-w", "1"])
    run_sub(["inspect", "batch", data_path("bracket.toml"), d / "b.npy", "--db", url, "-w", "1"])
    return url


def run_surfaces(c: Census, tmp: Path, quick: bool) -> None:
    """inspect, export, compensate-nc, batches, stats, db (issue 22)."""
    from tests.hostile.surfaces import command_cases

    machine, _, _ = _data()
    _, cal = _obs_file(tmp)
    for group, label, argv, mode in command_cases(tmp, machine, cal, _good_db(tmp), quick):
        # a valid drawing inspects 20 callouts: on a loaded 2-core machine that takes over a minute
        limit = 300 if group.startswith("inspect") else 120 if mode == "sub" else TIME_LIMIT
        c.add(group, label, _run_case(argv, mode, limit=limit))


def classify_http(status: int, data) -> tuple[str, str]:
    """A studio answer: 4xx with a JSON error is clean, 2xx with finite JSON ok."""
    if status is None:
        return "hangs", "no answer"
    if 400 <= status < 500:
        if isinstance(data, dict) and isinstance(data.get("error"), str) and data["error"]:
            return "clean", ""
        return "tracebacks", f"{status} without a JSON error"
    if 200 <= status < 300:
        return ("ok", "") if data is None or is_finite_json(data) else ("wrong", "non-finite value")
    return "tracebacks", f"HTTP {status}: {str(data)[:200]}"


def run_studio(c: Census, tmp: Path, quick: bool) -> None:
    """The studio's HTTP API on one real server (uvicorn on 127.0.0.1)."""
    import shutil

    from gagekit.samples import data_path
    from tests.hostile.surfaces import studio_cases
    from tests.servers import StudioServer

    folder, outside = tmp / "studio", tmp / "outside"
    folder.mkdir()
    outside.mkdir()
    shutil.copy(data_path("casting_ok.ply"), folder / "casting.ply")
    shutil.copy(data_path("casting_ok.toml"), folder / "casting.toml")
    (outside / "secret.toml").write_text("[motion]\n")
    os.mkfifo(folder / "pipe.toml")
    os.mkfifo(folder / "pipe.ply")
    (folder / "out.ply").symlink_to(data_path("casting_ok.ply"))
    (folder / "outdir").symlink_to(outside, target_is_directory=True)
    server = StudioServer(str(folder / "casting.ply"), str(folder / "casting.toml"))
    try:
        gage_doc = server.request("GET", "/api/state")[1]["spec"]["doc"]
        from gagekit.studio.specdoc import parse_text

        part_doc = parse_text(data_path("bracket.toml").read_text(), "bracket.toml")
        for group, label, method, path, body in studio_cases(gage_doc, part_doc, quick):
            if server.proc.poll() is not None:
                c.add(group, label, ("panics", f"the server exited ({server.proc.returncode})"))
                continue
            try:
                status, data, _ = server.request(method, path, body, timeout=TIME_LIMIT)
            except OSError as exc:  # a timeout, a reset connection
                status, data = None, str(exc)
            c.add(group, label, classify_http(status, data))
        for label, token in (("no token", False), ("wrong token", "x")):
            server_token = server.token
            if token == "x":
                server.token = "wrong"
            status, data, _ = server.request("GET", "/api/state", token=bool(token))
            server.token = server_token
            c.add("studio HTTP: access", label, ("clean", "") if status == 401 else ("wrong", f"HTTP {status} without the token"))
        code = server.interrupt(timeout=15)
        c.add("studio HTTP: access", "Ctrl-C after it all", ("clean", "") if code is not None else ("hangs", "Ctrl-C did not stop it"))
    finally:
        server.stop()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a fifth of the generated cases")
    ap.add_argument("--only", default="", help="comma-separated groups: specs,csv,numeric,outputs,history,interrupts,points,"
                                               "surfaces,studio")
    ap.add_argument("--show", type=int, default=5, help="examples per failing category")
    ap.add_argument("--pytest", action="store_true", help="also count the pytest cases of tests/hostile (other owners' readers and fits)")
    args = ap.parse_args(argv)
    import warnings

    warnings.simplefilter("ignore")
    from gagekit import _progress

    _progress.set_quiet()
    runs = {"specs": run_specs, "csv": run_csv, "numeric": run_numeric, "outputs": run_outputs,
            "history": run_history, "interrupts": run_interrupts, "points": run_point_files,
            "surfaces": run_surfaces, "studio": run_studio}
    only = [s for s in args.only.split(",") if s] or list(runs)
    census = Census(args.show)
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="gagekit-census-") as d:
        for name in only:
            sub = Path(d) / name
            sub.mkdir()
            t = time.perf_counter()
            runs[name](census, sub, args.quick)
            print(f"[{name}: {time.perf_counter() - t:.0f} s]", file=sys.stderr, flush=True)
        for root, dirs, files in os.walk(d):
            for x in dirs:
                with contextlib.suppress(OSError):
                    os.chmod(os.path.join(root, x), 0o755)
    if args.pytest:
        p = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(ROOT / "tests" / "hostile")],
                           capture_output=True, text=True)
        census.rows["pytest tests/hostile"]["tries"] += 1
        census.rows["pytest tests/hostile"]["ok" if p.returncode == 0 else "wrong"] += 1
        print(p.stdout.strip().splitlines()[-1] if p.stdout.strip() else p.stderr[-300:], file=sys.stderr)
    print(census.table())
    print(f"\n({time.perf_counter() - t0:.0f} s)")
    bad = sum(row[c] for row in census.rows.values() for c in ("tracebacks", "panics", "hangs", "wrong"))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
