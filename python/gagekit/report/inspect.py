"""The inspection section of a report: the callout table, and an interactive 3-D view of
the scan coloured by each point's deviation from its feature with the datum frame drawn
on the part (plotly, with plotly.js embedded in the page: self-contained, offline)."""

from __future__ import annotations

import html
import json
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["add_inspection", "callout_rows", "write_report", "MAX_PLOT_POINTS"]

#: The 3-D view shows at most this many points (an even subsample of each feature).
MAX_PLOT_POINTS = 40_000


def callout_rows(result) -> list[list[Any]]:
    """One row per callout: #, feature, characteristic, datums, zone, tolerance, measured,
    margin, result."""
    rows = []
    for k, t in enumerate(result.tolerances, 1):
        ch = t.characteristic + (f" {t.angle:g} deg" if t.angle is not None else "")
        rows.append([k, t.feature, ch, "|".join(t.datums) or "-", t.zone, t.tolerance, t.measured, t.margin,
                     "PASS" if t.passed else "FAIL"])
    return rows


def _num(v: float) -> str:
    return f"{v:.6f}" if abs(v) < 1e3 else f"{v:.6g}"


def _table(result) -> str:
    head = ["#", "feature", "characteristic", "datums", "zone", "tolerance (mm)", "measured (mm)", "margin (mm)", "result"]
    body = []
    for r in callout_rows(result):
        ok = r[-1] == "PASS"
        cls = "ok" if ok else "bad"
        style = "background:#e7f5ec" if ok else "background:#fbe9e7"
        cells = [f'<td class="num">{r[0]}</td>'] + [f"<td>{html.escape(str(c))}</td>" for c in r[1:5]]
        cells += [f'<td class="num">{_num(c)}</td>' for c in r[5:7]]
        cells.append(f'<td class="num {cls}">{_num(r[7])}</td>')
        cells.append(f'<td class="{cls}">{r[8]}</td>')
        body.append(f'<tr style="{style}" data-result="{r[8]}">' + "".join(cells) + "</tr>")
    ths = "".join(f"<th>{html.escape(h)}</th>" for h in head)
    return (f'<table class="callouts"><caption>Callouts: measured zone size against the tolerance '
            f'(margin = tolerance - measured)</caption><thead><tr>{ths}</tr></thead><tbody>{"".join(body)}</tbody></table>')


def _uncertainty_table(result) -> str:
    """Each callout's Monte Carlo uncertainty and decision (issue 26), when computed."""
    if result.monte_carlo is None:
        return ""
    s = result.monte_carlo
    head = ["#", "feature", "characteristic", "measured (mm)", "u (mm)", "U 95 % (mm)", "95 % interval (mm)",
            "MC bias (mm)", "decision"]
    body = []
    for k, t in enumerate(result.tolerances, 1):
        u, dec = t.uncertainty, t.to_dict()["decision"]
        cls = {"conforming": "ok", "nonconforming": "bad"}.get(dec, "")
        cells = [str(k), html.escape(t.feature), html.escape(t.characteristic), _num(t.measured), _num(u["u"]), _num(u["U"]),
                 f"[{_num(u['interval'][0])}, {_num(u['interval'][1])}]", f"{u['bias']:+.6f}"]
        body.append("<tr>" + "".join(f'<td class="num">{c}</td>' if i in (0, 3, 4, 5, 7) else f"<td>{c}</td>"
                                     for i, c in enumerate(cells)) + f'<td class="{cls}">{dec}</td></tr>')
    ths = "".join(f"<th>{html.escape(h)}</th>" for h in head)
    cap = (f"Uncertainty: {s['method']}, {s['trials']} simulated scans (seed {s['seed']}, {s['stopping']}), noise sigma "
           f"{s['model']['sigma']:.6g} mm; interval: probabilistically symmetric 95 %; bias: mean of the trials minus "
           "the measured value (a minimum-zone form error of noisy points is biased upward)")
    return (f'<table class="callouts"><caption>{html.escape(cap)}</caption><thead><tr>{ths}</tr></thead>'
            f'<tbody>{"".join(body)}</tbody></table>')


def _frame_table(result) -> str:
    if result.frame is None:
        return ""
    f = result.frame
    rows = [["origin", *f.origin]] + [[f"{k} axis", *f.axes[i]] for i, k in enumerate("xyz")]
    body = "".join("<tr>" + f"<td>{html.escape(r[0])}</td>" + "".join(f'<td class="num">{v:.9f}</td>' for v in r[1:]) + "</tr>" for r in rows)
    free = []
    if len(f.free_translations):
        free.append(f"{len(f.free_translations)} translation(s)")
    if f.free_rotation:
        free.append("the rotation about z")
    note = ("; free: " + ", ".join(free)) if free else ""
    cap = (f"Datum frame {'|'.join(f.datums)} in the scan's coordinates "
           f"({'right' if f.right_handed else 'left'}-handed{note})")
    return (f'<table><caption>{html.escape(cap)}</caption><thead><tr><th></th><th>x</th><th>y</th><th>z</th></tr></thead>'
            f"<tbody>{body}</tbody></table>")


