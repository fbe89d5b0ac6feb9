"""Chebyshev spheres (issue 13 part 4): minimum circumscribed (Welzl, exact), maximum
inscribed, minimum zone, with certificates; properties as for circles."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gagekit
from gagekit.errors import ConfigError, DegenerateGeometryError


def sphere_points(seed: int, n: int = 200, r: float = 25.0, noise: float = 0.01, c=(5.0, -3.0, 2.0)) -> np.ndarray:
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1)[:, None]
    return np.asarray(c) + v * (r + rng.uniform(-noise, noise, n))[:, None]


def test_criteria_order_and_certificates():
    pts = sphere_points(0)
    ls, mc, mi, mz = (gagekit.fit_sphere(pts, c) for c in ("lsq", "mcc", "mic", "mzc"))
    assert mi.radius <= ls.radius <= mc.radius
    assert mz.form_error <= ls.form_error + 1e-12 and mz.form_error <= 0.02 + 1e-12
    for f in (mc, mi, mz):
        d = np.linalg.norm(pts - f.center, axis=1)
        assert d.min() == pytest.approx(f.certificate.min_distance, abs=1e-12)
        assert d.max() == pytest.approx(f.certificate.max_distance, abs=1e-12)
    assert mc.radius == mc.certificate.max_distance and mi.radius <= mi.certificate.min_distance + 1e-12
    assert mz.inner_radius == mz.certificate.min_distance and mz.outer_radius == mz.certificate.max_distance
    assert set(mc.to_dict()) >= {"control_points", "certificate", "radius", "center"}


def test_bad_sphere_input():
    flat = np.column_stack([np.cos(np.arange(9.0)), np.sin(np.arange(9.0)), np.zeros(9)])
    with pytest.raises(DegenerateGeometryError):
        gagekit.fit_sphere(flat, "mz")
    assert gagekit.fit_sphere(flat, "mc").radius == pytest.approx(1.0, abs=1e-12)
    with pytest.raises(ConfigError):
        gagekit.fit_sphere(flat[:, :2], "mc")
    with pytest.raises(ConfigError):
        gagekit.fit_sphere(flat, "median")


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000), st.integers(5, 80), st.floats(-1e5, 1e5), st.floats(0, 6.28))
def test_properties(seed, n, shift, angle):
    pts = sphere_points(seed, n, noise=0.2)
    R = np.array([[np.cos(angle), 0, np.sin(angle)], [0, 1, 0], [-np.sin(angle), 0, np.cos(angle)]])
    moved = pts @ R.T + shift
    for crit in ("mc", "mi", "mz"):
        a, b = gagekit.fit_sphere(pts, crit), gagekit.fit_sphere(moved, crit)
        # invariance under rigid motion (the MI's centre can slide where fewer than four
        # points bind it, so only its radius is unique)
        tol = 1e-7 * (1 + abs(shift))
        assert abs(a.radius - b.radius) < tol
        if crit != "mi":
            assert abs(a.form_error - b.form_error) < tol
    mc = gagekit.fit_sphere(pts, "mc")
    # containment and optimality of the MC: every point inside, the control points on it,
    # and the centre in the convex hull of the control points (the optimality condition)
    ctrl = pts[list(mc.control_points)]
    assert np.all(np.linalg.norm(pts - mc.center, axis=1) <= mc.radius)
    assert np.allclose(np.linalg.norm(ctrl - mc.center, axis=1), mc.radius, atol=1e-9)
    w, *_ = np.linalg.lstsq(np.vstack([ctrl.T, np.ones(len(ctrl))]), np.append(mc.center, 1.0), rcond=None)
    assert np.all(w >= -1e-7)
    # adding a point never decreases the MC
    more = np.vstack([pts, pts[0] * 1.01])
    assert gagekit.fit_sphere(more, "mc").radius >= mc.radius - 1e-12
    # the zone is no wider than about the least-squares centre
    ls = gagekit.fit_sphere(pts, "lsq")
    assert gagekit.fit_sphere(pts, "mz").form_error <= ls.form_error + 1e-12


def test_global_bound_certifies_mi_and_mz():
    """Issue 13: MI and MZ are global (certified branch and bound over the centre); the
    bound is within 1e-9 mm of the value, on the right side of it."""
    rng = np.random.default_rng(7)
    u = rng.normal(size=(400, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    u = u[u[:, 2] > 0.3]  # a cap: the centre is loosely held along its axis
    pts = np.array([4.0, -2.0, 9.0]) + (30.0 + rng.uniform(-0.02, 0.02, len(u)))[:, None] * u
    mz = gagekit.fit_sphere(pts, "minimum-zone")
    mi = gagekit.fit_sphere(pts, "max-inscribed")
    assert mz.global_bound <= mz.form_error + 1e-15 and mz.form_error - mz.global_bound <= 1e-9
    assert mi.global_bound >= mi.radius - 1e-15 and mi.global_bound - mi.radius <= 1e-9
    assert mz.to_dict()["global_bound"] == mz.global_bound
    assert gagekit.fit_sphere(pts, "min-circumscribed").global_bound is None
