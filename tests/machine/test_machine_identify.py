"""Identification from simulated tracker data (Sec. 3.1.5, 3.2; ERRATA item 6)."""


import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import gagekit
from gagekit.errors import ConfigError, DegenerateGeometryError, FileFormatError, InvalidInputError
from gagekit.machine.identify import NOISE_FLOOR_FACTOR, rotation_from_vector

from conftest import EXAMPLE_MACHINE

EXAMPLE = EXAMPLE_MACHINE
SIGMA = 0.0089


@pytest.fixture(scope="module", params=[1, 7])
def case(request, machine, structure):
    """The dissertation's experiment, simulated: 290 + 50 quasi-random commands over Table 3.1,
    sigma 8.9 um, Table 3.3 magnitudes, tracker turned and moved arbitrarily."""
    seed = request.param
    truth = gagekit.Truth.random(machine, seed=seed)
    cal = gagekit.simulate(machine, truth, machine.sample_commands(290, seed=seed), noise=SIGMA, seed=100 + seed)
    test = gagekit.simulate(machine, truth, machine.sample_commands(50, seed=seed + 1000), noise=SIGMA, seed=200 + seed)
    res = {m: gagekit.identify(machine, cal, test=test, method=m, structure=structure) for m in ("joint", "two-step")}
    return truth, cal, test, res


def test_tracker_frame_is_arbitrary(case):
    truth = case[0]
    angle = np.degrees(np.arccos((np.trace(truth.frame.rotation) - 1) / 2))
    assert angle > 20 and np.linalg.norm(truth.frame.translation) > 500


def test_joint_residuals_reach_the_noise_floor(case):
    floor = NOISE_FLOOR_FACTOR * SIGMA  # 1.60 sigma: mean length of a 3-D noise vector
    joint = case[3]["joint"]
    assert abs(joint.residuals.model_mean / floor - 1) < 0.10
    assert abs(joint.test.model_mean / floor - 1) < 0.10
    assert joint.residuals.nominal_mean > 10 * floor  # the errors were there to begin with
    assert joint.residuals.decrease_mean_pct > 85
    assert joint.sigma == pytest.approx(SIGMA, rel=0.1)
    assert joint.rank == 32 and joint.dof == 3 * 290 - 36


def test_test_set_residual_matches_the_realised_noise(case, machine):
    """A 50-point mean of noise lengths scatters by ~6 % (1 sigma) around 1.60 sigma; against the
    noise actually drawn, the test-set residual (noise + prediction uncertainty) must agree to
    10 % for every seed (0.98 to 1.07 over 30 seeds), not only on average."""
    truth, _, test, res = case
    clean = gagekit.simulate(machine, truth, test.commands, noise=0.0)
    realised = np.linalg.norm(test.measured - clean.measured, axis=1).mean()
    assert abs(res["joint"].test.model_mean / realised - 1) < 0.10


def test_joint_groups_within_4_std_of_truth(case, machine, structure):
    truth, _, _, res = case
    joint = res["joint"]
    true_groups = truth.group_values(machine, structure)
    z = {g.name: (g.value - true_groups[g.name]) / g.std for g in joint.groups if not g.frame_confounded}
    assert len(z) == 30
    worst = max(z, key=lambda k: abs(z[k]))
    assert abs(z[worst]) < 4, (worst, z[worst])


def test_frame_takes_the_confounded_groups(case, machine, structure):
    """T1.beta (a turn about the B axis) and the y-shift group move the whole table frame
    rigidly: the identified frame is the true one followed by exactly that motion."""
    truth, _, _, res = case
    joint = res["joint"]
    conf = [g for g in joint.groups if g.frame_confounded]
    assert [g.leader for g in conf] == ["T1.beta", "T1.dy"]
    tv = truth.group_values(machine, structure)
    rel = truth.frame.rotation.T @ joint.frame.rotation
    small = np.array([rel[1, 0] - rel[0, 1], rel[0, 2] - rel[2, 0], rel[2, 1] - rel[1, 2]]) / 2  # (z, y, x)
    shift = truth.frame.rotation.T @ (joint.frame.translation - truth.frame.translation)
    expected = np.array([0.0, tv[conf[0].name], 0.0, 0.0, tv[conf[1].name], 0.0])
    got = np.concatenate([small, shift])
    std = np.array([joint.frame_std[k] for k in ("alpha0", "beta0", "gamma0", "x0", "y0", "z0")])
    assert np.all(np.abs(got - expected) < 4 * std), (got - expected) / std


