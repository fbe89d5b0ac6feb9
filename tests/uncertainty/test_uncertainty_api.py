"""The uncertainty API (issue 26 Sec. 1-2): measurement model, JCGM 101 Monte Carlo, ISO
14253-1 decisions -- typed errors, determinism on any thread count, the decision table."""

from __future__ import annotations

import numpy as np
import pytest

from gagekit.errors import ConfigError, ConfigFileError, InvalidInputError
from gagekit.uncertainty import (
    DecisionRule, coverage_interval, decide, decide_margin, estimate_sigma, load_measurement_model,
    measurement_model, monte_carlo, numerical_tolerance, parse_decision_rule, parse_trials, worst_decision,
)

ISO = parse_decision_rule("iso14253")


def _mean_eval(p):
    return {"x": float(p[:, 0].mean()), "r": float(np.linalg.norm(p, axis=1).mean())}


def test_a_value_exactly_at_its_limit_with_U_is_not_proven():
    assert decide(0.01, 0.001, upper=0.01, rule=ISO) == "not-proven"
    assert decide(0.01, 0.0, upper=0.01, rule=ISO) == "conforming"
    assert decide(0.01, 0.001, upper=0.01, rule=parse_decision_rule("simple")) == "conforming"
    assert decide(0.0089, 0.001, upper=0.01, rule=ISO) == "conforming"
    assert decide(0.009, 0.001, upper=0.01, rule=ISO) == "conforming"  # value + U on the limit: within
    assert decide(0.0111, 0.001, upper=0.01, rule=ISO) == "nonconforming"
    assert decide(0.0105, 0.001, upper=0.01, rule=ISO) == "not-proven"
    # two limits, and a lower limit alone (a virtual gage's allowance)
    assert decide(25.0, 0.002, upper=25.01, lower=24.99, rule=ISO) == "conforming"
    assert decide(24.991, 0.002, upper=25.01, lower=24.99, rule=ISO) == "not-proven"
    assert decide(0.0, 0.01, lower=0.0, rule=ISO) == "not-proven"
    assert decide(-0.5, 0.01, lower=0.0, rule=ISO) == "nonconforming"


def test_guard_bands_scale_with_U():
    g = parse_decision_rule("guard-band=0.5")
    assert g == DecisionRule("guard-band", 0.5) and g.label == "guard-band=0.5"
    assert decide_margin(0.6, 1.0, g) == "conforming"
    assert decide_margin(0.4, 1.0, g) == "not-proven"
    assert decide_margin(-0.6, 1.0, g) == "nonconforming"
    assert decide_margin(0.0, 1.0, parse_decision_rule("guard-band=0")) == "conforming"
    assert decide_margin(-1e-12, 1.0, parse_decision_rule("guard-band=0")) == "nonconforming"


def test_default_rule_follows_whether_an_uncertainty_is_computed():
    assert parse_decision_rule(None, True).name == "iso14253"
    assert parse_decision_rule(None, False).name == "simple"
    assert worst_decision(["conforming", "not-proven", "conforming"]) == "not-proven"
    assert worst_decision(["not-proven", "nonconforming"]) == "nonconforming"
    assert worst_decision([]) == "conforming"


@pytest.mark.parametrize("text", ["", "iso", "guard-band", "guard-band=-0.1", "guard-band=nan", "guard-band=inf",
                                  "guard-band=abc", "strict"])
def test_bad_rule_strings_are_typed_errors(text):
    with pytest.raises(InvalidInputError, match="decision rule"):
        parse_decision_rule(text)


@pytest.mark.parametrize("bad", [0, 9, -5, "9", "many", 2.5, True])
def test_fewer_than_ten_trials_or_a_non_number_is_refused(bad):
    with pytest.raises(InvalidInputError):
        parse_trials(bad)
    with pytest.raises(InvalidInputError):
        monte_carlo(_mean_eval, np.zeros((5, 3)), measurement_model(sigma=1.0), bad)


@pytest.mark.parametrize("key,value", [("sigma", -0.001), ("probing", -1.0), ("offset", float("nan")),
                                       ("scale_ppm", float("inf")), ("cte", -1e-6), ("delta_t", -1.0)])
def test_negative_or_non_finite_model_numbers_are_typed_errors(key, value):
    with pytest.raises(InvalidInputError, match=key):
        measurement_model(**{key: value})


