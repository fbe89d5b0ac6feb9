"""The uncertainty of a virtual-gage analysis and its ISO 14253-1 decisions (issue 26 Sec. 2).

A face's allowance after T* is the smallest signed distance of its points from its gage plane
at T* (Eq. 5.4). Its uncertainty comes from the JCGM 101 Monte Carlo of
:mod:`gagekit.uncertainty`: every point the analysis reads (the datum regions and the gage
regions, each box widened a little so that a simulated point may move in or out: the "active
set") is perturbed by the instrument's :class:`~gagekit.uncertainty.MeasurementModel`, and on
each simulated measurement the whole analysis is run again: the 3-2-1 alignment (Eqs.
5.13-5.19), the cut and the hull filter of every region (Sec. 5.4.1), and

- the allowance of every face at the measured T* (the transform the part will be machined
  with): its spread is the face's uncertainty. At T* found again on every trial the limiting
  faces sit at exactly 0 by construction of Eq. 5.11, so that spread says nothing about them;
- T* itself, solved again (``transform_uncertainty``: how much the correction moves).

The minimum of noisy distances is biased low (more noise, more negative outliers); the
simulation's ``bias`` says by how much, beside U.

Decisions (``decision_rule``: simple, iso14253 = guard band U, guard-band=FRACTION x U). A
face conforms when it keeps at least its guard band g_i of material, and the part can be
machined to print when one transform does that for every face, so the decision is made by
solving Eq. 5.11 again with each gage plane moved by g_i (the ISO 14253-1 acceptance and
rejection zones applied to the existence question of Ch. 5):

- ``guarded``: planes moved into the material by g_i. All slacks 0: conformity is proven,
  at that problem's transform (``guard_band.transform``; every face keeps >= g_i);
- ``relaxed``: planes moved out of the material by g_i. A positive slack there proves
  nonconformity of that face (even granting every face its U, no transform reaches it);
- otherwise a face with a positive slack in the guarded problem is ``not-proven``.

The part takes its worst face's decision. ``simple`` uses no guard band: the status of
Eq. 5.11 as before (a face on its limit is conforming). A face whose allowance after T* is
within g of zero is therefore ``not-proven`` unless another transform leaves it more.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any, Optional, Union

import numpy as np

from ..cloud.regions import Box, classify
from ..errors import InvalidInputError
from ..uncertainty import DecisionRule, MeasurementModel, monte_carlo, parse_decision_rule, worst_decision
from ..uncertainty.model import estimate_sigma
from .align import apply
from .analysis import (
    GageCheckResult,
    GageProblem,
    _as_spec,
    build_problem,
    build_problem_stream,
    region_in_scanner,
    solve_problem,
)

__all__ = ["check_gages_uncertainty", "gage_decisions", "MOTIONS", "WIDEN"]

MOTIONS = ("alpha", "beta", "gamma", "dx", "dy", "dz")
#: How much each region box is widened for the active set: this fraction of its size plus 1 mm.
WIDEN = (0.05, 1.0)


def _widened(box: Box) -> Box:
    frac, mm = WIDEN
    return Box(box.center, tuple(s * (1.0 + 2.0 * frac) + 2.0 * mm for s in box.size), box.rotation, name=box.name)


def _boxes(spec, alignment) -> list[Box]:
    """Every region's box in the scanner frame (part-frame boxes by the measured alignment), widened."""
    return [_widened(region_in_scanner(r, alignment)) for r in spec.regions]


def active_set(points: Any, spec, alignment, stream: bool = False) -> np.ndarray:
    """The points of every (widened) region, each scan point once, in file order."""
    boxes = _boxes(spec, alignment)
    if stream:
        from ..cloud.streamed import cut_stream

        p = cut_stream(points, boxes, ["all"] * len(boxes), all_indices=True)
        ids = np.concatenate([r.index_array() for r in p.regions])
        pts = np.concatenate([r.point_array() for r in p.regions])
        _, first = np.unique(ids, return_index=True)
        return np.ascontiguousarray(pts[first])  # in file order, as the whole read
    pts = np.asarray(points, dtype=np.float64)
    idx = np.unique(np.concatenate(classify(pts, boxes)))
    return np.ascontiguousarray(pts[idx])


def _allowances_at(problem: GageProblem, matrix: np.ndarray) -> np.ndarray:
    """Each gage's allowance (smallest signed distance of its hull vertices from its plane)
    at the fixed transform ``matrix`` (4 x 4, part frame)."""
    moved = apply(matrix, problem.points)
    gid = np.repeat(np.arange(len(problem.planes)), np.diff(problem.offsets))
    e = np.einsum("ij,ij->i", moved, problem.planes[gid, :3]) + problem.planes[gid, 3]
    return np.minimum.reduceat(e, np.asarray(problem.offsets[:-1]))


