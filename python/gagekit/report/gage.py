"""Report section, figures and report files of a virtual-gage analysis (Tables 5.3-5.4,
Figs. 5.16-5.19)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Union

import numpy as np

from .._util import dumps
from ..gage.analysis import GageCheckResult
from ..gage.summary import gage_table, human, summary_lines

__all__ = ["region_figure", "add_to_report", "write_report"]


def _view_axes(normals: list[np.ndarray], pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal (in-plane, largest spread) and vertical (the first gage normal) axes."""
    n = normals[0]
    c = pts - pts.mean(axis=0)
    c = c - np.outer(c @ n, n)
    _, _, vt = np.linalg.svd(c, full_matrices=False)
    h = vt[0] - (vt[0] @ n) * n
    return h / np.linalg.norm(h), n


def region_figure(result: GageCheckResult, region: str):
    """Side view of a region's points before and after T* with its gage planes
    (Figs. 5.16-5.19); returns a matplotlib Figure (Agg backend)."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    data = result.plot_data or {}
    pts = data["regions"][region]
    spec = data["spec"]
    gages = [g for g in spec.gages if g.region == region]
    normals = [np.asarray(g.plane[:3]) for g in gages]
    after = result.transform.apply(pts)
    h, v = _view_axes(normals, pts)
    fig = Figure(figsize=(10, 4.2), dpi=100)
    axes = fig.subplots(1, 2, sharey=True)
    both = np.vstack([pts, after])
    hu = both @ h
    span = (float(hu.min()), float(hu.max()))
    for ax, p, title in ((axes[0], pts, "before T*"), (axes[1], after, "after T*")):
        ax.scatter(p @ h, p @ v, s=1.5, c="#2a5d9f", alpha=0.5, linewidths=0, label="points")
        for g, col in zip(gages, ("#b3261e", "#17723a", "#8e44ad", "#d35400")):
            a = np.asarray(g.plane[:3])
            # the plane a.r + d = 0 in the view plane: r = s h + t v + c, c the region centroid
            c0 = p.mean(axis=0)
            c0 = c0 - (c0 @ h) * h - (c0 @ v) * v
            s = np.linspace(*span, 2)
            av, ah, ac = a @ v, a @ h, a @ c0 + g.plane[3]
            if abs(av) > 1e-9:
                side = "above" if av > 0 else "below"
                ax.plot(s, -(ah * s + ac) / av, color=col, lw=1.2, label=f"{g.name} (material {side})")
        ax.set_title(f"{region}: {title}")
        ax.set_xlabel("along the face (mm)")
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("along the gage normal (mm)")
    axes[1].legend(loc="best", fontsize=8, markerscale=4)
    fig.tight_layout()
    return fig


def add_to_report(rep, result: GageCheckResult, label: str = "") -> list[str]:
    """Add the summary, the allowance table and the region pictures of ``result``
    to a :class:`gagekit.report.Report` (for ``--report`` and the demo); returns
    the PNG file names the report will write."""
    prefix = f"{label}: " if label else ""
    rep.section(f"{prefix}virtual gage result")
    for line in summary_lines(result):
        rep.text(line, "ok" if line == "status: conforming" else ("bad" if line.startswith(("status", "zero margin"))
                                                                  else None))
    headers, rows = gage_table(result)
    rep.table(headers, rows, "Allowances (mm): smallest signed distance to each gage plane; q the largest; "
              "slack the release s_i (Tables 5.3-5.4)")
    names = []
    if result.plot_data:
        rep.section(f"{prefix}regions before and after T*")
        for region in result.plot_data["regions"]:
            name = f"{label}-region-{region}" if label else f"region-{region}"
            rep.figure(region_figure(result, region), name,
                       f"{region}: points and gage planes before and after T*")
            names.append(re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-") + ".png")
    return names


def write_report(result: GageCheckResult, out: Union[str, Path]) -> list[Path]:
    """Write into ``out``: ``result.json``, ``report.txt`` (the tables), ``report.html``
    and one PNG per region (``region-<name>.png``, before and after T*); returns the paths.

    The folder is built under a temporary name and renamed into place at the end
    (:func:`gagekit._files.atomic_dir`), so an interrupted run leaves the old folder or none."""
    from .._files import atomic_dir, write_text
    from . import Report

    out = Path(out)
    with atomic_dir(out) as tmp:
        names = [write_text(tmp / "result.json", dumps(result)).name,
                 write_text(tmp / "report.txt", human(result) + "\n").name]
        rep = Report("Virtual gage analysis", "Allowances before and after the correction T* (Eq. 5.11); "
                     "every number was computed by this run.")
        names += add_to_report(rep, result)
        names.append(rep.write(tmp).name)
    return [out / n for n in names]
