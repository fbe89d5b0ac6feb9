"""`gagekit cloud`: read point clouds, report their extent, filter them by convex hull."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Optional

import numpy as np
import typer

from ..cloud import convex_hull_indices, load_regions, write_points
from ._common import CHUNK_OPTION, JSON_OPTION, MEMORY_OPTION, UNITS_OPTION, emit, open_scan_cli, read_cloud_cli, table

app = typer.Typer(help="Point clouds: information, convex-hull filter.", no_args_is_help=True)


@app.command("info")
def info(
    file: Path = typer.Argument(..., help="Point cloud: XYZ/CSV/TXT, NIST .ds, PLY, .npy, LAS/LAZ, E57."),
    units: Optional[str] = UNITS_OPTION,
    as_json: bool = JSON_OPTION,
) -> None:
    """Number of points, their bounding box (mm), the file's unit and the conversion applied."""
    cloud = read_cloud_cli(file, units)
    pts = cloud.points
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    result = {
        **cloud.to_dict(),
        "min": lo.tolist(),
        "max": hi.tolist(),
        "size": (hi - lo).tolist(),
        "centroid": pts.mean(axis=0).tolist(),
    }

    def human(r: dict) -> str:
        rows = [[ax, r["min"][i], r["max"][i], r["size"][i]] for i, ax in enumerate("xyz")]
        conv = f"x {r['scale_to_mm']:g}" + (f" (z x {r['z_scale_to_mm']:g})" if r["z_scale_to_mm"] != r["scale_to_mm"] else "")
        lines = [
            f"{r['file']}: {r['count']} points ({r['format']}" + (f", {r['scans']} scans" if r["scans"] != 1 else "") + ")",
            f"unit: {r['source_unit']} ({r['unit_basis']}), converted to mm {conv}",
        ]
        if r["invalid_dropped"]:
            lines.append(f"invalid points dropped: {r['invalid_dropped']}")
        return "\n".join(lines) + "\n" + table(["axis", "min (mm)", "max (mm)", "size (mm)"], rows)

    emit(result, as_json, human)


@app.command("hull")
def hull(
    file: Path = typer.Argument(..., help="Point cloud file."),
    out: Optional[Path] = typer.Option(None, "--out", help="Write the hull vertices (mm) to this file (.ply, .csv, .xyz, .npy)."),
    units: Optional[str] = UNITS_OPTION,
    as_json: bool = JSON_OPTION,
    memory: Optional[str] = MEMORY_OPTION,
    chunk: Optional[int] = CHUNK_OPTION,
) -> None:
    """Keep only the vertices of the convex hull (Eq. 5.21): the points an LP over the cloud needs.

    A scan larger than --memory allows is streamed: each chunk hull-filtered, then the hull
    of the kept vertices (the same vertices as a whole read)."""
    from .._files import output_file
    from ..cloud.stream import CloudStream
    from ..cloud.streamed import hull_stream

    if out is not None:
        output_file(out)
    scan = open_scan_cli(file, units, memory, chunk)
    t0 = time.perf_counter()
    if isinstance(scan, CloudStream):
        count, idx, vertices = hull_stream(scan)
    else:
        pts = scan.points
        idx = convex_hull_indices(pts)
        count, vertices = len(pts), pts[idx]
    seconds = time.perf_counter() - t0
    if out is not None:
        write_points(out, vertices)
    result = {
        "file": str(file),
        "count": int(count),
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
    units: Optional[str] = UNITS_OPTION,
    as_json: bool = JSON_OPTION,
    memory: Optional[str] = MEMORY_OPTION,
    chunk: Optional[int] = CHUNK_OPTION,
) -> None:
    """Cut a cloud into its regions and hull-filter each one (Sec. 5.4.1); with an [alignment], part-frame regions after the 3-2-1 alignment, as `gage check` cuts them.

    A scan larger than --memory allows is streamed: only the points inside the regions
    are kept, hull-filtered chunk by chunk (the same vertices as a whole read); with an
    [alignment], a first pass over the datum regions."""
    from .._util import load_toml
    from ..cloud.stream import CloudStream
    from ..cloud.workflow import cut_and_filter, cut_and_filter_stream
    from ..gage.analysis import region_boxes, region_boxes_stream
    from ..gage.spec import parse_region_spec

    doc = load_toml(regions_toml, "regions")
    aligned = isinstance(doc, dict) and "alignment" in doc
    spec = parse_region_spec(doc, str(regions_toml)) if aligned else None
    boxes = None if aligned else load_regions(regions_toml)
    scan = open_scan_cli(file, units, memory, chunk)
    if isinstance(scan, CloudStream):
        boxes = region_boxes_stream(scan, spec) if aligned else boxes
        result = cut_and_filter_stream(scan, boxes)
    else:
        boxes = region_boxes(scan.points, spec) if aligned else boxes
        result = cut_and_filter(scan.points, boxes)

    def human(res) -> str:
        r = res.to_dict()
        rows = [[g["name"], g["points"], g["hull_vertices"], f"{g['reduction']:.1f}x"] for g in r["regions"]]
        return f"{r['points']} points, {len(rows)} regions\n" + table(["region", "points", "hull vertices", "reduction"], rows)

    emit(result, as_json, human)
