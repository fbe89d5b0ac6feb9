"""The public API type-checks for a strict client: ``mypy --strict`` on a small script that
uses it (tests/data/typing/use_api.py), with the package's own stubs (_core.pyi, py.typed)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

import gagekit

SCRIPT = Path(__file__).parent / "data" / "typing" / "use_api.py"


def test_package_ships_its_types():
    pkg = Path(gagekit.__file__).parent
    assert (pkg / "py.typed").is_file()
    assert (pkg / "_core.pyi").is_file()


def test_a_strict_client_type_checks(tmp_path):
    pytest.importorskip("mypy")
    # errors inside gagekit itself are not the client's: follow its imports silently
    proc = subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--follow-imports=silent", "--no-incremental",
         "--cache-dir", str(tmp_path / "cache"), str(SCRIPT)],
        capture_output=True, text=True, timeout=600,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_the_stub_lists_every_binding():
    # every public name of the extension is declared in _core.pyi (and nothing stale)
    from gagekit import _core

    stub = (Path(gagekit.__file__).parent / "_core.pyi").read_text()
    public = {n for n in dir(_core) if not n.startswith("__")}
    declared = set(re.findall(r"^(?:def |class )?(\w+)\s*[(:]", stub, flags=re.M)) - {"from", "import"}
    assert public - declared == set()
    assert {n for n in declared if not n.startswith("_")} - public == set()
