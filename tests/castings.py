"""A small plant's worth of simulated casting scans for the batch, store and SPC tests.

Castings of the bundled ``casting_ok`` pattern (gagekit/data/make_castings.py), each with
its own seed (form errors, noise) and its own pose on the spacers (shift, tilt), scanned by
the same scanner over the same fixture, so the bundled ``casting_ok.toml`` applies to all.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from gagekit.data.make_castings import make_casting, write_ply
from gagekit.samples import data_path

N_SCANS = 8
DENSITY = 0.25  # points per mm^2: about 20 000 points a scan, quick to check


def pose(k: int) -> dict:
    """Varied poses: shifts of 1.5-4 mm, tilts of -1.2..+1.2 degrees (deterministic)."""
    rng = np.random.default_rng(1000 + k)
    return {"seed": 200 + k, "shift": tuple(rng.uniform(1.5, 4.0, size=2)), "tilt": float(rng.uniform(-0.021, 0.021))}


def write_scans(folder: Path, n: int, density: float = DENSITY, start: int = 0) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for k in range(start, start + n):
        pts, _ = make_casting("casting_ok", density=density, **pose(k))
        p = folder / f"casting_{k:03d}.ply"
        write_ply(p, pts)
        t = 1_700_000_000 + 3600 * k  # one casting an hour
        os.utime(p, (t, t))
        paths.append(p)
    return paths


@pytest.fixture(scope="session")
def casting_set(tmp_path_factory):
    """(gage file, [scan paths]) of N_SCANS castings, written once per session."""
    root = tmp_path_factory.mktemp("castings")
    gages = root / "casting.toml"
    shutil.copy(data_path("casting_ok.toml"), gages)
    return gages, write_scans(root / "scans", N_SCANS)


@pytest.fixture
def scans_copy(casting_set, tmp_path):
    """A fresh copy of the casting set (gage file, scan folder) a test may change."""
    gages, scans = casting_set
    folder = tmp_path / "scans"
    folder.mkdir()
    for p in scans:
        shutil.copy2(p, folder / p.name)
    g = tmp_path / "casting.toml"
    shutil.copy(gages, g)
    return g, sorted(folder.iterdir())
