"""Ctrl-C and kill -9 during long runs (subprocesses, bounded in time): Ctrl-C is answered
within a second with one line and exit 130; the output is the old file or none, never a
truncated one under the final name (issue 12, item 9)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from .conftest import EXAMPLE_MACHINE, leftovers


def _start(*args):
    env = dict(os.environ, RUST_BACKTRACE="1")
    return subprocess.Popen([sys.executable, "-m", "gagekit", *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)


def _cpu_seconds(pid: int) -> float:
    """User + system CPU time of a process (Linux /proc), 0 once it has exited."""
    try:
        fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _interrupt(p, after, sig=signal.SIGINT):
    """Send ``sig`` once the child has used ``after`` s of CPU (past the interpreter's and
    the imports' start-up, whatever the machine's load), or has finished. Returns the CPU
    time the child used after the signal (its threads together), stdout and stderr: CPU
    time, not wall time, so that a loaded test machine does not count as a slow answer."""
    deadline = time.monotonic() + 300
    while p.poll() is None and _cpu_seconds(p.pid) < after and time.monotonic() < deadline:
        time.sleep(0.05)
    if p.returncode is not None:
        out, err = p.communicate()
        return 0.0, out, err
    before = _cpu_seconds(p.pid)
    p.send_signal(sig)
    _, status, usage = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    out, err = p.stdout.read(), p.stderr.read()
    return usage.ru_utime + usage.ru_stime - before, out, err


@pytest.mark.parametrize("after", [1.5, 6.0])
def test_design_answers_ctrl_c_within_a_second(tmp_path, after):
    out = tmp_path / "plan.csv"
    p = _start("machine", "design", EXAMPLE_MACHINE, "--candidates", 100000, "--out", out)
    dt, so, se = _interrupt(p, after)
    if p.returncode == 0:
        pytest.skip("finished before the signal")
    assert dt < 1.0 * (os.cpu_count() or 1), f"answered Ctrl-C after {dt:.2f} s of CPU"
    assert p.returncode == 130 and se.strip() == "gagekit: error: interrupted", (p.returncode, se)
    assert not out.exists() and leftovers(tmp_path) == []


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGKILL])
def test_an_interrupted_simulation_leaves_the_old_file(tmp_path, sig):
    out = tmp_path / "obs.csv"
    out.write_text("old\n")
    p = _start("machine", "simulate", EXAMPLE_MACHINE, "--points", 400000, "--out", out)
    dt, so, se = _interrupt(p, 2.0, sig)
    if p.returncode == 0:
        assert sum(1 for _ in open(out)) == 400001
        return
    assert out.read_text() == "old\n"
    if sig == signal.SIGINT:
        assert dt < 1.0 * (os.cpu_count() or 1), f"answered Ctrl-C after {dt:.2f} s of CPU"
        assert p.returncode == 130 and se.strip() == "gagekit: error: interrupted", se
        assert leftovers(tmp_path) == []


def test_a_killed_report_folder_is_old_or_absent(tmp_path):
    from .conftest import CASTING_PLY, CASTING_TOML

    rep = tmp_path / "rep"
    p = _start("gage", "check", CASTING_PLY, CASTING_TOML, "--report", rep)
    _interrupt(p, 3.0, signal.SIGKILL)
    # killed before the rename: no folder; after it: the complete report (never a part of it)
    if rep.exists():
        assert (rep / "report.html").exists() and (rep / ".gagekit-report").exists()
    assert [x.name for x in tmp_path.iterdir() if x.name != "rep" and ".gk-tmp" not in x.name] == []