def test_two_step_is_biased_and_joint_is_not_without_noise(machine, structure):
    """ERRATA item 6: noise-free, the two-step residual stays at several um, the joint one vanishes."""
    truth = gagekit.Truth.random(machine, seed=3)
    obs = gagekit.simulate(machine, truth, machine.sample_commands(290, seed=3), noise=0.0)
    joint = gagekit.identify(machine, obs, structure=structure)
    two = gagekit.identify(machine, obs, method="two-step", structure=structure)
    assert joint.residuals.model_mean < 1e-4  # < 0.1 um: first-order model error only
    assert two.residuals.model_mean > 1e-3
    assert joint.iterations >= 2


def test_prediction_reproduces_noise_free_measurements(machine, structure):
    truth = gagekit.Truth.random(machine, seed=4)
    obs = gagekit.simulate(machine, truth, machine.sample_commands(290, seed=4), noise=0.0)
    cal = gagekit.identify(machine, obs, structure=structure)
    new = machine.sample_commands(40, seed=99)
    q = gagekit.simulate(machine, truth, new, noise=0.0).measured
    p = machine.nominal(new) + gagekit.predict(machine, cal, new, structure=structure)
    assert np.abs(cal.frame.to_tracker(p) - q).max() < 2e-4


def test_compensation_cancels_the_predicted_error(machine, structure):
    truth = gagekit.Truth.random(machine, seed=5)
    obs = gagekit.simulate(machine, truth, machine.sample_commands(100, seed=5), noise=0.0)
    cal = gagekit.identify(machine, obs, structure=structure)
    cmds = machine.sample_commands(20, seed=8)
    corrected, remaining = gagekit.compensate(machine, cal, cmds, structure=structure)
    assert np.abs(remaining).max() < 1e-9
    assert np.array_equal(corrected[:, 0], cmds[:, 0])  # the rotary axis is not touched
    assert 1e-3 < np.abs(corrected - cmds).max() < 2.0
    c2, r2 = gagekit.compensate(machine, cal, cmds, axes=["X", "Y", "Z"], structure=structure)
    assert np.array_equal(c2[:, 4], cmds[:, 4]) and np.abs(r2).max() < 1e-9
    with pytest.raises(InvalidInputError, match="unknown joint"):
        gagekit.compensate(machine, cal, cmds, axes=["Q"], structure=structure)


def test_calibration_json_round_trip_and_machine_mismatch(machine, structure, tmp_path, case):
    cal = case[3]["joint"]
    path = tmp_path / "cal.json"
    cal.save(path)
    back = gagekit.load_calibration(path)
    assert back.values == cal.values and back.rank == 32
    cmds = machine.sample_commands(5, seed=1)
    assert np.allclose(gagekit.predict(machine, back, cmds), gagekit.predict(machine, cal, cmds))
    long_tool = gagekit.parse_machine(EXAMPLE.read_text().replace("-312.035]", "-435.185]"))
    with pytest.raises(ConfigError, match="does not match machine"):
        gagekit.predict(long_tool, back, cmds)
    (tmp_path / "bad.json").write_text("{}")
    with pytest.raises(FileFormatError, match="malformed"):
        gagekit.load_calibration(tmp_path / "bad.json")


def test_refit_test_frame_handles_a_moved_tracker(machine, structure):
    truth = gagekit.Truth.random(machine, seed=6)
    obs = gagekit.simulate(machine, truth, machine.sample_commands(290, seed=6), noise=SIGMA, seed=1)
    moved = gagekit.Truth(truth.machine, truth.parameter_names, truth.parameters, gagekit.Frame(rotation_from_vector([0.3, -1.0, 2.0]), [100.0, -4000.0, 5.0]))
    test = gagekit.simulate(machine, moved, machine.sample_commands(50, seed=60), noise=SIGMA, seed=2)
    same = gagekit.identify(machine, obs, test=test, structure=structure)
    refit = gagekit.identify(machine, obs, test=test, test_frame="refit", structure=structure)
    floor = NOISE_FLOOR_FACTOR * SIGMA
    assert same.test.model_mean > 100 * floor
    assert refit.test.model_mean < 1.3 * floor


