"""Issue 14 leftovers: a datum axis at its basic angle to the primary plane, sphere datums
(a datum point, ISO 5459), and the exact flatness zone."""

import math

import numpy as np
import pytest

from gagekit import inspect_scan
from gagekit.errors import ConfigError
from gagekit.inspect import part_spec_from_dict
from gagekit.inspect.datums import DatumSystem
from gagekit.inspect.features import extract

LEAN = math.radians(30.0)  # the bore's axis leans 30 degrees from A's normal: 60 degrees to A
AZIMUTH = math.radians(35.0)


def _plane_a():
    u, v = np.meshgrid(np.linspace(-40, 40, 41), np.linspace(-40, 40, 41), indexing="ij")
    return np.column_stack([u.ravel(), v.ravel(), 0 * u.ravel()])


def _bore_axis():
    return np.array([math.sin(LEAN) * math.cos(AZIMUTH), math.sin(LEAN) * math.sin(AZIMUTH), math.cos(LEAN)])


def _bore(radius=6.0):
    d = _bore_axis()
    u = np.cross(d, [0.0, 0.0, 1.0])
    u /= np.linalg.norm(u)
    v = np.cross(d, u)
    t, h = np.meshgrid(np.linspace(0, 2 * math.pi, 90, endpoint=False), np.linspace(5, 25, 21), indexing="ij")
    t, h = t.ravel(), h.ravel()
    r = radius + 0.002 * np.cos(3 * t)  # a trilobe: the inscribed cylinder is not the LS one
    return np.array([60.0, 0.0, 0.0]) + np.outer(h, d) + np.outer(r * np.cos(t), u) + np.outer(r * np.sin(t), v)


def _ball(center, r=5.0):
    th, ph = np.meshgrid(np.linspace(0, 2 * math.pi, 24, endpoint=False), np.linspace(-1.2, 1.2, 13), indexing="ij")
    th, ph = th.ravel(), ph.ravel()
    return np.asarray(center) + r * np.column_stack([np.cos(th) * np.cos(ph), np.sin(th) * np.cos(ph), np.sin(ph)])


def _spec(bore_angle, tolerances, extra=()):
    d = _bore_axis()
    mid = np.array([60.0, 0.0, 0.0]) + 15 * d
    doc = {
        "feature": [
            {"name": "A", "shape": "plane", "region": {"center": [0, 0, 0], "size": [82, 82, 0.5]}, "outward": [0, 0, -1]},
            {"name": "bore", "shape": "cylinder", "kind": "hole", "direction": d.tolist(),
             "region": {"center": mid.tolist(), "size": [40, 40, 26]}},
            {"name": "ball", "shape": "sphere", "kind": "shaft", "region": {"center": [-60, 0, 20], "size": [12, 12, 12]}},
            {"name": "ball2", "shape": "sphere", "region": {"center": [-60, 30, 24], "size": [12, 12, 12]}},
            *extra,
        ],
        "datums": {"A": "A", "D": {"feature": "bore", "angle": bore_angle}, "S": "ball"},
        "tolerance": tolerances,
    }
    return part_spec_from_dict(doc, "leftovers.toml")


def _points():
    return np.concatenate([_plane_a(), _bore(), _ball([-60, 0, 20]), _ball([-60, 30.0, 24.0])])


def test_datum_axis_at_its_basic_angle_to_the_primary_plane():
    spec = _spec(60.0, [{"feature": "ball", "characteristic": "position", "tolerance": 0.1, "datums": ["A", "D"],
                         "nominal": {"point": [0, 0, 0], "direction": [0, 0, 1]}}])
    pts = _points()
    system = DatumSystem(spec, extract(pts, spec.features))
    d = system.datum(("A", "D"))
    assert "at 60 degrees to A" in d.method
    # exactly on the cone of the basic angle, turned to the bore's lean
    assert math.degrees(math.acos(d.vector @ np.array([0, 0, 1.0]))) == pytest.approx(30.0, abs=1e-9)
    assert np.linalg.norm(np.cross(d.vector, _bore_axis())) < 1e-6
    # the maximum inscribed cylinder: the trilobe's inner radius
    assert d.radius == pytest.approx(6.0 - 0.002, abs=1e-6)
    # the lean fixes the frame's x (no free rotation about A's normal)
    frame = system.frame(("A", "D"))
    assert not frame.free_rotation
    lean = _bore_axis() - _bore_axis()[2] * np.array([0, 0, 1.0])
    assert np.linalg.norm(np.cross(frame.axes[0], lean)) < 1e-6


