"""`gagekit machine export | compensate-nc`: from a calibration to the controller (Sec. 7.1.1 (3)).

Registered on the ``machine`` sub-application by :func:`register`, called in ``cli/__init__.py``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from ..errors import InvalidInputError
from ._common import JSON_OPTION, emit, number_option as _number, parse_assignments, seed_option
from .machine import MACHINE_ARG, _warnings_to_stderr

CAL_ARG = typer.Argument(..., help="Calibration JSON from identify --out.")


def _per_axis_option(text: Optional[str], what: str):
    """'50' (every axis) or 'X=50,B=5'."""
    if text is None:
        return None
    if "=" not in text:
        return _number(text, what)
    return {k: _number(v, f"{what} {k}") for k, v in parse_assignments(text, what).items()}


def _limits(text: Optional[str]) -> dict:
    out = {}
    for k, v in parse_assignments(text, "--limits").items():
        if ":" not in v:
            raise InvalidInputError(f"--limits {k}: expected LO:HI, got '{v}'")
        lo, hi = v.split(":", 1)
        out[k] = (_number(lo, f"--limits {k}"), _number(hi, f"--limits {k}"))
    return out


def export_cmd(
    machine_file: Path = MACHINE_ARG,
    calibration: Path = CAL_ARG,
    fmt: str = typer.Option(
        ..., "--format", help="grid-csv, isg-csv (ISG/Beckhoff TF5280), fanuc-3d, linuxcnc, or kinematics (rotary-axis "
        "location corrections: LinuxCNC trtkins, Heidenhain kinematics rows, Siemens TRAFO5; OUT_linuxcnc.hal ...)."
    ),
    out: Path = typer.Option(..., "--out", help="File to write (linuxcnc: one file per axis, OUT_<joint>.ext)."),
    axes: Optional[str] = typer.Option(None, "--axes", help="Grid joints, e.g. X,Y,Z (default depends on the format)."),
    step: Optional[str] = typer.Option(None, "--step", help="Node spacing: one value (file units) or X=50,B=5 (default 50 mm, 5 deg)."),
    points: Optional[str] = typer.Option(None, "--points", help="Nodes per axis: one value or X=51,Y=44 (instead of --step)."),
    at: Optional[str] = typer.Option(None, "--at", help="Fixed values of the other joints, e.g. B=0,W=-500 (default 0 or mid-range)."),
    limits: Optional[str] = typer.Option(None, "--limits", help="Grid extent inside the joint ranges, e.g. X=-1000:1000."),
    increment: float = typer.Option(0.001, "--increment", help="fanuc-3d: detection unit, mm (0.001 IS-B, 0.0001 IS-C)."),
    seed: int = seed_option(help="Seed of the random commands of the read-back check."),
    uncertainty: bool = typer.Option(
        False, "--uncertainty", help="Also write each entry's standard uncertainty from the calibration's covariance "
        "(GUM 5.1.2): grid-csv columns uc<joint>; the other formats a companion CSV OUT_u.csv beside the table."
    ),
    as_json: bool = JSON_OPTION,
) -> None:
    """Write a compensation table for a controller and read it back as the controller interpolates it."""
    from ..machine import load_calibration, load_machine
    from ..machine.export import export

    m = load_machine(machine_file)
    cal = load_calibration(calibration)
    ax = [a.strip() for a in axes.split(",") if a.strip()] if axes else None
    fixed = {k: _number(v, f"--at {k}") for k, v in parse_assignments(at, "--at").items()}
    if fmt == "kinematics":
        from .machine_instruments import export_kinematics_cmd

        return export_kinematics_cmd(m, cal, out, fixed, calibration_stamp(calibration, cal), as_json, uncertainty)
    with _warnings_to_stderr():
        res = export(
            m, cal, fmt, out, axes=ax, step=_per_axis_option(step, "--step"), points=_per_axis_option(points, "--points"),
            at=fixed, limits=_limits(limits), increment=increment, stamp=calibration_stamp(calibration, cal), seed=seed,
            uncertainty=uncertainty,
        )

    def human(r) -> str:
        rb = r.readback
        g = r.grid
        text = (
            f"wrote {r.format} ({' x '.join(str(n) for n in g.shape)} nodes over {', '.join(g.axes)}) to "
            f"{', '.join(r.files)}\nread back at {rb['n']} random commands: {rb['quantity']} within "
            f"{rb['max_um']:.3g} um (RMS {rb['rms_um']:.3g} um)"
        )
        if r.uncertainty is not None:
            u = r.uncertainty
            text += (f"\nstandard uncertainty (k = 1) of the {u['quantity']} in {u['file']} ({u['columns']}): "
                     f"up to {1e3 * u['max_mm']:.3g} um" + (f", {u['max_rad']:.3g} rad" if "max_rad" in u else ""))
        return text

    emit(res, as_json, human)


def calibration_stamp(path: Path, cal) -> str:
    """'<date>, file <name>': the calibration's ``created`` field, else the file's date."""
    import datetime
    import json

    created = None
    try:
        created = json.loads(Path(path).read_text(encoding="utf-8")).get("created")
    except (OSError, ValueError, AttributeError):
        pass
    if not isinstance(created, str) or not created:
        ts = Path(path).stat().st_mtime
        created = datetime.datetime.fromtimestamp(ts, datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC") + " (file date)"
    return f"{created}, file {Path(path).name}"


def compensate_nc_cmd(
    machine_file: Path = MACHINE_ARG,
    calibration: Path = CAL_ARG,
    program: Path = typer.Argument(..., help="G-code program (ISO 6983 / RS-274) with the machine's joint letters."),
    out: Path = typer.Option(..., "--out", help="Corrected program to write."),
    axes: Optional[str] = typer.Option(None, "--axes", help="Joints that compensate (default: the first prismatic joint along x, y and z; a redundant axis such as W only when named)."),
    max_step: float = typer.Option(0.001, "--max-step", help="Subdivide G1 moves whose correction changes by more than this, mm."),
    linearize_arcs: Optional[float] = typer.Option(None, "--linearize-arcs", help="Turn G2/G3 into chords within TOL mm (default: arcs are errors)."),
    start: Optional[str] = typer.Option(None, "--start", help="Joint positions before the program, e.g. B=0,W=-500."),
    decimals: int = typer.Option(4, "--decimals", help="Decimals of the written coordinates."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Correct an NC program point by point through the inverse error model (arcs, cycles, macros: errors)."""
    from ..machine import load_calibration, load_machine
    from ..machine.nc import compensate_nc

    m = load_machine(machine_file)
    cal = load_calibration(calibration)
    ax = [a.strip() for a in axes.split(",") if a.strip()] if axes else None
    st = {k: _number(v, f"--start {k}") for k, v in parse_assignments(start, "--start").items()}
    res = compensate_nc(
        m, cal, program, out, axes=ax, max_step=max_step, linearize_arcs=linearize_arcs, start=st,
        decimals=decimals, stamp=calibration_stamp(calibration, cal),
    )
    emit(
        res,
        as_json,
        lambda r: (
            f"wrote {r.out}: {r.lines_written} lines ({r.lines} read), axes {', '.join(r.axes)} corrected in {r.moves} moves "
            f"(largest correction {r.max_correction:.4f} mm), {r.inserted} points inserted in {r.subdivided} moves; "
            f"predicted error left <= {r.max_remaining_um:.2g} um"
        ),
    )


