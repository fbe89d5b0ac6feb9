"""Every import of the package is declared in pyproject.toml, and every declared dependency is
used (issue 22 item 1: scipy was imported by `machine export` but only in the test extra; rich
came only through Typer). deptry checks the package against pyproject.toml's [tool.deptry]:
missing (DEP001), unused (DEP002), transitive (DEP003) dependencies, and the package importing
a package of the development-only `test` extra (DEP004)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

from servers import unavailable

ROOT = Path(__file__).resolve().parents[1]


def _deptry() -> list[str]:
    exe = shutil.which("deptry", path=str(Path(sys.executable).parent)) or shutil.which("deptry")
    if exe is None:
        unavailable("deptry is not installed (pip install '.[test]' brings it)")
    return [exe]


def test_deptry_finds_no_dependency_issue():
    p = subprocess.run([*_deptry(), "python"], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr


def test_deptry_refuses_a_test_only_import(tmp_path):
    """The configuration can fail: the package importing scipy (test extra only) is an error."""
    pkg = tmp_path / "python" / "gagekit"
    shutil.copytree(ROOT / "python" / "gagekit", pkg, ignore=shutil.ignore_patterns("*.so", "data", "__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    (pkg / "uses_scipy.py").write_text("import scipy\n")
    p = subprocess.run([*_deptry(), "python"], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert p.returncode != 0 and "DEP004" in p.stdout + p.stderr and "scipy" in p.stdout + p.stderr
