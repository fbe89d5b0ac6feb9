"""Sizes (ISO 14405-1) with analytic answers: lobed shafts, ovals, widths, spheres, ISO 286."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gagekit import inspect_scan
from gagekit.errors import ConfigError
from gagekit.inspect import part_spec_from_dict
from gagekit.inspect.iso286 import RANGES, _IT_UM, fit_deviations, it_formula

R, A = 10.0, 0.05


def lobed(lobes, r=R, a=A, n_theta=360, heights=np.linspace(-10, 10, 21), center=(0.0, 0.0, 0.0)):
    th = np.linspace(0, 2 * math.pi, n_theta, endpoint=False)
    T, Z = np.meshgrid(th, heights, indexing="ij")
    rho = r + a * np.cos(lobes * T)
    return np.column_stack([(rho * np.cos(T)).ravel(), (rho * np.sin(T)).ravel(), Z.ravel()]) + np.array(center)


def spec(callouts, shape="cylinder", kind="shaft", size=(30, 30, 24), extra_features=(), part=None):
    doc = {"feature": [{"name": "f", "shape": shape, "kind": kind, "direction": [0, 0, 1],
                        "region": {"center": [0, 0, 0], "size": list(size)}}, *extra_features],
           "tolerance": [dict({"feature": "f", "characteristic": "size", "nominal": 2 * R}, **c) for c in callouts]}
    if shape == "sphere":
        del doc["feature"][0]["direction"]
    if part:
        doc["part"] = part
    return part_spec_from_dict(doc, "test")


MODS = ["LP", "GG", "GX", "GN", "SX", "SN", "SA", "SM", "SD", "SR", "CC", "CA", "CV"]


def test_three_lobed_shaft():
    pts = lobed(3)
    s = spec([{"upper": 0.01, "lower": -0.1, "modifier": m} for m in MODS])
    res = {t.extra["modifier"]: t for t in inspect_scan(pts, s).tolerances}
    lp = res["LP"]
    assert lp.extra["local_sizes"]["n"] == 10 * 180
    assert lp.extra["local_sizes"]["min"] == pytest.approx(2 * R, abs=1e-12)
    assert lp.extra["local_sizes"]["max"] == pytest.approx(2 * R, abs=1e-12)
    assert lp.measured == pytest.approx(2 * R, abs=1e-12)
    assert res["GN"].measured == pytest.approx(2 * (R + A), abs=1e-9)
    assert res["GX"].measured == pytest.approx(2 * (R - A), abs=1e-9)
    assert res["GG"].measured == pytest.approx(2 * R, abs=1e-9)
    for m in ("SX", "SN", "SA", "SM", "SD"):
        assert res[m].measured == pytest.approx(2 * R, abs=1e-12)
    assert res["SR"].measured == pytest.approx(0.0, abs=1e-12)
    # the two-point size passes (20 within 19.9 .. 20.01), the GN of 20.1 fails
    assert lp.passed and lp.margin == pytest.approx(0.01, abs=1e-12)
    assert not res["GN"].passed and res["GN"].margin == pytest.approx(0.01 - 2 * A, abs=1e-9)
    # CA: the area of the profile polygon through the 360 points, 1/2 sin(dt) sum r_i r_(i+1)
    th = np.linspace(0, 2 * math.pi, 360, endpoint=False)
    r = R + A * np.cos(3 * th)
    area = 0.5 * math.sin(2 * math.pi / 360) * float((r * np.roll(r, -1)).sum())
    assert res["CA"].measured == pytest.approx(2 * math.sqrt(area / math.pi), abs=1e-12)
    assert res["CV"].measured == pytest.approx(res["CA"].measured, abs=1e-9)
    assert res["CC"].measured > 2 * R


def test_envelope_catches_the_lobed_shaft():
    pts = lobed(3)
    ok = inspect_scan(pts, spec([{"upper": 0.01, "lower": -0.1}])).tolerances[0]
    env = inspect_scan(pts, spec([{"upper": 0.01, "lower": -0.1, "envelope": True}])).tolerances[0]
    asme = inspect_scan(pts, spec([{"upper": 0.01, "lower": -0.1}], part={"standard": "asme"})).tolerances[0]
    indep = inspect_scan(pts, spec([{"upper": 0.01, "lower": -0.1, "envelope": False}], part={"standard": "asme"})).tolerances[0]
    assert ok.passed and indep.passed and "envelope" not in ok.to_dict()
    for t in (env, asme):
        assert not t.passed
        assert t.extra["envelope"]["mating_size"] == pytest.approx(2 * (R + A), abs=1e-9)
        assert t.extra["envelope"]["mmc_size"] == pytest.approx(2 * R + 0.01)
        assert t.margin == pytest.approx(0.01 - 2 * A, abs=1e-9)


def test_oval_two_point_range():
    pts = lobed(2, n_theta=720)
    t = inspect_scan(pts, spec([{"upper": 0.2, "lower": -0.2}])).tolerances[0]
    ls = t.extra["local_sizes"]
    assert ls["min"] == pytest.approx(2 * R - 2 * A, abs=1e-12)
    assert ls["max"] == pytest.approx(2 * R + 2 * A, abs=1e-12)
    assert t.passed and t.margin == pytest.approx(0.2 - 2 * A, abs=1e-12)
    tight = inspect_scan(pts, spec([{"upper": 0.05, "lower": -0.2}])).tolerances[0]
    assert tight.measured == pytest.approx(2 * R + 2 * A) and not tight.passed


def test_hole_fit_and_json():
    pts = lobed(3, r=10.01, a=0.002)
    s = spec([{"fit": "H7"}], kind="hole")
    t = inspect_scan(pts, s).tolerances[0]
    d = t.to_dict()
    assert d["upper_limit"] == pytest.approx(20.021) and d["lower_limit"] == pytest.approx(20.0)
    assert d["fit"] == "H7" and d["tolerance"] == pytest.approx(0.021)
    assert set(d["local_sizes"]) == {"n", "min", "max", "mean"}
    assert d["measured"] == pytest.approx(20.02, abs=1e-12) and d["pass"]
    assert d["margin"] == pytest.approx(0.001, abs=1e-9)


def test_circle_sphere_cone_widths():
    circle = lobed(3, heights=np.array([0.0]))
    t = inspect_scan(circle, spec([{"upper": 0.1, "lower": -0.1}, {"upper": 0.2, "lower": 0, "modifier": "GN"}], shape="circle",
                             size=(30, 30, 1))).tolerances
    assert t[0].measured == pytest.approx(2 * R, abs=1e-12) and t[1].measured == pytest.approx(2 * (R + A), abs=1e-9)
    # a sphere of radius 10: every two-point size 20
    lat = np.linspace(-math.pi / 2, math.pi / 2, 61)[1:-1]
    lon = np.linspace(0, 2 * math.pi, 120, endpoint=False)
    LA, LO = np.meshgrid(lat, lon, indexing="ij")
    ball = R * np.column_stack([(np.cos(LA) * np.cos(LO)).ravel(), (np.cos(LA) * np.sin(LO)).ravel(), np.sin(LA).ravel()])
    t = inspect_scan(ball, spec([{"upper": 0.1, "lower": -0.1, "modifier": m} for m in ("LS", "GN", "GG")], shape="sphere",
                           size=(30, 30, 30))).tolerances
    assert t[0].extra["local_sizes"]["min"] == pytest.approx(2 * R, abs=1e-9)
    assert t[0].extra["local_sizes"]["max"] == pytest.approx(2 * R, abs=1e-9)
    assert t[1].measured == pytest.approx(2 * R, abs=1e-9) and t[2].measured == pytest.approx(2 * R, abs=1e-9)


def width_points(width=10.0, bow=0.02):
    x, y = np.meshgrid(np.linspace(-15, 15, 61), np.linspace(-8, 8, 33), indexing="ij")
    x, y = x.ravel(), y.ravel()
    a = np.column_stack([x, y, 0 * x])
    b = np.column_stack([x, y, width + bow * (1 - (x / 15) ** 2)])
    return np.vstack([a, b]), x


@pytest.mark.parametrize("shape", ["slot", "tab"])
def test_width(shape):
    bow = 0.02
    pts, x = width_points(bow=bow)
    doc = {"feature": [{"name": "w", "shape": shape, "direction": [0, 0, 1], "region": {"center": [0, 0, 5], "size": [40, 20, 14]}}],
           "tolerance": [{"feature": "w", "characteristic": "size", "nominal": 10.0, "upper": 0.1, "lower": -0.1, "modifier": m}
                         for m in ("LP", "GX", "GN", "GG")]}
    t = inspect_scan(pts, part_spec_from_dict(doc, "t")).tolerances
    # a flat face z = 0 and a bowed one z = 10 + bow (1 - (x / 15)^2), symmetric: the common normal is z
    ls = t[0].extra["local_sizes"]
    assert ls["n"] == len(x)
    assert ls["min"] == pytest.approx(10.0, abs=1e-12) and ls["max"] == pytest.approx(10 + bow, abs=1e-12)
    assert t[1].measured == pytest.approx(10.0, abs=1e-12)        # GX: the widest slab between the faces
    assert t[2].measured == pytest.approx(10 + bow, abs=1e-12)    # GN: the thinnest slab holding both
    assert t[3].measured == pytest.approx(10 + bow * float(np.mean(1 - (x / 15) ** 2)), abs=1e-12)


def test_iso286_published_values():
    assert fit_deviations("H7", 20) == (0.021, 0.0)
    assert fit_deviations("g6", 20) == (-0.007, -0.02)
    # ISO 286-2 tables: 50 H8 = +0.039/0, 50 f7 = -0.025/-0.050, 10 k6 = +0.010/+0.001, 100 s6 = +0.093/+0.071,
    # 25 N7 = -0.007/-0.028, 6 js6 = +-0.004, 200 P7 = -0.033/-0.079
    assert fit_deviations("H8", 50) == (0.039, 0.0)
    assert fit_deviations("f7", 50) == (-0.025, -0.05)
    assert fit_deviations("k6", 10) == (0.01, 0.001)
    assert fit_deviations("s6", 100) == (0.093, 0.071)
    assert fit_deviations("N7", 25) == (-0.007, -0.028)
    assert fit_deviations("js6", 6) == (0.004, -0.004)
    assert fit_deviations("P7", 200) == (-0.033, -0.079)
    with pytest.raises(ConfigError, match="500"):
        fit_deviations("H7", 600)
    with pytest.raises(ConfigError, match="not tabulated"):
        fit_deviations("q7", 20)


def test_iso286_table_is_its_formula():
    """IT5 ... IT11 of Table 1 (3 to 500 mm) are the formula values rounded: within 5 % from IT7 on,
    10 % for IT5 / IT6 (the standard's rounding of small values); the first range is tabulated only."""
    for grade in range(5, 12):
        for k in range(1, len(RANGES)):
            exact = it_formula(grade, k)
            assert abs(_IT_UM[grade][k] - exact) <= (0.05 if grade >= 7 else 0.10) * exact, (grade, RANGES[k])


@settings(max_examples=8, deadline=None)
@given(st.floats(-math.pi, math.pi), st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1),
       st.floats(-300, 300), st.floats(-300, 300), st.floats(-300, 300))
