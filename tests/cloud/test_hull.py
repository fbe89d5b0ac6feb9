"""Convex-hull filter (Sec. 5.4.1, Eq. 5.21): properties, degenerate input, peers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.optimize import linprog
from scipy.spatial import ConvexHull

import gagekit
from gagekit.errors import InvalidInputError

from conftest import NIST as _NIST

REF = _NIST


def hull_idx(points) -> np.ndarray:
    idx = gagekit.convex_hull_indices(points)
    assert idx.dtype == np.int64
    assert np.all(np.diff(idx) > 0), "ascending, no repeats"
    return idx


def in_hull(vertices: np.ndarray, x: np.ndarray) -> bool:
    """Is x a convex combination of the rows of vertices (LP feasibility)?"""
    k = len(vertices)
    if k == 0:
        return False
    a_eq = np.vstack([vertices.T, np.ones((1, k))])
    b_eq = np.append(x, 1.0)
    res = linprog(np.zeros(k), A_eq=a_eq, b_eq=b_eq, bounds=[(0, None)] * k, method="highs")
    return res.status == 0


def noisy_patch(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.c_[rng.uniform(0, 200, n), rng.uniform(0, 150, n), rng.normal(0, 0.02, n)]


def random_rotation(angles) -> np.ndarray:
    a, b, g = angles
    rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rx = np.array([[1, 0, 0], [0, np.cos(g), -np.sin(g)], [0, np.sin(g), np.cos(g)]])
    return rz @ ry @ rx


# ---------------------------------------------------------------- properties

# magnitudes below 1e-60 are rejected by design (see test_out_of_range_names_the_point)
coords = st.floats(min_value=-100, max_value=100, allow_nan=False, width=64).map(lambda v: 0.0 if abs(v) < 1e-60 else v)
clouds = arrays(np.float64, st.tuples(st.integers(5, 60), st.just(3)), elements=coords)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(clouds)
def test_every_point_inside_hull_of_result(pts):
    idx = hull_idx(pts)
    sub = pts[idx]
    try:
        eq = ConvexHull(sub).equations
    except Exception:  # lower-dimensional result: check each point by LP
        assert all(in_hull(sub, x) for x in pts)
        return
    scale = np.abs(pts).max() + 1.0
    assert np.all(pts @ eq[:, :3].T + eq[:, 3] <= 1e-9 * scale)


grids = arrays(np.float64, st.tuples(st.integers(4, 25), st.just(3)), elements=st.integers(0, 3).map(float))


@settings(max_examples=40, deadline=None)
@given(grids)
def test_degenerate_integer_clouds_exact_and_minimal(pts):
    """Small integer coordinates: coplanar faces, points on edges, duplicates."""
    idx = hull_idx(pts)
    sub = pts[idx]
    assert len(np.unique(sub, axis=0)) == len(sub), "no duplicate vertices"
    for x in pts:
        assert in_hull(sub, x)
    for k in range(len(sub)):
        assert not in_hull(np.delete(sub, k, axis=0), sub[k]), f"vertex {sub[k]} is not extreme"
    # among duplicates the lowest index is reported
    for i in idx:
        assert not np.any(np.all(pts[:i] == pts[i], axis=1))


@settings(max_examples=40, deadline=None)
@given(clouds, st.randoms(use_true_random=False))
def test_invariant_under_point_order(pts, rnd):
    perm = np.arange(len(pts))
    rnd.shuffle(perm)
    a = {tuple(p) for p in pts[hull_idx(pts)]}
    b = {tuple(p) for p in pts[perm][hull_idx(pts[perm])]}
    assert a == b


@settings(max_examples=30, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(8, 300),
    st.tuples(*[st.floats(-np.pi, np.pi)] * 3),
    st.tuples(*[st.floats(-1e3, 1e3)] * 3),
)
def test_invariant_under_rigid_motion(seed, n, angles, shift):
    pts = np.random.default_rng(seed).normal(size=(n, 3)) * [30.0, 20.0, 10.0]
    moved = pts @ random_rotation(angles).T + np.asarray(shift)
    np.testing.assert_array_equal(hull_idx(pts), hull_idx(moved))


# ---------------------------------------------------------------- peers, reference data


@pytest.mark.parametrize(
    "make",
    [
        lambda r: r.normal(size=(5000, 3)),
        lambda r: r.uniform(-1, 1, size=(20000, 3)),
        lambda r: noisy_patch(50_000, int(r.integers(1 << 30))),
        lambda r: noisy_patch(20_664, 7) @ random_rotation((0.3, -1.1, 0.7)).T,
        lambda r: noisy_patch(300_000, 8),
        lambda r: r.normal(size=(300_000, 3)) * [50.0, 20.0, 3.0],
    ],
    ids=["ball", "cube", "patch", "tilted-face", "patch-300k", "ellipsoid-300k"],
)
def test_agrees_with_qhull(make):
    pts = make(np.random.default_rng(42))
    np.testing.assert_array_equal(hull_idx(pts), np.sort(ConvexHull(pts).vertices))


def test_scanned_face_like_table_5_2():
    """A nearly planar face of 20,664 points keeps a few hundred at most (Table 5.2: 87)."""
    idx = hull_idx(noisy_patch(20_664, 3))
    assert 20 < len(idx) < 400


def nist_sets():
    return sorted(REF.glob("*/*.ds")) if REF.exists() else []


@pytest.mark.skipif(not nist_sets(), reason="reference data not available")
@pytest.mark.parametrize("path", nist_sets(), ids=lambda p: p.stem)
def test_nist_reference_sets_agree_with_qhull(path):
    pts = np.loadtxt(path, skiprows=1).reshape(-1, 3)
    idx = hull_idx(pts)
    flat = [k for k in range(3) if np.ptp(pts[:, k]) == 0.0]
    if len(pts) < 4:  # too few for Qhull: all distinct points are vertices here
        want = np.unique(pts, axis=0, return_index=True)[1]
    elif flat:  # an exactly planar 2-D set: compare with the 2-D hull
        keep = [k for k in range(3) if k not in flat]
        want = ConvexHull(pts[:, keep]).vertices
    else:
        want = ConvexHull(pts).vertices
    np.testing.assert_array_equal(idx, np.sort(want))


# ---------------------------------------------------------------- degenerate input


def test_empty_and_few_points():
    assert hull_idx(np.empty((0, 3))).size == 0
    assert hull_idx([[1.0, 2.0, 3.0]]).tolist() == [0]
    assert hull_idx([[1.0, 2.0, 3.0], [1.0, 2.0, 3.0]]).tolist() == [0]
    assert hull_idx([[0, 0, 0], [1, 0, 0]]).tolist() == [0, 1]
    assert hull_idx([[0, 0, 0], [1, 0, 0], [0, 1, 0]]).tolist() == [0, 1, 2]
    assert hull_idx([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]).tolist() == [0, 1, 2, 3]


def test_duplicates_give_lowest_index():
    pts = np.array([[1, 1, 1], [0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1], [0, 0, 0]], float)
    assert hull_idx(pts).tolist() == [0, 1, 2, 3, 4]


def test_collinear_gives_end_points():
    t = np.random.default_rng(1).permutation(100).astype(float)
    pts = np.c_[t, 2 * t - 7, -0.5 * t]
    assert hull_idx(pts).tolist() == sorted([int(np.argmin(t)), int(np.argmax(t))])


def test_exactly_planar_gives_polygon():
    # a regular grid in the tilted plane z = x - 2 y, with interior and edge points
    x, y = np.meshgrid(np.arange(30.0), np.arange(20.0), indexing="ij")
    pts = np.c_[x.ravel(), y.ravel(), x.ravel() - 2 * y.ravel()]
    corners = [0, 19, 29 * 20, 29 * 20 + 19]
    assert hull_idx(pts).tolist() == corners
    # a planar disc: the vertices of its 2-D hull
    rng = np.random.default_rng(5)
    uv = rng.normal(size=(5000, 2))
    disc = np.c_[uv, np.full(5000, 12.5)]
    np.testing.assert_array_equal(hull_idx(disc), np.sort(ConvexHull(uv).vertices))


def test_cube_grid_gives_corners():
    g = np.stack(np.meshgrid(*[np.arange(7.0)] * 3, indexing="ij"), -1).reshape(-1, 3)
    got = g[hull_idx(g)]
    assert len(got) == 8 and set(map(tuple, got)) == {(a, b, c) for a in (0, 6) for b in (0, 6) for c in (0, 6)}


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf, 1e300, -1e-200])
def test_non_finite_or_out_of_range_names_the_point(bad):
    pts = np.zeros((6, 3))
    pts[4, 1] = bad
    with pytest.raises(InvalidInputError, match="point 4"):
        gagekit.convex_hull_indices(pts)


def test_wrong_shape_and_type():
    with pytest.raises(InvalidInputError):
        gagekit.convex_hull_indices(np.zeros((5, 2)))
    with pytest.raises(InvalidInputError):
        gagekit.convex_hull_indices([["a", "b", "c"]])


def test_accepts_lists_and_non_contiguous_arrays():
    pts = np.random.default_rng(3).normal(size=(200, 6))[:, ::2]
    np.testing.assert_array_equal(hull_idx(pts), hull_idx(pts.tolist()))