def test_simulation_is_deterministic(machine):
    t1, t2 = gagekit.Truth.random(machine, seed=9), gagekit.Truth.random(machine, seed=9)
    assert np.array_equal(t1.parameters, t2.parameters)
    c = machine.sample_commands(10, seed=9)
    a = gagekit.simulate(machine, t1, c, seed=3).measured
    assert np.array_equal(a, gagekit.simulate(machine, t2, c, seed=3).measured)
    assert not np.array_equal(a, gagekit.simulate(machine, t2, c, seed=4).measured)


def test_bad_observations(machine, structure):
    truth = gagekit.Truth.random(machine, seed=2)
    obs = gagekit.simulate(machine, truth, machine.sample_commands(20, seed=2))
    with pytest.raises(DegenerateGeometryError, match="20 observations are fewer than the 32 identifiable groups"):
        gagekit.identify(machine, obs, structure=structure)
    flat = machine.sample_commands(100, seed=2)
    flat[:, 0] = 0.0  # B never turns: the rotary-joint errors are invisible
    obs = gagekit.simulate(machine, truth, flat)
    with pytest.raises(DegenerateGeometryError, match="cannot separate all groups.*B\\."):
        gagekit.identify(machine, obs, structure=structure)
    with pytest.raises(InvalidInputError, match="point 3 has a non-finite measured"):
        q = obs.measured.copy()
        q[3, 1] = np.nan
        gagekit.Observations(obs.commands, q, obs.joint_names)
    with pytest.raises(InvalidInputError, match="method must be"):
        gagekit.identify(machine, obs, method="three-step")


def _write(path, header, rows):
    path.write_text(",".join(header) + "\n" + "\n".join(",".join(str(v) for v in r) for r in rows) + "\n")


def test_observation_files(machine, tmp_path):
    ok = ["B", "X", "Z", "Y", "W", "x", "y", "z"]
    row = [10, 0, 1000, 500, -300, 1, 2, 3]
    _write(tmp_path / "ok.csv", ["x", "y", "z", "W", "Y", "Z", "X", "B"], [row[5:] + row[:5][::-1]])
    obs = gagekit.read_observations(tmp_path / "ok.csv", machine)
    assert obs.commands.tolist() == [[10, 0, 1000, 500, -300]] and obs.measured.tolist() == [[1, 2, 3]]
    _write(tmp_path / "m.csv", [c for c in ok if c != "W"], [row[:4] + row[5:]])
    with pytest.raises(FileFormatError, match="missing column\\(s\\) W"):
        gagekit.read_observations(tmp_path / "m.csv", machine)
    _write(tmp_path / "e.csv", ok + ["A"], [row + [0]])
    with pytest.raises(FileFormatError, match="unknown column\\(s\\) A"):
        gagekit.read_observations(tmp_path / "e.csv", machine)
    _write(tmp_path / "n.csv", ok, [row, row[:4] + ["nan"] + row[5:]])
    with pytest.raises(InvalidInputError, match="data row 2 has a non-finite value in column W"):
        gagekit.read_observations(tmp_path / "n.csv", machine)
    _write(tmp_path / "t.csv", ok, [row, row[:3] + ["abc"] + row[4:]])
    with pytest.raises(FileFormatError, match="line 3: 'abc' in column Y is not a number"):
        gagekit.read_observations(tmp_path / "t.csv", machine)
    _write(tmp_path / "r.csv", ok, [[10, 1300] + row[2:]])
    with pytest.warns(UserWarning, match="outside the machine's joint ranges \\(X: 1\\)"):
        gagekit.read_observations(tmp_path / "r.csv", machine, warn_range=True)
    (tmp_path / "empty.csv").write_text("")
    with pytest.raises(FileFormatError, match="empty file"):
        gagekit.read_observations(tmp_path / "empty.csv", machine)


def test_identify_warns_for_commands_outside_the_ranges(machine, structure):
    truth = gagekit.Truth.random(machine, seed=2)
    c = machine.sample_commands(60, seed=2)
    c[0, 3] = 2600.0  # Y beyond 2500
    obs = gagekit.simulate(machine, truth, c)
    with pytest.warns(UserWarning, match=r"\(Y: 1\)"):
        gagekit.identify(machine, obs, structure=structure)