def test_sizes_invariant_under_rigid_motion(angle, ax, ay, az, tx, ty, tz):
    axis = np.array([ax, ay, az])
    if np.linalg.norm(axis) < 1e-3:
        axis = np.array([0.0, 0.0, 1.0])
    axis = axis / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    Rm = np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K
    t = np.array([tx, ty, tz])
    pts = lobed(2, n_theta=144, heights=np.linspace(-10, 10, 5))
    # 7 sections: no ring of the scan lies on a section boundary (a ring split between two
    # sections by rounding would change CA, honestly: its profile has half the points)
    s = spec([{"upper": 0.25, "lower": -0.2, "modifier": m, "sections": 7} for m in ("LP", "GX", "GN", "CA")])
    base = inspect_scan(pts, s).tolerances
    moved = inspect_scan(pts @ Rm.T + t, s.moved(Rm, t)).tolerances
    for a, b in zip(base, moved):
        # LP, CA: 1e-9; GX / GN of the oval come from the free-direction cylinder search of
        # gagekit.form (its inscribed cylinder touches two lines only: a flat optimum), 1e-5
        tol = 1e-5 if a.extra["modifier"] in ("GX", "GN") else 1e-9
        assert b.measured == pytest.approx(a.measured, abs=tol), a.extra["modifier"]
        assert b.extra.get("local_sizes", {}).get("min", 0) == pytest.approx(a.extra.get("local_sizes", {}).get("min", 0), abs=1e-9)