def _auto_sigma(problem: GageProblem) -> tuple[float, str]:
    """sigma from the least-squares plane residuals of every gage region's hull vertices is
    not usable (hull vertices are the extremes); the regions' plotted samples are a uniform
    draw of each region's points: their plane residuals, 3 parameters each."""
    sets = []
    for pts in problem.plot_points.values():
        if len(pts) > 10:
            c = pts.mean(axis=0)
            _, _, vt = np.linalg.svd(pts - c, full_matrices=False)
            sets.append(((pts - c) @ vt[2], 3))
    if not sets:
        raise InvalidInputError("--noise auto: no region has enough points to estimate the noise from (give sigma)")
    sigma, note = estimate_sigma(sets)
    return sigma, note + " (plane residuals of the gage regions: a casting's form error counts as noise)"


def gage_decisions(problem: GageProblem, result: GageCheckResult, U: Optional[list], rule: DecisionRule) -> tuple:
    """(per-gage decisions, part decision, guard_band dict or None); see the module docstring."""
    if rule.name == "simple" or U is None:
        d = ["conforming" if g.slack == 0.0 else "nonconforming" for g in result.gages]
        return d, worst_decision(d), None
    g = rule.fraction * np.asarray(U, dtype=np.float64)
    guarded = solve_problem(replace(problem, planes=problem.planes - np.c_[np.zeros((len(g), 3)), g]), groups=False)
    band: dict = {"fraction_of_U": rule.fraction, "g_mm": {o.name: float(v) for o, v in zip(result.gages, g)},
                  "guarded": {"status": guarded.status, "transform": guarded.transform.to_dict(),
                              # against the real gage planes (the guarded problem's are g_i higher)
                              "allowances_after": {o.name: o.allowance_after + float(v) for o, v in zip(guarded.gages, g)},
                              "slacks": {o.name: o.slack for o in guarded.gages}}}
    if guarded.status == "conforming":
        d = ["conforming"] * len(g)
        return d, "conforming", band
    relaxed = solve_problem(replace(problem, planes=problem.planes + np.c_[np.zeros((len(g), 3)), g]), groups=False)
    band["relaxed"] = {"status": relaxed.status, "slacks": {o.name: o.slack for o in relaxed.gages}}
    d = []
    for go, ro in zip(guarded.gages, relaxed.gages):
        d.append("nonconforming" if ro.slack > 0.0 else "not-proven" if go.slack > 0.0 else "conforming")
    return d, worst_decision(d), band


def check_gages_uncertainty(points: Any, spec: Any, model: MeasurementModel, trials: Union[None, int, str] = None, *,
                            seed: int = 0, threads: Optional[int] = None, rule: Union[None, str, DecisionRule] = None,
                            groups: bool = True, stream: bool = False, digits: int = 1) -> GageCheckResult:
    """:func:`gagekit.check_gages` with each face's allowance uncertainty, T*'s uncertainty
    and the ISO 14253-1 decisions (module docstring). ``points``: the cloud (n, 3), or with
    ``stream=True`` a re-iterable of chunks (:class:`~gagekit.cloud.stream.CloudStream`)."""
    t0 = time.perf_counter()
    spec = _as_spec(spec)
    rule = rule if isinstance(rule, DecisionRule) else parse_decision_rule(rule, True)
    problem = build_problem_stream(points, spec) if stream else build_problem(points, spec)
    result = solve_problem(problem, groups=groups)
    if model.sigma_auto:
        model = model.with_sigma(*_auto_sigma(problem))
    active = active_set(points, spec, problem.alignment, stream)
    t_star = result.transform.as_array()
    free = [m for m, f in zip(MOTIONS, problem.free) if f]
    names = [f"{i}.allowance_after" for i in range(len(result.gages))]

    def evaluate(p: np.ndarray) -> dict:
        pb = build_problem(p, spec)
        out = dict(zip(names, map(float, _allowances_at(pb, t_star))))
        sol = solve_problem(pb, groups=False)
        out.update({f"transform.{m}": float(getattr(sol.transform, m)) for m in free})
        return out

    base = {n: float(g.allowance_after) for n, g in zip(names, result.gages)}
    base.update({f"transform.{m}": float(getattr(result.transform, m)) for m in free})
    mc = monte_carlo(evaluate, active, model, trials, seed=seed, threads=threads, values=base, digits=digits)
    U = [mc[n].U for n in names]
    decisions, part, band = gage_decisions(problem, result, U, rule)
    gages = tuple(g.replace(uncertainty=mc[n].to_dict(), decision=d) for g, n, d in zip(result.gages, names, decisions))
    settings = mc.settings()
    settings["active_points"] = int(len(active))
    settings["seconds"] = time.perf_counter() - t0
    return replace(result, gages=gages, decision=part, decision_rule=rule.to_dict(), monte_carlo=settings,
                   transform_uncertainty={m: mc[f"transform.{m}"].to_dict() for m in free}, guard_band=band)


def decide_gages(result: GageCheckResult, rule: Union[None, str, DecisionRule] = None) -> GageCheckResult:
    """A result without an uncertainty with its decisions under ``rule`` (U = 0: every rule
    reduces to the status of Eq. 5.11 per face)."""
    rule = rule if isinstance(rule, DecisionRule) else parse_decision_rule(rule, False)
    d = ["conforming" if g.slack == 0.0 else "nonconforming" for g in result.gages]
    return replace(result, gages=tuple(g.replace(decision=x) for g, x in zip(result.gages, d)),
                   decision=worst_decision(d), decision_rule=rule.to_dict())
