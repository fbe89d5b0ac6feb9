"""`gagekit inspect`: a scan against its drawing -- GD&T callouts with datum frames.

``gagekit inspect SCAN PART.toml`` (short for ``gagekit inspect scan SCAN PART.toml``)
inspects one scan; ``gagekit inspect batch PART.toml SCAN...`` many (:mod:`.batch`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Optional

import typer
from typer.core import TyperGroup

from ._common import CHUNK_OPTION, JSON_OPTION, MEMORY_OPTION, UNITS_OPTION, emit, open_scan_cli, seed_option, table
from ._uncertainty import (MEASUREMENT_OPTION, NOISE_OPTION, RULE_OPTION, THREADS_OPTION, UNCERTAINTY_OPTION, rule_of,
                           uncertainty_settings)
from .qif import INSTRUMENT_OPTION, QIF_RESULTS_OPTION, check_output, write_results


class DefaultScanGroup(TyperGroup):
    """``inspect``'s sub-commands, where a first argument that names none of them (a scan
    file) is the single-scan command's: ``inspect SCAN PART`` = ``inspect scan SCAN PART``."""

    default_command = "scan"

    def parse_args(self, ctx: Any, args: list) -> list:
        if args and args[0] not in self.commands and args[0] not in ("--help", "-h"):
            args = [self.default_command, *args]
        return super().parse_args(ctx, args)


app = typer.Typer(cls=DefaultScanGroup, no_args_is_help=True,
                  help="GD&T inspection against the drawing (ISO 1101, ISO 5459): `inspect SCAN PART.toml` for one "
                       "scan, `inspect batch PART.toml SCAN...` for many.")


def human(result) -> str:
    from ..report.inspect import callout_rows

    mc = result.monte_carlo is not None
    rows = []
    for r, t in zip(callout_rows(result), result.tolerances):
        d = t.to_dict()
        row = [r[0], r[1], r[2], r[3], r[4], f"{r[5]:.4f}", f"{r[6]:.6f}", f"{r[7]:+.6f}", r[8]]
        if mc:
            u = d["uncertainty"]
            row += [f"{u['U']:.6f}", f"{u['bias']:+.6f}"]
        rows.append(row + [d["decision"]])
    head = ["#", "feature", "characteristic", "datums", "zone", "tolerance", "measured", "margin", "result"]
    head += ["U (95 %)", "MC bias"] if mc else []
    text = table(head + ["decision"], rows)
    lines = [text, "", f"{result.part}: {result.status} ({sum(t.passed for t in result.tolerances)}/{len(result.tolerances)} "
             f"callouts pass); decision {result.decision}",
             f"decision rule: {result.rule.label} -- {result.rule.describe()}"]
    if mc:
        s = result.monte_carlo
        lines.append(f"uncertainty: {s['method']}, {s['trials']} trials, seed {s['seed']}, {s['stopping']}"
                     f"{'' if s['stabilized'] else ' (not stabilized to one significant digit of u)'}; "
                     f"noise sigma {s['model']['sigma']:.6g} mm" + (f" ({s['model']['sigma_source']})" if 'sigma_source' in s['model'] else ""))
    return "\n".join(lines)


def inspect(
    scan: Path = typer.Argument(..., help="Scanned cloud: XYZ/CSV/TXT, NIST .ds, PLY, .npy, LAS/LAZ, E57."),
    part: Path = typer.Argument(..., help="The drawing (TOML): [[feature]], [datums], [[tolerance]]."),
    units: Optional[str] = UNITS_OPTION,
    as_json: bool = JSON_OPTION,
    report: Optional[Path] = typer.Option(None, "--report", help="Write report.html (callouts, datum frame, 3-D deviation view) and result.json into DIR."),
    memory: Optional[str] = MEMORY_OPTION,
    chunk: Optional[int] = CHUNK_OPTION,
    qif_results: Optional[Path] = QIF_RESULTS_OPTION,
    instrument: str = INSTRUMENT_OPTION,
    uncertainty: Optional[str] = UNCERTAINTY_OPTION,
    noise: Optional[str] = NOISE_OPTION,
    measurement: Optional[Path] = MEASUREMENT_OPTION,
    decision_rule: Optional[str] = RULE_OPTION,
    seed: int = seed_option(help="Seed of the Monte Carlo trials (--uncertainty)"),
    threads: Optional[int] = THREADS_OPTION,
) -> None:
    """Evaluate every GD&T callout of PART.toml on the scan (ISO 1101 zones, ISO 5459 datums);
    with --uncertainty, each callout's JCGM 101 uncertainty and ISO 14253-1 decision.

    Exit status 0 whether or not the part conforms (read `status` and `decision`); 2 on errors.
    """
    from ..inspect import inspect as run_inspect, load_part_spec

    from ..cloud.stream import CloudStream
    from ..inspect import inspect_stream

    check_output(qif_results)
    mc = uncertainty_settings(uncertainty, noise, measurement)
    rule = rule_of(decision_rule, mc is not None)
    spec = load_part_spec(part)
    # a drawing with a CAD model matches the whole scan to it: read whole
    cloud = open_scan_cli(scan, units, memory, chunk, whole=getattr(spec, "cad", None) is not None)
    streamed = isinstance(cloud, CloudStream)
    if mc is not None:
        from ..uncertainty import inspect_uncertainty

        result = inspect_uncertainty(cloud if streamed else cloud.points, spec, mc[1], mc[0], seed=seed, threads=threads,
                                     rule=rule, stream=streamed)
    else:
        from ..uncertainty import decide_inspection

        result = decide_inspection(inspect_stream(cloud, spec) if streamed else run_inspect(cloud.points, spec), rule)
    if report is not None:
        from ..report.inspect import write_report

        write_report(result, report)
    if qif_results is not None:
        from .._util import check_finite_result, to_jsonable

        check_finite_result(result)
        write_results(qif_results, [{"scan": str(scan), "result": to_jsonable(result)}], spec, part, instrument)
    emit(result, as_json, human)
