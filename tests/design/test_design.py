"""gagekit.optimal_design: Table 4.1 (with ERRATA item 7), known optimal designs, bad input."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import gagekit
from gagekit import optimal_design
from gagekit._util import dumps
from gagekit.design.optimal import search_design
from gagekit.errors import DegenerateGeometryError, InfeasibleError, InvalidInputError


def line(X):
    """Eq. 4.6: y = p1 x + p2, one row [x, 1] per point."""
    return np.stack([X[:, 0], np.ones(len(X))], axis=1)[:, None, :]


def quadratic(X):
    x = X[:, 0]
    return np.stack([np.ones_like(x), x, x * x], axis=1)


ZONES = [(0.0, 0.25, 1), (0.25, 0.75, 2), (0.75, 1.0, 1)]

# Table 4.1; the K rows as corrected by ERRATA item 7.
TABLE_4_1 = [
    ("A", None, [0, 0, 1, 1], 1.5, 0.25, 2.618),
    ("D", None, [0, 0, 1, 1], 1.5, 0.25, 2.618),
    ("A", ZONES, [0, 0.25, 0.75, 1], 2.25, 0.4, 3.25),
    ("D", ZONES, [0, 0.25, 0.75, 1], 2.25, 0.4, 3.25),
    ("K", None, [0, 0, 0, 1], 1.667, 0.333, 2.484),
    ("K", ZONES, [0, 0.25, 0.25, 1], 2.278, 0.444, 3.093),
]


@pytest.mark.parametrize("crit,zones,xs,tr,det,kappa", TABLE_4_1)
def test_table_4_1(crit, zones, xs, tr, det, kappa):
    r = optimal_design(line, [[0.0, 1.0]], 4, crit, zones=zones)
    assert sorted(r.points[:, 0]) == pytest.approx(xs, abs=1e-9)
    assert r.trace == pytest.approx(tr, abs=1e-3)
    assert r.det == pytest.approx(det, abs=1e-3)
    assert r.log_det == pytest.approx(np.log(det), abs=1e-2)
    assert r.condition_number == pytest.approx(kappa, abs=1e-3)
    assert r.criterion == crit
    if zones:
        for p, z in zip(r.points[:, 0], r.zone):
            lo, hi, _ = ZONES[z]
            assert lo <= p <= hi
    d = json.loads(dumps(r))
    assert d["criterion"] == crit and len(d["points"]) == 4 and d["trace"] == pytest.approx(tr, abs=1e-3)


def test_refinement_reaches_interior_optimum():
    # D-optimal quadratic regression on [-1, 1] with 3 points: -1, 0, 1. The
    # shifted quasi-random candidates do not contain 0; refinement must find it
    # (to ~1e-5: the objective is flat to 1e-10 there, the search's tolerance).
    r = search_design(quadratic, [[-1.0, 1.0]], 3, "D", n_candidates=50, seed=3)
    assert sorted(r.points[:, 0]) == pytest.approx([-1, 0, 1], abs=1e-4)
    # A-optimal quadratic design: weights 1/4, 1/2, 1/4 (Pukelsheim), so -1, 0, 0, 1.
    r = search_design(quadratic, [[-1.0, 1.0]], 4, "A", n_candidates=50, seed=3)
    assert sorted(r.points[:, 0]) == pytest.approx([-1, 0, 0, 1], abs=1e-4)


def test_first_order_model_takes_the_cube_corners():
    def first_order(X):
        return np.column_stack([np.ones(len(X)), X])

    r = optimal_design(first_order, [[-1, 1]] * 3, 8, "D", seed=1)
    # any orthogonal array of corners (full factorial or a replicated half fraction) gives F = 8 I
    assert np.abs(r.points) == pytest.approx(np.ones((8, 3)))
    assert r.log_det == pytest.approx(-4 * np.log(8), abs=1e-9)
    assert r.condition_number == pytest.approx(1.0)


def test_given_candidates_are_used_as_they_are():
    cand = np.linspace(0.1, 0.9, 9)[:, None]
    r = optimal_design(line, [[0, 1]], 4, "D", candidates=cand)
    assert sorted(r.points[:, 0]) == pytest.approx([0.1, 0.1, 0.9, 0.9])


def test_e_and_i_criteria():
    e = optimal_design(quadratic, [[-1, 1]], 6, "E")
    i = optimal_design(quadratic, [[-1, 1]], 6, "I")
    a = optimal_design(quadratic, [[-1, 1]], 6, "A")
    assert np.isfinite(e.objective) and e.objective == pytest.approx(1 / e.lambda_min)
    # each criterion is best at its own objective among the three designs
    assert e.lambda_min >= a.lambda_min - 1e-9 and e.lambda_min >= i.lambda_min - 1e-9
    assert a.trace <= e.trace + 1e-9 and a.trace <= i.trace + 1e-9


def test_same_seed_same_design_on_any_thread_count():
    code = (
        "import numpy as np, gagekit;"
        "f=lambda X: np.stack([np.ones(len(X)), X[:,0], X[:,1], X[:,0]*X[:,1], X[:,0]**2], 1);"
        "r=gagekit.optimal_design(f, [[-1,1],[0,2]], 9, 'K', zones=[([-1,0],[0,1],3)], seed=7);"
        "print(repr(r.points.tolist()), r.objective)"
    )
    outs = []
    for threads in ("1", "2"):
        env = dict(os.environ, RAYON_NUM_THREADS=threads)
        outs.append(subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout)
    assert outs[0] == outs[1]


@settings(max_examples=15, deadline=None)
@given(a=st.floats(-100, 100), w=st.floats(0.01, 50))
def test_d_optimal_line_is_two_at_each_end(a, w):
    # D-optimality is affine-equivariant: on any [a, b] the 4-point design is a, a, b, b
    # (b - a kept >= 1 % of |a|: narrower far from 0 the model is numerically rank 1).
    w = max(w, 0.01 * abs(a))
    r = optimal_design(line, [[a, a + w]], 4, "D")
    assert sorted(r.points[:, 0]) == pytest.approx([a, a, a + w, a + w], abs=1e-9 * max(1, abs(a) + w))


@settings(max_examples=10, deadline=None)
@given(cuts=st.lists(st.floats(0.05, 0.95), min_size=2, max_size=2, unique=True),
       counts=st.lists(st.integers(0, 3), min_size=2, max_size=2), crit=st.sampled_from("ADK"))
def test_zones_are_honoured(cuts, counts, crit):
    c0, c1 = sorted(cuts)
    zones = [([c0, 0.0], [c1, 0.5], counts[0]), ([0.0, 0.5], [1.0, 1.0], counts[1])]
    f = lambda X: np.column_stack([np.ones(len(X)), X, X[:, 0] * X[:, 1]])
    r = optimal_design(f, [[0, 1], [0, 1]], 6, crit, zones=zones)
    for z, (zl, zu, cnt) in enumerate(zones):
        inside = r.points[r.zone == z]
        assert len(inside) == cnt
        assert ((inside >= np.array(zl) - 1e-12) & (inside <= np.array(zu) + 1e-12)).all()
    assert ((r.points >= 0) & (r.points <= 1)).all()


@pytest.mark.parametrize(
    "kwargs,exc,msg",
    [
        (dict(criterion="Q"), InvalidInputError, "unknown design criterion"),
        (dict(bounds=[[1, 0]]), InvalidInputError, "lower 1.0 > upper 0.0"),
        (dict(bounds=[[0, np.nan]]), InvalidInputError, "finite"),
        (dict(n_points=1), InvalidInputError, "at least 2 points"),
        (dict(n_points=0), InvalidInputError, "at least one point"),
        (dict(zones=[(0, 0.5, 3), (0.5, 1, 2)]), InvalidInputError, "ask for 5 points but the plan has only 4"),
        (dict(zones=[(2, 3, 1)]), InfeasibleError, "does not overlap"),
        (dict(zones=[(0.4, 0.5, 1)], candidates=[[0.0], [1.0]]), InfeasibleError, "no usable candidate"),
        (dict(candidates=[[0.0], [2.0]]), InvalidInputError, "point 1 (2) lies outside"),
        (dict(rows=lambda X: np.full((len(X), 1, 2), np.nan)), InvalidInputError, "not finite"),
        (dict(rows=lambda X: np.ones((3, 2))), InvalidInputError, "(m, r, k)"),
        (dict(rows=lambda X: np.column_stack([X[:, 0], X[:, 0]])), DegenerateGeometryError, "only 1 independent"),
    ],
)
def test_bad_input(kwargs, exc, msg):
    args = dict(rows=line, bounds=[[0, 1]], n_points=4, criterion="A")
    args.update(kwargs)
    with pytest.raises(exc, match=None) as info:
        optimal_design(**args)
    assert msg in str(info.value)


def test_public_api():
    assert gagekit.optimal_design is optimal_design
    assert "optimal_design" in gagekit.__all__ and "DesignResult" in gagekit.__all__


def test_feasible_mask_and_average_over():
    # keep the plan out of the middle third; the I criterion averages over given points only
    feasible = lambda X: np.abs(X[:, 0] - 0.5) > 1 / 6
    r = search_design(quadratic, [[0.0, 1.0]], 6, "D", feasible=feasible, n_candidates=200)
    assert (np.abs(r.points[:, 0] - 0.5) > 1 / 6).all()
    cand = np.linspace(0, 1, 41)[:, None]
    left = (cand[:, 0] <= 0.5)
    a = search_design(quadratic, [[0.0, 1.0]], 6, "I", candidates=cand, average_over=left)
    b = search_design(quadratic, [[0.0, 1.0]], 6, "I", candidates=cand)
    # averaging the prediction variance over [0, 0.5] only pulls the plan to the left
    assert a.points.mean() < b.points.mean()
    with pytest.raises(InvalidInputError, match="average_over"):
        search_design(quadratic, [[0.0, 1.0]], 6, "I", candidates=cand, average_over=[True])
