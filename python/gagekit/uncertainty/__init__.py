"""Measurement uncertainty and decision rules (issue 26 Sec. 1-2).

- :mod:`.model`: the instrument's measurement model (per-point noise, isotropic or along the
  line of sight with a range-dependent sigma; probing error P_FTU; MPE_E scale and thermal
  expansion; a systematic offset), from a ``[measurement]`` TOML table or options, and the
  ``--noise auto`` estimate of sigma;
- :mod:`.montecarlo`: JCGM 101:2008 Monte Carlo propagation through any evaluation,
  seeded per trial (the same on any number of threads), with adaptive stopping (7.9.4);
- :mod:`.decision`: ISO 14253-1:2017 decisions (simple, iso14253, guard bands);
- :mod:`.tasks`: the inspection, form-fit and CAD-comparison evaluations run through it.

A gage (or any other evaluation) uses the same three calls::

    model = measurement_model(sigma=0.002)            # or load_measurement_model("scanner.toml")
    mc = monte_carlo(lambda p: {"allowance": evaluate(p)}, points, model, 1000, seed=0)
    decide(mc.values["allowance"], mc["allowance"].U, lower=0.0, rule=parse_decision_rule(None, True))
"""

from .decision import DECISIONS, RULES, DecisionRule, decide, decide_margin, parse_decision_rule, worst_decision
from .model import MODEL_KEYS, MeasurementModel, estimate_sigma, load_measurement_model, measurement_model, trial_rng
from .montecarlo import METHOD, MIN_TRIALS, MonteCarlo, Uncertainty, coverage_interval, monte_carlo, numerical_tolerance, parse_trials
from .tasks import compare_uncertainty, decide_inspection, fit_uncertainty, inspect_uncertainty

__all__ = [
    "MeasurementModel", "measurement_model", "load_measurement_model", "estimate_sigma", "trial_rng", "MODEL_KEYS",
    "monte_carlo", "MonteCarlo", "Uncertainty", "parse_trials", "coverage_interval", "numerical_tolerance", "METHOD",
    "MIN_TRIALS",
    "DecisionRule", "parse_decision_rule", "decide", "decide_margin", "worst_decision", "DECISIONS", "RULES",
    "inspect_uncertainty", "decide_inspection", "fit_uncertainty", "compare_uncertainty",
]
