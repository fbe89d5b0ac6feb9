"""Roundness report (ISO 12181): the polar plot of the profile about its reference circle,
with the reference and zone circles and the filtered profile, and the harmonic spectrum, as
roundness instruments (Talyrond, MarForm) draw them; the table of parameters."""

from __future__ import annotations

import numpy as np

from .html import Report


def _deviation_about(points: np.ndarray, center, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Angle (rad, sorted) and radial deviation (um) of points about a circle."""
    d = np.asarray(points, dtype=float) - np.asarray(center, dtype=float)
    ang = np.mod(np.arctan2(d[:, 1], d[:, 0]), 2 * np.pi)
    dev = 1e3 * (np.hypot(d[:, 0], d[:, 1]) - radius)
    order = np.argsort(ang, kind="stable")
    return ang[order], dev[order]


def polar_figure(res, title: str = "Roundness"):
    """The measured profile (grey) and the evaluated (filtered) profile (blue) as radial
    deviations from the reference circle, magnified (the plot's radius is the deviation in
    um about an inner limit, not to scale), with the reference circle (dashed) and the
    circles of the largest peak and deepest valley (red: RONp, RONv; MZCI: the zone)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    raw_t, raw_d = _deviation_about(res.points, res.center, res.radius)
    t, d = _deviation_about(res.profile, res.center, res.radius)
    lo = min(float(raw_d.min()), float(d.min()))
    hi = max(float(raw_d.max()), float(d.max()))
    span = max(hi - lo, 1e-6)
    base = lo - 0.6 * span
    fig = plt.figure(figsize=(6.5, 6.5))
    ax = fig.add_subplot(projection="polar")
    circ = np.linspace(0, 2 * np.pi, 721)
    filtered = res.filter["type"] != "none"
    ax.plot(np.append(raw_t, raw_t[:1]), np.append(raw_d, raw_d[:1]), color="#999999", lw=0.6,
            label="measured profile" if filtered else "profile")
    if filtered:
        ax.plot(np.append(t, t[:1]), np.append(d, d[:1]), color="#2a5d9f", lw=1.2,
                label=f"filtered, {res.filter['upr']:g} UPR Gaussian")
    ax.plot(circ, np.zeros_like(circ), color="black", lw=0.8, ls="--", label=f"reference circle {res.reference}")
    p, v = res.parameters["RONp"], res.parameters["RONv"]
    ax.plot(circ, np.full_like(circ, 1e3 * p), color="#b3261e", lw=0.8, ls=":", label="peak / valley circles")
    ax.plot(circ, np.full_like(circ, -1e3 * v), color="#b3261e", lw=0.8, ls=":")
    ax.set_rorigin(base)
    ax.set_ylim(base, hi + 0.15 * span)
    ax.set_thetagrids([0, 90, 180, 270], ["0", "90", "180", "270"])
    ax.set_rlabel_position(22.5)
    ax.set_title(f"{title}: RONt = {1e3 * res.parameters['RONt']:.3f} um ({res.reference})\n"
                 "radial deviation from the reference circle, um (magnified)", fontsize=9)
    ax.legend(fontsize=7, loc="lower right", bbox_to_anchor=(1.18, -0.12))
    return fig


def spectrum_figure(res, title: str = "Harmonic spectrum"):
    """Amplitude (um) per undulation per revolution of the evaluated profile, with the
    filter's transmission exp(-pi (alpha k / UPR)^2) on the right axis."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..form.parameters import gaussian_transmission

    k = np.arange(1, len(res.amplitude) + 1)
    fig, ax = plt.subplots(figsize=(8.0, 3.6))
    ax.bar(k, 1e3 * np.asarray(res.amplitude), width=0.8, color="#2a5d9f")
    ax.set_xlabel("undulations per revolution (UPR)")
    ax.set_ylabel("amplitude (um)")
    shown = len(k) if res.filter["type"] == "none" else min(len(k), int(np.ceil(3 * res.filter["upr"])))
    ax.set_xlim(0, shown + 1)
    ax.grid(alpha=0.3, axis="y")
    if res.filter["type"] != "none":
        ax2 = ax.twinx()
        ax2.plot(k, gaussian_transmission(k, res.filter["upr"]), color="#b3261e", lw=1.0)
        ax2.set_ylim(0, 1.05)
        ax2.set_ylabel(f"transmission, {res.filter['upr']:g} UPR", color="#b3261e")
    ax.set_title(f"{title} (harmonic 1 = eccentricity about the least-squares centre)", fontsize=9)
    fig.tight_layout()
    return fig


def add_roundness(report: Report, res, label: str) -> None:
    """Parameters, reference circle, eccentricity, the polar plot and the spectrum."""
    d = res.to_dict()
    f = d["filter"]
    report.section(f"Roundness of {label}")
    filt = "none" if f["type"] == "none" else f"Gaussian (ISO 16610-21), {f['upr']:g} UPR"
    rows = [[k, 1e3 * v] for k, v in d["parameters"].items()]
    report.table(["parameter", "value (um)"], rows,
                 caption=f"ISO 12181-1, reference {d['reference']}, filter {filt}, {d['n_points']} points")
    e = d["eccentricity"]
    c = d["reference_circle"]
    report.table(["quantity", "value"], [
        ["reference centre x (mm)", c["center"][0]], ["reference centre y (mm)", c["center"][1]],
        ["reference radius (mm)", c["radius"]],
        ["eccentricity (um)", 1e3 * e["magnitude"]], ["eccentricity angle (deg)", e["angle_deg"]],
        ["resampled at (equal angles)", d["resampling"]["samples"]],
        ["largest gap (deg)", d["resampling"]["largest_gap_deg"]],
    ], caption="Eccentricity: the reference centre from the coordinate origin (the spindle axis)")
    report.figure(polar_figure(res, label), "roundness-polar", caption="Polar plot: profile about the reference circle")
    report.figure(spectrum_figure(res), "roundness-spectrum", caption="Amplitude per UPR of the evaluated profile")
