"""`gagekit gage`: Virtual gages: can a scanned casting be machined to print? (Ch. 5)"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Optional

import typer

from ._common import CHUNK_OPTION, JSON_OPTION, MEMORY_OPTION, UNITS_OPTION, emit, open_scan_cli, seed_option, warn
from ._uncertainty import (MEASUREMENT_OPTION, NOISE_OPTION, RULE_OPTION, THREADS_OPTION, UNCERTAINTY_OPTION, rule_of,
                           uncertainty_settings)
from .qif import INSTRUMENT_OPTION, QIF_RESULTS_OPTION, check_output

app = typer.Typer(help="Virtual gages: can a scanned casting be machined to print? (Ch. 5)", no_args_is_help=True)


@app.command("check")
def check(
    cloud: Path = typer.Argument(..., help="Scanned cloud: XYZ/CSV/TXT, NIST .ds, PLY, .npy, LAS/LAZ, E57."),
    gages: Path = typer.Argument(..., help="Gage file (TOML): [motion], [alignment], [[region]], [[gage]]."),
    as_json: bool = JSON_OPTION,
    report: Optional[Path] = typer.Option(None, "--report", help="Write tables, PNG pictures and an HTML page into DIR."),
    out_cloud: Optional[Path] = typer.Option(None, "--out-cloud", help="Write the cloud in the part frame with T* applied."),
    no_groups: bool = typer.Option(False, "--no-groups", help="Skip the infeasible-group LPs of Eq. 5.10."),
    units: Optional[str] = UNITS_OPTION,
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
    """Find the correction T* of the machining frame (Eq. 5.11) and every gage's allowance;
    with --uncertainty, each allowance's JCGM 101 uncertainty and the ISO 14253-1 decision
    per face and for the part (a face within its guard band of zero is not-proven).

    Exit status 0 whether or not the part conforms; read `status` (conforming /
    nonconforming) and, with --uncertainty or --decision-rule, `decision`. Errors in the
    files: one line on stderr, exit 2.
    """
    from ..cloud import write_points
    from ..gage import GageSpec, check_gages, corrected_cloud
    from ..gage.summary import human
    from ..report.gage import write_report
    from .._files import output_dir, output_file

    if report is not None:
        output_dir(report)
    if out_cloud is not None:
        output_file(out_cloud)
    check_output(qif_results)
    mc = uncertainty_settings(uncertainty, noise, measurement)
    rule = rule_of(decision_rule, mc is not None) if (mc is not None or decision_rule is not None) else None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        spec = GageSpec.load(gages)
    for w in caught:
        warn(w.message)
    from ..cloud.stream import CloudStream
    from ..gage.analysis import check_gages_stream

    # --out-cloud writes every point: the scan is read whole for it
    scan = open_scan_cli(cloud, units, memory, chunk, whole=out_cloud is not None)
    streamed = isinstance(scan, CloudStream)
    pts = None if streamed else scan.points
    if mc is not None:
        from ..gage.uncertainty import check_gages_uncertainty

        result = check_gages_uncertainty(scan if streamed else pts, spec, mc[1], mc[0], seed=seed, threads=threads,
                                         rule=rule, groups=not no_groups, stream=streamed)
    elif streamed:
        result = check_gages_stream(scan, spec, groups=not no_groups)
    else:
        result = check_gages(pts, spec, groups=not no_groups)
    if mc is None and rule is not None:
        from ..gage.uncertainty import decide_gages

        result = decide_gages(result, rule)
    if report is not None:
        write_report(result, report)
    if out_cloud is not None:
        write_points(out_cloud, corrected_cloud(pts, result))
    if qif_results is not None:
        from .._util import check_finite_result, to_jsonable
        from ..qif.results import write_gage_results

        check_finite_result(result)
        write_gage_results(qif_results, cloud, to_jsonable(result), instrument)
    emit(result, as_json, human)
