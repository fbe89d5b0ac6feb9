"""The SPC report: capability tables, individuals / moving-range charts with the Western
Electric signals, trends of allowances and T*, machines' drift across calibrations."""

from __future__ import annotations

from datetime import datetime
from pathlib import Path
from typing import Union

from .html import Report

__all__ = ["capability_rows", "imr_figure", "trend_figure", "drift_figure", "write_spc_report"]

HEADERS = ["characteristic", "unit", "n", "mean", "sd", "min margin", "Cp", "Cpk", "Pp", "Ppk", "trend / day", "signals"]


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def date_axis(ax, times: list) -> None:
    """Dates and times on a time axis (``2026-03-02 07:00``), whatever the span: matplotlib's
    automatic format shows ``53:23.300000`` for data within a minute. Seconds appear when
    the data span less than a day, microseconds when less than a minute."""
    import matplotlib.dates as mdates

    span = (max(times) - min(times)).total_seconds() if times else 0.0
    fmt = "%Y-%m-%d %H:%M" if span >= 86400 else ("%Y-%m-%d %H:%M:%S" if span >= 60 else "%Y-%m-%d %H:%M:%S.%f")
    ax.xaxis.set_major_locator(mdates.AutoDateLocator(minticks=3, maxticks=6))
    ax.xaxis.set_major_formatter(mdates.DateFormatter(fmt))
    ax.set_xlabel("time (UTC)")


def _g(d: dict, k: str):
    v = d.get(k)
    return "-" if v is None else v


def capability_rows(chars: list) -> list[list]:
    return [[c["name"], c["unit"], c["n"], c["mean"], _g(c, "sd"), _g(c, "min_margin"), _g(c, "cp"), _g(c, "cpk"),
             _g(c, "pp"), _g(c, "ppk"), _g(c, "trend_per_day"), len(c.get("chart", {}).get("signals", []))] for c in chars]


def imr_figure(c: dict):
    """Individuals chart (limits, specification limits, signals in red) over the MR chart."""
    plt = _plt()
    x = c["series"]["value"]
    k = list(range(1, len(x) + 1))
    ch = c["chart"]
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 5), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    a1.plot(k, x, marker="o", ms=3, lw=1, color="#2a5d9f")
    for y, style, label in ((ch["center"], "-", "centre"), (ch["ucl"], "--", "UCL"), (ch["lcl"], "--", "LCL")):
        a1.axhline(y, ls=style, color="#555", lw=1, label=label)
    for key, label in (("lower", "LSL"), ("upper", "USL")):
        if key in c:
            a1.axhline(c[key], color="#b3261e", lw=1.2, label=label)
    sig = ch["signals"]
    if sig:
        a1.plot([s["index"] + 1 for s in sig], [x[s["index"]] for s in sig], "o", mfc="none", mec="#b3261e", ms=9,
                label="Western Electric signal")
    a1.set_ylabel(f"{c['unit']}")
    a1.set_title(c["name"])
    a1.legend(fontsize=7, ncol=3)
    mr = [abs(x[i] - x[i - 1]) for i in range(1, len(x))]
    a2.plot(k[1:], mr, marker="o", ms=3, lw=1, color="#2a5d9f")
    a2.axhline(ch["mr_center"], color="#555", lw=1)
    a2.axhline(ch["mr_ucl"], color="#555", lw=1, ls="--")
    a2.set_ylabel("moving range")
    a2.set_xlabel("part (time order)")
    fig.tight_layout()
    return fig


def trend_figure(chars: list, title: str, ylabel: str):
    """Several series against the scan time."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 4))
    every = []
    for c in chars:
        t = [datetime.fromisoformat(s) for s in c["series"]["time"]]
        every += t
        ax.plot(t, c["series"]["value"], marker="o", ms=3, lw=1, label=c["name"].split(": ")[-1])
    ax.set_title(title)
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=7, ncol=2)
    ax.grid(alpha=0.3)
    date_axis(ax, every)
    fig.autofmt_xdate()
    fig.tight_layout()
    return fig


def drift_figure(machine: dict, top: int = 8):
    """Fig. 4.8 across days: each group's change since the first calibration."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 4.5))
    every = []
    for g in machine["groups"][:top]:
        t = [datetime.fromisoformat(s) for s in g["times"]]
        every += t
        if "effect_mm_per_unit" in g:
            y = [(v - g["first"]) * g["effect_mm_per_unit"] * 1000.0 for v in g["values"]]
        else:
            y = [v - g["first"] for v in g["values"]]
        name = g["name"] if len(g["name"]) < 40 else g["name"][:37] + "..."
        ax.plot(t, y, marker="o", label=name)
    effect = all("effect_mm_per_unit" in g for g in machine["groups"][:top])
    ax.set_ylabel("effect of the change since the first calibration (um RMS)" if effect
                  else "change since the first calibration (group units)")
    ax.set_title(f"{machine['machine']}: parameter drift across calibrations (Fig. 4.8)")
    ax.legend(fontsize=7, ncol=2)
    ax.grid(alpha=0.3)
    date_axis(ax, every)
    fig.autofmt_xdate()
    fig.tight_layout()
    return fig


