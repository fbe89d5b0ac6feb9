"""The hostile-input suite (issue 12): every case runs the real console script in a
subprocess with a time bound and checks the contract of :func:`assert_clean_error`:
exactly one stderr line starting ``gagekit: error:``, exit status 2, no traceback, no
Rust panic, nothing on stdout; or, for a valid input, a correct result."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

import gagekit
from gagekit.samples import data_path

EXAMPLE_MACHINE = gagekit.machine.example_machine_path()
CASTING_PLY = data_path("casting_ok.ply")
CASTING_TOML = data_path("casting_ok.toml")


def gk(*args, timeout: float = 120, cwd=None, input=None, env=None) -> subprocess.CompletedProcess:
    """Run ``python -m gagekit ARGS`` (bounded in time; a hang fails the test)."""
    e = dict(os.environ, RUST_BACKTRACE="1", PYTHONWARNINGS="default")
    if env:
        e.update(env)
    return subprocess.run([sys.executable, "-m", "gagekit", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, cwd=cwd, input=input, env=e)


def assert_clean_error(proc: subprocess.CompletedProcess, match: str | None = None, code: int = 2) -> str:
    """One stderr line ``gagekit: error: ...``, the exit status, no traceback or panic."""
    err = proc.stderr
    assert "Traceback" not in err and "panicked" not in err and "RUST_BACKTRACE" not in err, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, f"expected one stderr line, got:\n{err}"
    assert lines[0].startswith("gagekit: error: "), err
    assert proc.returncode == code, (proc.returncode, err)
    assert proc.stdout == "", proc.stdout
    if match is not None:
        assert match in lines[0], lines[0]
    return lines[0]


def assert_ok(proc: subprocess.CompletedProcess) -> None:
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr and "panicked" not in proc.stderr, proc.stderr


def leftovers(folder: Path) -> list[str]:
    """Temporary files of an atomic write left in ``folder`` (must be none after a clean run)."""
    return sorted(p.name for p in Path(folder).iterdir() if ".gk-tmp" in p.name or ".gk-old" in p.name)


@pytest.fixture(scope="session")
def machine_file() -> Path:
    return EXAMPLE_MACHINE


@pytest.fixture(scope="session")
def sim(tmp_path_factory):
    """A small simulated data set: observations, calibration, plan (made once per session)."""
    d = tmp_path_factory.mktemp("sim")
    assert_ok(gk("machine", "simulate", EXAMPLE_MACHINE, "--points", 120, "--out", d / "obs.csv", "--seed", 1))
    assert_ok(gk("machine", "identify", EXAMPLE_MACHINE, d / "obs.csv", "--out", d / "cal.json"))
    return d


def gk_inproc(*args) -> tuple[int, str, str]:
    """Run the CLI in this process (fast, for hundreds of generated cases): (exit status,
    stdout, stderr). An exception escaping ``main`` is a traceback: it propagates."""
    import contextlib
    import io

    from gagekit.cli import main

    out, err = io.StringIO(), io.StringIO()
    code = 0
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            main([str(a) for a in args])
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
    return code, out.getvalue(), err.getvalue()


def check_outcome(code: int, out: str, err: str, what: str) -> str:
    """The contract for one case: a clean error ("clean") or a valid, finite JSON result
    ("ok"). Anything else fails with ``what`` in the message."""
    import json

    from .mutants import is_finite_json

    lines = [ln for ln in err.splitlines() if ln.strip()]
    if code == 0:
        assert not any(ln.startswith("gagekit: error") for ln in lines), (what, err)
        data = json.loads(out)
        assert is_finite_json(data), (what, out[:500])
        return "ok"
    assert code == 2, (what, code, err)
    assert len(lines) == 1 and lines[0].startswith("gagekit: error: "), (what, err)
    assert "internal error" not in lines[0], (what, lines[0])
    assert out == "", (what, out[:200])
    return "clean"
