"""The report of ``gagekit compare``: the CAD model coloured by deviation (plotly Mesh3d,
each vertex coloured by the mean deviation of the scan points nearest to its triangles,
grey where no point is), the scan points, labelled callouts at the largest deviation of
every face, the deviation histogram and the per-face table. plotly.js is embedded: the
page works offline."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from .inspect import MAX_PLOT_POINTS, _Encoder, _subsample

__all__ = ["add_compare", "write_report", "callouts", "colour_limit", "vertex_rgb", "colour_stops", "MAX_MESH_TRIANGLES"]

#: The deviation map's colour scale (matplotlib's name): blue inside the material, red outside.
COLOURMAP = "RdBu_r"
#: The colour of a vertex no point is near.
NO_POINT = (200, 200, 200)
#: Larger models are drawn by their points only (a browser cannot turn more smoothly).
MAX_MESH_TRIANGLES = 400_000


def callouts(result) -> list[dict[str, Any]]:
    """Per face with points: the point of largest |deviation| (its position in the CAD
    frame, value, input index), largest first."""
    out = []
    used = np.isfinite(result.deviation)
    for face in result.faces:
        sel = np.flatnonzero(used & (result.face == face.index))
        if len(sel) == 0:
            continue
        k = sel[int(np.argmax(np.abs(result.deviation[sel])))]
        out.append({"face": face.label, "id": face.id, "index": int(k), "deviation": float(result.deviation[k]),
                    "point": result.aligned[k].tolist()})
    out.sort(key=lambda c: -abs(c["deviation"]))
    return out


def colour_limit(deviation: np.ndarray) -> float:
    """The half range of the deviation colour scale (mm): the 99.5th percentile of the
    finite |deviations| (a few outliers do not wash out the map), 1 um when all are 0."""
    d = np.abs(np.asarray(deviation, dtype=np.float64))
    d = d[np.isfinite(d)]
    lim = float(np.percentile(d, 99.5)) if len(d) else 1.0
    return lim or 1e-3


def vertex_rgb(mean: np.ndarray, count: np.ndarray, lim: float) -> np.ndarray:
    """(n, 3) uint8 colours of the deviation map's vertices (:func:`gagekit.cad.compare.vertex_deviations`):
    RdBu_r from -``lim`` (blue, inside the material) to +``lim`` (red, outside), grey where no point is."""
    import matplotlib

    rgba = matplotlib.colormaps[COLOURMAP](np.clip(0.5 + 0.5 * np.asarray(mean, dtype=np.float64) / lim, 0.0, 1.0))
    rgb = (255 * np.asarray(rgba)[:, :3]).astype(np.uint8)
    rgb[np.asarray(count) == 0] = NO_POINT
    return rgb.reshape(-1, 3)


def colour_stops(n: int = 11) -> list[str]:
    """The colour scale of :func:`vertex_rgb` as ``n`` evenly spaced ``#rrggbb`` stops from
    -lim to +lim (a legend's gradient)."""
    import matplotlib

    rgba = matplotlib.colormaps[COLOURMAP](np.linspace(0.0, 1.0, n))
    return ["#%02x%02x%02x" % tuple(int(255 * c) for c in q[:3]) for q in rgba]


def _vertex_colours(result, lim: float) -> list[str]:
    from ..cad.compare import vertex_deviations

    model = result.model
    used = np.isfinite(result.deviation)
    tri = model.distances(result.aligned[used]).triangle  # nearest triangle of each used point
    mean, count = vertex_deviations(model, tri, result.deviation[used])
    return [f"rgb({r},{g},{b})" for r, g, b in vertex_rgb(mean, count, lim).tolist()]


def _figure(result, slug: str) -> str:
    import plotly.graph_objects as go

    used = np.flatnonzero(np.isfinite(result.deviation))
    idx = used[_subsample(len(used), MAX_PLOT_POINTS)]
    p = result.aligned[idx]
    c = 1e3 * result.deviation[idx]
    lim = colour_limit(result.deviation[used])
    fig = go.Figure()
    model = result.model
    if model is not None and len(model.triangles) <= MAX_MESH_TRIANGLES:
        v, t = model.vertices, model.triangles
        fig.add_trace(go.Mesh3d(x=v[:, 0], y=v[:, 1], z=v[:, 2], i=t[:, 0], j=t[:, 1], k=t[:, 2],
                                vertexcolor=_vertex_colours(result, lim), name="CAD", opacity=1.0, flatshading=True,
                                hoverinfo="skip", showlegend=True))
    fig.add_trace(go.Scatter3d(
        x=p[:, 0], y=p[:, 1], z=p[:, 2], mode="markers", name="scan", visible="legendonly" if model is not None else True,
        marker=dict(size=2, color=c, colorscale="RdBu_r", cmin=-1e3 * lim, cmax=1e3 * lim, colorbar=dict(title="deviation (um)")),
        hovertemplate="x %{x:.3f} y %{y:.3f} z %{z:.3f}<br>deviation %{marker.color:.2f} um<extra></extra>"))
    cs = callouts(result)
    if cs:
        q = np.array([k["point"] for k in cs])
        fig.add_trace(go.Scatter3d(x=q[:, 0], y=q[:, 1], z=q[:, 2], mode="markers+text", name="largest per face",
                                   text=[f"{k['face']}: {k['deviation'] * 1e3:+.1f} um" for k in cs],
                                   marker=dict(size=5, color="black", symbol="diamond"), textfont=dict(size=11)))
    fig.update_layout(height=700, margin=dict(l=0, r=0, t=30, b=0), scene=dict(aspectmode="data"), legend=dict(x=0, y=1),
                      title="Deviation from the CAD surface (positive outside the material)")
    spec = fig.to_plotly_json()
    div_id = f"plot-{slug}"
    return (f'<div id="{div_id}" class="plotly-3d" style="height:700px"></div><script>Plotly.newPlot("{div_id}", '
            f'{json.dumps(spec["data"], cls=_Encoder)}, {json.dumps(spec["layout"], cls=_Encoder)}, '
            '{"responsive": true, "displaylogo": false});</script>')


def _histogram(result):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    d = result.deviation[np.isfinite(result.deviation)] * 1e3
    fig, ax = plt.subplots(figsize=(8, 3.5))
    ax.hist(d, bins=60, color="#2a5d9f")
    ax.axvline(0.0, color="k", lw=0.8)
    ax.set_xlabel("deviation (um), positive outside the material")
    ax.set_ylabel("points")
    return fig


def add_compare(report, result) -> None:
    """Add the comparison's section to ``report``."""
    from plotly.offline import get_plotlyjs

    d = result.to_dict()
    s, a = d["deviations"], d["alignment"]
    report.section("Deviation from the CAD model")
    report.text(f"{d['cad']['file']}: {d['cad']['faces']} faces, {d['cad']['triangles']} triangles. {d['n_points']} points, "
                f"{d['n_used']} used, {d['n_beyond']} beyond the maximum distance. Alignment {a['method']}: RMS "
                f"{a['rms_before']:.6f} -> {a['rms_after']:.6f} mm. Distances: {d['distance_method']}.")
    report.table(["min", "max", "mean", "sd", "rms", "profile (2 max |d|)"],
                 [[s["min"], s["max"], s["mean"], s["sd"], s["rms"], s["profile"]]], "Deviations (mm)")
    if "certificate" in a:
        c = a["certificate"]
        report.text(f"Minimax certificate: largest |deviation| {c['max_abs_deviation']:.9f} mm, LP optimum "
                    f"{c['lp_optimum']:.9f} mm (gap {c['gap']:.2e} mm).")
    report.script("plotly", get_plotlyjs())
    report.raw(_figure(result, f"compare-{len(report.sections)}"))
    report.text("The CAD model coloured by the mean deviation of the points nearest to each vertex's triangles (grey: no "
                "point); the scan's points are in the legend; diamonds mark each face's largest deviation.")
    report.figure(_histogram(result), "deviation-histogram", "Histogram of the deviations")
    rows = [[f["id"], f["name"] or "-", f["kind"], f["n"]] + ([f["min"], f["max"], f["mean"], f["rms"]] if f["n"] else ["-"] * 4)
            for f in d["faces"]]
    report.table(["face", "name", "surface", "points", "min (mm)", "max (mm)", "mean (mm)", "rms (mm)"], rows, "Per CAD face")
    cs = callouts(result)
    report.table(["face", "deviation (mm)", "x", "y", "z", "point #"],
                 [[c["face"], c["deviation"], *c["point"], c["index"]] for c in cs], "Callouts: the largest deviation of each face")


def write_report(result, out: Path) -> Path:
    """Write ``report.html`` and ``result.json`` into ``out`` (atomically); return the page."""
    from .._files import atomic_dir, write_text
    from .._util import dumps
    from .html import Report

    out = Path(out)
    with atomic_dir(out) as tmp:
        write_text(tmp / "result.json", dumps(result))
        rep = Report("Scan against CAD", "Signed deviations from the CAD surface; every number was computed by this run.")
        add_compare(rep, result)
        name = rep.write(tmp).name
    return out / name
