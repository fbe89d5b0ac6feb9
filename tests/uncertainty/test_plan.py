"""The compiled inspection (issue 26, speed): a Monte Carlo trial of the bracket is one step
of one kernel call (gagekit_gdt::plan). Its values equal the Python evaluation of the same
perturbed scan (the same kernels, the same warm starts), any thread count and any split
into blocks gives the same values, a drawing the plan does not cover runs the Python
evaluation and says why, and a bad plan is refused with a typed error."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from gagekit import _core, read_points
from gagekit._util import parse_toml
from gagekit.errors import InvalidInputError
from gagekit.inspect import _evaluate, load_part_spec, part_spec_from_dict
from gagekit.inspect.features import FeatureData, extract
from gagekit.samples import data_path
from gagekit.uncertainty import inspect_uncertainty, measurement_model
from gagekit.uncertainty.plan import compile_plan
from gagekit.uncertainty.tasks import PLAN_METHOD, PYTHON_METHOD, _active_set, _warm_starts

sys.path.insert(0, str(Path(__file__).parent))
from coverage_part import SIGMA, part_toml, scan  # noqa: E402


@pytest.fixture(scope="module")
def bracket():
    spec = load_part_spec(data_path("bracket.toml"))
    pts = read_points(data_path("bracket.ply"))
    feats = extract(pts, spec.features, spec.source, None)
    res = _evaluate(spec, feats, len(pts), 0.0)
    near = {t.feature: r.details for t, r in zip(spec.tolerances, res.tolerances) if t.characteristic == "sphericity"}
    warm = _warm_starts(feats)
    active, rows = _active_set(feats)
    plan, why = compile_plan(spec, feats, rows, warm, near)
    assert plan is not None, why
    return spec, pts, feats, res, near, warm, active, rows, plan


def _python_values(bracket, p):
    spec, pts, feats, _, near, warm, _, rows, _ = bracket
    fs = {}
    for name, fd in feats.items():
        f = FeatureData(fd.spec, fd.indices, np.ascontiguousarray(p[rows[name]]))
        if name in near:
            f._cache["near_zone"] = near[name]
        f._cache["warm"] = warm[name]
        fs[name] = f
    r = _evaluate(spec, fs, len(pts), 0.0)
    return np.array([v for t in r.tolerances for v in (t.measured, t.margin)])


def test_the_compiled_trial_equals_the_python_evaluation_of_the_same_scan(bracket):
    spec, _, _, res, _, _, active, _, plan = bracket
    measured = np.array([v for t in res.tolerances for v in (t.measured, t.margin)])
    got, _, fallbacks = plan.evaluate(active)
    assert np.abs(got - measured).max() <= 1e-9 and fallbacks == 0
    model = measurement_model(sigma=0.001, probing=0.002, scale_ppm=5)
    for i in range(4):
        p = model.simulate(active, 7, i)
        a, (b, fits, fallbacks) = _python_values(bracket, p), plan.evaluate(p)
        assert len(a) == 2 * len(spec.tolerances)
        bad = [spec.tolerances[j // 2].characteristic for j in np.nonzero(np.abs(a - b) > 1e-9)[0]]
        assert not bad, (i, bad)
        assert fits == 2 and fallbacks == 0  # the bore's minimum zone, datum D's cylinder


def test_blocks_and_threads_give_the_same_trials(bracket):
    active, plan = bracket[6], bracket[8]
    args = measurement_model(sigma=0.001).kernel_args()
    one, fits, _ = plan.run(active, args, 3, 0, 6, 1)
    two, _, _ = plan.run(active, args, 3, 0, 6, 2)
    split = np.vstack([plan.run(active, args, 3, 0, 2, 2)[0], plan.run(active, args, 3, 2, 4, 2)[0]])
    assert one.shape == (6, 40) and fits == 12
    assert np.array_equal(one, two) and np.array_equal(one, split)
    # trial i is the plan's evaluation of simulated measurement i: its plane features on their
    # certified extreme blocks (gagekit_gdt::plan::sparse), the same zones to the active sets'
    # containment tolerance (1e-9 mm) as every point
    assert np.abs(one[4] - plan.evaluate(plan.simulate(active, args, 3, 4))[0]).max() <= 1e-9
    every, fits_every, _ = plan.run(active, args, 3, 0, 6, 2, every_point=True)
    assert np.abs(every - one).max() <= 1e-9 and fits_every == fits


def test_the_trials_draw_each_block_of_points_from_seed_trial_and_block(bracket):
    active, plan = bracket[6], bracket[8]
    args = measurement_model(sigma=0.001).kernel_args()
    a = plan.simulate(active, args, 3, 4)
    assert np.array_equal(a, plan.simulate(active, args, 3, 4)) and not np.array_equal(a, plan.simulate(active, args, 3, 5))
    d = (a - active).ravel()
    assert abs(d.mean()) < 2e-5 and abs(d.std() - 0.001) < 2e-5
    # a model beyond isotropic noise draws as the measurement model's simulate
    other = measurement_model(sigma=0.001, probing=0.002)
    assert np.array_equal(plan.simulate(active, other.kernel_args(), 3, 4), other.simulate(active, 3, 4))


def test_inspect_uncertainty_runs_the_plan_and_a_drawing_it_does_not_cover_runs_python():
    r = inspect_uncertainty(read_points(data_path("bracket.ply")), data_path("bracket.toml"),
                            measurement_model(sigma=0.001), 10, seed=0, threads=2)
    assert r.monte_carlo["evaluation"] == PLAN_METHOD and r.monte_carlo["trials"] == 10
    spec = part_spec_from_dict(parse_toml(part_toml(), "coverage.toml"), "coverage.toml")
    r = inspect_uncertainty(scan(np.random.default_rng(1)), spec, measurement_model(sigma=SIGMA), 10, seed=0)
    assert r.monte_carlo["evaluation"].startswith(PYTHON_METHOD) and "(size of 'hole'): size" in r.monte_carlo["evaluation"]


def test_adaptive_stopping_runs_the_plan_in_blocks(bracket):
    from gagekit.uncertainty.montecarlo import monte_carlo

    active, plan, res = bracket[6], bracket[8], bracket[3]
    model = measurement_model(sigma=0.001)
    values = {f"{i}.{k}": v for i, t in enumerate(res.tolerances) for k, v in (("measured", t.measured), ("margin", t.margin))}
    asked = []

    def block(start, stop):
        asked.append((start, stop))
        return plan.run(active, model.kernel_args(), 2, start, stop - start, 2)[0]

    mc = monte_carlo(lambda p: values, active, model, None, seed=2, batch=10, max_trials=40, values=values, block=block)
    assert asked[0] == (0, 20) and all(a[1] == b[0] for a, b in zip(asked, asked[1:]))
    assert mc.adaptive and mc.trials == asked[-1][1] <= 40 and mc.samples.shape == (mc.trials, 40)


def test_a_bad_plan_or_model_is_refused_with_a_typed_error(bracket):
    active, plan = bracket[6], bracket[8]
    with pytest.raises(InvalidInputError, match="out of range"):
        plan.evaluate(active[:10])
    with pytest.raises(InvalidInputError, match="not finite|NaN|finite"):
        bad = active.copy()
        bad[3, 1] = np.nan
        plan.evaluate(bad)
    with pytest.raises(InvalidInputError, match=">= 0"):
        plan.run(active, (-1.0, None, 0.0, 0.0, 0.0, 0.0), 0, 0, 2, 1)
    with pytest.raises(InvalidInputError, match="unsupported shape"):
        _core.gdt.InspectionPlan([("cone", np.arange(3), None, (0, 0, 1), ((1, 0, 0), (0, 1, 0), (0, 0, 1)), False,
                                   (None, None, None, None, None, None))], [], [], [])


def test_the_simulated_measurement_depends_on_seed_and_trial_only():
    m = measurement_model(sigma=0.01, probing=0.004, offset=0.002, scale_ppm=10)
    p = np.random.default_rng(0).uniform(-50, 50, (2000, 3))
    a, b = m.simulate(p, 4, 9), m.simulate(p, 4, 9)
    assert np.array_equal(a, b) and not np.array_equal(a, m.simulate(p, 4, 10))
    noise = measurement_model(sigma=0.01).simulate(p, 0, 0) - p
    assert abs(noise.std() - 0.01) < 0.0005 and abs(noise.mean()) < 0.0005
    flat = measurement_model(sigma=0.01, probing=0.004).simulate(p[:, :2].copy(), 1, 2)
    assert flat.shape == (2000, 2)
