"""`gagekit gage batch`, `gagekit form batch`, `gagekit inspect batch`: many scans, local
workers or a Dask cluster.

Registered on the ``gage``, ``form`` and ``inspect`` groups by :mod:`gagekit.cli`. Each scan's result is
exactly what the single-scan command prints with ``--json``; results go to the results
database (``--db``, default ``gagekit.db`` beside the ``--report`` folder, else in the
current one), and a batch run again skips what is stored there.

``--json`` prints one line per scan, ``{"scan": PATH, "status": "ok" | "error" | "skipped",
"result": {...}}`` or ``{"scan": PATH, "status": "error", "error": MESSAGE}``, then
``{"summary": {"scans": N, "ok": .., "failed": .., "skipped": ..}}``. Exit status 0 when
the batch ran (even with failed scans), 2 when it could not.
"""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path
from typing import Callable, List, Optional

import typer

from ._common import UNITS_OPTION, seed_option, warn
from ._uncertainty import MEASUREMENT_OPTION, NOISE_OPTION, RULE_OPTION, UNCERTAINTY_OPTION, batch_options
from .qif import INSTRUMENT_OPTION, QIF_RESULTS_OPTION, check_output, write_results

BATCH_THREADS_OPTION = typer.Option(
    None, "--threads", min=1, max=1024,
    help="Threads for each scan's Monte Carlo trials (default 1: the workers run in parallel); the result does not "
         "depend on it.")

SCANS_ARG = typer.Argument(..., help="Scan files, folders (searched for scan files) or glob patterns ('scans/*.ply').")
WORKERS_OPTION = typer.Option(None, "--workers", "-w", help="Local worker processes (default: one per core).")
SCHEDULER_OPTION = typer.Option(None, "--scheduler", help="Run on a Dask cluster: the scheduler's address, tcp://host:8786.")
DB_OPTION = typer.Option(None, "--db", help="Results database: sqlite:///FILE (default gagekit.db beside the --report folder, else here) or postgresql://...")
REPORT_OPTION = typer.Option(None, "--report", help="Write batch.json and an HTML summary into DIR.")
RETRY_OPTION = typer.Option(False, "--retry-failed", help="Evaluate again the scans whose stored result is an error.")
PART_OPTION = typer.Option(None, "--part", help="Part number to file the results under (default: the spec file's name).")
JSON_LINES = typer.Option(False, "--json", help="One JSON line per scan, then a summary line.")


def _db_url(db: Optional[str], report: Optional[Path]) -> str:
    """--db, or gagekit.db beside the report folder (not inside: the folder is replaced
    whole when the report is written again), else in the current folder."""
    if db:
        return db
    folder = Path(report).resolve().parent if report is not None else Path(".")
    return f"sqlite:///{folder / 'gagekit.db'}"


def _executor(workers: Optional[int], scheduler: Optional[str]):
    from ..batch import DaskCluster, LocalPool
    from ..errors import ConfigError

    if workers is not None and scheduler is not None:
        raise ConfigError("give --workers (local processes) or --scheduler (a Dask cluster), not both")
    return DaskCluster(scheduler) if scheduler is not None else LocalPool(workers)


def _units(units: Optional[str]) -> dict:
    """The ``units`` option (checked now: a bad unit stops the batch before it starts)."""
    from ..cloud.units import check_units

    return {} if units is None else {"units": check_units(units)}


def _human_line(ev) -> str:
    if ev.status == "error":
        # the readers' messages begin with the file's path: not twice on the line
        return f"error    {ev.scan}: {ev.error.removeprefix(f'{ev.scan}: ')}"
    what = ""
    if ev.result is not None:
        what = ev.result.get("status") or f"form error {ev.result.get('form_error', float('nan')):.6g} mm"
        tols = ev.result.get("tolerances")
        if isinstance(tols, list):
            what += f" ({sum(bool(t.get('pass')) for t in tols)}/{len(tols)} callouts pass)"
    elif ev.error:
        what = f"stored error: {ev.error}"
    return f"{ev.status:<8} {ev.scan}  {what}".rstrip()