def test_compensation_warns_when_the_axes_cannot_reach(machine, structure, case):
    cmds = machine.sample_commands(5, seed=8)
    with pytest.warns(UserWarning, match="cannot move the target in every direction"):
        _, rem = gagekit.compensate(machine, case[3]["joint"], cmds, axes=["X"], structure=structure)
    assert np.abs(rem).max() > 1e-4


def test_singular_chain_is_a_clear_error():
    line = gagekit.parse_machine(
        'chain = ["X"]\n[joints.X]\ntype = "prismatic"\naxis = [1.0, 0.0, 0.0]\nrange = [0, 100]\n[tool]\noffset = [0.0, 0.0, 0.0]\n'
    )
    s = line.structure(n=200)
    assert s.rank == 3 and s.no_effect == ("X.dgamma",)  # roll about the line moves nothing on it
    truth = gagekit.Truth.random(line, seed=1)
    obs = gagekit.simulate(line, truth, line.sample_commands(50, seed=1))
    with pytest.raises(DegenerateGeometryError, match="collinear"):
        gagekit.identify(line, obs)


@settings(max_examples=30, deadline=None)
@given(
    st.lists(st.floats(-3.2, 3.2), min_size=3, max_size=3),
    st.lists(st.floats(-5000, 5000), min_size=3, max_size=3),
)
def test_step1_recovers_any_tracker_placement(rotvec, shift):
    """Closed-form rigid fit: any rotation (up to 180 degrees) and shift, no small angles."""
    m = gagekit.load_machine(EXAMPLE)
    frame = gagekit.Frame(rotation_from_vector(rotvec), shift)
    p = m.nominal(m.sample_commands(30, seed=1))
    fit = gagekit._core.kinematics.rigid_fit(p, frame.to_tracker(p))
    r, t, rms = fit.rotation, fit.translation, fit.rms
    assert rms < 1e-8
    assert np.allclose(r, frame.rotation, atol=1e-10) and np.allclose(t, frame.translation, atol=1e-7)


def test_design_matrix_independent_of_thread_count(machine):
    import subprocess, sys, os

    code = (
        "import gagekit, hashlib;"
        f"m = gagekit.load_machine({str(EXAMPLE)!r});"
        "print(hashlib.sha256(m.design_matrix(m.sample_commands(5000, seed=3)).tobytes()).hexdigest())"
    )
    env = {**os.environ, "RAYON_NUM_THREADS": "1"}
    one = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout.strip()
    import hashlib

    here = hashlib.sha256(machine.design_matrix(machine.sample_commands(5000, seed=3)).tobytes()).hexdigest()
    assert one == here


def test_wrong_units_are_flagged(machine, structure):
    truth = gagekit.Truth.random(machine, seed=2)
    c = machine.sample_commands(60, seed=2)
    obs = gagekit.simulate(machine, truth, c)
    as_rad = gagekit.Observations(np.c_[np.radians(c[:, :1]), c[:, 1:]], obs.measured, obs.joint_names)
    with pytest.warns(UserWarning) as rec:
        gagekit.identify(machine, as_rad, structure=structure)
    messages = " | ".join(str(w.message) for w in rec)
    assert "fits the observations to only" in messages and "did not settle" in messages


def test_prediction_uncertainty_is_calibrated(machine, structure):
    """Over repeated simulated calibrations, the spread of the predicted error at fixed commands
    matches the propagated standard uncertainty (sqrt(diag(M_L Sigma M_L^T)))."""
    truth = gagekit.Truth.random(machine, seed=11)
    cmds = machine.sample_commands(290, seed=11)
    probe = machine.sample_commands(8, seed=12)
    preds, us = [], []
    for k in range(40):
        obs = gagekit.simulate(machine, truth, cmds, noise=SIGMA, seed=1000 + k)
        cal = gagekit.identify(machine, obs, structure=structure)
        preds.append(gagekit.predict(machine, cal, probe, structure=structure))
        us.append(gagekit.predict_uncertainty(machine, cal, probe, structure=structure))
    spread = np.std(np.array(preds), axis=0, ddof=1)
    ratio = spread / np.mean(np.array(us), axis=0)
    assert 0.7 < np.median(ratio) < 1.3, np.median(ratio)
