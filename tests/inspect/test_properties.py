"""Properties of the measured values (hypothesis): never negative, zero for a perfect
feature, never lowered by adding a point outside the zone."""

import math

import numpy as np
from hypothesis import given, settings, strategies as st

from gagekit import inspect_scan
from gagekit.inspect import part_spec_from_dict

PLANE_CHARS = [
    {"characteristic": "flatness"},
    {"characteristic": "parallelism", "datums": ["A"]},
    {"characteristic": "profile", "datums": ["A"], "nominal": {"point": [0, 0, 10], "direction": [0, 0, 1]}},
    {"characteristic": "position", "datums": ["A"], "nominal": {"point": [0, 0, 10], "direction": [0, 0, 1]}},
    {"characteristic": "angularity", "datums": ["A"], "angle": 5.0},
    {"characteristic": "perpendicularity", "datums": ["S"]},
]


def _grid(n):
    u, v = np.meshgrid(np.linspace(0, 40, n), np.linspace(0, 30, n), indexing="ij")
    return u.ravel(), v.ravel()


def _part(amp: float, seed: int):
    """A datum plane A (z = 0, perfect), a side S (x = 0, perfect) and a top F at z = 10
    with a random bounded form deviation of amplitude amp, a sphere and a circle with
    random radial deviations of amplitude amp."""
    rng = np.random.default_rng(seed)
    x, y = _grid(12)
    a = np.column_stack([x, y, 0 * x])
    s = np.column_stack([0 * x - 5, x * 0.75, 1 + y * 0.25])
    f = np.column_stack([x, y, 10 + amp * rng.uniform(-1, 1, len(x))])
    th, ph = np.meshgrid(np.linspace(0, 2 * math.pi, 24, endpoint=False), np.linspace(0.2, 1.4, 8), indexing="ij")
    r = 5 + amp * rng.uniform(-1, 1, th.size)
    sph = np.column_stack([70 + r * np.cos(th.ravel()) * np.cos(ph.ravel()), 20 + r * np.sin(th.ravel()) * np.cos(ph.ravel()),
                           10 + r * np.sin(ph.ravel())])
    t = np.linspace(0, 2 * math.pi, 90, endpoint=False)
    rc = 4 + amp * rng.uniform(-1, 1, t.size)
    circ = np.column_stack([100 + rc * np.cos(t), 20 + rc * np.sin(t), 0 * t + 5])
    return np.concatenate([a, s, f, sph, circ])


def _spec():
    doc = {
        "feature": [
            {"name": "A", "shape": "plane", "region": {"center": [20, 15, 0], "size": [42, 32, 0.5]}, "outward": [0, 0, -1]},
            {"name": "S", "shape": "plane", "region": {"center": [-5, 15, 5], "size": [0.5, 32, 9]}, "outward": [-1, 0, 0]},
            {"name": "F", "shape": "plane", "region": {"center": [20, 15, 10], "size": [42, 32, 4]}, "outward": [0, 0, 1]},
            {"name": "ball", "shape": "sphere", "region": {"center": [70, 20, 13], "size": [14, 14, 9]}},
            {"name": "ring", "shape": "circle", "region": {"center": [100, 20, 5], "size": [10, 10, 1]}},
        ],
        "datums": {"A": "A", "S": "S"},
        "tolerance": [{"feature": "F", "tolerance": 0.1, **c} for c in PLANE_CHARS]
        + [{"feature": "ball", "characteristic": "sphericity", "tolerance": 0.1},
           {"feature": "ring", "characteristic": "roundness", "tolerance": 0.1}],
    }
    return part_spec_from_dict(doc, "props.toml")


SPEC = _spec()


def test_a_perfect_part_measures_zero():
    res = inspect_scan(_part(0.0, 0), SPEC)
    for t in res.tolerances:
        want = 0.0
        if t.characteristic in ("profile", "position"):
            want = 0.0  # the top sits exactly at its basic height
        if t.characteristic == "angularity":
            want = 40 * math.sin(math.radians(5.0))  # a flat face measured against a 5-degree zone: not perfect
            continue
        assert abs(t.measured - want) < 1e-9, (t.characteristic, t.measured)


@settings(max_examples=15, deadline=None)
@given(amp=st.floats(1e-4, 0.05), seed=st.integers(0, 10_000))
def test_never_negative_and_outside_points_never_lower_it(amp, seed):
    pts = _part(amp, seed)
    base = inspect_scan(pts, SPEC)
    for t in base.tolerances:
        assert t.measured >= 0.0 and math.isfinite(t.measured)
    # one more point, clearly outside every zone of F, the ball and the ring
    extra = np.array([[20.0, 15.0, 10 + 1.5], [70.0, 20.0, 10 + 5.0 + 0.9], [100.0 + 4.0 + 0.4, 20.0, 5.0]])
    more = inspect_scan(np.concatenate([pts, extra]), SPEC)
    for a, b in zip(base.tolerances, more.tolerances):
        assert b.measured >= a.measured - 1e-12, (a.characteristic, a.feature, a.measured, b.measured)