def run(job, scans: List[str], db: Optional[str], report: Optional[Path], workers: Optional[int],
        scheduler: Optional[str], as_json: bool, retry_failed: bool, title: str,
        on_done: Optional[Callable[[list], None]] = None) -> None:
    """Run a batch from the command line (shared by every `... batch` command);
    ``on_done(lines)`` gets every scan's line once the batch has run (--qif-results)."""
    from .. import _progress
    from ..batch import BatchSummary, expand_scans, run_batch
    from ..store import ResultStore

    if report is not None:
        from .._files import output_dir

        output_dir(report)  # checked before the work
    paths = expand_scans(scans)
    store = ResultStore(_db_url(db, report))
    executor = _executor(workers, scheduler)
    summary = BatchSummary()
    lines: list = []
    out: Callable[[str], None] = (lambda s: print(s, flush=True)) if as_json else typer.echo
    try:
        events = run_batch(job, paths, store, executor, retry_failed=retry_failed, summary=summary)
        for ev in _progress.track(events, f"{len(paths)} scans", total=len(paths)):
            line = ev.to_dict()
            lines.append(line)
            out(json.dumps(line, allow_nan=False) if as_json else _human_line(ev))
    except KeyboardInterrupt:
        executor.close()
        store.close()
        print(f"gagekit: error: interrupted after {summary.scans} of {len(paths)} scans; the results stored are kept, "
              "run the same command again to finish", file=sys.stderr)
        raise typer.Exit(130)
    executor.close()
    store.close()
    if report is not None:
        from ..report.batch import write_batch_report

        write_batch_report(report, title, lines, summary)
    if on_done is not None:
        on_done(lines)
    if as_json:
        out(json.dumps({"summary": summary.to_dict()}))
    else:
        s = summary
        out(f"{s.scans} scans: {s.ok} ok, {s.failed} failed, {s.skipped} skipped in {s.seconds:.1f} s "
            f"on {s.executor}; results in {s.database}")


def gage_batch(
    gages: Path = typer.Argument(..., help="Gage file (TOML), as for `gage check`."),
    scans: List[str] = SCANS_ARG,
    units: Optional[str] = UNITS_OPTION,
    workers: Optional[int] = WORKERS_OPTION,
    scheduler: Optional[str] = SCHEDULER_OPTION,
    db: Optional[str] = DB_OPTION,
    report: Optional[Path] = REPORT_OPTION,
    as_json: bool = JSON_LINES,
    no_groups: bool = typer.Option(False, "--no-groups", help="Skip the infeasible-group LPs of Eq. 5.10."),
    retry_failed: bool = RETRY_OPTION,
    part: Optional[str] = PART_OPTION,
    uncertainty: Optional[str] = UNCERTAINTY_OPTION,
    noise: Optional[str] = NOISE_OPTION,
    measurement: Optional[Path] = MEASUREMENT_OPTION,
    decision_rule: Optional[str] = RULE_OPTION,
    seed: int = seed_option(help="Seed of the Monte Carlo trials (--uncertainty)"),
    threads: Optional[int] = BATCH_THREADS_OPTION,
) -> None:
    """Virtual-gage check (Eq. 5.11) of many scans: each result as `gage check --json` prints it
    (with --uncertainty: each allowance's U and ISO 14253-1 decision, per scan, in the database)."""
    from .._util import load_toml
    from ..batch import Job
    from ..gage import GageSpec

    doc = load_toml(gages)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        GageSpec.from_dict(doc, str(gages))  # a bad gage file stops the batch before it starts
    for w in caught:
        warn(w.message)
    options = {"groups": not no_groups, **_units(units),
               **batch_options(uncertainty, noise, measurement, decision_rule, seed, threads)}
    job = Job("gage", {"spec": doc}, options, source=str(gages), part=part or gages.stem)
    run(job, scans, db, report, workers, scheduler, as_json, retry_failed, f"Virtual-gage batch: {gages.name}")


