"""Agreement with the NIST least-squares reference fits (ASME B89.4.10 data sets).

Diameters and positions within 1e-7 mm, directions within 1e-8 rad (up to sign);
positions of lines and axes compared by the distance between the lines.
"""

from __future__ import annotations

import numpy as np
import pytest

import gagekit
from conftest import NIST

REF = NIST

POS_TOL = 1e-7
DIA_TOL = 1e-7
ANG_TOL = 1e-8


def _pairs(kind: str) -> list[str]:
    d = REF / kind
    if not d.is_dir():
        return []
    return sorted(p.stem for p in d.glob("*.ds"))


def _load(kind: str, name: str) -> tuple[np.ndarray, np.ndarray]:
    pts = np.loadtxt(REF / kind / f"{name}.ds", skiprows=1, ndmin=2)
    fit = np.loadtxt(REF / kind / f"{name}.fit")
    return pts, fit


def angle(a, b) -> float:
    a, b = (np.pad(np.asarray(v, float), (0, 3 - len(v))) for v in (a, b))
    return float(np.arctan2(np.linalg.norm(np.cross(a, b)), abs(a @ b)))


def point_line_distance(p, q, a) -> float:
    a = np.asarray(a, float) / np.linalg.norm(a)
    d = np.asarray(p, float) - np.asarray(q, float)
    return float(np.linalg.norm(d - (d @ a) * a))


def _drop_constant(pts: np.ndarray) -> tuple[np.ndarray, int]:
    k = int(np.argmin(np.ptp(pts, axis=0)))
    assert np.ptp(pts[:, k]) == 0.0
    return np.delete(pts, k, axis=1), k


def test_reference_data_present():
    counts = {k: len(_pairs(k)) for k in ("line2d", "line3d", "plane", "circle2d", "circle3d", "sphere", "cylinder", "cone")}
    assert all(counts.values()), counts


@pytest.mark.parametrize("name", _pairs("line2d") + _pairs("line3d"))
def test_line(name):
    kind = "line2d" if name.startswith("lin2d") else "line3d"
    pts, ref = _load(kind, name)
    r = gagekit.fit_line(pts)
    assert angle(r.direction, ref[3:6]) < ANG_TOL
    assert point_line_distance(ref[:3], r.point, r.direction) < POS_TOL
    if kind == "line2d":  # the same line from the 2-D coordinates
        p2, k = _drop_constant(pts)
        r2 = gagekit.fit_line(p2)
        assert angle(r2.direction, np.delete(ref[3:6], k)) < ANG_TOL
        assert point_line_distance(np.delete(ref[:3], k), r2.point, r2.direction) < POS_TOL


@pytest.mark.parametrize("name", _pairs("plane"))
def test_plane(name):
    pts, ref = _load("plane", name)
    r = gagekit.fit_plane(pts)
    assert angle(r.normal, ref[3:6]) < ANG_TOL
    assert abs((ref[:3] - np.array(r.point)) @ np.array(r.normal)) < POS_TOL


@pytest.mark.parametrize("name", _pairs("circle2d") + _pairs("circle3d"))
def test_circle(name):
    kind = "circle2d" if name.startswith("cir2d") else "circle3d"
    pts, ref = _load(kind, name)
    r = gagekit.fit_circle_3d(pts)
    assert abs(2 * r.radius - ref[6]) < DIA_TOL
    assert np.linalg.norm(np.array(r.center) - ref[:3]) < POS_TOL
    assert angle(r.normal, ref[3:6]) < ANG_TOL
    if kind == "circle2d":  # the same circle from the 2-D coordinates
        p2, k = _drop_constant(pts)
        r2 = gagekit.fit_sphere(p2)
        assert r2.shape == "circle"
        assert abs(2 * r2.radius - ref[6]) < DIA_TOL
        assert np.linalg.norm(np.array(r2.center) - np.delete(ref[:3], k)) < POS_TOL


@pytest.mark.parametrize("name", _pairs("sphere"))
def test_sphere(name):
    pts, ref = _load("sphere", name)
    r = gagekit.fit_sphere(pts)
    assert abs(2 * r.radius - ref[3]) < DIA_TOL
    assert np.linalg.norm(np.array(r.center) - ref[:3]) < POS_TOL


@pytest.mark.parametrize("name", _pairs("cylinder"))
def test_cylinder(name):
    pts, ref = _load("cylinder", name)
    r = gagekit.fit_cylinder(pts, "least-squares")
    assert abs(2 * r.radius - ref[6]) < DIA_TOL
    assert angle(r.direction, ref[3:6]) < ANG_TOL
    assert point_line_distance(ref[:3], r.point, r.direction) < POS_TOL


@pytest.mark.parametrize("name", _pairs("cylinder"))
def test_cylinder_translated_1e6(name):
    pts, ref = _load("cylinder", name)
    shift = np.array([1e6, -1e6, 5e5])
    r = gagekit.fit_cylinder(pts + shift, "lsq")
    assert abs(2 * r.radius - ref[6]) < DIA_TOL
    assert angle(r.direction, ref[3:6]) < ANG_TOL
    assert point_line_distance(ref[:3] + shift, r.point, r.direction) < POS_TOL


@pytest.mark.parametrize("name", _pairs("cone"))
def test_cone(name):
    pts, ref = _load("cone", name)
    r = gagekit.fit_cone(pts)
    assert angle(r.direction, ref[3:6]) < ANG_TOL
    assert point_line_distance(ref[:3], r.point, r.direction) < POS_TOL
    assert abs(np.degrees(r.apex_angle) - ref[7]) < ANG_TOL * 180 / np.pi
    # distance to the surface from the reference point (moved onto our axis)
    z = (ref[:3] - np.array(r.point)) @ np.array(r.direction)
    d_ref = r.distance + z * np.sin(r.apex_angle / 2)
    assert abs(abs(d_ref) - abs(ref[6])) < POS_TOL
