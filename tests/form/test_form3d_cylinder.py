"""Minimax cylinders (MCC, MIC, MZC; Sec. 6.3) and the PSO circle cross-check.

The dissertation's data sets 1 and 3: circumscribed radius no larger, inscribed radius
no smaller, zone width no larger than reported (Tables 6.2, 6.4), each up to half a unit
of the last reported digit (5e-8 mm: the tables print 7 decimals, rounded), and a 3-D
certificate consistent with the reported radii to 1e-9 mm.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gagekit
from conftest import SEED_CYLINDERS
from gagekit.errors import ConfigError, DegenerateGeometryError, InvalidInputError

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

SEED = SEED_CYLINDERS
ROUNDING = 5e-8  # half a unit of the 7th decimal printed in Tables 6.2 and 6.4
CERT_TOL = 1e-9

CRITERIA = {"mcc": "min_circumscribed", "mic": "max_inscribed", "mzc": "minimum_zone"}


def load_set(name):
    return np.loadtxt(SEED / f"{name}.csv", delimiter=",", skiprows=1)


def expected():
    with open(SEED / "expected.toml", "rb") as f:
        return tomllib.load(f)


def axis_distances(pts, point, direction):
    a = np.asarray(direction) / np.linalg.norm(direction)
    d = pts - np.asarray(point)
    return np.linalg.norm(d - np.outer(d @ a, a), axis=1)


def check_certificate(r, pts):
    d = axis_distances(pts, r.point, r.direction)
    c = r.certificate
    assert abs(c.min_distance - d.min()) < CERT_TOL and abs(c.max_distance - d.max()) < CERT_TOL
    if r.criterion == "min-circumscribed":
        assert abs(c.max_distance - r.radius) < CERT_TOL
    elif r.criterion == "max-inscribed":
        assert abs(c.min_distance - r.radius) < CERT_TOL
    else:
        assert abs(c.min_distance - r.inner_radius) < CERT_TOL
        assert abs(c.max_distance - r.outer_radius) < CERT_TOL
        assert abs(r.form_error - (r.outer_radius - r.inner_radius)) < CERT_TOL
    t, f = r.theta, r.phi
    a = [np.sin(t) * np.cos(f), np.sin(t) * np.sin(f), np.cos(t)]
    assert np.allclose(a, r.direction, atol=1e-14) and 0 <= t <= np.pi / 2


@pytest.mark.parametrize("name", ["set1", "set3"])
@pytest.mark.parametrize("crit", ["mcc", "mic", "mzc"])
def test_seed_sets_meet_reported_bounds(name, crit):
    pts = load_set(name)
    exp = expected()[name][CRITERIA[crit]]
    r = gagekit.fit_cylinder(pts, crit, seed=0)
    check_certificate(r, pts)
    if crit == "mcc":
        assert r.radius <= exp["radius"] + ROUNDING
    elif crit == "mic":
        assert r.radius >= exp["radius"] - ROUNDING
    else:
        assert r.form_error <= exp["width"] + ROUNDING
    # the axis agrees with the reported one (angles printed to ~5 digits)
    assert abs(r.theta - exp["theta"]) < 5e-5 and abs(r.phi - exp["phi"]) < 5e-3
    assert r.control_points and r.iterations > 0 and r.evaluations > 0
    json.dumps(r.to_dict())


def test_minimum_zone_is_bounded_by_lsq_and_cylinders_nest():
    pts = load_set("set3")
    lsq = gagekit.fit_cylinder(pts)
    mcc, mic, mzc = (gagekit.fit_cylinder(pts, c) for c in ("mcc", "mic", "mzc"))
    assert mzc.form_error <= lsq.form_error
    assert mic.radius <= mzc.inner_radius + mzc.form_error
    assert mic.radius < lsq.radius < mcc.radius
    assert mcc.radius <= lsq.certificate.max_distance
    assert mic.radius >= lsq.certificate.min_distance
    d = mzc.to_dict()
    assert {"inner_radius", "outer_radius", "theta", "phi", "axis_point", "axis_direction"} <= set(d)


def test_deterministic_for_a_seed():
    pts = load_set("set1")
    a = gagekit.fit_cylinder(pts, "mzc", seed=7)
    b = gagekit.fit_cylinder(pts, "mzc", seed=7)
    assert a == b


def noisy_cylinder(rng, n=80):
    t = rng.uniform(0, 2 * np.pi, n)
    z = rng.uniform(0, 60, n)
    r = 20 + 0.01 * np.sin(3 * t) + rng.normal(0, 0.002, n)
    return np.column_stack([r * np.cos(t), r * np.sin(t), z])


def rotation(a, b, g):
    rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rx = np.array([[1, 0, 0], [0, np.cos(g), -np.sin(g)], [0, np.sin(g), np.cos(g)]])
    return rz @ ry @ rx


@settings(max_examples=6, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.tuples(*[st.floats(-np.pi, np.pi)] * 3),
    st.tuples(*[st.floats(-1e6, 1e6)] * 3),
)
def test_mcc_invariant_under_rigid_motion_order_and_translation(seed, ang, shift):
    rng = np.random.default_rng(seed)
    pts = noisy_cylinder(rng)
    base = gagekit.fit_cylinder(pts, "mcc")
    R = rotation(*ang)
    moved = (pts @ R.T + np.array(shift))[rng.permutation(len(pts))]
    r = gagekit.fit_cylinder(moved, "mcc", seed=3)
    assert abs(r.radius - base.radius) < 1e-8
    check_certificate(r, moved)


def test_pso_circles_agree_with_exact_kernels():
    rng = np.random.default_rng(5)
    t = rng.uniform(0, 2 * np.pi, 150)
    r = 10 + 0.05 * np.sin(5 * t) + rng.normal(0, 0.01, 150)
    pts = np.column_stack([r * np.cos(t) + 1e6, r * np.sin(t) - 3.0])
    for crit in ("mc", "mi", "mz"):
        exact = gagekit.fit_circle(pts, crit)
        swarm = gagekit.fit_circle(pts, crit, method="pso", seed=2)
        assert swarm.method == "pso"
        assert abs(swarm.radius - exact.radius) < 1e-8
        assert abs(swarm.form_error - exact.form_error) < 1e-8
        assert set(exact.control_points) <= set(swarm.control_points)
    with pytest.raises(ConfigError):
        gagekit.fit_circle(pts, "lsq", method="pso")
    with pytest.raises(ConfigError):
        gagekit.fit_circle(pts, "mc", method="pso", colour="red")


@pytest.mark.parametrize(
    "pts, kwargs, err",
    [
        (np.zeros((4, 3)), {}, InvalidInputError),
        (np.array([[0.0, 0.0, np.nan]] * 9), {}, InvalidInputError),
        (np.outer(np.arange(9.0), [1, 2, 3]), {}, DegenerateGeometryError),
        (np.ones((9, 3)), {}, DegenerateGeometryError),
        (np.random.default_rng(0).normal(size=(9, 3)), {"particles": 0}, ConfigError),
        (np.random.default_rng(0).normal(size=(9, 3)), {"max_tilt": -1.0}, ConfigError),
        (np.random.default_rng(0).normal(size=(9, 3)), {"max_tilt": 90.5}, ConfigError),
        (np.random.default_rng(0).normal(size=(9, 3)), {"max_tilt": float("nan")}, ConfigError),
        (np.random.default_rng(0).normal(size=(9, 3)), {"axis": [0, 0, 0]}, ConfigError),
        (np.random.default_rng(0).normal(size=(9, 3)), {"axis": [0, 1]}, ConfigError),
        (np.random.default_rng(0).normal(size=(9, 3)), {"axis": [0, float("inf"), 1]}, ConfigError),
        (np.random.default_rng(0).normal(size=(9, 3)), {"seed": -1}, ConfigError),
    ],
)
def test_bad_cylinder_input(pts, kwargs, err):
    with pytest.raises(err):
        gagekit.fit_cylinder(pts, "mzc", **kwargs)


def test_search_cone_around_given_axis():
    pts = load_set("set3")
    r = gagekit.fit_cylinder(pts, "mcc", axis=[0, 0, 1], max_tilt=math.degrees(0.05))
    full = gagekit.fit_cylinder(pts, "mcc")
    assert abs(r.radius - full.radius) < 1e-9


def test_cli_cylinder_json():
    out = subprocess.run(
        [sys.executable, "-m", "gagekit", "form", "cylinder", str(SEED / "set3.csv"), "--criterion", "mzc", "--seed", "1", "--json"],
        capture_output=True, text=True, timeout=120,
    )
    assert out.returncode == 0, out.stderr
    d = json.loads(out.stdout)
    assert d["criterion"] == "minimum-zone" and d["n_points"] == 24
    assert d["form_error"] <= 0.0027883 + ROUNDING
    assert abs(d["certificate"]["max_distance"] - d["outer_radius"]) < CERT_TOL


def test_partial_cylinder_mic_is_flagged_ill_posed():
    rng = np.random.default_rng(4)
    t = rng.uniform(0, np.radians(60), 80)
    z = rng.uniform(0, 40, 80)
    pts = np.column_stack([15 * np.cos(t), 15 * np.sin(t), z]) + rng.normal(0, 0.001, (80, 3))
    r = gagekit.fit_cylinder(pts, "mic", max_tilt=math.degrees(0.1))
    assert r.ill_posed and r.arc_deg < 90 and "ill-posed" in r.warnings[0]
    full = gagekit.fit_cylinder(load_set("set3"), "mic")
    assert not full.ill_posed and full.arc_deg > 270 and full.to_dict()["warnings"] == []


def test_thread_count_does_not_change_the_result():
    code = (
        "import json, numpy as np, gagekit; "
        f"p = np.loadtxt({str(SEED / 'set3.csv')!r}, delimiter=',', skiprows=1); "
        "print(json.dumps(gagekit.fit_cylinder(p, 'mzc', seed=5).to_dict()))"
    )
    outs = []
    for threads in ("1", "3"):
        env = {**os.environ, "RAYON_NUM_THREADS": threads}
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
        assert proc.returncode == 0, proc.stderr
        outs.append(json.loads(proc.stdout))
    assert outs[0] == outs[1]


def _project(pts, direction):
    """Eq. 6.12 (ERRATA item 1): q = [I2 0] Ry(-t) Rz(-f) p for the axis (t, f)."""
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    t, f = np.arccos(d[2]), np.arctan2(d[1], d[0])
    u = np.array([np.cos(t) * np.cos(f), np.cos(t) * np.sin(f), -np.sin(t)])
    v = np.array([-np.sin(f), np.cos(f), 0.0])
    q = pts - pts.mean(0)
    return np.ascontiguousarray(np.column_stack([q @ u, q @ v]))


@pytest.mark.parametrize("name", ["set1", "set3"])
@pytest.mark.parametrize("crit, circ", [("mcc", "mc"), ("mic", "mi"), ("mzc", "mz")])
def test_no_nearby_axis_is_better(name, crit, circ):
    pts = load_set(name)
    r = gagekit.fit_cylinder(pts, crit, seed=1)
    a = np.array(r.direction)
    # the projection along the reported axis reproduces the reported fit exactly
    c0 = gagekit.fit_circle(_project(pts, a), circ)
    value = {"mc": c0.radius, "mi": -c0.radius, "mz": c0.form_error}
    reported = {"mcc": r.radius, "mic": -r.radius, "mzc": r.form_error}[crit]
    assert abs(value[circ] - reported) < 1e-10
    u = np.cross(a, [1.0, 0, 0])
    u /= np.linalg.norm(u)
    v = np.cross(a, u)
    for eps in (1e-7, 1e-5, 1e-3):
        for k in range(8):
            th = np.pi * k / 4
            c = gagekit.fit_circle(_project(pts, a + eps * (np.cos(th) * u + np.sin(th) * v)), circ)
            val = {"mc": c.radius, "mi": -c.radius, "mz": c.form_error}[circ]
            assert val >= reported - 1e-11, (eps, k, val, reported)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_set3_minimum_zone_reaches_the_best_known_basin(seed):
    # Two local minima lie 4.6e-5 rad apart in a narrow valley (0.0027882926 and
    # 0.0027882986 mm); the swarm alone finds the lower one for 5 of 8 seeds, basin
    # hopping for all of them.
    r = gagekit.fit_cylinder(load_set("set3"), "mzc", seed=seed)
    assert r.form_error < 0.00278829262


def test_axis_angles_upper_half_sphere():
    from gagekit.form import axis_angles

    t, f = axis_angles([0.0, -1.0, -1.0])  # flipped into the upper half sphere
    assert abs(t - np.pi / 4) < 1e-15 and abs(f - np.pi / 2) < 1e-15
    assert axis_angles((0, 0, 2)) == (0.0, 0.0)
