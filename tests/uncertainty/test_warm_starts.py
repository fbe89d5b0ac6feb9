"""Warm-started trials (issue 26, speed): each Monte Carlo trial of the bracket's inspection
starts its minimax cylinders, least-squares cylinders, flatness slabs and roundness
sections from the measured evaluation; its values equal those of the same perturbed scan
evaluated from scratch (the global searches), and the JSON counts the warm fits and the
fallbacks to the global search."""

from __future__ import annotations

import numpy as np

from gagekit import read_points
from gagekit.inspect import _evaluate, load_part_spec
from gagekit.inspect.features import FeatureData, extract
from gagekit.samples import data_path
from gagekit.uncertainty import inspect_uncertainty, measurement_model, trial_rng
from gagekit.uncertainty.tasks import _active_set, _warm_starts


def test_warm_trials_equal_trials_from_scratch():
    spec = load_part_spec(data_path("bracket.toml"))
    pts = read_points(data_path("bracket.ply"))
    feats = extract(pts, spec.features, spec.source, None)
    _evaluate(spec, feats, len(pts), 0.0)
    warm = _warm_starts(feats)
    assert {"minimum-zone", "least-squares"} <= set(warm["bore"]) and "min-circumscribed" in warm["boss"]
    assert "slab" in warm["A"]
    active, rows = _active_set(feats)
    model = measurement_model(sigma=0.001)
    for i in range(3):
        p = model.perturb(active, trial_rng(5, i))
        cold = {n: FeatureData(fd.spec, fd.indices, np.ascontiguousarray(p[rows[n]])) for n, fd in feats.items()}
        hot = {n: FeatureData(fd.spec, fd.indices, np.ascontiguousarray(p[rows[n]])) for n, fd in feats.items()}
        for n, f in hot.items():
            f._cache["warm"] = warm[n]
        a = _evaluate(spec, cold, len(pts), 0.0)
        b = _evaluate(spec, hot, len(pts), 0.0)
        for x, y in zip(a.tolerances, b.tolerances):
            assert abs(x.measured - y.measured) <= 1e-9, (x.feature, x.characteristic, x.measured, y.measured)
        assert all(v.warm_fallback is False for f in hot.values() for k, v in f._cache.items()
                   if isinstance(k, tuple) and k[0] == "cylinder")


def test_monte_carlo_counts_warm_fits_and_fallbacks():
    spec = load_part_spec(data_path("bracket.toml"))
    r = inspect_uncertainty(read_points(data_path("bracket.ply")), spec, measurement_model(sigma=0.001), 10, seed=0,
                            threads=2)
    w = r.monte_carlo["warm_starts"]
    assert w["fits"] == 20 and w["fallbacks"] == 0  # the bore's minimum zone and datum D's cylinder, 10 trials
    assert "global search" in w["method"]
