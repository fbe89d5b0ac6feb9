"""Circles in any pose (issue 13 part 4): (n, 3) points are fitted in their
least-squares plane with every criterion; results move rigidly with the points."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gagekit
from gagekit import read_points

NIST = Path(__file__).resolve().parents[1] / "data" / "nist-l2"
CRITERIA = ("lsq", "mc", "mi", "mz")


def rotation(a: float, b: float, c: float) -> np.ndarray:
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    rz = np.array([[ca, -sa, 0], [sa, ca, 0], [0, 0, 1]])
    ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    rx = np.array([[1, 0, 0], [0, cc, -sc], [0, sc, cc]])
    return rz @ ry @ rx


def test_nist_2d_file_fits_as_read():
    """The issue's call: 3-D points of a 2-D NIST set, fitted as read."""
    pts = read_points(NIST / "circle2d" / "cir2d1.ds")
    assert pts.shape[1] == 3
    const = [k for k in range(3) if np.ptp(pts[:, k]) == 0]
    flat = np.delete(pts, const[-1], axis=1)
    for crit in CRITERIA:
        r3, r2 = gagekit.fit_circle(pts, crit), gagekit.fit_circle(flat, crit)
        assert r3.radius == r2.radius and abs(r3.form_error - r2.form_error) < 1e-12  # certificate recomputed in 3-D
        assert np.delete(np.array(r3.center), const[-1]).tolist() == list(r2.center)
        assert abs(r3.normal[const[-1]]) == 1.0 and r3.out_of_plane == 0.0


@pytest.mark.parametrize("name", sorted(p.stem for p in (NIST / "circle3d").glob("*.ds")))
def test_nist_3d_circles_every_criterion(name):
    pts = read_points(NIST / "circle3d" / f"{name}.ds")
    ref = [float(x) for x in (NIST / "circle3d" / f"{name}.fit").read_text().split()]
    ls = gagekit.fit_circle(pts, "lsq")
    assert abs(2 * ls.radius - ref[6]) < 1e-7 * max(1.0, ref[6])
    assert np.linalg.norm(np.array(ls.center) - ref[:3]) < 1e-6 * max(1.0, ref[6])
    assert abs(abs(np.dot(ls.normal, ref[3:6])) - 1) < 1e-10
    mc, mi, mz = (gagekit.fit_circle(pts, c) for c in ("mc", "mi", "mz"))
    assert mi.radius <= mc.radius
    if ls.arc_deg > 270:  # on a short arc the least-squares circle can be the largest
        assert mi.radius <= ls.radius <= mc.radius
    assert mz.form_error <= ls.form_error + 1e-12 and mz.form_error <= mc.form_error + 1e-12
    # certificates: the in-plane distances bound every point
    for f in (mc, mi, mz):
        n = np.array(f.normal)
        d = pts - f.center
        radial = np.linalg.norm(d - np.outer(d @ n, n), axis=1)
        assert abs(radial.min() - f.r_in) < 1e-9 and abs(radial.max() - f.r_out) < 1e-9
    assert abs(mc.r_out - mc.radius) < 1e-12 and abs(mi.r_in - mi.radius) < 1e-12


@settings(max_examples=25, deadline=None)
@given(
    st.integers(0, 10_000),
    st.floats(0, 2 * np.pi), st.floats(0, np.pi), st.floats(0, 2 * np.pi),
    st.floats(-1e4, 1e4),
)
def test_rigid_motion_moves_the_circle(seed, a, b, c, shift):
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0, 2 * np.pi, 40))
    r = 20 + rng.normal(0, 0.01, 40)
    flat = np.column_stack([r * np.cos(t), r * np.sin(t), np.zeros(40)])
    R = rotation(a, b, c)
    moved = flat @ R.T + shift
    for crit in CRITERIA:
        f2 = gagekit.fit_circle(flat[:, :2], crit)
        f3 = gagekit.fit_circle(moved, crit)
        assert abs(f3.radius - f2.radius) < 1e-7 and abs(f3.form_error - f2.form_error) < 1e-7
        c2 = np.array([*f2.center, 0.0]) @ R.T + shift
        assert np.linalg.norm(np.array(f3.center) - c2) < 1e-6
        assert abs(abs(np.dot(f3.normal, R[:, 2])) - 1) < 1e-9
        assert f3.r_in <= f3.radius + 1e-9 <= f3.r_out + 2e-9


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000), st.floats(-50, 50), st.floats(-50, 50))
def test_adding_a_point_never_shrinks_the_mc(seed, x, y):
    rng = np.random.default_rng(seed)
    pts = rng.normal(0, 10, (30, 3)) * [1, 1, 0] @ rotation(0.3, 0.7, 0.1).T
    more = np.vstack([pts, np.array([x, y, 0.0]) @ rotation(0.3, 0.7, 0.1).T])
    assert gagekit.fit_circle(more, "mc").radius >= gagekit.fit_circle(pts, "mc").radius - 1e-9


def test_cli_fits_any_3d_circle_and_circle3d_is_an_alias():
    f = NIST / "circle3d" / "cir10.ds"
    outs = [subprocess.run([sys.executable, "-m", "gagekit", "form", "fit", shape, str(f), "-c", "mz", "--json"],
                           capture_output=True, text=True, timeout=120) for shape in ("circle", "circle3d")]
    assert all(o.returncode == 0 for o in outs), outs[0].stderr
    assert outs[0].stdout == outs[1].stdout
    d = json.loads(outs[0].stdout)
    assert len(d["center"]) == 3 and len(d["normal"]) == 3 and d["criterion"] == "minimum-zone"
    assert d["certificate"]["max_distance"] - d["certificate"]["min_distance"] == pytest.approx(d["form_error"], abs=1e-12)
