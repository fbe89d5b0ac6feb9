"""End-to-end tests of the `gagekit` console script."""

import subprocess
import sys

import gagekit


def run(*args, check=True):
    proc = subprocess.run(
        [sys.executable, "-m", "gagekit", *args], capture_output=True, text=True, timeout=600
    )
    if check:
        assert proc.returncode == 0, proc.stderr
    return proc


def test_version():
    assert run("--version").stdout.strip() == f"gagekit {gagekit.__version__}"


def test_help_lists_the_groups():
    out = run("--help").stdout
    for group in ("cloud", "form", "gage", "machine", "demo"):
        assert group in out
