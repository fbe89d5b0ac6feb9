"""Issue 26 Sec. 2, virtual gages: the allowance after T* gets a JCGM 101 uncertainty, and a
face within its guard band of zero is `not-proven`, not "conforming" (ISO 14253-1)."""

import numpy as np
import pytest

from gagekit.gage import check_gages
from gagekit.gage.uncertainty import check_gages_uncertainty
from gagekit.uncertainty import measurement_model

N_FACE = 10


def _face(allowance: float, free=(), seed=0):
    """A flat face of N_FACE points on z = 0 (random x, y) and a gage plane below it that
    leaves ``allowance`` of material: e = z + allowance."""
    rng = np.random.default_rng(seed)
    pts = np.c_[rng.uniform(-20, 20, (N_FACE, 2)), np.zeros(N_FACE)]
    doc = {"motion": {"free": list(free), "max_angle": 0.05, "max_shift": 5},
           "region": [{"name": "top", "center": [0.0, 0.0, 0.0], "size": [50.0, 50.0, 4.0]}],
           "gage": [{"name": "top face", "region": "top", "plane": [0.0, 0.0, 1.0, float(allowance)]}]}
    return pts, doc


def test_allowance_uncertainty_is_that_of_the_minimum_of_noisy_distances():
    """Fixed transform (no free motion), flat face of 10 points, isotropic noise sigma: the
    simulated allowance is a + sigma min(Z_1..Z_10), whose mean and sd are -1.5388 sigma and
    0.5868 sigma (order statistics of the normal; here from 10^6 direct draws)."""
    sigma = 0.004
    pts, doc = _face(1.0)
    res = check_gages_uncertainty(pts, doc, measurement_model(sigma=sigma), 3000, seed=3, threads=1)
    (g,) = res.gages
    z = np.random.default_rng(0).standard_normal((1_000_000, N_FACE)).min(axis=1)
    assert z.mean() == pytest.approx(-1.5388, abs=2e-3) and z.std() == pytest.approx(0.5868, abs=2e-3)
    u = g.uncertainty
    assert u["u"] == pytest.approx(sigma * z.std(), rel=0.04)
    assert u["bias"] == pytest.approx(sigma * z.mean(), rel=0.03)  # the minimum of noisy points is biased low
    lo, hi = np.quantile(1.0 + sigma * z, [0.025, 0.975])
    assert u["interval"][0] == pytest.approx(lo, abs=0.05 * sigma) and u["interval"][1] == pytest.approx(hi, abs=0.05 * sigma)
    assert u["trials"] == 3000 and g.decision == "conforming" and res.decision == "conforming"
    assert res.monte_carlo["active_points"] == N_FACE and res.transform_uncertainty == {}


@pytest.mark.parametrize("allowance, want", [(0.0, "not-proven"), (0.05, "conforming"), (-0.05, "nonconforming"),
                                             (0.004, "not-proven"), (-0.004, "not-proven")])
def test_decisions_on_and_near_the_limit(allowance, want):
    """sigma 2 um: U of the allowance is about 2.3 um; a face exactly at its limit, or within
    U of it, is not-proven; simple acceptance keeps the old verdict."""
    pts, doc = _face(allowance)
    res = check_gages_uncertainty(pts, doc, measurement_model(sigma=0.002), 200, seed=1, threads=1)
    U = res.gages[0].uncertainty["U"]
    assert 0.001 < U < 0.004
    if abs(allowance) == 0.004:
        want = "not-proven" if abs(allowance) < U else ("conforming" if allowance > 0 else "nonconforming")
    assert res.gages[0].decision == want and res.decision == want
    assert res.decision_rule["name"] == "iso14253"
    simple = check_gages_uncertainty(pts, doc, measurement_model(sigma=0.002), 20, seed=1, threads=1, rule="simple")
    assert simple.decision == ("conforming" if allowance >= 0 else "nonconforming")
    # guard-band=0: accept on the limit, reject beyond it
    g0 = check_gages_uncertainty(pts, doc, measurement_model(sigma=0.002), 20, seed=1, threads=1, rule="guard-band=0")
    assert g0.decision == ("conforming" if allowance >= 0 else "nonconforming")


def test_a_free_motion_can_prove_what_the_stock_minimising_transform_cannot():
    """Two opposite faces 1 mm apart in z with dz free: T* of Eq. 5.11 puts one of them on
    its limit (allowance 0, within U of zero), but a transform leaving U on both exists, so
    the part is proven conforming at the guard-banded transform, which the JSON gives."""
    rng = np.random.default_rng(4)
    top = np.c_[rng.uniform(-20, 20, (40, 2)), np.full(40, 0.5)]
    bot = np.c_[rng.uniform(-20, 20, (40, 2)), np.full(40, -0.5)]
    doc = {"motion": {"free": ["dz"], "max_angle": 0.05, "max_shift": 5},
           "region": [{"name": "t", "center": [0, 0, 0.5], "size": [50, 50, 0.6]},
                      {"name": "b", "center": [0, 0, -0.5], "size": [50, 50, 0.6]}],
           "gage": [{"name": "top", "region": "t", "plane": [0, 0, 1, -0.2], "weight": 1.0},
                    {"name": "bottom", "region": "b", "plane": [0, 0, -1, -0.2], "weight": 2.0}]}
    pts = np.vstack([top, bot])
    plain = check_gages(pts, doc)
    assert plain.status == "conforming" and min(g.allowance_after for g in plain.gages) == pytest.approx(0.0, abs=1e-12)
    res = check_gages_uncertainty(pts, doc, measurement_model(sigma=0.002), 100, seed=2, threads=1)
    assert res.decision == "conforming" and [g.decision for g in res.gages] == ["conforming", "conforming"]
    band = res.guard_band["guarded"]
    assert band["status"] == "conforming"
    for g in res.gages:
        assert band["allowances_after"][g.name] >= res.guard_band["g_mm"][g.name] - 1e-9
    assert "dz" in res.transform_uncertainty and res.transform_uncertainty["dz"]["u"] > 0
    # squeeze the stock to 0.6 mm: no transform leaves U on both faces, none misses by more than U
    doc["gage"][0]["plane"] = [0, 0, 1, -0.5]
    doc["gage"][1]["plane"] = [0, 0, -1, -0.5]
    res = check_gages_uncertainty(pts, doc, measurement_model(sigma=0.002), 100, seed=2, threads=1)
    assert res.status == "conforming" and res.decision == "not-proven"
    assert res.guard_band["guarded"]["status"] == "nonconforming" and res.guard_band["relaxed"]["status"] == "conforming"


def test_seeded_and_thread_count_independent():
    pts, doc = _face(0.01)
    a = check_gages_uncertainty(pts, doc, measurement_model(sigma=0.003), 60, seed=9, threads=1).to_dict()
    b = check_gages_uncertainty(pts, doc, measurement_model(sigma=0.003), 60, seed=9, threads=2).to_dict()
    for d in (a, b):
        d["monte_carlo"].pop("seconds")
    a["monte_carlo"].pop("threads", None)
    b["monte_carlo"].pop("threads", None)
    assert a == b
