"""`gagekit cloud`: read point clouds, report their extent, filter them by convex hull."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Optional

import numpy as np
import typer

from ..cloud import convex_hull_indices, load_regions, read_points, write_points
from ._common import JSON_OPTION, emit, table

app = typer.Typer(help="Point clouds: information, convex-hull filter.", no_args_is_help=True)


@app.command("info")
def info(
    file: Path = typer.Argument(..., help="Point cloud: XYZ/CSV/TXT, NIST .ds, PLY, .npy, LAS/LAZ, E57."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Number of points and their bounding box."""
    pts = read_points(file)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    result = {
        "file": str(file),
        "count": int(len(pts)),
        "min": lo.tolist(),
        "max": hi.tolist(),
        "size": (hi - lo).tolist(),
        "centroid": pts.mean(axis=0).tolist(),
    }

    def human(r: dict) -> str:
        rows = [[ax, r["min"][i], r["max"][i], r["size"][i]] for i, ax in enumerate("xyz")]
        return f"{r['file']}: {r['count']} points\n" + table(["axis", "min (mm)", "max (mm)", "size (mm)"], rows)

    emit(result, as_json, human)


@app.command("hull")
def hull(
    file: Path = typer.Argument(..., help="Point cloud file."),
    out: Optional[Path] = typer.Option(None, "--out", help="Write the hull vertices to this file (.ply, .csv, .xyz, .npy)."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Keep only the vertices of the convex hull (Eq. 5.21): the points an LP over the cloud needs."""
    from .._files import output_file

    if out is not None:
        output_file(out)
    pts = read_points(file)
    t0 = time.perf_counter()
    idx = convex_hull_indices(pts)
    seconds = time.perf_counter() - t0
    if out is not None:
        write_points(out, pts[idx])
    result = {
        "file": str(file),
        "count": int(len(pts)),
        "hull_vertices": int(len(idx)),
        "seconds": seconds,
        "indices": idx.tolist(),
        "out": str(out) if out is not None else None,
    }

    def human(r: dict) -> str:
        line = f"{r['file']}: {r['count']} points -> {r['hull_vertices']} hull vertices ({r['seconds'] * 1e3:.1f} ms)"
        return line + (f"\nwritten to {r['out']}" if r["out"] else "")

    emit(result, as_json, human)


@app.command("regions")
def regions(
    file: Path = typer.Argument(..., help="Point cloud file."),
    regions_toml: Path = typer.Argument(..., help="TOML file with [[region]] tables (a gage file works)."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Cut a cloud into its regions and hull-filter each one (Sec. 5.4.1)."""
    from ..cloud.workflow import cut_and_filter

    result = cut_and_filter(read_points(file), load_regions(regions_toml))

    def human(res) -> str:
        r = res.to_dict()
        rows = [[g["name"], g["points"], g["hull_vertices"], f"{g['reduction']:.1f}x"] for g in r["regions"]]
        return f"{r['points']} points, {len(rows)} regions\n" + table(["region", "points", "hull vertices", "reduction"], rows)

    emit(result, as_json, human)
