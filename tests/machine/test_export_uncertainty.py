"""Issue 26 §2, machine side: every compensation-table entry and every predicted error gets
its standard uncertainty from the identification's group covariance (exact linear
propagation, GUM 5.1.2), checked against a Monte Carlo over that covariance (JCGM 101) and
against the analytic single-group case."""

import dataclasses
import json
import subprocess
import sys

import numpy as np
import pytest

from conftest import EXAMPLE_MACHINE
from gagekit.errors import ConfigError
from gagekit.machine import Truth, identify, predict, predict_covariance, predict_uncertainty, simulate
from gagekit.machine.export import (
    companion_path,
    correction_uncertainty,
    corrections,
    export,
    isg_entries,
    isg_uncertainty,
    make_grid,
)

AXES = ["X", "Y", "Z"]


@pytest.fixture(scope="module")
def cal(machine):
    truth = Truth.random(machine, seed=5)
    obs = simulate(machine, truth, machine.sample_commands(290, seed=5), seed=6)
    return identify(machine, obs)


@pytest.fixture(scope="module")
def grid(machine):
    return make_grid(machine, AXES, points=3, at={"B": 30.0, "W": -500.0})


def _with_values(cal, g):
    return dataclasses.replace(cal, groups=tuple(dataclasses.replace(x, value=float(v)) for x, v in zip(cal.groups, g)))


def _with_cov(cal, cov):
    return dataclasses.replace(cal, covariance=cov)


def _draws(cal, n, seed):
    """Group vectors drawn from N(values, Sigma). Sigma is singular (frame-taken groups) and
    mixes mm^2 with rad^2 (eigenvalues 1e-20 to 1e-3): its square root is taken from the
    correlation matrix, since an eigendecomposition of Sigma itself loses the angle groups."""
    cov = np.asarray(cal.covariance)
    d = np.sqrt(np.diag(cov))
    s = np.where(d > 0, d, 1.0)
    lam, v = np.linalg.eigh(cov / np.outer(s, s))
    root = s[:, None] * (v * np.sqrt(np.clip(lam, 0.0, None)))
    z = np.random.default_rng(seed).standard_normal((n, len(lam)))
    return np.array([g.value for g in cal.groups]) + z @ root.T


def test_prediction_and_corrections_match_a_monte_carlo_over_the_covariance(machine, cal, grid):
    """The propagated u of e and of the corrections c = -pinv(J) e at the nodes of a grid
    (B = 30 deg: J is not the identity) against the spread of 4000 draws of the groups from
    N(g, Sigma), each predicted by the public path (predict, corrections)."""
    cmds = grid.commands(machine)
    u_e = predict_uncertainty(machine, cal, cmds)
    u_c = correction_uncertainty(machine, cal, cmds, AXES)
    es, cs = [], []
    for g in _draws(cal, 4000, seed=1):
        e = predict(machine, _with_values(cal, g), cmds)
        es.append(e)
        cs.append(corrections(machine, cmds, e, AXES))
    ratio_e = np.std(es, axis=0, ddof=1) / u_e
    ratio_c = np.std(cs, axis=0, ddof=1) / u_c
    # the relative standard error of a standard deviation from 4000 draws is 1.1 %
    for r in (ratio_e, ratio_c):
        assert abs(np.median(r) - 1.0) < 0.02, np.median(r)
        assert np.abs(r - 1.0).max() < 0.06, np.abs(r - 1.0).max()
    # the corrections' u is not the errors' u: the Jacobian at B = 30 deg mixes x and z
    assert np.abs(u_c - u_e).max() > 1e-4