def test_model_file_errors(tmp_path):
    p = tmp_path / "m.toml"
    p.write_text("[measurement]\nsigma = 0.002\norigin = [0, 0, 1000]\nsigma_per_m = 0.01\nprobing = 0.003\n"
                 "scale_ppm = 2\ncte = 1.15e-5\ndelta_t = 0.5\noffset = 0.001\n")
    m = load_measurement_model(p)
    assert m.origin == (0.0, 0.0, 1000.0) and m.relative_scale == pytest.approx(2e-6 + 0.5 * 1.15e-5)
    p.write_text("[measurement]\nsigma = 'auto'\n")
    assert load_measurement_model(p).sigma_auto
    p.write_text("[measurement]\nsigma = 'loud'\n")
    with pytest.raises(ConfigError, match="auto"):
        load_measurement_model(p)
    p.write_text("[measurement]\nsigmaa = 0.1\n")
    with pytest.raises(ConfigError, match="unknown key"):
        load_measurement_model(p)
    p.write_text("[other]\n")
    with pytest.raises(ConfigError, match=r"\[measurement\]"):
        load_measurement_model(p)
    p.write_text("[measurement\n")
    with pytest.raises(ConfigFileError):
        load_measurement_model(p)
    with pytest.raises(ConfigError, match="origin"):
        measurement_model(sigma_per_m=0.1)


def test_same_seed_same_answer_on_any_thread_count():
    rng = np.random.default_rng(3)
    pts = rng.normal(size=(200, 3))
    m = measurement_model(sigma=0.01, probing=0.005, scale_ppm=10, offset=0.002)
    a = monte_carlo(_mean_eval, pts, m, 64, seed=7, threads=1)
    b = monte_carlo(_mean_eval, pts, m, 64, seed=7, threads=2)
    c = monte_carlo(_mean_eval, pts, m, 64, seed=7, threads=5)
    assert np.array_equal(a.samples, b.samples) and np.array_equal(a.samples, c.samples)
    d = monte_carlo(_mean_eval, pts, m, 64, seed=8, threads=2)
    assert not np.array_equal(a.samples, d.samples)
    # the first 64 trials of a longer run are the same trials
    e = monte_carlo(_mean_eval, pts, m, 100, seed=7, threads=2)
    assert np.array_equal(e.samples[:64], a.samples)


def test_a_linear_quantity_gets_its_analytic_uncertainty():
    # the mean of n coordinates with sigma per coordinate: u = sigma / sqrt(n)
    pts = np.zeros((400, 3))
    mc = monte_carlo(_mean_eval, pts, measurement_model(sigma=0.02), 4000, seed=1, threads=2)
    x = mc["x"]
    assert x.u == pytest.approx(0.02 / 20, rel=0.05)
    assert x.k == pytest.approx(1.96, abs=0.1)
    assert x.interval[0] < 0 < x.interval[1] and abs(x.bias) < 3 * x.u / np.sqrt(4000) * 3
    assert x.to_dict().keys() == {"u", "U", "k", "coverage", "interval", "bias", "method", "trials"}


def test_adaptive_stopping_stabilizes_and_states_its_tolerance():
    pts = np.zeros((50, 3))
    mc = monte_carlo(lambda p: {"x": float(p[:, 0].mean())}, pts, measurement_model(sigma=1.0), None, seed=2,
                     threads=2, batch=100)
    s = mc.settings()
    assert mc.adaptive and mc.stabilized and mc.trials % 100 == 0 and mc.trials >= 200
    assert s["numerical_tolerance"]["x"] == numerical_tolerance(float(mc.samples[:, 0].std(ddof=1)), 1)
    assert numerical_tolerance(0.0123, 2) == pytest.approx(0.0005) and numerical_tolerance(0.0123, 1) == pytest.approx(0.005)


def test_jcgm101_coverage_interval_indices():
    y = np.arange(1, 10001, dtype=float)
    assert coverage_interval(y) == (250.0, 9750.0)  # q = 9500, r = 250: [y_250, y_9750]
    assert coverage_interval(np.arange(1, 101, dtype=float)) == (3.0, 98.0)  # q = 95, r = 2.5 -> 3


def test_noise_auto_is_the_dof_corrected_rms():
    r = np.array([0.001, -0.002, 0.0015, -0.0005, 0.0])
    s, how = estimate_sigma([(r, 3)])
    assert s == pytest.approx(np.sqrt((r @ r) / 2)) and "degrees of freedom" in how
    with pytest.raises(InvalidInputError):
        estimate_sigma([(r[:3], 3)])
    with pytest.warns(UserWarning, match="below any instrument's noise"):  # computed points: U would count nothing
        s, _ = estimate_sigma([(r * 1e-13, 3)])
    assert s == pytest.approx(np.sqrt((r @ r) / 2) * 1e-13)


def test_scale_and_line_of_sight_perturbations():
    from gagekit.uncertainty import trial_rng

    p = np.array([[100.0, 0, 0], [0, 200.0, 0]])
    m = measurement_model(scale_ppm=100)
    q = m.perturb(p, trial_rng(0, 0))
    s = q[0, 0] / 100.0
    assert abs(s - 1) <= 1e-4 and q[1, 1] / 200.0 == pytest.approx(s, rel=1e-12)
    los = measurement_model(sigma=0.01, origin=(0, 0, 0))
    q = los.perturb(p, trial_rng(0, 1))
    assert q[0, 1] == 0 and q[0, 2] == 0 and q[1, 0] == 0  # noise only along the line of sight
