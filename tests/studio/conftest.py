"""Shared pieces of the studio tests: a small plate scan made here, the bundled casting."""

from pathlib import Path

import numpy as np
import pytest

import gagekit
from gagekit.demo import data_path

CASTING = data_path("casting_ok.ply")
CASTING_SPEC = data_path("casting_ok.toml")
DATA = Path(__file__).with_name("data")


def plate_points(seed: int = 0) -> np.ndarray:
    """A 100 x 60 x 10 mm plate: top face at z = 10 with 0.02 mm noise, bottom at 0, four sides."""
    rng = np.random.default_rng(seed)
    top = np.column_stack([rng.uniform(0, 100, 6000), rng.uniform(0, 60, 6000), 10 + rng.normal(0, 0.02, 6000)])
    bottom = np.column_stack([rng.uniform(0, 100, 3000), rng.uniform(0, 60, 3000), np.zeros(3000)])
    sx = np.column_stack([rng.choice([0.0, 100.0], 1500), rng.uniform(0, 60, 1500), rng.uniform(0, 10, 1500)])
    sy = np.column_stack([rng.uniform(0, 100, 1500), rng.choice([0.0, 60.0], 1500), rng.uniform(0, 10, 1500)])
    return np.vstack([top, bottom, sx, sy])


@pytest.fixture()
def plate(tmp_path) -> Path:
    path = tmp_path / "plate.ply"
    gagekit.write_points(path, plate_points())
    return path
