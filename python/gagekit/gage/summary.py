"""The printed (text) report of a virtual-gage analysis (Tables 5.3-5.4).

The figures, the HTML section and ``write_report`` live in :mod:`gagekit.report.gage`."""

from __future__ import annotations

import math

from ..report.text import table
from .analysis import GageCheckResult

__all__ = ["gage_table", "summary_lines", "human", "zero_margin_line"]


def _f(v: float, nd: int = 4) -> float:
    """Rounded to 0.1 um, without a "-0" for a face that touches its gage."""
    return round(float(v), nd) + 0.0


def gage_table(result: GageCheckResult) -> tuple[list[str], list[list]]:
    """Headers and rows of the allowance table (Tables 5.3 and 5.4), mm."""
    headers = ["gage", "region", "points", "filtered", "allowance before", "allowance after", "q", "slack"]
    rows = [[g.name, g.region, g.points, g.filtered_points, _f(g.allowance_before), _f(g.allowance_after),
             _f(g.q), _f(g.slack)] for g in result.gages]
    if any(g.uncertainty is not None for g in result.gages):
        headers += ["U (95 %)", "MC bias"]
        for r, g in zip(rows, result.gages):
            r += [_f(g.uncertainty["U"], 6), _f(g.uncertainty["bias"], 6)]
    if result.decision is not None:
        headers.append("decision")
        for r, g in zip(rows, result.gages):
            r.append(g.decision)
    return headers, rows


def zero_margin_line(result: GageCheckResult) -> str:
    """The flag of a conforming part that sits on its limits after T*."""
    names = result.zero_margin_gages
    return (f"zero margin: {'gage' if len(names) == 1 else 'gages'} {', '.join(names)} "
            f"{'sits' if len(names) == 1 else 'sit'} on the limit after T* (allowance 0 within {result.resolution:g} mm): "
            "conforming, but nothing is left for measurement noise or fixturing")


def summary_lines(result: GageCheckResult) -> list[str]:
    """Status, T*, the objective, groups and bound limits as text lines."""
    t = result.transform
    out = [f"status: {result.status}"]
    if result.decision is not None:
        rule = result.decision_rule or {}
        out.append(f"decision: {result.decision} (rule {rule.get('name')}: {rule.get('description')})")
        band = result.guard_band
        if band is not None and band["guarded"]["status"] == "conforming":
            g = band["guarded"]["transform"]
            out.append("  proven at the guard-banded transform (every face keeps its guard band): "
                       f"alpha {g['alpha']:.6f}, beta {g['beta']:.6f}, gamma {g['gamma']:.6f} rad, "
                       f"dx {g['dx']:.4f}, dy {g['dy']:.4f}, dz {g['dz']:.4f} mm")
    if result.monte_carlo is not None:
        s = result.monte_carlo
        out.append(f"uncertainty: {s['method']}, {s['trials']} trials, seed {s['seed']}, {s['stopping']}, "
                   f"{s['active_points']} active points; noise sigma {s['model']['sigma']:.6g} mm")
    if result.zero_margin_gages:
        out.append(zero_margin_line(result))
    out += [
        f"T*: alpha = {t.alpha:.6f} rad, beta = {t.beta:.6f} rad ({math.degrees(t.beta):.4f} deg), "
        f"gamma = {t.gamma:.6f} rad",
        f"    dx = {t.dx:.4f} mm, dy = {t.dy:.4f} mm, dz = {t.dz:.4f} mm",
        f"objective (Eq. 5.11): {result.objective:.4f} mm;  largest release u = {result.largest_release:.4f} mm",
    ]
    if result.infeasible_groups:
        for grp in result.infeasible_groups:
            out.append("infeasible group (Eq. 5.10): " + ", ".join(grp))
    if result.limited_by_motion_bounds:
        out.append("limited by motion bounds: " + ", ".join(f"{b.motion} {b.side} (multiplier {b.dual:.3g})"
                                                           for b in result.bound_limits))
    else:
        out.append("motion bounds: not limiting")
    if result.alignment is not None:
        a = result.alignment
        out.append("alignment (3-2-1): datum zones "
                   f"z {a.primary.zone:.4f} / y {a.secondary.zone:.4f} / x {a.tertiary.zone:.4f} mm, "
                   f"origin ({', '.join(f'{v:.3f}' for v in a.origin)}) in the scanner frame")
    out.append(f"solver: clarabel ({result.lp_status}), {result.iterations} re-linearisations, "
               f"last step {result.last_step:.1e} mm")
    return out


def human(result: GageCheckResult) -> str:
    """The printed report of ``gagekit gage check``."""
    headers, rows = gage_table(result)
    return "\n".join(summary_lines(result)) + "\n\n" + table(headers, rows) + \
        "\n\nallowances in mm: smallest signed distance to the gage plane (negative: short of material)"
