"""ISO 230-2:2014 report: the standard's graph (mean unidirectional positional deviations with
their +/- 2 s bands in both directions, against the target position) and its tables."""

from __future__ import annotations

import numpy as np

from .html import Report


def figure(result, title: str = "ISO 230-2 positioning"):
    """The standard's plot: x_i(up), x_i(down) and x_i(up/down) +/- 2 s_i (um) over the targets."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.array([r.target for r in result.targets])
    mu = 1e3 * np.array([r.mean_up for r in result.targets])
    md = 1e3 * np.array([r.mean_down for r in result.targets])
    su = 1e3 * np.array([r.s_up for r in result.targets])
    sd = 1e3 * np.array([r.s_down for r in result.targets])
    fig, ax = plt.subplots(figsize=(10, 4.5))
    for m, s, color, label in ((mu, su, "#2a5d9f", "up (+)"), (md, sd, "#b3261e", "down (-)")):
        ax.plot(t, m, "o-", color=color, lw=1.2, ms=4, label=f"mean deviation {label}")
        ax.plot(t, m + 2 * s, "--", color=color, lw=0.8, label=f"mean {label} +/- 2s")
        ax.plot(t, m - 2 * s, "--", color=color, lw=0.8)
    for j in range(result.deviations_up.shape[1]):
        ax.plot(t, 1e3 * result.deviations_up[:, j], ".", color="#2a5d9f", ms=2, alpha=0.5)
        ax.plot(t, 1e3 * result.deviations_down[:, j], ".", color="#b3261e", ms=2, alpha=0.5)
    ax.axhline(0.0, color="black", lw=0.5)
    ax.set_xlabel("target position (mm)")
    ax.set_ylabel("positional deviation (um)")
    ax.set_title(f"{title}: A = {1e3 * result.A:.2f} um, E = {1e3 * result.E:.2f} um, R = {1e3 * result.R:.2f} um, B = {1e3 * result.B:.2f} um")
    ax.legend(fontsize=8, ncol=2)
    ax.grid(alpha=0.3)
    return fig


def add_iso230_2(report: Report, result, title: str = "ISO 230-2 positioning") -> None:
    """Axis figures, the per-target table and the plot."""
    report.section(title)
    keys = ("A", "A_up", "A_down", "E", "E_up", "E_down", "M", "R", "R_up", "R_down", "B", "B_mean")
    report.table(["figure", "value (um)"], [[k, 1e3 * getattr(result, k)] for k in keys],
                 caption=f"Axis figures, ISO 230-2:2014, {len(result.targets)} targets, {result.cycles} cycles per direction")
    headers = ["target (mm)", "mean up (um)", "mean down (um)", "mean (um)", "s up (um)", "s down (um)",
               "R up (um)", "R down (um)", "R (um)", "B (um)"]
    rows = [[r.target] + [1e3 * v for v in (r.mean_up, r.mean_down, r.mean, r.s_up, r.s_down, r.R_up, r.R_down, r.R, r.B)]
            for r in result.targets]
    report.table(headers, rows, caption="Per target")
    report.figure(figure(result, title), "iso230-2", caption="Mean unidirectional positional deviations and +/- 2s bands")
