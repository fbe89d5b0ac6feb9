"""ASTM E2807 (E57) scans. Unit: metres, by the standard."""

from __future__ import annotations

import os
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ...errors import FileFormatError
from . import Raw


@contextmanager
def _quiet_fd2():
    """Send the C-level stderr (file descriptor 2) to a temporary file for the duration:
    libE57 prints its debug dump there. Returns the captured text through the list."""
    captured: list = []
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):
        yield captured
        return
    with tempfile.TemporaryFile() as tmp:
        os.dup2(tmp.fileno(), 2)
        try:
            yield captured
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            captured.append(tmp.read().decode("utf-8", "replace"))


def read(p: Path, dim: int) -> Raw:
    try:
        import pye57
    except ImportError:
        raise FileFormatError(f"{p}: E57 needs the optional extra: pip install 'gagekit[e57]'") from None
    parts, dropped = [], 0
    with _quiet_fd2():
        try:
            e57 = pye57.E57(str(p))
            nscans = e57.scan_count
            for i in range(nscans):
                h = e57.get_header(i)
                n = h.point_count
                d = e57.read_scan(i, ignore_missing_fields=True, transform=True)
                xyz = np.column_stack([d["cartesianX"], d["cartesianY"], d["cartesianZ"]])
                dropped += n - len(xyz)
                parts.append(xyz)
        except Exception as exc:  # libE57 raises E57Exception; pye57 ValueError/KeyError
            raise FileFormatError(f"{p}: not a readable E57 file ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") from None
    if not parts:
        raise FileFormatError(f"{p}: the E57 file holds no scans")
    pts = np.ascontiguousarray(np.vstack(parts), dtype=np.float64)
    return Raw(pts, "e57", unit="m", unit_basis="E57 standard (ASTM E2807): metres", scans=len(parts), invalid_dropped=dropped)
