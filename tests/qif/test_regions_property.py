"""Regions derived from nominal geometry (hypothesis): in any pose, a cylinder's or cone's
box holds every point of its nominal surface at least ``inset`` from its ends and none
beyond them; a plane's box holds every point of its face at least ``inset`` inside the
boundary."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings, strategies as st

from gagekit._rotation import rotation_from_vector
from gagekit.cloud.regions import Box, classify
from gagekit.qif.model import FeatureNominal
from gagekit.qif.nominal import basis, feature_region, sample_feature

unit = st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1).map(lambda v: np.array(v) / np.linalg.norm(v))
point = st.tuples(*[st.floats(-500, 500)] * 3).map(np.array)


def _box(reg) -> Box:
    return Box(reg.center, reg.size, reg.rotation)


@settings(max_examples=60, deadline=None)
@given(d=unit, p=point, dia=st.floats(1, 100), length=st.floats(6, 200), band=st.floats(0.05, 1), inset=st.floats(0, 1.4))
def test_cylinder_region_holds_its_surface_between_the_insets(d, p, dia, length, band, inset):
    f = FeatureNominal("1", "Cylinder", "", {"point": p, "direction": d, "diameter": dia, "length": length}, True)
    reg = feature_region(f, band, inset)
    pts = sample_feature(f, 3000)
    t = (pts - p) @ d
    inside = np.zeros(len(pts), bool)
    inside[classify(pts, [_box(reg)])[0]] = True
    tol = 1e-9 * (1 + np.abs(p).max() + length)
    assert inside[(t >= inset + tol) & (t <= length - inset - tol)].all()
    assert not inside[(t < inset - tol) | (t > length - inset + tol)].any()


@settings(max_examples=60, deadline=None)
@given(d=unit, p=point, dia=st.floats(2, 80), half=st.floats(1, 30), large=st.floats(6, 100), inset=st.floats(0, 1.4))
def test_cone_region_holds_its_surface(d, p, dia, half, large, inset):
    f = FeatureNominal("1", "Cone", "", {"point": p, "direction": d, "diameter": dia, "half_angle": half,
                                         "large_end": large, "small_end": 0.0}, False)
    reg = feature_region(f, 0.5, inset)
    pts = sample_feature(f, 3000)
    t = (pts - p) @ d
    inside = np.zeros(len(pts), bool)
    inside[classify(pts, [_box(reg)])[0]] = True
    tol = 1e-9 * (1 + np.abs(p).max() + large)
    assert inside[(t >= inset + tol) & (t <= large - inset - tol)].all()


@settings(max_examples=60, deadline=None)
@given(n=unit, p=point, w=st.floats(5, 300), h=st.floats(5, 300), turn=st.floats(-3.1, 3.1), inset=st.floats(0, 1.2))
def test_plane_region_holds_its_face_inside_the_inset(n, p, w, h, turn, inset):
    B = basis(n)
    R = rotation_from_vector(n * turn)  # the rectangle turned in its plane: boxes need not align
    u, v = R @ B[0], R @ B[1]
    corners = np.array([p + a * u * w / 2 + b * v * h / 2 for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
    f = FeatureNominal("1", "Plane", "", {"location": p, "normal": n, "polyline": corners})
    reg = feature_region(f, 0.5, inset)
    pts = sample_feature(f, 3000)
    s, r = (pts - p) @ u, (pts - p) @ v
    deep = (np.abs(s) <= w / 2 - inset * 1.5 - 1e-6) & (np.abs(r) <= h / 2 - inset * 1.5 - 1e-6)
    inside = np.zeros(len(pts), bool)
    inside[classify(pts, [_box(reg)])[0]] = True
    assert inside[deep].all()
