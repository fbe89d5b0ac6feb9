"""Task-specific uncertainties of gagekit's measured results: an inspection's callouts, a form
fit's parameters, a CAD comparison's deviation statistics (:func:`monte_carlo` over the
whole evaluation of each).

What is perturbed and re-evaluated:

- ``inspect``: the points of every feature region (the only points the evaluation reads:
  the "active set", cut once; a point in two regions is perturbed once), then datums,
  datum frames and every zone are evaluated again from scratch on each simulated
  measurement. Each callout's ``measured`` and ``margin`` get an uncertainty; the decision
  uses the margin's U (equal to the measured value's for a plain zone; with a material
  bonus or two limits the margin is what is decided).
- ``form fit``: every point, then the fit (seeded swarms keep their seed).
- ``compare``: every point, then the alignment and the signed distances.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any, Mapping, Optional, Union

import numpy as np

from ..errors import InvalidInputError
from .decision import DecisionRule, decide_margin, parse_decision_rule, worst_decision
from .model import FEATURE_PARAMETERS, MeasurementModel, estimate_sigma
from .montecarlo import MonteCarlo, monte_carlo

__all__ = ["inspect_uncertainty", "decide_inspection", "fit_uncertainty", "compare_uncertainty", "FIT_KEYS",
           "COMPARE_KEYS"]


# -- inspection --------------------------------------------------------------------------


def _active_set(feats: Mapping[str, Any]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The union of the features' points (each scan point once) and each feature's rows in it."""
    names = list(feats)
    ids = np.concatenate([np.asarray(feats[n].indices, dtype=np.int64) for n in names])
    union, inverse = np.unique(ids, return_inverse=True)
    active = np.empty((len(union), 3))
    rows: dict[str, np.ndarray] = {}
    k = 0
    for n in names:
        m = len(feats[n].indices)
        r = inverse[k:k + m]
        active[r] = feats[n].points
        rows[n] = r
        k += m
    return active, rows


#: How a trial's minimax cylinders start (the JSON ``monte_carlo.warm_starts.method``).
WARM_METHOD = ("the exact local method (2-D fit, SLP; no basin hopping) from the measured fit's axis, verified on "
               "every point; the global search where it cannot decide (a fallback)")


#: How the trials of a compiled inspection run (the JSON ``monte_carlo.evaluation``).
PLAN_METHOD = ("compiled: each block of trials is one kernel call (gagekit_gdt::plan), the trials in parallel, "
               "trial i's perturbation drawn by the generator of (seed, i); with isotropic noise alone each block of "
               "64 points by the generator of (seed, i, block), and the plane features evaluated on their blocks that "
               "can be extreme, certified: every other block lies inside every zone read (no bound on the noise "
               "assumed; gagekit_gdt::plan::sparse)")
#: ... and of one the plan does not cover.
PYTHON_METHOD = "the Python evaluation of each trial"