def test_isg_entries_match_a_monte_carlo_over_the_covariance(machine, cal, grid):
    keys, vals, u = isg_uncertainty(machine, cal, grid)
    from gagekit.machine.export import calibration_parameters

    draws = np.array([isg_entries(machine, calibration_parameters(machine, _with_values(cal, g)), grid)[1]
                      for g in _draws(cal, 3000, seed=2)])
    assert np.allclose(isg_entries(machine, calibration_parameters(machine, cal), grid)[1], vals, atol=0, rtol=0)
    live = u > 1e-6 * u.max()
    ratio = np.std(draws, axis=0, ddof=1)[live] / u[live]
    assert abs(np.median(ratio) - 1.0) < 0.02 and np.abs(ratio - 1.0).max() < 0.07
    # entries with (next to) no u do not move in the simulation either (roundoff only)
    assert np.ptp(draws[:, ~live], axis=0).max(initial=0.0) < 1e-9


def test_zero_variance_gives_zero_u_and_one_group_gives_its_sensitivity(machine, cal, grid):
    cmds = grid.commands(machine)
    rank = len(cal.groups)
    zero = _with_cov(cal, np.zeros((rank, rank)))
    assert (predict_uncertainty(machine, zero, cmds) == 0.0).all()
    assert (correction_uncertainty(machine, zero, cmds, AXES) == 0.0).all()
    assert (isg_uncertainty(machine, zero, grid)[2] == 0.0).all()
    # only group k varies: u = sigma_k |d entry / d g_k| (the model is linear in g: a unit step is exact)
    k = next(i for i, g in enumerate(cal.groups) if g.std and g.unit == "rad")
    sigma = 3e-6
    cov = np.zeros((rank, rank))
    cov[k, k] = sigma**2
    one = _with_cov(cal, cov)
    g = np.array([x.value for x in cal.groups])
    step = np.zeros(rank)
    step[k] = 1e-5
    de = (predict(machine, _with_values(cal, g + step), cmds) - predict(machine, cal, cmds)) / 1e-5
    assert np.allclose(predict_uncertainty(machine, one, cmds), sigma * np.abs(de), rtol=1e-6, atol=1e-15)
    dc = corrections(machine, cmds, de, AXES)
    assert np.allclose(correction_uncertainty(machine, one, cmds, AXES), sigma * np.abs(dc), rtol=1e-6, atol=1e-15)
    assert np.allclose(predict_covariance(machine, one, cmds), sigma**2 * np.einsum("ni,nj->nij", de, de), rtol=1e-6, atol=1e-20)


