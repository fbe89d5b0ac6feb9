"""IndexedCloud: grid queries give exactly what a full classification gives."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gagekit import GagekitError, select
from gagekit.cloud.grid import IndexedCloud
from gagekit.cloud.regions import Box


def _cloud(n=20000, seed=0):
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-50, 50, (n, 3)) * [1.0, 0.6, 0.2]
    pts[: n // 10] = np.round(pts[: n // 10])  # lattice points: on faces and cell borders
    return pts


CLOUD = _cloud()
INDEX = IndexedCloud(CLOUD, per_cell=16)

coord = st.floats(-60, 60, allow_nan=False)
size = st.floats(0.01, 120, allow_nan=False)
angle = st.floats(-3.2, 3.2, allow_nan=False)


@settings(max_examples=150, deadline=None)
@given(st.tuples(coord, coord, coord), st.tuples(size, size, size), st.tuples(angle, angle, angle))
def test_grid_matches_full_pass(center, sz, rot):
    box = Box(center, sz, rot)
    want = select(CLOUD, box)
    got = INDEX.select(box)
    assert np.array_equal(got, want)
    assert INDEX.count(box) == len(want)


def test_axis_aligned_lattice_boundary_is_inside():
    pts = np.array([[i, j, k] for i in range(-5, 6) for j in range(-5, 6) for k in range(-2, 3)], dtype=float)
    ic = IndexedCloud(pts, per_cell=2)
    box = Box((0, 0, 0), (4, 2, 2))
    assert ic.count(box) == 5 * 3 * 3
    assert np.array_equal(ic.select(box), select(pts, box))


def test_points_are_read_only_and_bad_input_raises():
    ic = IndexedCloud(CLOUD.copy())
    with pytest.raises(ValueError):
        ic.points[0, 0] = 1.0
    with pytest.raises(GagekitError):
        IndexedCloud(np.zeros((0, 3)))
    bad = CLOUD[:10].copy()
    bad[3, 1] = np.nan
    with pytest.raises(GagekitError, match="point 3"):
        IndexedCloud(bad)
    assert len(ic) == len(CLOUD) and ic.cell_size > 0
    lo, hi = ic.bounds
    assert np.array_equal(lo, CLOUD.min(axis=0)) and np.array_equal(hi, CLOUD.max(axis=0))
