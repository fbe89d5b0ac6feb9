"""A bare install runs every command the README and docs show (issue 22 item 1).

The wheel is built (``maturin build --release``, reusing ``target/``; ``pip wheel`` where
maturin is not installed), installed with NO extras into a fresh venv (no system site
packages) in a temporary folder, and every command line of the fenced blocks of README.md
and docs/*.md is run there verbatim on the bundled samples:

* a line is a fenced line starting with ``gagekit ``; a comment (`` # ...``) is dropped;
* an optional group ``[...]`` is kept (its options run too) unless it offers a choice
  (``|``) or elides (``...``): then it is left out. A choice or a brace form outside
  brackets (``-c {lsq,mc}``, ``parquet|csv``) is refused: write one runnable line each;
* every placeholder is replaced through PLACEHOLDERS below (bundled samples, inputs made by
  the test env's gagekit before the run, fresh output paths); an unknown one fails the test.

A line that needs an extra (NEEDS_EXTRA) must fail in the bare venv with ONE line naming
``gagekit[extra]``, and is then run for real with the test env's gagekit, where the extra is
installed (a real PostgreSQL server for ``postgresql://``, the studio's server until it
listens). Every other line must succeed in the bare venv: exit 0, no traceback, no error.

It always runs in CI (``CI=true``: a missing cargo or network fails it instead of skipping).
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from servers import unavailable

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
TEST_DATA = ROOT / "tests" / "data"

#: Placeholders of the documented commands -> what they stand for in the run. ``sample:NAME`` is
#: `gagekit data path NAME` (inside the installed package); ``made:NAME`` an input written by the
#: test env's gagekit before the run (copied into each command's own folder); ``out:NAME`` a
#: new path in the command's folder; ``test:PATH`` a file of tests/data; anything else literal.
PLACEHOLDERS = {
    "SCAN.ply": "sample:casting",  # with PART.toml on the line: sample:bracket
    "SCAN": "sample:bracket",  # docs/inspection.md: `gagekit inspect SCAN PART.toml`
    "GAGES.toml": "sample:casting-gages",
    "PART.toml": "sample:bracket-part",
    "SCAN.e57": "test:e57/bunnyDouble.e57",
    "ROUND.csv": "sample:round",
    "BORE.csv": "sample:bore",
    "BALL.csv": "sample:ball",
    "CONE.csv": "sample:cone",
    "PLANE.csv": "test:nist-l2/plane/pla22.ds",
    "LINE.csv": "test:nist-l2/line3d/lin3.ds",
    "MACHINE.toml": "sample:machine",
    "PROGRAM.nc": "sample:program",
    "RUNS.csv": "sample:iso230-2",
    "OBS.csv": "made:OBS.csv",  # machine simulate --points 120
    "CAL.json": "made:CAL.json",  # machine identify OBS.csv
    "CMDS.csv": "made:CMDS.csv",  # five commands inside the joint ranges
    "PLAN.csv": "made:PLAN.csv",  # machine design --points 40 --candidates 2000
    "CYCLES.csv": "made:CYCLES.csv",  # machine simulate --plan PLAN.csv --cycles 6
    "T.csv": "made:CYCLES.csv",  # its temp_* columns
    "TRACK.json": "made:TRACK/track.json",  # machine track CYCLES.csv --report TRACK
    "H.sqlite": "made:H.sqlite",  # the history of that track
    "EXCL.toml": "made:EXCL.toml",  # one [[box]] to avoid
    "URL": "made:plant.db",  # sqlite:///... of a gage batch of the two castings
    "scans/*.ply": "made:scans/*.ply",  # the two castings (the bracket with PART.toml)
    "bores/": "made:bores/",  # the bore and the dissertation's cylinder set 1
    "postgresql://user@host/plant": "postgresql://user@host/plant",  # the test server's, in the test env
    "HULL.ply": "out:HULL.ply", "CORRECTED.ply": "out:CORRECTED.ply", "CORRECTED.csv": "out:CORRECTED.csv",
    "E.csv": "out:E.csv", "GRID.csv": "out:GRID.csv", "ISG.csv": "out:ISG.csv", "COMP.tap": "out:COMP.tap",
    "COMP.txt": "out:COMP.txt", "OUT.nc": "out:OUT.nc", "DIR": "out:DIR", "FILE": "out:FILE",
    "U": "mm", "H": "127.0.0.1", "P": "port", "TOL": "0.001", "N": "1",
    "I": "I",  # --criterion I: a value, not a placeholder
    "TRACKER.csv": "made:OBS.csv",  # laser-tracker observations
    "SPHERE.csv": "sample:sphere",  # a probed sphere, '# kind = sphere'
    "RTEST.csv": "sample:rtest",  # an R-test, '# kind = rtest'
    "RUN.csv": "sample:ballbar",  # a simulated ballbar run, XY plane, R 150 mm
    "KIN.txt": "out:KIN.txt",
    "PROBING.csv": "sample:sphere-cycles",  # sphere probing cycles ('# kind = sphere')
    "STUDY.csv": "sample:grr-study",  # a gage R&R study (columns part,appraiser,trial,value)
    "BALLBAR.csv": "sample:ballbar",  # the same run: its '# kind = ballbar' lines make it an observation file
    "R": "150", "F": "1000", "XY": "XY",
    "MODEL.qif": "pkg:data/nist_ctc_01_asme1_ap242.qif.gz",
    "OUT.qif": "out:OUT.qif",
    "PROFILE.csv": "sample:roundness", "TRACE.csv": "sample:straightness",  # form roundness / straightness
    "LSCI": "LSCI", "MZCI": "MZCI", "MZPL": "MZPL",  # reference features: values, not placeholders
    "CAD.step": "sample:bracket-step", "CADPART.toml": "sample:bracket-cad-part", "OUT.npy": "out:OUT.npy", "D": "5",
}
#: the value after these options is written: always a new path in the command's folder (so that
#: `--out PART.toml` never writes over a bundled sample)
OUTPUT_OPTIONS = ("--out", "--out-cloud", "--report", "--qif-results")
#: where one placeholder letter means two things: the value after these options
OPTION_VALUES = {"--pitch": "5"}  # ballbar: lead of the screw, mm (P is the studio's --port elsewhere)
PLACEHOLDER = re.compile(r"^[A-Z][A-Z0-9_]*(\.[a-z0-9]+)?$")

#: a documented line containing KEY needs the extra: in the bare venv it must say so in one line
NEEDS_EXTRA = {"gagekit studio": "studio", "postgresql://": "postgresql", "--format parquet": "parquet",
               "gagekit qif": "qif", "--qif-results": "qif", "CAD.step": "cad", "CADPART.toml": "cad"}


# ----- the documented lines ------------------------------------------------------------------
def documented_lines() -> list[tuple[str, str]]:
    """(where, line) of every fenced `gagekit ...` line of README.md and docs/*.md."""
    out = []
    for doc in DOCS:
        fenced = False
        for n, raw in enumerate(doc.read_text(encoding="utf-8").splitlines(), 1):
            if raw.lstrip().startswith("```"):
                fenced = not fenced
                continue
            line = re.split(r"\s#", raw, maxsplit=1)[0].strip()
            if fenced and line.startswith("gagekit "):
                out.append((f"{doc.relative_to(ROOT)}:{n}", line))
    return out


def runnable(line: str) -> list[str]:
    """The documented line as arguments, optional groups kept or left out (module docstring)."""
    text = re.sub(r"\[([^\[\]]*)\]", lambda m: "" if ("|" in m.group(1) or "..." in m.group(1)) else m.group(1), line)
    for mark in ("{", "|", "..."):
        assert mark not in text, f"{line!r}: write each alternative ({mark}) as its own runnable line"
    return shlex.split(text)


LINES = documented_lines()


def test_the_docs_have_command_lines():
    wheres = {w.split(":")[0] for w, _ in LINES}
    assert "README.md" in wheres and len(LINES) > 40, LINES
    for _, line in LINES:
        args = runnable(line)
        for a in args:
            if PLACEHOLDER.match(a):
                assert a in PLACEHOLDERS, f"{line!r}: placeholder {a} is not in PLACEHOLDERS of tests/test_bare_install.py"


# ----- the bare venv ---------------------------------------------------------------------------
def _run(cmd, timeout, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([str(c) for c in cmd], capture_output=True, text=True, timeout=timeout, **kw)


@pytest.fixture(scope="session")
def bare_venv(tmp_path_factory) -> Path:
    """A fresh venv holding the wheel and its required dependencies only; its bin folder."""
    tmp = tmp_path_factory.mktemp("bare")
    if shutil.which("cargo") is None:
        unavailable("cargo is needed to build the wheel")
    env = {**os.environ, "CARGO_TARGET_DIR": os.environ.get("CARGO_TARGET_DIR", str(ROOT / "target"))}
    maturin = shutil.which("maturin") or shutil.which("maturin", path=str(Path(sys.executable).parent))
    wheels = tmp / "wheels"
    if maturin:
        cmd = [maturin, "build", "--release", "--out", wheels]
    else:  # pip fetches maturin (the build backend) itself
        cmd = [sys.executable, "-m", "pip", "wheel", "--no-deps", "--disable-pip-version-check", "-w", wheels, ROOT]
    p = _run(cmd, 3600, cwd=ROOT, env=env)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    (wheel,) = wheels.glob("gagekit-*.whl")
    venv = tmp / "venv"
    p = _run([sys.executable, "-m", "venv", venv], 300)
    assert p.returncode == 0, p.stderr
    py = venv / "bin" / "python"
    p = _run([py, "-m", "pip", "install", "--disable-pip-version-check", "-q", wheel], 1800)
    if p.returncode != 0:
        unavailable(f"cannot install the wheel's dependencies from the package index: {p.stderr.strip()[-500:]}")
    p = _run([py, "-c", "import importlib.util as u; print(' '.join(m for m in "
                        "('scipy', 'pyarrow', 'starlette', 'psycopg', 'distributed', 'laspy', 'pytest') if u.find_spec(m)))"], 120)
    assert p.returncode == 0 and p.stdout.strip() == "", f"the venv is not bare: {p.stdout} {p.stderr}"
    return venv / "bin"


# ----- inputs made before the run --------------------------------------------------------------
def _gk(*args, cwd: Path, timeout: int = 600) -> None:
    p = _run([sys.executable, "-m", "gagekit", *args], timeout, cwd=cwd)
    assert p.returncode == 0, f"gagekit {' '.join(map(str, args))}: {p.stderr}"


@pytest.fixture(scope="session")
def made(tmp_path_factory) -> Path:
    """The inputs the documented lines read, written by the test env's gagekit."""
    from gagekit.samples import sample_path

    d = tmp_path_factory.mktemp("made")
    m = sample_path("machine")
    _gk("machine", "simulate", m, "--points", 120, "--seed", 1, "--out", "OBS.csv", cwd=d)
    _gk("machine", "identify", m, "OBS.csv", "--out", "CAL.json", cwd=d)
    (d / "CMDS.csv").write_text("B,X,Z,Y,W\n0,-1000,1000,400,-500\n90,0,1500,1000,-500\n180,500,2000,2000,-300\n"
                                "270,1200,950,2400,-700\n45,-500,1200,800,-400\n")
    _gk("machine", "design", m, "--points", 40, "--candidates", 2000, "--out", "PLAN.csv", cwd=d)
    _gk("machine", "simulate", m, "--plan", "PLAN.csv", "--cycles", 6, "--out", "CYCLES.csv", cwd=d)
    _gk("machine", "track", m, "CYCLES.csv", "--history", "H.sqlite", "--report", "TRACK", cwd=d)
    (d / "EXCL.toml").write_text("[[box]]\nX = [-1250.0, -1000.0]\nZ = [900.0, 1100.0]\n")
    for sub, names in (("scans", ("casting", "casting-short")), ("part-scans", ("bracket",)), ("bores", ("bore", "cylinder-set1"))):
        (d / sub).mkdir()
        for name in names:
            shutil.copy(sample_path(name), d / sub / sample_path(name).name)
    _gk("gage", "batch", sample_path("casting-gages"), "scans", "--workers", 1, "--db", "sqlite:///plant.db", cwd=d)
    return d


def _pending(line: str) -> list[str]:
    """What a documented line needs that is neither bundled nor made here yet."""
    return [PLACEHOLDERS[a][8:] for a in runnable(line) if PLACEHOLDERS.get(a, "").startswith("pending:")]


def _args(line: str, work: Path, made: Path, bare: bool, request) -> list[str]:
    """The documented line's arguments with every placeholder replaced; run in ``work``."""
    from gagekit.samples import sample_path

    import gagekit

    part = "PART.toml" in line
    out: list[str] = []
    for a in runnable(line):
        v = PLACEHOLDERS.get(a, a) if PLACEHOLDER.match(a) or a in PLACEHOLDERS else a
        if out and out[-1] in OUTPUT_OPTIONS:
            v = f"out:{Path(a).name}"
        elif out and out[-1] in OPTION_VALUES and PLACEHOLDER.match(a):
            v = OPTION_VALUES[out[-1]]
        elif a.startswith("python/gagekit/"):  # a path of the source tree: the installed package's file
            v = f"pkg:{a[len('python/gagekit/'):]}"
        if a in ("SCAN.ply", "SCAN") and part:
            v = "sample:bracket"
        if a == "scans/*.ply" and part:
            v = "made:part-scans/*.ply"
        if v.startswith("sample:"):
            v = str(sample_path(v[7:]))
        elif v.startswith("pkg:"):
            v = str(Path(gagekit.__file__).resolve().parent / v[4:])
        elif v.startswith("test:"):
            v = str(TEST_DATA / v[5:])
        elif v.startswith("made:"):
            rel = v[5:]
            v = f"sqlite:///{work / rel}" if rel.endswith(".db") else str(work / rel)
        elif v.startswith("out:"):
            v = str(work / "out" / v[4:])
        elif v == "port":
            with socket.socket() as s:
                s.bind(("127.0.0.1", 0))
                v = str(s.getsockname()[1])
        elif v.startswith("postgresql://") and not bare:
            v = request.getfixturevalue("postgres_url")
        out.append(v)
    return out


def _work(made: Path, tmp_path: Path) -> Path:
    work = tmp_path / "work"
    shutil.copytree(made, work)
    (work / "out").mkdir()
    return work


def _clean(p: subprocess.CompletedProcess) -> None:
    assert "Traceback" not in p.stderr and "panicked" not in p.stderr, p.stderr


def _studio(argv: list[str], cwd: Path) -> None:
    """Run the studio's server until it listens on its --port, then stop it with Ctrl-C."""
    port = int(argv[argv.index("--port") + 1])
    proc = subprocess.Popen(argv, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                time.sleep(0.3)
        assert proc.poll() is None, proc.communicate()[1]
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
        try:
            _, err = proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            _, err = proc.communicate()
    assert "Traceback" not in err, err


@pytest.mark.parametrize("where,line", LINES, ids=[f"{w} {ln[:70]}" for w, ln in LINES])
def test_documented_command_runs_on_a_bare_install(where, line, bare_venv, made, tmp_path, request):
    if _pending(line):
        pytest.skip(f"no sample for {', '.join(_pending(line))} yet: bundle one or make it in the `made` fixture")
    extra = next((e for key, e in NEEDS_EXTRA.items() if key in line), None)
    work = _work(made, tmp_path)
    args = _args(line, work, made, True, request)
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONPATH", "PYTHONHOME")}
    env["PATH"] = f"{bare_venv}{os.pathsep}{env.get('PATH', '')}"
    argv = [str(bare_venv / "gagekit"), *args[1:]]
    p = _run(argv, 900, cwd=work, env=env)
    _clean(p)
    if extra is None:
        assert p.returncode == 0 and "gagekit: error" not in p.stderr, f"{where}: {line}\n{p.stderr}"
        return
    # the bare venv names the extra in one line ...
    assert p.returncode == 2 and p.stdout == "", f"{where}: {line}\n{p.stdout}\n{p.stderr}"
    assert p.stderr.count("\n") == 1 and re.search(rf"install '?gagekit\[{extra}\]'?", p.stderr), p.stderr
    # ... and the test env, which has it, runs the line for real
    work = _work(made, tmp_path / "full")
    argv = [sys.executable, "-m", "gagekit", *_args(line, work, made, False, request)[1:]]
    if extra == "studio":
        pytest.importorskip("starlette")
        _studio(argv, work)
        return
    p = _run(argv, 900, cwd=work)
    _clean(p)
    assert p.returncode == 0 and "gagekit: error" not in p.stderr, f"{where}: {line}\n{p.stderr}"