def write_spc_report(stats: dict, directory: Union[str, Path]) -> Path:
    """``report.html`` (and PNGs) of :func:`gagekit.stats.collect`'s result."""
    rep = Report("Statistical process control", f"{stats['database']} ({stats['generated']})")
    for spec in stats["specs"]:
        label = spec.get("part") or spec.get("source") or spec["spec"]
        rep.section(f"{spec['kind']} {label} ({spec['spec']})")
        res = stats["resolution"]
        rep.text(f"{spec['results']} results, {spec['failed']} failed scans. Cp/Cpk: within sigma = MRbar/1.128; "
                 "Pp/Ppk: overall sample standard deviation (ISO 22514-2, AIAG SPC); one limit: one-sided indices; "
                 "indices only against specification limits. "
                 f"Resolution {res['mm']:g} mm ({res['rad']:g} rad): values within it of a limit are on the limit, "
                 "no index without variation above it. Capability from "
                 f"{stats['min_values_for_capability']} values (AIAG), trends from {stats['min_trend_days']:g} day of data; "
                 "times: the scan's acquisition time, else when its result was stored.")
        chars = spec["characteristics"]
        if not chars:
            rep.text("no successful results yet")
            continue
        rep.table(HEADERS, capability_rows(chars))
        meas = [c for c in chars if "measurement" in c]
        if meas:
            rep.text(f"Measurement standard uncertainty u = {meas[0]['measurement']['u']:g} (k = 1): "
                     f"{meas[0]['measurement']['model']}. The table above is observed; with the measurement "
                     "variance removed (sigma_process = sqrt(sigma_observed^2 - u^2)):")
            rep.table(["characteristic", "u", "Cp", "Cpk", "Pp", "Ppk", "Q_MP (%)"],
                      [[c["name"], c["measurement"]["u"]] + [_g(c["measurement"]["process"], k) for k in ("cp", "cpk", "pp", "ppk")]
                       + [_g(c["measurement"], "q_mp_pct")] for c in meas])
        from ..stats.collect import messages

        for c in chars:
            for kind, line in messages(c):
                rep.text(f"{kind}: {line}", None if kind == "note" else "bad")
        allow = [c for c in chars if c["name"].startswith("allowance after")]
        tstar = [c for c in chars if c["name"].startswith("T* ")]
        if allow:
            rep.figure(trend_figure(allow, "Allowances after T* over time", "mm"), f"{spec['spec']}-allowances",
                       "Allowance of every gage after T*, by scan time")
        for unit in ("mm", "rad"):
            group = [c for c in tstar if c["unit"] == unit]
            if group:
                rep.figure(trend_figure(group, f"T* over time ({unit})", unit), f"{spec['spec']}-tstar-{unit}",
                           "The correction T* of each part, by scan time")
        for c in chars:
            if "chart" in c and not c["name"].startswith(("allowance before", "stock")):
                rep.figure(imr_figure(c), f"{spec['spec']}-{c['name']}", "Individuals and moving-range chart; "
                           "red circles: Western Electric signals")
    for mach in stats["machines"]:
        rep.section(f"machine {mach['machine']}")
        rep.text(f"{mach['calibrations']} tracking runs from {mach['from']} to {mach['to']}, "
                 f"{mach['identifications']} identifications (one per measurement cycle)")
        rows = [[g["name"], g.get("unit", ""), g["identifications"], g["first"], g["last"], g["max_change"],
                 g.get("max_change_effect_um", "-"), g.get("trend_per_day", "-")] for g in mach["groups"][:20]]
        rep.table(["group", "unit", "n", "first", "last", "largest change", "its effect (um)", "trend / day"], rows)
        if mach["identifications"] >= 2:
            rep.figure(drift_figure(mach), f"drift-{mach['machine']}", "Parameter drift across calibrations")
    from .._files import atomic_dir

    with atomic_dir(Path(directory)) as tmp:  # the old folder or the new one, never half of each
        rep.write(tmp)
    return Path(directory) / "report.html"