def _datum_table(result) -> str:
    rows = []
    for d in result.datums:
        vec = "normal" if d.type == "plane" else "direction"
        orient = "point (no orientation)" if d.type == "point" else f"{vec}: " + ", ".join(f"{v:.9f}" for v in d.vector)
        rows.append([d.letter + ("" if not d.precedence else f" (after {'|'.join(d.precedence)})"), d.feature, d.method,
                     ", ".join(f"{v:.6f}" for v in d.point), orient])
    if not rows:
        return ""
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
    return ("<table><caption>Simulated datums (ISO 5459)</caption><thead><tr><th>datum</th><th>feature</th><th>method</th>"
            f"<th>point (mm)</th><th>orientation</th></tr></thead><tbody>{body}</tbody></table>")


def _subsample(n: int, keep: int) -> np.ndarray:
    if n <= keep:
        return np.arange(n)
    return np.linspace(0, n - 1, keep).round().astype(np.int64)


def _figure(result, slug: str) -> str:
    import plotly.graph_objects as go

    devs = result.deviations
    total = sum(len(p) for p, _ in devs.values()) or 1
    xs, ys, zs, cs, texts = [], [], [], [], []
    for name, (pts, dev) in devs.items():
        idx = _subsample(len(pts), max(50, int(MAX_PLOT_POINTS * len(pts) / total)))
        xs.append(pts[idx, 0])
        ys.append(pts[idx, 1])
        zs.append(pts[idx, 2])
        cs.append(1e3 * dev[idx])
        texts += [name] * len(idx)
    x, y, z, c = (np.concatenate(a) for a in (xs, ys, zs, cs))
    lim = float(np.percentile(np.abs(c), 99.5)) or 1.0
    fig = go.Figure()
    fig.add_trace(go.Scatter3d(
        x=x, y=y, z=z, mode="markers", name="scan", text=texts,
        marker=dict(size=2, color=c, colorscale="RdBu_r", cmin=-lim, cmax=lim,
                    colorbar=dict(title="deviation (um)")),
        hovertemplate="%{text}<br>x %{x:.3f} y %{y:.3f} z %{z:.3f}<br>deviation %{marker.color:.2f} um<extra></extra>"))
    if result.frame is not None:
        f = result.frame
        span = float(np.ptp(np.column_stack([x, y, z]), axis=0).max()) * 0.25
        for k, (axis, colour) in enumerate(zip("xyz", ("#d62728", "#2ca02c", "#1f77b4"))):
            end = f.origin + span * f.axes[k]
            fig.add_trace(go.Scatter3d(x=[f.origin[0], end[0]], y=[f.origin[1], end[1]], z=[f.origin[2], end[2]],
                                       mode="lines+text", text=["", f"{axis} ({'|'.join(f.datums)})"],
                                       line=dict(color=colour, width=8), name=f"datum frame {axis}", showlegend=True))
    fig.update_layout(height=640, margin=dict(l=0, r=0, t=30, b=0), scene=dict(aspectmode="data"),
                      title=f"{result.part}: deviation of each point from its feature (least squares) and the datum frame",
                      legend=dict(x=0, y=1))
    div_id = f"plot-{slug}"
    spec = fig.to_plotly_json()
    data = json.dumps(spec["data"], cls=_Encoder)
    layout = json.dumps(spec["layout"], cls=_Encoder)
    return (f'<div id="{div_id}" class="plotly-3d" style="height:640px"></div>'
            f'<script>Plotly.newPlot("{div_id}", {data}, {layout}, {{"responsive": true, "displaylogo": false}});</script>')


class _Encoder(json.JSONEncoder):
    def default(self, o):  # numpy arrays and scalars inside plotly's JSON
        if isinstance(o, np.ndarray):
            return o.tolist()
        if isinstance(o, np.generic):
            return o.item()
        return super().default(o)


def add_inspection(report, result, title: str | None = None) -> None:
    """Add one section for ``result`` (an InspectionResult) to ``report``."""
    import re

    from plotly.offline import get_plotlyjs

    name = title or f"Inspection of {result.part}"
    report.section(name)
    n_fail = sum(not t.passed for t in result.tolerances)
    report.text(f"{result.part}: {len(result.tolerances)} callouts, {n_fail} failing; status {result.status}. "
                f"{result.n_points} scan points, inspected in {result.seconds:.2f} s.",
                "ok" if result.status == "conforming" else "bad")
    rule = result.rule
    report.text(f"Decision rule: {rule.label} -- {rule.describe()}. Part decision: {result.decision}.",
                "ok" if result.decision == "conforming" else "bad")
    report.raw(_table(result))
    report.raw(_uncertainty_table(result))
    report.raw(_datum_table(result))
    report.raw(_frame_table(result))
    report.script("plotly", get_plotlyjs())
    slug = re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-")
    report.raw(_figure(result, f"{slug}-{len(report.sections)}"))
    report.text("Drag to turn, scroll to zoom, hover for a point's deviation; the coloured lines are the datum frame's "
                "x (red), y (green) and z (blue) axes from its origin.")


def write_report(result, out: Path) -> Path:
    """Write ``report.html`` and ``result.json`` into ``out``; return the page. The folder
    is built under a temporary name and renamed into place (:func:`gagekit._files.atomic_dir`)."""
    from .._files import atomic_dir, write_text
    from .._util import dumps
    from .html import Report

    out = Path(out)
    with atomic_dir(out) as tmp:
        write_text(tmp / "result.json", dumps(result))
        rep = Report(f"Inspection of {result.part}",
                     "GD&T callouts against the scan (ISO 1101, ISO 5459); every number was computed by this run.")
        add_inspection(rep, result)
        name = rep.write(tmp).name
    return out / name
