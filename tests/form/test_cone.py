"""Cones (issue 25 §3): least squares, minimum zone (conicity), minimum circumscribed and
maximum inscribed, free or fixed half angle; analytic answers, invariance, errors, CLI and
the inspect `conicity` characteristic."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gagekit
from gagekit.errors import ConfigError, DegenerateGeometryError, InvalidInputError
from gagekit.samples import sample_path
from test_form3d_cylinder import rotation

CRITERIA = ("least-squares", "minimum-zone", "min-circumscribed", "max-inscribed")
P0 = np.array([12.0, -7.0, 30.0])
AXIS = np.array([0.3, -0.2, 0.9]) / np.linalg.norm([0.3, -0.2, 0.9])


def _basis(a):
    u = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    return u, np.cross(a, u)


def cone_points(psi, r0, dev=lambda t, z: 0.0 * t, zs=np.linspace(0.0, 20.0, 5), m=36, p0=P0, a=AXIS):
    """Points of the cone of half angle ``psi`` (radius ``r0`` at ``p0``), each moved by
    ``dev(t, z)`` along the surface normal; section s is turned by 0.1 s rad."""
    u, v = _basis(a)
    out = []
    for s, z in enumerate(zs):
        t = 2 * np.pi * np.arange(m) / m + 0.1 * s
        d = dev(t, z)
        rho = r0 + z * math.tan(psi) + d * math.cos(psi)
        zz = z - d * math.sin(psi)
        out.append(p0 + np.outer(zz, a) + (np.outer(np.cos(t), u) + np.outer(np.sin(t), v)) * rho[:, None])
    return np.vstack(out)


@pytest.mark.parametrize("criterion", CRITERIA)
@pytest.mark.parametrize("fixed", [False, True])
def test_points_on_a_cone_return_its_parameters(criterion, fixed):
    psi = math.radians(25.0)
    p = cone_points(psi, 20.0)
    f = gagekit.fit_cone(p, criterion, angle=25.0 if fixed else None)
    apex = P0 - AXIS * 20.0 / math.tan(psi)
    zc = float((p.mean(axis=0) - P0) @ AXIS)
    assert abs(f.half_angle - psi) < 1e-9
    assert np.linalg.norm(np.array(f.direction) - AXIS) < 1e-9
    assert np.linalg.norm(np.array(f.apex) - apex) < 1e-9
    assert abs(f.radius - (20.0 + zc * math.tan(psi))) < 1e-9
    assert f.form_error < 1e-9 and f.fixed_angle == fixed
    # the reported axis point is the reference section's: the foot of the centroid
    assert abs(float((p.mean(axis=0) - np.array(f.point)) @ AXIS)) < 1e-9


def test_lobed_cone_has_the_known_minimum_zone():
    # a 3-lobed normal deviation of amplitude a: the zone is 2a wide about the true cone
    psi, amp = math.radians(17.0), 0.004
    p = cone_points(psi, 15.0, lambda t, z: amp * np.cos(3 * (t - 0.1 * z / 5.0)))
    mz = gagekit.fit_cone(p, "mz")
    assert abs(mz.form_error - 2 * amp) < 1e-9
    assert abs(mz.half_angle - psi) < 1e-9 and mz.gap < 1e-9
    assert abs((mz.outer_radius - mz.inner_radius) * math.cos(psi) - 2 * amp) < 1e-9
    ls = gagekit.fit_cone(p)
    assert mz.form_error <= ls.form_error + 1e-12
    d = mz.to_dict()
    assert d["certificate"]["max_distance"] - d["certificate"]["min_distance"] == pytest.approx(2 * amp, abs=1e-9)


@pytest.mark.parametrize("seed", range(3))
def test_circumscribed_least_squares_inscribed_at_the_reference_section(seed):
    rng = np.random.default_rng(seed)
    c = rng.uniform(0.002, 0.006, 4)
    ph = rng.uniform(0, 2 * np.pi, 4)

    def dev(t, z):
        return c[0] * np.cos(2 * t + ph[0]) + c[1] * np.cos(5 * t + ph[1]) + c[2] * np.sin(0.3 * z + ph[2]) + c[3] * np.cos(7 * t + ph[3])

    p = cone_points(math.radians(10 + 15 * seed), 12.0, dev, zs=np.linspace(0, 25, 7), m=30)
    ls, mz, mc, mi = (gagekit.fit_cone(p, k) for k in CRITERIA)
    assert mc.radius >= ls.radius >= mi.radius
    # the circumscribed cone holds every point, the inscribed one none (normal deviations)
    assert abs(mc.certificate.max_distance) < 1e-9 and abs(mi.certificate.min_distance) < 1e-9
    assert mz.form_error <= min(ls.form_error, mc.form_error, mi.form_error) + 1e-12
    # the free zone's own angle, fixed, gives the same zone
    fixed = gagekit.fit_cone(p, "mz", angle=math.degrees(mz.half_angle))
    assert fixed.form_error == pytest.approx(mz.form_error, abs=1e-9)


def test_fixed_angle_equals_the_free_fit_at_the_true_angle():
    psi = math.radians(30.0)
    p = cone_points(psi, 10.0, lambda t, z: 0.003 * np.cos(3 * (t - 0.1 * z / 5.0)))
    for crit in CRITERIA:
        free, fixed = gagekit.fit_cone(p, crit), gagekit.fit_cone(p, crit, angle=30.0)
        assert fixed.form_error == pytest.approx(free.form_error, abs=1e-9), crit
        assert fixed.radius == pytest.approx(free.radius, abs=1e-9), crit
        assert np.allclose(fixed.apex, free.apex, atol=1e-8), crit


@settings(max_examples=10, deadline=None)
@given(st.tuples(*[st.floats(-3.0, 3.0)] * 3), st.tuples(*[st.floats(-1000.0, 1000.0)] * 3), st.integers(0, 10_000))
def test_invariant_under_a_rigid_motion(angles, shift, seed):
    rng = np.random.default_rng(seed)
    c, ph = rng.uniform(0.001, 0.004, 3), rng.uniform(0, 2 * np.pi, 3)
    p = cone_points(math.radians(rng.uniform(8, 50)), rng.uniform(5, 30),
                    lambda t, z: c[0] * np.cos(3 * t + ph[0]) + c[1] * np.cos(2 * t + ph[1]) + c[2] * np.sin(0.2 * z + ph[2]))
    rot = rotation(*angles)
    moved = p @ rot.T + np.array(shift)
    for crit in ("least-squares", "minimum-zone"):
        f0, f1 = gagekit.fit_cone(p, crit), gagekit.fit_cone(moved, crit)
        assert f1.form_error == pytest.approx(f0.form_error, abs=1e-9), crit
        assert f1.radius == pytest.approx(f0.radius, abs=1e-9), crit
        assert f1.half_angle == pytest.approx(f0.half_angle, abs=1e-9), crit
        assert np.allclose(rot @ np.array(f0.apex) + np.array(shift), f1.apex, atol=1e-7), crit
    # MC / MI with a free angle: the radius they optimise is invariant; their cone is not
    # always unique (a ridge of optima where fewer points than unknowns touch it: the
    # radius at the reference section varies there by ~1e-9 of the size while the half
    # angle moves), so neither the angle nor the form about it is compared (seen, seed
    # 1070, a 1 rad turn about z: MI half angle 0.236857 -> 0.236875 rad, form 0.01935 ->
    # 0.01969 mm, radius within 6e-9 mm); the search along that ridge is local (its
    # certificate too): the radius agrees to 1e-6 mm (seen: 1.5e-7 mm on a pure
    # translation, seed 3377), far below any scan's noise
    for crit in ("min-circumscribed", "max-inscribed"):
        f0, f1 = gagekit.fit_cone(p, crit), gagekit.fit_cone(moved, crit)
        assert f1.radius == pytest.approx(f0.radius, abs=1e-6), crit


def test_bad_input_raises_typed_errors():
    p = cone_points(0.3, 10.0, zs=np.linspace(0, 10, 3), m=8)
    with pytest.raises(InvalidInputError):
        gagekit.fit_cone(p[:5], "mz")
    with pytest.raises(DegenerateGeometryError, match="cylinder"):
        gagekit.fit_cone(cone_points(0.0, 10.0), "mz")
    flat = np.column_stack([np.cos(np.arange(30.0)) * np.arange(1, 31), np.sin(np.arange(30.0)) * 3, np.full(30, 2.0)])
    with pytest.raises(DegenerateGeometryError, match="coplanar"):
        gagekit.fit_cone(flat)
    for bad in (0.0, -5.0, 90.0, 120.0, float("nan"), "steep"):
        with pytest.raises(ConfigError):
            gagekit.fit_cone(p, "mz", angle=bad)
    with pytest.raises(ConfigError):
        gagekit.fit_cone(p, "bogus")


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "gagekit", "form", *args], capture_output=True, text=True, timeout=120)


def test_cli_on_the_bundled_cone():
    # data/cone.csv (make_form_samples.py): half angle 30 degrees, apex (0, 0, 40), axis -z
    # (the radius grows towards -z), 1 um normal noise
    path = str(sample_path("cone"))
    out = {}
    for crit in ("lsq", "mz", "mc", "mi"):
        r = _cli("fit", "cone", path, "-c", crit, "--json")
        assert r.returncode == 0, r.stderr
        out[crit] = d = json.loads(r.stdout)
        assert d["shape"] == "cone" and d["n_points"] == 180
        assert abs(d["half_angle_deg"] - 30.0) < 0.01 and np.allclose(d["apex"], [0, 0, 40], atol=0.02)
        assert np.allclose(np.abs(d["axis_direction"]), [0, 0, 1], atol=1e-3) and d["axis_direction"][2] < 0
        for key in ("axis_point", "radius", "form_error", "certificate", "apex_angle", "distance"):
            assert key in d
    assert out["mz"]["form_error"] < 0.008 and out["mz"]["gap"] < 1e-9
    assert out["mz"]["form_error"] <= out["lsq"]["form_error"]
    assert out["mc"]["radius"] >= out["lsq"]["radius"] >= out["mi"]["radius"]
    assert out["mz"]["inner_radius"] < out["mz"]["radius"] < out["mz"]["outer_radius"]
    fixed = json.loads(_cli("fit", "cone", path, "-c", "mz", "--angle", "30", "--json").stdout)
    assert fixed["fixed_angle"] and fixed["half_angle_deg"] == pytest.approx(30.0, abs=1e-12)
    human = _cli("fit", "cone", path, "-c", "mc")
    assert human.returncode == 0 and "half_angle_deg" in human.stdout and "apex" in human.stdout


@pytest.mark.parametrize("args", [("cone", "-c", "mz", "--angle", "95"), ("cone", "-c", "mz", "--angle", "0"),
                                  ("plane", "--angle", "30"), ("cone", "-c", "bogus")])
def test_cli_bad_options_are_one_line(args):
    shape, *rest = args
    r = _cli("fit", shape, str(sample_path("cone")), *rest)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.startswith("gagekit: error:") and r.stderr.count("\n") == 1


def test_cli_refuses_too_few_and_cylindrical_points(tmp_path):
    few = tmp_path / "few.csv"
    np.savetxt(few, cone_points(0.3, 10.0)[:5], delimiter=",")
    cyl = tmp_path / "cyl.csv"
    np.savetxt(cyl, cone_points(0.0, 10.0), delimiter=",")
    for f in (few, cyl):
        r = _cli("fit", "cone", str(f), "-c", "mz")
        assert r.returncode == 2 and r.stderr.startswith("gagekit: error:") and r.stderr.count("\n") == 1


def test_inspect_conicity(tmp_path):
    psi, amp = math.radians(20.0), 0.005
    p = cone_points(psi, 15.0, lambda t, z: amp * np.cos(3 * (t - 0.1 * z / 5.0)), p0=np.zeros(3), a=np.array([0.0, 0.0, 1.0]))
    scan = tmp_path / "cone.csv"
    np.savetxt(scan, p, delimiter=",", header="x,y,z", comments="")
    part = tmp_path / "part.toml"
    part.write_text(
        '[[feature]]\nname = "taper"\nshape = "cone"\nregion = { center = [0, 0, 10], size = [60, 60, 30] }\n\n'
        '[[tolerance]]\nfeature = "taper"\ncharacteristic = "conicity"\ntolerance = 0.012\n\n'
        '[[tolerance]]\nfeature = "taper"\ncharacteristic = "conicity"\ntolerance = 0.008\nhalf_angle = 20.0\n'
    )
    r = subprocess.run([sys.executable, "-m", "gagekit", "inspect", str(scan), str(part), "--json"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode in (0, 1), r.stderr
    res = json.loads(r.stdout)
    tols = res["tolerances"] if "tolerances" in res else res["results"]
    assert [t["characteristic"] for t in tols] == ["conicity", "conicity"]
    assert all(t["measured"] == pytest.approx(2 * amp, abs=1e-9) for t in tols)
    assert [t["pass"] for t in tols] == [True, False]
    bad = tmp_path / "bad.toml"
    for extra, msg in (("half_angle = 95.0", "half_angle"), ('datums = ["A"]', "datums")):
        bad.write_text(part.read_text().split("[[tolerance]]")[0] + '[[tolerance]]\nfeature = "taper"\n'
                       f'characteristic = "conicity"\ntolerance = 0.01\n{extra}\n')
        r = subprocess.run([sys.executable, "-m", "gagekit", "inspect", str(scan), str(bad)], capture_output=True, text=True, timeout=120)
        assert r.returncode == 2 and r.stderr.startswith("gagekit: error:") and msg in r.stderr, r.stderr


@pytest.mark.parametrize("seed", range(3))
def test_no_independent_search_finds_a_narrower_zone(seed):
    # scipy's Nelder-Mead on the zone width over (axis tilt, offset, half angle), from the
    # least-squares cone and 20 perturbed starts, never beats the kernel's minimum zone
    optimize = pytest.importorskip("scipy.optimize")
    rng = np.random.default_rng(100 + seed)
    c, ph = rng.uniform(0.002, 0.006, 3), rng.uniform(0, 2 * np.pi, 3)
    p = cone_points(math.radians(rng.uniform(10, 40)), 15.0,
                    lambda t, z: c[0] * np.cos(2 * t + ph[0]) + c[1] * np.cos(3 * t + ph[1]) + c[2] * np.sin(0.4 * z + ph[2]),
                    zs=np.linspace(0, 20, 6), m=24)
    p = p + rng.normal(0, 0.001, p.shape)
    mz, ls = gagekit.fit_cone(p, "mz"), gagekit.fit_cone(p)
    a0, p0 = np.array(ls.direction), np.array(ls.point)
    u, v = _basis(a0)

    def width(x):
        a = a0 + x[0] * u + x[1] * v
        a /= np.linalg.norm(a)
        q = p - (p0 + x[2] * u + x[3] * v)
        z = q @ a
        rho = np.linalg.norm(q - np.outer(z, a), axis=1)
        psi = ls.half_angle + x[4]
        d = rho * math.cos(psi) - z * math.sin(psi)
        return d.max() - d.min()

    best = np.inf
    for k in range(21):
        x0 = np.zeros(5) if k == 0 else rng.normal(0, [1e-3, 1e-3, 1e-2, 1e-2, 1e-3])
        r = optimize.minimize(width, x0, method="Nelder-Mead", options={"xatol": 1e-12, "fatol": 1e-14, "maxiter": 20000})
        best = min(best, r.fun)
    assert mz.form_error <= best + 1e-9, (mz.form_error, best)


def test_conicity_goes_to_qif_results_valid_against_the_schema(tmp_path):
    # the conicity callout is written as a QIF 3.0 ConicityCharacteristic (form: no datums)
    etree = pytest.importorskip("lxml.etree")
    from pathlib import Path

    xsd = Path(__file__).resolve().parents[1] / "data" / "qif" / "xsd" / "QIFApplications" / "QIFDocument.xsd"
    p = cone_points(math.radians(20.0), 15.0, lambda t, z: 0.004 * np.cos(3 * t), p0=np.zeros(3), a=np.array([0.0, 0.0, 1.0]))
    scan = tmp_path / "cone.csv"
    np.savetxt(scan, p, delimiter=",", header="x,y,z", comments="")
    part = tmp_path / "part.toml"
    part.write_text('[[feature]]\nname = "taper"\nshape = "cone"\nregion = { center = [0, 0, 10], size = [60, 60, 30] }\n\n'
                    '[[tolerance]]\nfeature = "taper"\ncharacteristic = "conicity"\ntolerance = 0.01\n')
    out = tmp_path / "res.qif"
    r = subprocess.run([sys.executable, "-m", "gagekit", "inspect", str(scan), str(part), "--json", "--qif-results", str(out)],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    doc = etree.parse(str(out))
    schema = etree.XMLSchema(etree.parse(str(xsd)))
    assert schema.validate(doc), schema.error_log
    ns = {"q": "http://qifstandards.org/xsd/qif3"}
    assert doc.xpath("//q:ConicityCharacteristicMeasurement", namespaces=ns)
