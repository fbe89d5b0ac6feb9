"""The public API type-checks for a strict client: ``mypy --strict`` on a small script that
uses it (tests/data/typing/use_api.py), with the package's own stubs (the generated _core/*.pyi, py.typed; tests/test_stubs.py
keeps them current)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest


SCRIPT = Path(__file__).parent / "data" / "typing" / "use_api.py"


def test_a_strict_client_type_checks(tmp_path):
    pytest.importorskip("mypy")
    # errors inside gagekit itself are not the client's: follow its imports silently
    proc = subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--follow-imports=silent", "--no-incremental",
         "--cache-dir", str(tmp_path / "cache"), str(SCRIPT)],
        capture_output=True, text=True, timeout=600,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
