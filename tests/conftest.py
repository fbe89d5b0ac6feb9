"""Shared test settings: where the read-only reference data lives; the example machine."""

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# shared/ sits beside the checkout (../shared), in development and in CI.
SHARED = Path(os.environ.get("GAGEKIT_SHARED", ROOT.parent / "shared"))
if not (SHARED / "reference-data").is_dir():
    raise RuntimeError(f"reference data not found at {SHARED}; set GAGEKIT_SHARED to the shared/ folder")
REFERENCE = SHARED / "reference-data"
# the dissertation's 5-axis machine (Eq. 3.1, Table 3.1), as shipped in shared/examples
EXAMPLE_MACHINE = SHARED / "examples" / "dissertation-5axis.toml"


@pytest.fixture(scope="session")
def machine():
    import gagekit

    return gagekit.load_machine(EXAMPLE_MACHINE)


@pytest.fixture(scope="session")
def structure(machine):
    return machine.structure()
