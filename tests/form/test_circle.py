"""2-D circle fits (Sec. 6.2): NIST least-squares references and geometric properties."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from typer.testing import CliRunner

import gagekit
from gagekit import fit_circle
from gagekit.cli import app
from gagekit.errors import ConfigError, DegenerateGeometryError, InvalidInputError

from conftest import NIST as _NIST

NIST = _NIST / "circle2d"
NIST_SETS = sorted(NIST.glob("*.ds"))


def _load_ds(path: Path) -> tuple[np.ndarray, int]:
    """NIST .ds: count, then x y z; 2-D sets lie in a coordinate plane (drop that axis)."""
    xyz = np.loadtxt(path, skiprows=1, ndmin=2)
    drop = [k for k in range(3) if np.ptp(xyz[:, k]) == 0.0][-1]
    return np.delete(xyz, drop, axis=1), drop


def test_nist_circle2d_sets_present() -> None:
    assert len(NIST_SETS) >= 5


@pytest.mark.parametrize("ds", NIST_SETS, ids=lambda p: p.stem)
def test_nist_circle2d_least_squares(ds: Path) -> None:
    pts, drop = _load_ds(ds)
    ref = np.loadtxt(ds.with_suffix(".fit"))
    center_ref = np.delete(ref[:3], drop)
    fit = fit_circle(pts, "lsq")
    assert np.max(np.abs(np.array(fit.center) - center_ref)) < 1e-7
    assert abs(2.0 * fit.radius - ref[6]) < 1e-7


def _ring(rng: np.random.Generator, n: int, noise: float, arc: float = 2 * math.pi) -> np.ndarray:
    a = rng.uniform(0.0, arc, n)
    r = 20.0 + rng.uniform(-noise, noise, n)
    return np.c_[5.0 + r * np.cos(a), -3.0 + r * np.sin(a)]


def _radii(pts: np.ndarray, c) -> np.ndarray:
    return np.hypot(pts[:, 0] - c[0], pts[:, 1] - c[1])


point_sets = st.builds(
    lambda seed, n, noise, arc: _ring(np.random.default_rng(seed), n, noise, arc),
    st.integers(0, 2**32 - 1),
    st.integers(4, 300),
    st.floats(0.01, 3.0),
    st.sampled_from([2 * math.pi, 3.0, 1.0]),
)


@settings(max_examples=40, deadline=None)
@given(point_sets)
def test_mc_contains_all_points(pts: np.ndarray) -> None:
    mc = fit_circle(pts, "mc")
    assert np.all(_radii(pts, mc.center) <= mc.radius + 1e-12 * (1 + mc.radius))
    ctrl = _radii(pts[list(mc.control_points)], mc.center)
    assert np.allclose(ctrl, mc.radius, rtol=0, atol=1e-9)


@settings(max_examples=40, deadline=None)
@given(point_sets)
def test_no_point_strictly_inside_mi(pts: np.ndarray) -> None:
    mi = fit_circle(pts, "mi")
    mc = fit_circle(pts, "mc")
    assert np.all(_radii(pts, mi.center) >= mi.radius - 1e-12 * (1 + mi.radius))
    assert math.dist(mi.center, mc.center) + mi.radius <= mc.radius + 1e-9


def _width(pts: np.ndarray, c) -> float:
    d = _radii(pts, c)
    return float(d.max() - d.min())


@settings(max_examples=40, deadline=None)
@given(point_sets, st.integers(0, 2**32 - 1))
def test_mz_width_not_improved_by_nearby_centres(pts: np.ndarray, seed: int) -> None:
    mz = fit_circle(pts, "mz")
    assert abs(_width(pts, mz.center) - mz.form_error) < 1e-12
    rng = np.random.default_rng(seed)
    for scale in (1e-7, 1e-4, 1e-2, 1.0):
        for c in mz.center + scale * rng.normal(size=(50, 2)):
            assert _width(pts, c) >= mz.form_error - 1e-10
    # and it beats the other criteria's centres
    for crit in ("lsq", "mc", "mi"):
        assert fit_circle(pts, crit).form_error >= mz.form_error - 1e-10


@settings(max_examples=25, deadline=None)
@given(point_sets, st.floats(0, 2 * math.pi), st.sampled_from([0.0, 1e6, -1e6]), st.integers(0, 2**32 - 1))
def test_invariance_under_order_rigid_motion_and_translation(pts, angle, shift, seed) -> None:
    rng = np.random.default_rng(seed)
    perm = rng.permutation(len(pts))
    rot = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
    t = np.array([shift + 12.5, -0.5 * shift])
    moved = pts[perm] @ rot.T + t
    for crit in ("lsq", "mc", "mi", "mz"):
        a, b = fit_circle(pts, crit), fit_circle(moved, crit)
        tol = 1e-9 * (1 + abs(shift) * 1e-3)  # 1e6 mm coordinates carry ~1e-10 mm rounding
        assert abs(a.radius - b.radius) < max(tol, 1e-9), crit
        assert abs(a.form_error - b.form_error) < max(tol, 1e-9), crit
        if crit != "mi":  # MI centre need not be unique on symmetric sets
            assert np.allclose(rot @ np.array(a.center) + t, b.center, atol=max(tol, 1e-7) * 100)


def test_errors_are_gagekit_errors() -> None:
    with pytest.raises(InvalidInputError, match="point 2"):
        fit_circle([[0, 0], [1, 0], [np.nan, 1], [0, 1]], "mz")
    with pytest.raises(InvalidInputError, match="at least 3"):
        fit_circle([[0, 0], [1, 0]], "lsq")
    with pytest.raises(InvalidInputError, match="at least 1"):
        fit_circle(np.zeros((0, 2)), "mc")
    for crit in ("lsq", "mi", "mz"):
        with pytest.raises(DegenerateGeometryError, match="straight line"):
            fit_circle([[0, 0], [1, 1], [2, 2], [5, 5]], crit)
        with pytest.raises(DegenerateGeometryError, match="coincide"):
            fit_circle([[1, 1]] * 4, crit)
    with pytest.raises(ConfigError, match="unknown circle criterion"):
        fit_circle([[0, 0], [1, 0], [0, 1]], "best")
    with pytest.raises(InvalidInputError, match=r"\(n, 2\)"):
        fit_circle(np.zeros((5, 4)), "mc")  # (n, 3) is a circle in space since issue 13


def test_mc_two_points_and_duplicates() -> None:
    mc = fit_circle([[0, 0], [2, 0]], "mc")
    assert mc.radius == 1.0 and mc.center == (1.0, 0.0)
    pts = np.array([[1, 0], [0, 1], [-1, 0], [0, -1], [1, 0], [0, 1]], float)
    for crit in ("mc", "mi", "mz", "lsq"):
        f = fit_circle(pts, crit)
        assert abs(f.radius - 1.0) < 1e-12 and f.form_error < 1e-12


def test_short_arc_flags_mi_as_ill_posed() -> None:
    pts = _ring(np.random.default_rng(3), 200, 0.01, arc=math.radians(60))
    mi = fit_circle(pts, "mi")
    assert mi.ill_posed and "ill-posed" in mi.warnings[0]
    assert not fit_circle(_ring(np.random.default_rng(3), 200, 0.01), "mi").ill_posed


def test_to_dict_is_json_ready() -> None:
    fit = fit_circle(_ring(np.random.default_rng(1), 100, 0.1), "minimum-zone")
    d = json.loads(gagekit._util.dumps(fit))
    assert d["criterion"] == "minimum-zone" and d["shape"] == "circle"
    assert abs(d["outer_radius"] - d["inner_radius"] - d["form_error"]) < 1e-12
    assert set(d["control_in"]) | set(d["control_out"]) == set(d["control_points"])


def test_cli_circle(tmp_path: Path) -> None:
    pts = _ring(np.random.default_rng(2), 60, 0.05)
    f = tmp_path / "ring.txt"
    np.savetxt(f, np.c_[pts, np.full(len(pts), 7.0)])
    runner = CliRunner()
    res = runner.invoke(app, ["form", "circle", str(f), "--criterion", "all", "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert set(d) == {"least-squares", "min-circumscribed", "max-inscribed", "minimum-zone"}
    assert abs(d["minimum-zone"]["form_error"] - fit_circle(pts, "mz").form_error) < 1e-12
    res = runner.invoke(app, ["form", "circle", str(f), "-c", "mz"])
    assert res.exit_code == 0 and "minimum-zone" in res.stdout
    bad = tmp_path / "bad.txt"
    bad.write_text("1 2 3\n4 5 6\n7 8 x\n")
    proc = subprocess.run([sys.executable, "-m", "gagekit", "form", "circle", str(bad)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2 and "bad.txt" in proc.stderr and proc.stdout == ""


_DET_SCRIPT = """
import json, numpy as np, gagekit
rng = np.random.default_rng(5)
a = rng.uniform(0, 2 * np.pi, 20000)
r = 50 + rng.normal(0, 0.003, 20000)
P = np.c_[r * np.cos(a) + 7e5, r * np.sin(a)]
print(json.dumps({c: gagekit.fit_circle(P, c).to_dict() for c in ["lsq", "mc", "mi", "mz"]}, sort_keys=True))
"""


def test_results_do_not_depend_on_thread_count() -> None:
    import os

    outs = []
    for threads in ("1", "2"):
        env = {**os.environ, "RAYON_NUM_THREADS": threads}
        proc = subprocess.run([sys.executable, "-c", _DET_SCRIPT], capture_output=True, text=True, env=env, timeout=300)
        assert proc.returncode == 0, proc.stderr
        outs.append(proc.stdout)
    assert outs[0] == outs[1]


@pytest.mark.parametrize("arc", [2 * math.pi, 2.0])
def test_large_sets_run_by_subsets_stay_optimal(arc: float) -> None:
    # above a few thousand points MI and MZ are solved on growing subsets
    pts = _ring(np.random.default_rng(11), 20000, 0.05, arc)
    mz = fit_circle(pts, "mz")
    assert abs(_width(pts, mz.center) - mz.form_error) < 1e-12
    rng = np.random.default_rng(0)
    for scale in (1e-8, 1e-5, 1e-3):
        for c in mz.center + scale * rng.normal(size=(20, 2)):
            assert _width(pts, c) >= mz.form_error - 1e-12
    mi = fit_circle(pts, "mi")
    mc = fit_circle(pts, "mc")
    assert np.all(_radii(pts, mi.center) >= mi.radius - 1e-12)
    assert math.dist(mi.center, mc.center) + mi.radius <= mc.radius + 1e-9
    # MI cannot grow by moving the centre a little (within MC)
    for c in mi.center + 1e-4 * rng.normal(size=(40, 2)):
        g = min(_radii(pts, c).min(), mc.radius - math.dist(c, mc.center))
        assert g <= mi.radius + 1e-12


def test_deprecated_aliases_and_canonical_criterion() -> None:
    # one stored form of a criterion name; the old attribute names still answer, with a warning
    pts = np.array([[1, 0], [0, 1], [-1, 0], [0, -1.1]], float)
    f = fit_circle(pts, "MZ")
    assert f.criterion == "minimum-zone" and f.to_dict()["criterion"] == "minimum-zone"
    with pytest.warns(DeprecationWarning, match="form_error"):
        assert f.width == f.form_error
    from gagekit.form import fit_cylinder

    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    cyl = np.column_stack([np.cos(t), np.sin(t), np.linspace(0, 5, 40)])
    c = fit_cylinder(cyl)
    with pytest.warns(DeprecationWarning, match="use point"):
        assert c.axis_point == c.point
    with pytest.warns(DeprecationWarning, match="use direction"):
        assert c.axis_direction == c.direction
    assert c.to_dict()["axis_point"] == list(c.point)
