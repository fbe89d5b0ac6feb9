"""Chebyshev cylinders and 3-D lines that respect the feature's axis (issue 13 part 3):
the search stays within ``max_tilt`` of a reference axis, reports ``tilt_deg``, and warns
when a search over all orientations finds a better optimum outside the cone."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

import gagekit
from gagekit.samples import data_path
from gagekit.errors import ConfigError, InvalidInputError


def short_bore(seed: int = 1) -> np.ndarray:
    """The issue's case: a bore of diameter 120 mm, 26 mm deep, 20 points."""
    rng = np.random.default_rng(seed)
    t = rng.uniform(0, 2 * np.pi, 20)
    z = rng.uniform(0, 26, 20)
    r = 60 + rng.normal(0, 0.005, 20)
    return np.column_stack([r * np.cos(t), r * np.sin(t), z])


def test_short_bore_mcc_is_the_bores():
    pts = short_bore()
    free = gagekit.fit_cylinder(pts, "mcc", max_tilt=90)
    # over all orientations the smallest enclosing cylinder lies across the bore
    assert free.radius < 56 and free.tilt_deg > 70 and free.warnings == ()
    r = gagekit.fit_cylinder(pts, "mcc")
    radial = np.hypot(pts[:, 0], pts[:, 1])
    assert 59.99 < r.radius <= radial.max() + 1e-9  # no larger than the true axis gives
    assert r.tilt_deg < 1.0
    assert r.certificate.max_distance <= r.radius + 1e-9
    (w,) = r.warnings
    assert f"{free.radius:.9g}" in w and "outside max_tilt = 10 degrees" in w
    d = r.to_dict()
    assert d["tilt_deg"] == r.tilt_deg and d["warnings"] == [w]


def test_short_bore_mic_and_mzc_stay_near_the_axis():
    pts = short_bore()
    for crit in ("mic", "mzc"):
        r = gagekit.fit_cylinder(pts, crit)
        assert r.tilt_deg <= 10.0 + 1e-9
        assert r.certificate.max_distance < 60.1 and r.certificate.min_distance > 59.9


def test_fixed_orientation_is_the_projection_fit():
    pts = short_bore()
    r = gagekit.fit_cylinder(pts, "mcc", axis=(0, 0, 2), max_tilt=0)
    assert r.tilt_deg < 1e-12
    assert np.allclose(r.direction, [0, 0, 1], atol=1e-15)
    mc = gagekit.fit_circle(pts[:, :2], "mc")
    assert abs(r.radius - mc.radius) < 1e-9


def test_nominal_axis_is_the_reference():
    pts = short_bore()
    r = gagekit.fit_cylinder(pts, "mcc", axis=(0, 0, -1), max_tilt=2)
    assert r.tilt_deg <= 2 + 1e-9
    assert math.isclose(r.tilt_deg, math.degrees(math.acos(abs(r.direction[2]))), abs_tol=1e-9)


@pytest.mark.parametrize("name", ["set1", "set3"])
@pytest.mark.parametrize("crit", ["mcc", "mic", "mzc"])
def test_dissertation_sets_keep_their_optimum(name, crit):
    pts = np.loadtxt(data_path(f"cylinders/{name}.csv"), delimiter=",", skiprows=1)
    cone = gagekit.fit_cylinder(pts, crit)
    free = gagekit.fit_cylinder(pts, crit, max_tilt=90)
    key = "form_error" if crit == "mzc" else "radius"
    scale = 1e-9 * free.radius
    assert abs(getattr(cone, key) - getattr(free, key)) < scale
    assert cone.tilt_deg < 1.0 and cone.warnings == ()


def test_partial_arc_mcc_does_not_depend_on_the_seed():
    """Issue 12: a 120-degree arc's MCC depended on the swarm's seed (half sphere)."""
    rng = np.random.default_rng(1)
    t = rng.uniform(0, np.radians(120), 12)
    z = rng.uniform(0, 40, 12)
    pts = np.column_stack([10 * np.cos(t), 10 * np.sin(t), z])
    radii = {round(gagekit.fit_cylinder(pts, "mcc", seed=s).radius, 9) for s in range(6)}
    assert len(radii) == 1, radii
    rng = np.random.default_rng(2)
    t = rng.uniform(0, np.radians(120), 12)
    z = rng.uniform(0, 5, 12)
    flat = np.column_stack([50 * np.cos(t), 50 * np.sin(t), z])
    fits = [gagekit.fit_cylinder(flat, "mcc", seed=s) for s in range(4)]
    assert len({round(f.radius, 9) for f in fits}) == 1
    # the constraint is active there: said so
    assert all("boundary of the search cone" in f.warnings[0] for f in fits)