#: (command name, function) of this module, in help order.
COMMANDS = (
    ("export", export_cmd),
    ("compensate-nc", compensate_nc_cmd),
)


def register(app: typer.Typer) -> None:
    """Add this module's commands to the ``machine`` sub-application ``app``."""
    for name, fn in COMMANDS:
        app.command(name)(fn)


def iso230_2_cmd(
    runs: Path = typer.Argument(..., help="Laser-interferometer runs CSV: target,direction,cycle,measured (mm; direction + or -)."),
    report: Optional[Path] = typer.Option(None, "--report", help="Directory for report.html with the standard's plot."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Accuracy and repeatability of positioning of an axis, ISO 230-2:2014."""
    from ..machine.iso230_2 import iso230_2, read_runs
    from ..report.text import table

    from .._files import atomic_dir, output_dir

    if report is not None:
        output_dir(report)
    res = iso230_2(*read_runs(runs))
    if report is not None:
        from ..report import Report
        from ..report.iso230_2 import add_iso230_2

        rep = Report(f"ISO 230-2 positioning: {runs.name}", f"{len(res.targets)} targets, {res.cycles} cycles per direction")
        add_iso230_2(rep, res)
        with atomic_dir(report) as tmp:
            rep.write(tmp)

    def human(r) -> str:
        keys = ("A", "A_up", "A_down", "E", "E_up", "E_down", "M", "R", "R_up", "R_down", "B", "B_mean")
        from ..report.text import fixed

        # every um value to 0.001 um, printed with three decimals (the targets in mm)
        rows = [[t.target] + [fixed(1e3 * v, 3) for v in (t.mean_up, t.mean_down, t.s_up, t.s_down, t.R, t.B)]
                for t in r.targets]
        return "\n".join([
            f"ISO 230-2:2014, {len(r.targets)} targets, {r.cycles} cycles per direction (um)",
            "  ".join(f"{k} {fixed(1e3 * getattr(r, k), 3)}" for k in keys),
            "",
            table(["target (mm)", "mean up", "mean down", "s up", "s down", "R", "B"], rows),
        ])

    emit(res, as_json, human)


COMMANDS = COMMANDS + (("iso230-2", iso230_2_cmd),)
