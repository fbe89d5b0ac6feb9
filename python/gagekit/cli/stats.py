"""`gagekit stats`: statistical process control of the results database."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from ._common import JSON_OPTION, emit, table


def _human(s: dict) -> str:
    from ..stats.collect import messages

    res = s["resolution"]
    out = [f"SPC of {s['database']} (resolution {res['mm']:g} mm, {res['rad']:g} rad: values within it of a limit are on "
           f"the limit; capability from {s['min_values_for_capability']} values, trends from {s['min_trend_days']:g} day)"]
    if "measurement" in s:
        m = s["measurement"]
        out.append(f"measurement standard uncertainty u = {m['u']:g} mm (k = 1) on {m['applies_to']}: {m['model']}; "
                   "Cpk/Ppk in the table are observed, the process indices follow each table")
    for spec in s["specs"]:
        label = spec.get("part") or spec.get("source") or spec["spec"]
        out.append(f"\n{spec['kind']} {label} ({spec['spec']}): {spec['results']} results, {spec['failed']} failed")
        rows = []
        for c in spec["characteristics"]:
            g = lambda k: c.get(k, "-")  # noqa: E731
            rows.append([c["name"], c["n"], c["mean"], g("sd"), g("min_margin"), g("cpk"), g("ppk"),
                         len(c.get("chart", {}).get("signals", []))])
        if rows:
            out.append(table(["characteristic", "n", "mean", "sd", "min margin", "Cpk", "Ppk", "signals"], rows))
            out += [f"  {kind}: {line}" for c in spec["characteristics"] for kind, line in messages(c)]
    for mach in s["machines"]:
        out.append(f"\nmachine {mach['machine']}: {mach['calibrations']} tracking runs, "
                   f"{mach['identifications']} identifications; largest drifts:")
        out.append(table(["group", "first", "last", "largest change"],
                         [[g["name"], g["first"], g["last"], g["max_change"]] for g in mach["groups"][:8]]))
    return "\n".join(out)


def stats(
    ctx: typer.Context,
    db: Optional[str] = typer.Option(None, "--db", help="Results database: sqlite:///FILE or postgresql://..."),
    spec: Optional[Path] = typer.Option(None, "--spec", help="Only the results of this gage file or drawing (GAGES.toml or PART.toml)."),
    tolerance: Optional[float] = typer.Option(None, "--tolerance", help="Upper limit of form errors (mm, > 0), for Cp/Cpk of form batches."),
    resolution: float = typer.Option(1e-9, "--resolution", help="Resolution of lengths (mm; angles: this / 1000 rad). "
                                                                 "Values within it of a limit are on the limit; no "
                                                                 "capability without variation above it."),
    measurement_u: Optional[float] = typer.Option(
        None, "--measurement-uncertainty", metavar="U",
        help="Standard uncertainty (k = 1, mm) of a measured length: capability also with the measurement variance "
             "removed (ISO 22514-7: observed = process + measurement), beside the observed indices."),
    report: Optional[Path] = typer.Option(None, "--report", help="Write report.html with the charts into DIR."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Per gage or tolerance: n, mean, sd, minimum margin, Cp/Cpk and Pp/Ppk, I-MR charts with
    the Western Electric rules, trends of the allowances and T*; per machine: drift across calibrations.
    `gagekit stats grr`: gage R&R and Type-1 studies."""
    if ctx.invoked_subcommand is not None:  # `gagekit stats grr ...`
        return
    if db is None:
        from ..errors import ConfigError

        raise ConfigError("stats: missing option --db URL (the results database); `gagekit stats grr` for gage R&R")
    from .._util import load_toml
    from ..stats import collect

    from ..errors import ConfigError

    if report is not None:
        from .._files import output_dir

        output_dir(report)  # checked before the work
    documents = None
    if spec is not None:
        doc = load_toml(spec)
        documents = [{"spec": doc}, {"part": doc}]
    s = collect(db, documents=documents, tolerance=tolerance, resolution=resolution, measurement_u=measurement_u)
    if spec is not None and not s["specs"]:
        raise ConfigError(f"{spec}: no results of this spec in {s['database']}")
    if report is not None:
        from ..report.spc import write_spc_report

        write_spc_report(s, report)
    emit(s, as_json, _human)
