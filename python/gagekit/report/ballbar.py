"""Ballbar report (ISO 230-4:2022): the polar plot of both runs about the least-squares centre
(deviations magnified about the nominal circle) and the table of figures and diagnostics."""

from __future__ import annotations

import numpy as np

from .html import Report


def polar_figure(result, title: str = "Ballbar"):
    """Both directions on one polar plot: radius = radial deviation about the common
    least-squares centre (um), the zero circle drawn; the scale is the deviations', as on a
    ballbar plot (the radius itself is not to scale)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = result.residual_paths()
    lo = min(float(r.min()) for _, r in paths.values())
    hi = max(float(r.max()) for _, r in paths.values())
    span = max(hi - lo, 1e-6)
    base = lo - 0.5 * span  # inner limit of the plot: keeps the shape readable
    fig = plt.figure(figsize=(6.5, 6.5))
    ax = fig.add_subplot(projection="polar")
    colors = {"ccw": "#2a5d9f", "cw": "#b3261e"}
    for name, (ang, r) in paths.items():
        order = np.argsort(np.mod(ang, 360.0), kind="stable")
        t = np.radians(np.mod(ang, 360.0))[order]
        ax.plot(np.append(t, t[:1]), np.append(r[order], r[order][:1]), color=colors[name], lw=1.0,
                label={"ccw": "counter-clockwise", "cw": "clockwise"}[name])
    ax.plot(np.linspace(0, 2 * np.pi, 361), np.zeros(361), color="black", lw=0.6, ls="--", label="least-squares circle")
    ax.set_rorigin(base)
    ax.set_ylim(base, hi + 0.1 * span)
    a1, a2 = result.axes
    ax.set_thetagrids([0, 90, 180, 270], [f"+{a1}", f"+{a2}", f"-{a1}", f"-{a2}"])
    ax.set_title(f"{title}: G = {result.circular_deviation_um:.2f} um (plane {result.plane}, R {result.radius_mm:g} mm)\n"
                 "radial deviation about the least-squares centre, um", fontsize=9)
    ax.legend(fontsize=8, loc="lower right", bbox_to_anchor=(1.15, -0.1))
    return fig


def add_ballbar(report: Report, result, title: str = "Ballbar test (ISO 230-4)") -> None:
    """Figures, diagnostics with their share of G, and the polar plot."""
    d = result.to_dict()
    report.section(title)
    rows = [[f"G {k}", v] for k, v in d["circular_deviation_um"].items()]
    rows += [["F max", d["radial_deviation_um"]["max"]], ["F min", d["radial_deviation_um"]["min"]]]
    if "hysteresis_um" in d:
        rows.append(["H", d["hysteresis_um"]])
    report.table(["figure", "value (um)"], rows, caption=f"ISO 230-4:2022, plane {d['plane']}, radius {d['radius_mm']:g} mm")
    diag = [
        ["squareness (um/m)", d["squareness_um_per_m"]["value"], d["squareness_um_per_m"]["fraction_of_G"], d["squareness_um_per_m"]["sign"]],
        ["scale mismatch (um/m)", d["scale_mismatch_um_per_m"]["value"], d["scale_mismatch_um_per_m"]["fraction_of_G"], d["scale_mismatch_um_per_m"]["sign"]],
    ]
    for ax, b in d["backlash_um"].items():
        vals = ", ".join(f"{k} {v:.3f}" for k, v in b.items() if k != "fraction_of_G")
        diag.append([f"backlash {ax} (um)", vals, b["fraction_of_G"], "outward step at the reversal"])
    if "servo_mismatch_ms" in d:
        s = d["servo_mismatch_ms"]
        diag.append(["servo mismatch (ms)", s["value"], s["fraction_of_G"], s["sign"]])
    elif "servo_lag_um" in d:
        s = d["servo_lag_um"]
        diag.append(["servo lag (um, no feed given)", s["value"], s["fraction_of_G"], s["sign"]])
    if "cyclic_error_um" in d:
        c = d["cyclic_error_um"]
        for ax in result.axes:
            diag.append([f"cyclic error {ax} (um), pitch {c['pitch_mm']:.3f} mm", c[ax]["amplitude"], c[ax]["fraction_of_G"], c["pitch_source"]])
    for ax, s in d["reversal_spikes_um"].items():
        diag.append([f"reversal spikes {ax} (um)", f"+end {s['positive_end']:.3f}, -end {s['negative_end']:.3f}", "", ""])
    c = d["centre_offset_um"]["both"]
    diag.append(["centre offset (um)", f"x {c['x']:.3f}, y {c['y']:.3f}", d["centre_offset_um"]["fraction_of_G"], "about the pivot"])
    report.table(["diagnostic", "value", "fraction of G", "convention"], diag,
                 caption="Diagnostics from one least-squares fit of both runs; fraction of G = (G - G without the term) / G")
    report.figure(polar_figure(result), "ballbar-polar", caption="Polar plot, both directions (deviations magnified)")