@pytest.mark.parametrize("bad, match", [
    ({"upper": 0.1}, "'lower' is missing"),
    ({"upper": -0.1, "lower": 0.1}, "below"),
    ({"fit": "H7", "upper": 0.1, "lower": 0}, "either 'fit'"),
    ({"upper": 0.1, "lower": 0, "modifier": "XX"}, "modifier"),
    ({"upper": 0.1, "lower": 0, "datums": ["A"]}, "no datums|not in"),
    ({}, "limits are missing"),
    ({"upper": 0.1, "lower": 0, "envelope": "yes"}, "envelope"),
])
def test_bad_size_callouts(bad, match):
    with pytest.raises(ConfigError, match=match):
        spec([bad])


def test_size_needs_a_feature_of_size():
    doc = {"feature": [{"name": "p", "shape": "plane", "outward": [0, 0, 1], "region": {"center": [0, 0, 0], "size": [1, 1, 1]}}],
           "tolerance": [{"feature": "p", "characteristic": "size", "nominal": 1.0, "upper": 0.1, "lower": 0}]}
    with pytest.raises(ConfigError, match="does not apply to a plane"):
        part_spec_from_dict(doc, "t")


def test_bracket_with_sizes_and_material_conditions():
    """The bundled bracket's whole drawing (bracket_sizes.toml): its 20 geometric callouts as in
    bracket.toml, and sizes, distances, angles, MMC bonuses and a datum shift at their analytic values."""
    from bracket_fixture import key, load_generator
    from gagekit import load_part_spec, read_points
    from gagekit.samples import data_path

    gen = load_generator()
    pts = read_points(data_path("bracket.ply"))
    res = inspect_scan(pts, load_part_spec(data_path("bracket_sizes.toml")))
    assert len(res.tolerances) == len(gen.EXPECTED) + len(gen.EXPECTED_SIZES)
    for t in res.tolerances:
        want = gen.EXPECTED[key(t)] if key(t) in gen.EXPECTED else gen.EXPECTED_SIZES[key(t)]
        assert t.measured == pytest.approx(want, abs=1e-9), key(t)
    by = {t.name: t for t in res.tolerances if t.name}
    for name, bonus in gen.BONUS.items():
        assert by[name].extra["bonus"] == pytest.approx(bonus, abs=1e-9), name
        assert by[name].extra["tolerance_zone"] == pytest.approx(by[name].tolerance + bonus, abs=1e-9)
        assert by[name].margin == pytest.approx(by[name].extra["tolerance_zone"] - by[name].measured)
    # 0 at MMC: the whole zone is the bonus, and the pin's 0.02 fits in 0.024
    assert by["position of pin 0 at MMC"].passed
    assert by["position of pin to A|D(M)"].extra["datum_shift"] == pytest.approx(0.0065 / 2, abs=1e-9)
    bore = by["size of bore"].to_dict()
    assert bore["envelope"]["mating_size"] == pytest.approx(gen.BORE_GX, abs=1e-9)
    assert bore["local_sizes"]["n"] == 1800 and bore["local_sizes"]["max"] == pytest.approx(20.0, abs=1e-9)
    assert {k for k in bore} >= {"measured", "local_sizes", "upper_limit", "lower_limit", "pass", "margin"}