def form_batch(
    shape: str = typer.Argument(..., help="circle, line, plane, sphere, circle3d, cylinder or cone"),
    scans: List[str] = SCANS_ARG,
    criterion: str = typer.Option("least-squares", "--criterion", "-c", help="Fit criterion, as for `form fit`."),
    seed: int = seed_option(help="Seed of the particle swarm (cylinders, 3-D lines)"),
    units: Optional[str] = UNITS_OPTION,
    workers: Optional[int] = WORKERS_OPTION,
    scheduler: Optional[str] = SCHEDULER_OPTION,
    db: Optional[str] = DB_OPTION,
    report: Optional[Path] = REPORT_OPTION,
    as_json: bool = JSON_LINES,
    retry_failed: bool = RETRY_OPTION,
    part: Optional[str] = PART_OPTION,
) -> None:
    """Form fits of many files: each result as `form fit SHAPE FILE -c C --json` prints it."""
    from ..batch import Job
    from ..form.criteria import SHAPE_CRITERIA, criterion_name
    from ..form.files import normalize_shape

    name = normalize_shape(shape)
    criterion_name(criterion, SHAPE_CRITERIA[name], name)  # a bad criterion stops the batch before it starts
    job = Job("form", {"shape": name, "criterion": criterion, "seed": seed}, _units(units), source=None, part=part)
    run(job, scans, db, report, workers, scheduler, as_json, retry_failed, f"Form batch: {name} ({criterion})")


def inspect_batch(
    part: Path = typer.Argument(..., help="The drawing (TOML), as for `gagekit inspect`."),
    scans: List[str] = SCANS_ARG,
    units: Optional[str] = UNITS_OPTION,
    workers: Optional[int] = WORKERS_OPTION,
    scheduler: Optional[str] = SCHEDULER_OPTION,
    db: Optional[str] = DB_OPTION,
    report: Optional[Path] = REPORT_OPTION,
    as_json: bool = JSON_LINES,
    retry_failed: bool = RETRY_OPTION,
    part_name: Optional[str] = PART_OPTION,
    qif_results: Optional[Path] = QIF_RESULTS_OPTION,
    instrument: str = INSTRUMENT_OPTION,
    uncertainty: Optional[str] = UNCERTAINTY_OPTION,
    noise: Optional[str] = NOISE_OPTION,
    measurement: Optional[Path] = MEASUREMENT_OPTION,
    decision_rule: Optional[str] = RULE_OPTION,
    seed: int = seed_option(help="Seed of the Monte Carlo trials (--uncertainty)"),
    threads: Optional[int] = BATCH_THREADS_OPTION,
) -> None:
    """GD&T inspection (ISO 1101 / ISO 5459) of many scans: each result as `gagekit inspect --json` prints it
    (with --uncertainty: each callout's U and ISO 14253-1 decision, per scan, in the database)."""
    from .._util import load_toml
    from ..batch import Job
    from ..inspect import part_spec_from_dict

    check_output(qif_results)
    doc = load_toml(part)
    spec = part_spec_from_dict(doc, str(part))  # a bad drawing stops the batch before it starts
    options = {**_units(units), **batch_options(uncertainty, noise, measurement, decision_rule, seed, threads)}
    job = Job("inspect", {"part": doc}, options, source=str(part), part=part_name or spec.name)

    def qif(lines: list) -> None:  # one MeasurementResults per inspected scan, in the order of the scans
        runs = sorted(({"scan": x["scan"], "result": x["result"]} for x in lines if x.get("result") is not None),
                      key=lambda r: r["scan"])
        if not runs:
            warn(f"no scan was inspected; {qif_results} not written")
            return
        write_results(qif_results, runs, spec, part, instrument)

    run(job, scans, db, report, workers, scheduler, as_json, retry_failed, f"Inspection batch: {part.name}",
        on_done=qif if qif_results is not None else None)
