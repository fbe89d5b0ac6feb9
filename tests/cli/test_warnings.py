"""Warnings go to stderr as `gagekit: warning: ...` in the command line's words (issue 22
section 6): never inside the stdout table, never naming Python arguments (`max_tilt=90`)."""

from __future__ import annotations

import json
import subprocess
import sys

from gagekit.samples import sample_path


def _fit(*extra: str) -> subprocess.CompletedProcess:
    # the bore leans 0.2 degrees from z: a reference axis 5.7 degrees off with a 1-degree cone
    # puts the axis on the cone's boundary and finds a better zone outside it
    return subprocess.run([sys.executable, "-m", "gagekit", "form", "fit", "cylinder", str(sample_path("bore")),
                           "-c", "minimum-zone", "--axis", "0.1,0,1", "--max-tilt", "1", *extra],
                          capture_output=True, text=True, timeout=300)


def test_fit_warnings_go_to_stderr_naming_options():
    p = _fit()
    assert p.returncode == 0, p.stderr
    assert "warning" not in p.stdout
    lines = p.stderr.splitlines()
    assert len(lines) == 2 and all(ln.startswith("gagekit: warning: ") for ln in lines), p.stderr
    assert "pass --max-tilt 90 to accept it" in p.stderr and "(--axis X,Y,Z)" in p.stderr
    assert "max_tilt" not in p.stderr and "axis=" not in p.stderr


def test_json_keeps_the_warnings_and_stderr_says_them():
    p = _fit("--json")
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    assert len(d["warnings"]) == 2
    assert p.stderr.count("gagekit: warning: ") == 2


def test_cli_wording():
    from gagekit.cli._common import cli_wording

    assert cli_wording("outside max_tilt = 10 degrees; pass max_tilt=90") == "outside --max-tilt 10 degrees; pass --max-tilt 90"
    assert cli_wording("give the nominal axis (axis=...)") == "give the nominal axis (--axis X,Y,Z)"
    assert cli_wording("the x axis of the\nframe") == "the x axis of the frame"


def test_one_place_prints_warnings():
    """Every `gagekit: warning:` line of the command line comes from cli._common.warn."""
    from pathlib import Path

    import gagekit

    cli = Path(gagekit.__file__).parent / "cli"
    offenders = [f.name for f in cli.glob("*.py") if f.name != "_common.py" and "gagekit: warning: {" in f.read_text()]
    assert not offenders, offenders