def _arc(gen: int) -> np.ndarray:
    rng = np.random.default_rng(gen)
    t = rng.uniform(0, np.radians(120), 12)
    z = rng.uniform(0, 40 if gen % 2 else 5, 12)
    r = 10 if gen % 2 else 50
    return np.column_stack([r * np.cos(t), r * np.sin(t), z])


@pytest.mark.parametrize("gen, crit", [(1, "mcc"), (2, "mcc"), (3, "mic"), (7, "mic")])
def test_free_search_does_not_depend_on_the_seed(gen, crit):
    """Issue 12 item 11 with max_tilt=90 (the whole half sphere): these 120-degree arcs gave
    two or three different cylinders over seeds 0..5 before the deterministic grid search."""
    pts = _arc(gen)
    fits = [gagekit.fit_cylinder(pts, crit, seed=s, max_tilt=90) for s in range(6)]
    assert len({round(f.radius, 9) for f in fits}) == 1, [f.radius for f in fits]
    # and the free optimum is no worse than the default cone's
    cone = gagekit.fit_cylinder(pts, crit, seed=0)
    better = fits[0].radius <= cone.radius + 1e-9 if crit == "mcc" else fits[0].radius >= cone.radius - 1e-9
    assert better


@pytest.mark.parametrize(
    "kwargs",
    [{"max_tilt": -0.1}, {"max_tilt": 90.01}, {"max_tilt": "ten"}, {"axis": (0, 0, 0)}, {"axis": (1, 0)}],
)
def test_bad_search_settings(kwargs):
    with pytest.raises(ConfigError):
        gagekit.fit_cylinder(short_bore(), "mcc", **kwargs)
    with pytest.raises(ConfigError):
        gagekit.fit_line(short_bore(), "minimum-zone", **kwargs)


def test_collinear_3d_line_has_zero_straightness():
    pts = np.outer(np.arange(7.0), [1.0, 2.0, 3.0]) + [5.0, -1.0, 2.0]
    r = gagekit.fit_line(pts, "minimum-zone")
    assert r.form_error < 1e-12 and r.tilt_deg < 1e-9
    four = np.array([[0, 0, 0], [10, 0.1, 0], [20, 0, 0], [30, 0.05, 0.0]])
    r4 = gagekit.fit_line(four, "minimum-zone")
    assert 0.05 < r4.form_error <= 0.1 + 1e-12
    assert abs(r4.form_error - 2 * r4.certificate.max_distance) < 1e-15


def test_huge_coordinates_are_rejected_up_front():
    pts = np.random.default_rng(0).normal(size=(20, 3)) * 1e155
    for fit in (gagekit.fit_plane, gagekit.fit_line, gagekit.fit_sphere, gagekit.fit_cylinder):
        with pytest.raises(InvalidInputError, match="1e150"):
            fit(pts)


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "gagekit", *args], capture_output=True, text=True, timeout=120)


def test_cli_axis_and_max_tilt(tmp_path):
    f = tmp_path / "bore.csv"
    np.savetxt(f, short_bore(), delimiter=",")
    out = _cli("form", "cylinder", str(f), "-c", "mcc", "--json")
    assert out.returncode == 0, out.stderr
    d = json.loads(out.stdout)
    assert d["tilt_deg"] < 1 and len(d["warnings"]) == 1 and d["radius"] > 59.9
    out = _cli("form", "fit", "cylinder", str(f), "-c", "mcc", "--axis", "0,0,1", "--max-tilt", "0", "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["tilt_deg"] < 1e-12
    human = _cli("form", "cylinder", str(f), "-c", "mcc")
    assert human.returncode == 0 and "tilt_deg" in human.stdout and "warning" not in human.stdout
    assert human.stderr.startswith("gagekit: warning: ")  # warnings on stderr (issue 22 section 6)
    for bad in (["--max-tilt", "95"], ["--axis", "0,0,0"], ["--axis", "1,2"], ["--max-tilt", "-1"]):
        out = _cli("form", "cylinder", str(f), "-c", "mcc", *bad)
        assert out.returncode == 2, (bad, out.stderr)
        lines = out.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("gagekit: error:"), out.stderr
    big = tmp_path / "big.xyz"
    np.savetxt(big, np.random.default_rng(0).normal(size=(20, 3)) * 1e155)
    out = _cli("form", "fit", "plane", str(big), "--json")
    assert out.returncode == 2 and "null" not in out.stdout and out.stderr.startswith("gagekit: error:")
