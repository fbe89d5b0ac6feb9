"""Shared test settings: where the read-only reference data lives."""

import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# shared/ sits beside the checkout (../shared), in development and in CI.
SHARED = Path(os.environ.get("GAGEKIT_SHARED", ROOT.parent / "shared"))
if not (SHARED / "reference-data").is_dir():
    raise RuntimeError(f"reference data not found at {SHARED}; set GAGEKIT_SHARED to the shared/ folder")
REFERENCE = SHARED / "reference-data"
