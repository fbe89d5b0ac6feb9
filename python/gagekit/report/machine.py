"""Report sections and figures for machines: calibrations (Sec. 3.2, Fig. 3.12, Tables 3.4-3.5),
observer plans (Fig. 4.2) and thermal tracking (Tables 4.4-4.6, Fig. 4.8)."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence, Union

import numpy as np

from .html import Report


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def residual_table(cals: Sequence) -> tuple[list[str], list[list]]:
    """Rows of Tables 3.4/3.5: mean and max residual (um) before and after the model."""
    headers = ["method", "set", "points", "nominal mean (um)", "nominal max (um)", "model mean (um)", "model max (um)", "decrease of mean (%)"]
    rows = []
    for cal in cals:
        for label, st in (("identification", cal.residuals), ("test", cal.test)):
            if st is None:
                continue
            rows.append([cal.method, label, st.n_points, 1e3 * st.nominal_mean, 1e3 * st.nominal_max,
                         1e3 * st.model_mean, 1e3 * st.model_max, st.decrease_mean_pct])
    return headers, rows


def add_calibrations(report: Report, cals: Sequence) -> None:
    """Residual table and the per-point residuals before and after the model (Fig. 3.12)."""
    headers, rows = residual_table(cals)
    report.table(headers, rows, caption="Residual vector lengths before (nominal machine) and after the identified model")
    plt = _plt()
    fig, axes = plt.subplots(len(cals), 1, figsize=(10, 3.2 * len(cals)), squeeze=False)
    for ax, cal in zip(axes[:, 0], cals):
        pr = cal.point_residuals or {}
        for key, label, color in (("nominal", "nominal machine", "#b3261e"), ("model", "identified model", "#2a5d9f")):
            if key in pr:
                r = 1e3 * np.linalg.norm(np.asarray(pr[key]), axis=1)
                ax.plot(np.arange(1, len(r) + 1), r, ".-", ms=3, lw=0.6, color=color, label=f"{label} (mean {r.mean():.1f} um)")
        ax.set_title(f"method {cal.method}: residual per calibration point")
        ax.set_xlabel("measured point")
        ax.set_ylabel("|residual| (um)")
        ax.set_yscale("log")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    report.figure(fig, "machine-residuals", "Residuals per point before and after the model (cf. Fig. 3.12)")
    g = cals[0]
    report.table(
        ["group (identifiable combination)", "value", "standard uncertainty", "unit"],
        [[e.name, e.value, e.std if e.std is not None else "absorbed by the tracker frame", e.unit] for e in g.groups],
        caption=f"Identified groups ({g.method}; rank {g.rank}, condition number {g.condition_number:.3g})",
    )


def tracking_table(result) -> tuple[list[str], list[list]]:
    """Rows of Tables 4.4-4.6: mean and max residual (um) per cycle for each strategy."""
    headers = ["cycle", "observed mean (um)", "full mean (um)", "static mean (um)", "drift only mean (um)",
               "full max (um)", "static max (um)", "drift only max (um)"]
    rows = [[c["cycle"], 1e3 * c["observed"]["mean"], 1e3 * c["full"]["mean"], 1e3 * c["static"]["mean"],
             1e3 * c["drift_only"]["mean"], 1e3 * c["full"]["max"], 1e3 * c["static"]["max"],
             1e3 * c["drift_only"]["max"]] for c in result.cycles]
    return headers, rows


def add_tracking(report: Report, result) -> None:
    """Residuals per cycle for the three strategies and the parameter drift (Fig. 4.8)."""
    headers, rows = tracking_table(result)
    report.table(headers, rows, "Residuals per cycle: identified anew each cycle (full, Table 4.4), first cycle's "
                 "model kept (static, Table 4.5), observed change only (drift only, Table 4.6)")
    tm = result.temperature_model
    if tm and tm.get("fitted"):
        mean = {k: 1e3 * sum(c[k]["mean"] for c in result.cycles) / len(result.cycles) for k in ("full", "static", "drift_only")}
        report.text(f"Temperature model ({tm.get('model', 'linear')}) over {', '.join(tm['sensors'])}: "
                    f"leave-one-cycle-out mean residual {tm['leave_one_cycle_out_mean'] * 1000:.1f} um, against "
                    f"{mean['full']:.1f} um re-identified each cycle, {mean['drift_only']:.1f} um drift-only and "
                    f"{mean['static']:.1f} um static (means over the cycles).")
    report.figure(drift_figure(result), "parameter-drift", "Drift of the identified groups over the cycles (cf. Fig. 4.8)")


def plot_drift(result, path: Union[str, Path], top: int = 8) -> None:
    """Write :func:`drift_figure` as a PNG."""
    from .._files import atomic_path

    plt = _plt()
    fig = drift_figure(result, top)
    try:
        with atomic_path(path) as tmp:  # temp file in the same folder, then rename
            fig.savefig(tmp, dpi=120)
    finally:
        plt.close(fig)


def drift_figure(result, top: int = 8):
    """Fig. 4.8: how much each group's change since the first cycle moves the target, RMS
    over the plan's points (um), for the ``top`` groups that move it most."""
    plt = _plt()
    names = list(result.groups)
    vals = np.array([result.groups[n] for n in names]) * np.array([result.group_effect[n] for n in names])[:, None] * 1000.0
    change = vals - vals[:, :1]
    order = np.argsort(-np.abs(change).max(axis=1))[:top]
    x = [c["cycle"] for c in result.cycles]
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for i in order:
        ax.plot(x, change[i], marker="o", label=names[i] if len(names[i]) < 40 else names[i][:37] + "...")
    ax.set_xlabel("cycle")
    ax.set_ylabel(f"effect of the change since cycle {x[0]} (um RMS)")
    ax.set_title("Parameter drift over cycles (Fig. 4.8)")
    ax.legend(fontsize=7, ncol=2)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def plan_figure(machine, plan):
    """An observer plan in the workspace (cf. Fig. 4.2): X, Z+W and Y of each point,
    coloured by B; returns a matplotlib Figure."""
    plt = _plt()
    names = list(machine.joint_names)
    c = plan.commands
    x, y = c[:, names.index("X")], c[:, names.index("Y")]
    zw = c[:, names.index("Z")] + c[:, names.index("W")]
    fig = plt.figure(figsize=(7, 5.5))
    ax = fig.add_subplot(projection="3d")
    sc = ax.scatter(x, zw, y, c=c[:, names.index("B")], cmap="viridis", s=18)
    ax.set_xlabel("X (mm)")
    ax.set_ylabel("Z + W (mm)")
    ax.set_zlabel("Y (mm)")
    fig.colorbar(sc, ax=ax, shrink=0.6, label="B (deg)")
    zones = "no zones" if plan.zones == "none" else f"{plan.zones} zones"
    ax.set_title(f"{len(c)}-point {plan.criterion}-optimal plan ({zones})")
    return fig