def _warm_starts(feats: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """{feature: {criterion: (point, direction)}} of the minimax cylinders the measured
    evaluation fitted (:meth:`FeatureData.chebyshev_cylinder`) and ``"slab"``: the normal
    of a plane's flatness zone (:meth:`FeatureData.min_zone`): each trial starts there.
    Every feature gets an entry (a trial's feature is known by it)."""
    out: dict[str, dict[str, Any]] = {}
    for name, fd in feats.items():
        w = out[name] = {}
        for k, v in fd._cache.items():
            if isinstance(k, tuple) and k[0] == "cylinder":
                w[k[1]] = (tuple(v.point), tuple(v.direction))
        if "mz" in fd._cache:
            w["slab"] = tuple(fd._cache["mz"][1])
        if fd.shape == "cylinder" and "lsq" in fd._cache:
            w["least-squares"] = (tuple(fd._cache["lsq"].point), tuple(fd._cache["lsq"].direction))
    return out


def _auto_sigma_features(feats: Mapping[str, Any]) -> tuple[float, str]:
    sets = [(fd.deviations(), FEATURE_PARAMETERS.get(fd.shape, 6)) for fd in feats.values() if fd.shape != "surface"]
    if not sets:
        raise InvalidInputError("--noise auto: the drawing has no fitted feature to estimate the noise from (give sigma)")
    return estimate_sigma(sets)


def decide_inspection(result: Any, rule: Optional[DecisionRule] = None, mc: Optional[MonteCarlo] = None) -> Any:
    """The :class:`~gagekit.inspect.InspectionResult` with a ``decision`` per callout and for
    the part under ``rule`` (default: iso14253 with ``mc``, simple without), each callout's
    ``uncertainty`` from ``mc`` (keys ``"{i}.measured"`` / ``"{i}.margin"``)."""
    rule = rule if rule is not None else parse_decision_rule(None, mc is not None)
    rows = []
    for i, t in enumerate(result.tolerances):
        unc = margin_unc = None
        U = 0.0
        if mc is not None:
            unc = mc[f"{i}.measured"].to_dict()
            mu = mc[f"{i}.margin"]
            U = mu.U
            if t.margin_value is not None:
                margin_unc = mu.to_dict()
        rows.append(replace(t, uncertainty=unc, margin_uncertainty=margin_unc, decision=decide_margin(t.margin, U, rule)))
    return replace(result, tolerances=tuple(rows), decision_rule=rule,
                   monte_carlo=None if mc is None else mc.settings())


def inspect_uncertainty(points: Any, spec: Any, model: MeasurementModel, trials: Union[None, int, str] = None, *,
                        seed: int = 0, threads: Optional[int] = None, rule: Union[None, str, DecisionRule] = None,
                        stream: bool = False, digits: int = 1) -> Any:
    """:func:`gagekit.inspect.inspect` (or ``inspect_stream`` with ``stream=True``) with the
    Monte Carlo uncertainty of every callout and the decisions (module docstring).
    ``model.sigma_auto``: sigma is the pooled RMS of the features' least-squares residuals
    (:func:`~gagekit.uncertainty.model.estimate_sigma`)."""
    from ..inspect import _evaluate, load_part_spec
    from ..inspect.features import FeatureData, extract, extract_stream
    from ..inspect.spec import PartSpec

    t0 = time.perf_counter()
    rule = rule if isinstance(rule, DecisionRule) else parse_decision_rule(rule, True)
    if not isinstance(spec, PartSpec):
        spec = load_part_spec(spec)
    if stream:
        n, feats = extract_stream(points, spec.features, spec.source)
    else:
        from .._util import as_points

        pts = as_points(points)
        cad = None
        if spec.cad is not None:
            from ..cad.features import CadContext

            cad = CadContext.of_scan(spec.cad, pts)
        feats = extract(pts, spec.features, spec.source, cad)
        n = int(len(pts))
    result = _evaluate(spec, feats, n, t0)
    if model.sigma_auto:
        model = model.with_sigma(*_auto_sigma_features(feats))
    active, rows = _active_set(feats)
    # the measured minimum zones start each trial's active set (gagekit.form.active: exact by verification)
    near: dict[str, dict] = {}
    for tol, row in zip(spec.tolerances, result.tolerances):
        if tol.characteristic == "sphericity" and "center" in row.details:
            near[tol.feature] = row.details
    warm = _warm_starts(feats)
    fits: list[Optional[bool]] = []  # each trial's warm-started fits: did the global search run?

    def values(res: Any) -> dict[str, float]:
        out = {}
        for i, t in enumerate(res.tolerances):
            out[f"{i}.measured"] = float(t.measured)
            out[f"{i}.margin"] = float(t.margin)
        return out

    def evaluate(p: np.ndarray) -> dict[str, float]:
        fs = {}
        for name, fd in feats.items():
            f = FeatureData(fd.spec, fd.indices, np.ascontiguousarray(p[rows[name]]))
            if "cad" in fd._cache:
                f._cache["cad"] = fd._cache["cad"]
            if name in near:
                f._cache["near_zone"] = near[name]
            f._cache["warm"] = warm[name]
            fs[name] = f
        out = values(_evaluate(spec, fs, n, 0.0))
        fits.extend(v.warm_fallback for f in fs.values() for k, v in f._cache.items()
                    if isinstance(k, tuple) and k[0] == "cylinder" and v.warm_fallback is not None)
        return out

    from .montecarlo import default_threads
    from .plan import compile_plan

    plan, why = compile_plan(spec, feats, rows, warm, near)
    counts = [0, 0]  # the compiled trials' warm-started cylinder fits, of them fallbacks
    block = None
    if plan is not None:
        nthreads = default_threads() if threads is None else int(threads)

        def block(start: int, stop: int) -> np.ndarray:
            out, n_fits, n_fallbacks = plan.run(active, model.kernel_args(), int(seed), start, stop - start, max(nthreads, 1))
            counts[0] += n_fits
            counts[1] += n_fallbacks
            return out

    mc = monte_carlo(evaluate, active, model, trials, seed=seed, threads=threads, values=values(result), digits=digits,
                     block=block)
    how = (PLAN_METHOD if plan is not None else f"{PYTHON_METHOD} ({why})")
    if fits or counts[0]:
        mc = replace(mc, warm_starts={"fits": len(fits) + counts[0],
                                      "fallbacks": sum(1 for f in fits if f) + counts[1], "method": WARM_METHOD})
    mc = replace(mc, evaluation=how)
    out = decide_inspection(result, rule, mc)
    return replace(out, seconds=time.perf_counter() - t0)


# -- form fits -----------------------------------------------------------------------------

#: The scalar results of a fit that get an uncertainty (those the fit has).
FIT_KEYS = ("radius", "inner_radius", "outer_radius", "form_error", "distance", "apex_angle")


def _fit_values(fit: Any) -> dict[str, float]:
    d = fit.to_dict()
    out = {k: float(d[k]) for k in FIT_KEYS if isinstance(d.get(k), (int, float)) and not isinstance(d.get(k), bool)}
    c = d.get("center")
    if isinstance(c, (list, tuple)):
        for axis, v in zip("xyz", c):
            out[f"center.{axis}"] = float(v)
    return out


def fit_uncertainty(fit_points: Any, points: Any, model: MeasurementModel, trials: Union[None, int, str] = None, *,
                    seed: int = 0, threads: Optional[int] = None, digits: int = 1) -> tuple[Any, MonteCarlo]:
    """(the fit, its :class:`MonteCarlo`) of ``fit_points(points) -> fit`` (e.g. a closure
    over :func:`gagekit.form.files.fit_file`): each scalar result (radius, inner / outer
    radius, form_error, distance, apex_angle) and the centre's coordinates.
    ``model.sigma_auto``: sigma from the least-squares fit's residuals of the same shape."""
    pts = np.ascontiguousarray(np.asarray(points, dtype=float))
    fit = fit_points(pts)
    if model.sigma_auto:
        model = model.with_sigma(*estimate_sigma([(_residuals(fit, pts), _parameters(fit, pts))]))
    mc = monte_carlo(lambda p: _fit_values(fit_points(p)), pts, model, trials, seed=seed, threads=threads,
                     values=_fit_values(fit), digits=digits)
    return fit, mc


def _parameters(fit: Any, pts: np.ndarray) -> int:
    shape = getattr(fit, "shape", "circle")
    if shape == "circle" and pts.shape[1] == 2:
        return 3
    return FEATURE_PARAMETERS.get(shape, 6)


def _residuals(fit: Any, pts: np.ndarray) -> np.ndarray:
    """Residuals of the least-squares fit of the fit's shape (normal distances)."""
    from .. import form

    shape = getattr(fit, "shape", "circle")
    if shape == "circle":
        ls = form.fit_circle(pts, "least-squares")
        if pts.shape[1] == 2:
            return np.linalg.norm(pts - np.asarray(ls.center), axis=1) - ls.radius
        n = np.asarray(ls.normal) / np.linalg.norm(ls.normal)
        q = pts - np.asarray(ls.center)
        h = q @ n
        return np.concatenate([np.linalg.norm(q - np.outer(h, n), axis=1) - ls.radius, h])
    if shape == "sphere":
        ls = form.fit_sphere(pts)
        return np.linalg.norm(pts - np.asarray(ls.center), axis=1) - ls.radius
    if shape == "plane":
        ls = form.fit_plane(pts)
        return (pts - np.asarray(ls.point)) @ np.asarray(ls.normal)
    if shape in ("cylinder", "line"):
        ls = form.fit_cylinder(pts) if shape == "cylinder" else form.fit_line(pts)
        p0, d = np.asarray(ls.point), np.asarray(ls.direction)
        q = pts - p0
        r = np.linalg.norm(q - np.outer(q @ d, d), axis=1)
        return r - ls.radius if shape == "cylinder" else r
    ls = form.fit_cone(pts)
    p0, d = np.asarray(ls.point), np.asarray(ls.direction)
    q = pts - p0
    t = q @ d
    rho = np.linalg.norm(q - np.outer(t, d), axis=1)
    half = 0.5 * ls.apex_angle
    return rho * np.cos(half) - t * np.sin(half) - ls.distance


# -- CAD comparison ----------------------------------------------------------------------------

#: The deviation statistics of ``compare`` that get an uncertainty (and per face min/max/mean/rms).
COMPARE_KEYS = ("min", "max", "mean", "sd", "rms", "profile")


def _compare_values(res: Any) -> dict[str, float]:
    s = res.statistics()
    out = {f"deviations.{k}": float(s[k]) for k in COMPARE_KEYS}
    for f in res.face_statistics():
        if f["n"]:
            for k in ("min", "max", "mean", "rms"):
                out[f"faces.{f['id']}.{k}"] = float(f[k])
    return out


def compare_uncertainty(points: Any, cad_model: Any, model: MeasurementModel, trials: Union[None, int, str] = None, *,
                        seed: int = 0, threads: Optional[int] = None, digits: int = 1, **compare_options: Any
                        ) -> tuple[Any, MonteCarlo]:
    """(the :class:`~gagekit.cad.compare.CompareResult`, its :class:`MonteCarlo`): the
    alignment and the distances re-run on every simulated measurement. Keys
    ``deviations.{min,max,mean,sd,rms,profile}`` and ``faces.ID.{min,max,mean,rms}``.
    ``model.sigma_auto``: sigma is the RMS of the deviations after the alignment, with the
    6 degrees of freedom of the alignment removed (sqrt(sum d^2 / (n - 6)))."""
    from ..cad.compare import compare

    pts = np.ascontiguousarray(np.asarray(points, dtype=float))
    res = compare(pts, cad_model, **compare_options)
    if model.sigma_auto:
        d = res.deviation[res.used]
        model = model.with_sigma(*estimate_sigma([(d, 6)]))
    base = _compare_values(res)

    def evaluate(p: np.ndarray) -> dict[str, float]:
        v = _compare_values(compare(p, cad_model, **compare_options))
        # a face a trial leaves empty keeps the measured value's key set
        return {k: v.get(k, base[k]) for k in base}

    mc = monte_carlo(evaluate, pts, model, trials, seed=seed, threads=threads, values=base, digits=digits)
    return res, mc