def test_min_in_disk_is_exact():
    from gagekit.inspect.material import min_in_disk

    w = np.array([[1.0, 0.0], [3.0, 0.0]])
    assert min_in_disk(w, 5.0)[0] == pytest.approx(1.0)      # the enclosing circle's centre (2, 0) is reachable
    assert min_in_disk(w, 0.5)[0] == pytest.approx(2.5)      # s = (0.5, 0): the far point at 2.5
    assert min_in_disk(w, 0.0)[0] == pytest.approx(3.0)


def test_material_needs_a_size_callout():
    pts = lobed(3)
    doc = {"feature": [{"name": "a", "shape": "plane", "outward": [0, 0, -1], "region": {"center": [0, 0, -10], "size": [40, 40, 0.5]}},
                       {"name": "f", "shape": "cylinder", "kind": "shaft", "direction": [0, 0, 1],
                        "region": {"center": [0, 0, 0], "size": [30, 30, 18]}}],
           "datums": {"A": "a"},
           "tolerance": [{"feature": "f", "characteristic": "perpendicularity", "tolerance": 0.0, "material": "MMC", "datums": ["A"]}]}
    plane = np.column_stack([np.random.default_rng(0).uniform(-15, 15, (400, 2)), np.full(400, -10.0)])
    with pytest.raises(ConfigError, match="size limits"):
        inspect_scan(np.vstack([pts, plane]), part_spec_from_dict(doc, "t"))
    doc["tolerance"].append({"feature": "f", "characteristic": "size", "nominal": 20.0, "upper": 0.1, "lower": -0.1})
    t = inspect_scan(np.vstack([pts, plane]), part_spec_from_dict(doc, "t")).tolerances[0]
    # a shaft: bonus = MMC size 20.1 - GN 2 (R + a) = 0.1 - 2 a
    assert t.extra["bonus"] == pytest.approx(0.1 - 2 * A, abs=1e-9)
    doc["tolerance"][0]["tolerance"] = -0.1
    with pytest.raises(ConfigError, match="tolerance"):
        part_spec_from_dict(doc, "t")
