"""Least-squares lines, planes, spheres, 3-D circles and cylinders: invariants, errors, CLI.

The NIST agreement is in test_nist.py; the minimax cylinders in test_form3d_cylinder.py.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gagekit
from gagekit.errors import ConfigError, DegenerateGeometryError, InvalidInputError


def rotation(angles) -> np.ndarray:
    a, b, g = angles
    rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rx = np.array([[1, 0, 0], [0, np.cos(g), -np.sin(g)], [0, np.sin(g), np.cos(g)]])
    return rz @ ry @ rx


def noisy_cylinder(rng, n=60, r=10.0, length=30.0, noise=0.01):
    t = rng.uniform(0, 2 * np.pi, n)
    z = rng.uniform(-length / 2, length / 2, n)
    rr = r + rng.normal(0, noise, n)
    return np.column_stack([rr * np.cos(t), rr * np.sin(t), z])


def noisy_sphere(rng, n=50, r=7.0, noise=0.01):
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1)[:, None]
    return v * (r + rng.normal(0, noise, n))[:, None]


def angle(a, b):
    return float(np.arctan2(np.linalg.norm(np.cross(a, b)), abs(np.dot(a, b))))


def line_dist(p, q, a):
    d = np.asarray(p) - np.asarray(q)
    a = np.asarray(a) / np.linalg.norm(a)
    return float(np.linalg.norm(d - (d @ a) * a))


seeds = st.integers(0, 2**32 - 1)
angles3 = st.tuples(*[st.floats(-np.pi, np.pi)] * 3)
shifts = st.tuples(*[st.floats(-1e6, 1e6)] * 3)


@settings(max_examples=25, deadline=None)
@given(seeds, angles3, shifts)
def test_cylinder_rigid_motion_and_order(seed, ang, shift):
    rng = np.random.default_rng(seed)
    pts = noisy_cylinder(rng)
    base = gagekit.fit_cylinder(pts)
    R, t = rotation(ang), np.array(shift)
    moved = pts @ R.T + t
    perm = rng.permutation(len(pts))
    r = gagekit.fit_cylinder(moved[perm])
    assert abs(r.radius - base.radius) < 1e-9
    assert angle(r.direction, R @ base.direction) < 1e-9
    assert line_dist(R @ base.point + t, r.point, r.direction) < 1e-8
    assert abs(r.form_error - base.form_error) < 1e-9


@settings(max_examples=25, deadline=None)
@given(seeds, angles3, shifts)
def test_sphere_plane_line_circle_rigid_motion(seed, ang, shift):
    rng = np.random.default_rng(seed)
    R, t = rotation(ang), np.array(shift)
    s = noisy_sphere(rng)
    a, b = gagekit.fit_sphere(s), gagekit.fit_sphere(s[::-1] @ R.T + t)
    assert abs(a.radius - b.radius) < 1e-9
    assert np.linalg.norm(R @ a.center + t - b.center) < 1e-8

    c = noisy_cylinder(rng, r=5.0, length=0.0)  # a noisy circle in the x-y plane
    c[:, 2] = rng.normal(0, 0.01, len(c))
    a, b = gagekit.fit_circle_3d(c), gagekit.fit_circle_3d(c[::-1] @ R.T + t)
    assert abs(a.radius - b.radius) < 1e-9 and angle(R @ a.normal, b.normal) < 1e-9
    assert np.linalg.norm(R @ a.center + t - b.center) < 1e-8

    p = np.column_stack([rng.uniform(-20, 20, (40, 2)), rng.normal(0, 0.01, 40)])
    a, b = gagekit.fit_plane(p), gagekit.fit_plane(p[::-1] @ R.T + t)
    assert angle(R @ a.normal, b.normal) < 1e-9 and abs(a.form_error - b.form_error) < 1e-9

    ln = np.outer(rng.uniform(-50, 50, 30), [1.0, 2.0, -0.5]) + rng.normal(0, 0.01, (30, 3))
    a, b = gagekit.fit_line(ln), gagekit.fit_line(ln[::-1] @ R.T + t)
    assert angle(R @ a.direction, b.direction) < 1e-9
    assert line_dist(R @ a.point + t, b.point, b.direction) < 1e-8


def test_exact_features_recovered():
    rng = np.random.default_rng(1)
    pts = noisy_cylinder(rng, noise=0.0)
    r = gagekit.fit_cylinder(pts, "lsq")
    assert abs(r.radius - 10.0) < 1e-12 and r.form_error < 1e-12
    assert abs(r.certificate.max_distance - 10.0) < 1e-12
    assert r.theta < 1e-12  # axis along z
    s = gagekit.fit_sphere(noisy_sphere(rng, noise=0.0) + [1, 2, 3])
    assert abs(s.radius - 7.0) < 1e-12 and np.allclose(s.center, [1, 2, 3], atol=1e-12)


def test_line_2d_and_certificates():
    x = np.linspace(0, 10, 11)
    y = 2 * x + 1 + np.where(np.arange(11) % 2, 0.01, -0.01)
    r = gagekit.fit_line(np.column_stack([x, y]))
    assert len(r.direction) == 2 and angle([*r.direction, 0], [1, 2, 0]) < 1e-3
    assert r.certificate.min_distance < 0 < r.certificate.max_distance
    assert r.form_error == pytest.approx(r.certificate.max_distance - r.certificate.min_distance)
    d = r.to_dict()
    assert d["shape"] == "line" and d["criterion"] == "least-squares" and d["n_points"] == 11
    json.dumps(d)


@pytest.mark.parametrize(
    "fn, pts, err",
    [
        (gagekit.fit_line, np.ones((5, 3)), DegenerateGeometryError),
        (gagekit.fit_line, np.zeros((1, 3)), InvalidInputError),
        (gagekit.fit_plane, np.outer(np.arange(5.0), [1, 2, 3]), DegenerateGeometryError),
        (gagekit.fit_plane, np.zeros((2, 3)), InvalidInputError),
        (gagekit.fit_sphere, np.column_stack([np.eye(3)[:, :2] * 0 + np.random.default_rng(0).normal(size=(3, 2)), np.zeros(3)]), InvalidInputError),
        (gagekit.fit_sphere, np.column_stack([np.random.default_rng(0).normal(size=(9, 2)), np.zeros(9)]), DegenerateGeometryError),
        (gagekit.fit_sphere, np.outer(np.arange(5.0), [1, 2]), DegenerateGeometryError),
        (gagekit.fit_circle_3d, np.outer(np.arange(5.0), [1, 2, 3]), DegenerateGeometryError),
        (gagekit.fit_cylinder, np.outer(np.arange(9.0), [1, 2, 3]), DegenerateGeometryError),
        (gagekit.fit_cylinder, np.zeros((4, 3)), InvalidInputError),
        (gagekit.fit_cylinder, np.array([[0, 0, np.nan]] * 9), InvalidInputError),
        (gagekit.fit_cylinder, np.zeros((9, 2)), InvalidInputError),
        (gagekit.fit_plane, [[1, 2, "x"]] * 3, InvalidInputError),
        (gagekit.fit_line, np.zeros((0, 3)), InvalidInputError),
        (gagekit.fit_cone, np.outer(np.arange(9.0), [1, 2, 3]), DegenerateGeometryError),
        (gagekit.fit_cone, np.random.default_rng(0).normal(size=(5, 3)), InvalidInputError),
    ],
)
def test_bad_input_raises_gagekit_errors(fn, pts, err):
    with pytest.raises(err) as exc:
        fn(pts)
    assert str(exc.value)


def test_unknown_criterion():
    with pytest.raises(ConfigError, match="unknown fit criterion"):
        gagekit.fit_cylinder(np.zeros((9, 3)), "best")
    with pytest.raises(ConfigError):
        gagekit.fit_plane(np.eye(3), "max-inscribed")


def test_results_are_frozen():
    r = gagekit.fit_plane(np.eye(3))
    with pytest.raises(Exception):
        r.form_error = 0.0  # type: ignore[misc]


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "gagekit", "form", *args], capture_output=True, text=True, timeout=120)


def test_cli_fit_json(tmp_path):
    rng = np.random.default_rng(3)
    f = tmp_path / "cyl.csv"
    np.savetxt(f, noisy_cylinder(rng), delimiter=",", header="x,y,z", comments="")
    out = _cli("fit", "cylinder", str(f), "--json")
    assert out.returncode == 0, out.stderr
    d = json.loads(out.stdout)
    assert d["shape"] == "cylinder" and d["n_points"] == 60
    assert set(d["certificate"]) == {"min_distance", "max_distance"}
    assert abs(d["radius"] - 10.0) < 0.01
    ds = tmp_path / "s.ds"
    s = noisy_sphere(rng)
    ds.write_text(f"{len(s)}\n" + "\n".join(" ".join(map(str, p)) for p in s))
    d = json.loads(_cli("fit", "sphere", str(ds), "--json").stdout)
    assert d["shape"] == "sphere" and abs(d["radius"] - 7.0) < 0.01
    txt = _cli("cylinder", str(f))
    assert txt.returncode == 0 and "axis_direction" in txt.stdout


def test_cli_errors(tmp_path):
    bad = tmp_path / "bad.txt"
    bad.write_text("1 2 3\n4 five 6\n")
    for args in (("fit", "plane", str(bad)), ("fit", "cone", str(bad)), ("cylinder", str(tmp_path / "none.csv"))):
        out = _cli(*args)
        assert out.returncode == 2 and out.stdout == "" and out.stderr.startswith("gagekit: error:")


@settings(max_examples=20, deadline=None)
@given(seeds, angles3, shifts)
def test_min_zone_plane_is_minimal_and_invariant(seed, ang, shift):
    rng = np.random.default_rng(seed)
    p = np.column_stack([rng.uniform(-30, 30, (60, 2)), rng.normal(0, 0.02, 60)])
    mz, ls = gagekit.fit_plane(p, "minimum-zone"), gagekit.fit_plane(p)
    assert mz.form_error <= ls.form_error + 1e-12
    c = mz.certificate
    assert abs((c.max_distance - c.min_distance) - mz.form_error) < 1e-12
    n = np.array(mz.normal)
    u = np.cross(n, [1.0, 0, 0]) if abs(n[0]) < 0.9 else np.cross(n, [0, 1.0, 0])
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    for e in (1e-6, 1e-4):
        for d in (u, -u, v, -v):
            m = (n + e * d) / np.linalg.norm(n + e * d)
            h = p @ m
            assert np.ptp(h) >= mz.form_error - 1e-12
    R, t = rotation(ang), np.array(shift)
    moved = gagekit.fit_plane(p[::-1] @ R.T + t, "mz")
    assert abs(moved.form_error - mz.form_error) < 1e-9


def test_min_zone_line_2d():
    x = np.linspace(0, 100, 40)
    y = 0.2 * x + 0.01 * np.sin(x)
    y[7] += 0.5  # one bump pulls the least-squares line
    pts = np.column_stack([x, y])
    mz, ls = gagekit.fit_line(pts, "minimum-zone"), gagekit.fit_line(pts)
    assert mz.form_error < ls.form_error
    assert 7 in mz.control_points
    # in space: the thinnest enclosing cylinder around a bent 3-D line
    rng = np.random.default_rng(2)
    t = np.linspace(0, 50, 60)
    p3 = np.outer(t, [0.6, 0.0, 0.8]) + rng.normal(0, 0.005, (60, 3)) + [1e6, 0, 0]
    z3, l3 = gagekit.fit_line(p3, "minimum-zone"), gagekit.fit_line(p3)
    assert z3.form_error <= l3.form_error + 1e-12
    assert abs(z3.form_error - 2 * z3.certificate.max_distance) < 1e-12