def test_every_format_writes_its_uncertainty_beside_the_table(machine, cal, tmp_path):
    cmds_u = {}
    for fmt, name in (("grid-csv", "g.csv"), ("isg-csv", "i.csv"), ("fanuc-3d", "f.tap"), ("linuxcnc", "l.txt")):
        res = export(machine, cal, fmt, tmp_path / name, step=250, check_points=50, uncertainty=True)
        u = res.uncertainty
        assert u["k"] == 1 and "GUM 5.1.2" in u["method"] and u["max_mm"] > 0
        assert u["not_included"] == cal.frame_confounded  # the groups the frame takes
        if fmt == "grid-csv":
            assert res.files == (str(tmp_path / name),) and u["file"] == str(tmp_path / name)
            lines = (tmp_path / name).read_text().splitlines()
            assert lines[0].endswith("ux,uy,uz,ucX,ucY,ucZ")
            data = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
            cmds_u["grid"] = data
        else:
            comp = companion_path(tmp_path / name)
            assert comp.name == name.split(".")[0] + "_u.csv" and str(comp) in res.files and u["file"] == str(comp)
            assert comp.exists()
        d = res.to_dict()
        assert d["uncertainty"]["max_mm"] == u["max_mm"]
    # fanuc amounts' u equal the grid-csv corrections' u at the same nodes (B = 0: J = I)
    f = np.genfromtxt(tmp_path / "f_u.csv", delimiter=",", names=True)
    g = cmds_u["grid"]
    assert np.allclose(f["ucX"], g[:, 14], rtol=1e-12) and np.allclose(f["ucZ"], g[:, 16], rtol=1e-12)
    assert np.allclose(f["cX"], np.rint(g[:, 8] / 0.001) * 0.001, atol=1e-12)
    lin = np.genfromtxt(tmp_path / "l_u.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    assert set(lin["joint"]) == {"X", "Y", "Z"} and (lin["u_trim"] > 0).all()
    # without --uncertainty nothing changes: no companion, no uc columns
    res = export(machine, cal, "fanuc-3d", tmp_path / "plain.tap", step=250, check_points=50)
    assert res.uncertainty is None and "uncertainty" not in res.to_dict() and not (tmp_path / "plain_u.csv").exists()


def test_mixed_identification_carries_its_covariance_to_the_tables(machine, tmp_path):
    """A tracker + sphere calibration (identify_mixed) used to have no covariance, so grid-csv
    (which always writes ux, uy, uz) refused it."""
    from gagekit.machine.instruments import InstrumentObservations, identify_mixed
    from gagekit.machine.simulate_instruments import simulate_sphere

    truth = Truth.random(machine, seed=3)
    tr = simulate(machine, truth, machine.sample_commands(150, seed=4), seed=5)
    c = simulate_sphere(machine, "B", np.arange(12) * 30.0, np.array([150.0, 400.0, 250.0]), {"W": -500.0}, {},
                        noise_um=1.0, seed=6, params=truth.parameters)
    res = identify_mixed(machine, [InstrumentObservations("tracker", tr.commands, tr.measured, sigma=0.0089),
                                   InstrumentObservations("sphere", c, None, np.zeros(len(c), int), None, 0.001)])
    cal = res.calibration
    assert cal.covariance is not None
    std = np.sqrt(np.diag(cal.covariance))
    for g, s in zip(cal.groups, std):
        assert (g.std is None and s == 0.0) or s == pytest.approx(g.std, rel=1e-9)
    out = export(machine, cal, "grid-csv", tmp_path / "m.csv", step=250, check_points=20, uncertainty=True)
    assert out.uncertainty["max_mm"] > 0


def _run(*args):
    return subprocess.run([sys.executable, "-m", "gagekit", *map(str, args)], capture_output=True, text=True)


def test_cli_uncertainty_and_predict_json(machine, cal, tmp_path):
    calf = tmp_path / "cal.json"
    cal.save(calf)
    p = _run("machine", "export", EXAMPLE_MACHINE, calf, "--format", "linuxcnc", "--out", tmp_path / "c.txt",
             "--uncertainty", "--json")
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    assert d["uncertainty"]["file"] == str(tmp_path / "c_u.csv") and (tmp_path / "c_u.csv").exists()
    p = _run("machine", "export", EXAMPLE_MACHINE, calf, "--format", "fanuc-3d", "--out", tmp_path / "f.tap",
             "--uncertainty")
    assert p.returncode == 0 and "standard uncertainty (k = 1)" in p.stdout and "f_u.csv" in p.stdout
    # the predict JSON: u per component, the CSV's ux, uy, uz
    cmds = tmp_path / "cmds.csv"
    pts = machine.sample_commands(20, seed=3)
    cmds.write_text(",".join(machine.joint_names) + "\n" + "\n".join(",".join(repr(float(v)) for v in r) for r in pts) + "\n")
    p = _run("machine", "predict", EXAMPLE_MACHINE, calf, cmds, "--out", tmp_path / "e.csv", "--json")
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    u = predict_uncertainty(machine, cal, pts)
    assert d["u"]["k"] == 1 and d["u"]["max"]["y"] == pytest.approx(u[:, 1].max(), rel=1e-12)
    # a calibration without a covariance: one line, exit 2, nothing written
    old = json.loads(calf.read_text())
    del old["covariance"]
    calf.write_text(json.dumps(old))
    p = _run("machine", "export", EXAMPLE_MACHINE, calf, "--format", "isg-csv", "--out", tmp_path / "o.csv", "--uncertainty")
    assert p.returncode == 2 and p.stderr.startswith("gagekit: error: ") and len(p.stderr.splitlines()) == 1
    assert "covariance" in p.stderr and not (tmp_path / "o.csv").exists() and not (tmp_path / "o_u.csv").exists()
    with pytest.raises(ConfigError, match="covariance"):
        isg_uncertainty(machine, dataclasses.replace(cal, covariance=None), make_grid(machine, AXES, points=2))
