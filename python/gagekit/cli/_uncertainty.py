"""The options every measuring command shares for its uncertainty and its decision rule
(:mod:`gagekit.uncertainty`): ``--uncertainty N|auto``, ``--noise SIGMA|auto``,
``--measurement MODEL.toml``, ``--decision-rule``, ``--threads``."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Optional

import typer

UNCERTAINTY_OPTION = typer.Option(
    None, "--uncertainty", metavar="N|auto",
    help="JCGM 101 Monte Carlo: re-run the whole evaluation on N (>= 10) simulated measurements of the scan, or "
         "'auto' for adaptive stopping (JCGM 101 7.9, one significant digit of u); needs --noise or --measurement.")
NOISE_OPTION = typer.Option(
    None, "--noise", metavar="SIGMA|auto",
    help="Per-point noise, mm (isotropic, each coordinate), or 'auto': the pooled RMS of the fitted features' "
         "least-squares residuals with the degrees-of-freedom correction. Overrides the model file's sigma.")
MEASUREMENT_OPTION = typer.Option(
    None, "--measurement", metavar="MODEL.toml",
    help="The instrument's [measurement] table: sigma, origin + sigma_per_m (line of sight), probing (P_FTU), "
         "scale_ppm (MPE_E), cte + delta_t, offset.")
RULE_OPTION = typer.Option(
    None, "--decision-rule", metavar="RULE",
    help="simple, iso14253 or guard-band=FRACTION (of U): conforming / not-proven / nonconforming per callout "
         "(ISO 14253-1). Default: iso14253 with --uncertainty, simple without. The exit status does not change.")
THREADS_OPTION = typer.Option(
    None, "--threads", min=1, max=1024,
    help="Threads for the Monte Carlo trials (default: the CPUs available); the result does not depend on it.")


def uncertainty_settings(uncertainty: Optional[str], noise: Optional[str], measurement: Optional[Path]) -> Any:
    """(trials or None for adaptive, the model) when ``--uncertainty`` is given, else None;
    one-line errors (exit 2) for a model without --uncertainty or --uncertainty without model."""
    from ..errors import ConfigError, InvalidInputError
    from ..uncertainty import load_measurement_model, measurement_model, parse_trials

    if uncertainty is None:
        if noise is not None or measurement is not None:
            raise ConfigError("--noise / --measurement describe the instrument for --uncertainty N|auto: give it too")
        return None
    trials = parse_trials(uncertainty)
    sigma: Any = None
    if noise is not None:
        t = noise.strip().lower()
        if t == "auto":
            sigma = "auto"
        else:
            try:
                sigma = float(t)
            except ValueError:
                raise InvalidInputError(f"--noise {noise!r}: give a standard deviation in mm (e.g. 0.002) or auto") from None
    model = load_measurement_model(measurement, sigma=sigma) if measurement is not None else measurement_model(sigma=sigma)
    if model.is_null and not model.sigma_auto:
        raise ConfigError("--uncertainty needs the instrument's errors: --noise SIGMA|auto or --measurement MODEL.toml "
                          "(with at least one non-zero term)")
    return trials, model


def rule_of(text: Optional[str], with_uncertainty: bool) -> Any:
    from ..uncertainty import parse_decision_rule

    return parse_decision_rule(text, with_uncertainty)


def batch_options(uncertainty: Optional[str], noise: Optional[str], measurement: Optional[Path],
                  decision_rule: Optional[str], seed: int, threads: Optional[int]) -> dict:
    """The ``uncertainty`` option of a batch job (checked now: a bad model stops the batch
    before it starts), or {} without --uncertainty. JSON-able, so that it joins the spec
    hash (other settings: another result). Each worker runs its trials on ``threads``
    threads (default 1: the workers are the parallelism)."""
    from dataclasses import asdict

    mc = uncertainty_settings(uncertainty, noise, measurement)
    if mc is None:
        if decision_rule is not None:
            from ..errors import ConfigError

            raise ConfigError("--decision-rule in a batch needs --uncertainty N|auto (the rule decides with U)")
        return {}
    trials, model = mc
    rule = rule_of(decision_rule, True)
    return {"uncertainty": {"trials": trials, "model": asdict(model), "seed": int(seed), "threads": int(threads or 1),
                            "rule": decision_rule if decision_rule is not None else rule.label}}