def test_a_datum_axis_far_from_its_basic_angle_is_a_config_error():
    spec = _spec(20.0, [{"feature": "ball", "characteristic": "position", "tolerance": 0.1, "datums": ["A", "D"],
                         "nominal": {"point": [0, 0, 0], "direction": [0, 0, 1]}}])
    with pytest.raises(ConfigError, match="at its basic angle of 20 degrees to it; this axis is 60 degrees from the plane"):
        inspect_scan(_points(), spec)


def test_sphere_datum_is_the_centre_of_the_ball():
    spec = _spec(60.0, [
        {"feature": "ball2", "characteristic": "position", "tolerance": 0.1, "datums": ["S"],
         "nominal": {"point": [0, 30.0, 0], "direction": [0, 0, 1]}},
        {"feature": "ball2", "characteristic": "position", "tolerance": 0.1, "datums": ["S", "A"],
         "nominal": {"point": [0, 30.0, 4.0], "direction": [0, 0, 1]}},
    ])
    res = inspect_scan(_points(), spec)
    s = [d for d in res.datums if d.letter == "S"][0]
    assert s.type == "point" and "minimum circumscribed sphere" in s.method
    assert np.allclose(s.point, [-60, 0, 20], atol=1e-9) and s.radius == pytest.approx(5.0, abs=1e-9)
    assert "direction" not in s.to_dict() and "normal" not in s.to_dict()
    alone, with_a = (c.measured for c in res.tolerances)
    # alone: every rotation about S is free; the centre is sqrt(30^2 + 4^2) from S, nominal 30
    assert alone == pytest.approx(2 * (math.hypot(30.0, 4.0) - 30.0), abs=1e-9)
    # S then A: z is A's normal into the material (+z), the origin S's centre; the turn about
    # z is free, so only the height (4) and the distance in the plane (30) are located: 0
    assert with_a == pytest.approx(0.0, abs=1e-9)
    frame = [f for f in res.frames if f.datums == ("S", "A")][0]
    assert np.allclose(frame.origin, [-60, 0, 20], atol=1e-9) and frame.free_rotation


def test_orientation_to_a_datum_point_is_a_config_error():
    with pytest.raises(ConfigError, match="a datum point fixes no orientation"):
        _spec(60.0, [{"feature": "A", "characteristic": "parallelism", "tolerance": 0.1, "datums": ["S"]}])


def test_flatness_is_the_exact_minimum_width():
    """The exact 3-D width (hull facets and antipodal edge pairs) on a wedge-shaped cloud,
    where the minimum-zone normal is not near the least-squares one: no direction of a
    fine grid gives a thinner slab."""
    rng = np.random.default_rng(3)
    p = rng.uniform(-1, 1, (400, 3)) * [20.0, 12.0, 0.5]
    p[:, 2] += 0.05 * p[:, 0] + 0.02 * np.abs(p[:, 1])  # a bent plate
    spec = part_spec_from_dict({
        "feature": [{"name": "F", "shape": "plane", "region": {"center": [0, 0, 0], "size": [50, 30, 10]}, "outward": [0, 0, 1]}],
        "tolerance": [{"feature": "F", "characteristic": "flatness", "tolerance": 1.0}],
    }, "flat.toml")
    w = inspect_scan(p, spec).tolerances[0].measured
    th, ph = np.meshgrid(np.linspace(0, 0.4, 200), np.linspace(0, 2 * math.pi, 360), indexing="ij")
    n = np.column_stack([np.sin(th.ravel()) * np.cos(ph.ravel()), np.sin(th.ravel()) * np.sin(ph.ravel()), np.cos(th.ravel())])
    h = p @ n.T
    assert w <= (h.max(axis=0) - h.min(axis=0)).min() + 1e-12
