"""`gagekit form roundness | straightness | flatness`: filtered form parameters, as a
roundness instrument prints them (ISO 12181, ISO 12780, ISO 12781; ISO 16610-21 filters).

Registered on the ``form`` sub-application by :func:`register`, called in ``cli/__init__.py``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

import typer

from ._common import JSON_OPTION, UNITS_OPTION, emit, table


def _positive(value: Optional[float]) -> Optional[float]:
    if value is not None and not (math.isfinite(value) and value > 0):
        raise typer.BadParameter(f"must be a positive number, got {value}")
    return value


def _um(v: float) -> str:
    return f"{1e3 * v:.4f}"


def _params_table(params: dict) -> str:
    return table(["parameter", "value (um)"], [[k, _um(v)] for k, v in params.items()])


def roundness_cmd(
    file: Path = typer.Argument(..., help="Profile points x,y (mm; any file read_points reads; 3-D with one constant coordinate)."),
    filter: str = typer.Option("gaussian", "--filter", help="gaussian (ISO 16610-21) or none."),
    upr: float = typer.Option(50.0, "--upr", help="Cut-off, undulations per revolution (ISO 12181-2: 15, 50, 150, 500, 1500)."),
    reference: str = typer.Option("LSCI", "--reference", help="Reference circle: LSCI (least squares), MZCI (minimum zone), "
                                                              "MCCI (min circumscribed), MICI (max inscribed)."),
    samples: Optional[int] = typer.Option(None, "--samples", min=8, help="Resample at this many equal angles (default 3600, "
                                                                         "or 7 UPR rounded up to a multiple of 360)."),
    max_gap: Optional[float] = typer.Option(None, "--max-gap", callback=_positive,
                                            help="Widest gap bridged by interpolation, degrees (default 720/(7 UPR)).",),
    harmonics: Optional[int] = typer.Option(None, "--harmonics", min=1, help="Harmonics in the spectrum (default 500)."),
    report: Optional[Path] = typer.Option(None, "--report", help="Directory for report.html: polar plot and spectrum."),
    units: Optional[str] = UNITS_OPTION,
    as_json: bool = JSON_OPTION,
) -> None:
    """Roundness parameters RONt, RONp, RONv, RONq (ISO 12181-1) of a scanned section, filtered
    with the Gaussian filter of --upr (or --filter none), against the --reference circle;
    eccentricity and the harmonic spectrum."""
    from .._files import atomic_dir, output_dir
    from ..form.files import read_xy
    from ..form.parameters import roundness_parameters

    if report is not None:
        output_dir(report)
    res = roundness_parameters(read_xy(file, units), filter, upr, reference, samples=samples, max_gap_deg=max_gap,
                               harmonics=harmonics)
    if report is not None:
        from ..report import Report
        from ..report.roundness import add_roundness

        rep = Report(f"Roundness: {file.name}", "ISO 12181-1 parameters, ISO 16610-21 filter")
        add_roundness(rep, res, file.name)
        with atomic_dir(report) as tmp:
            rep.write(tmp)

    def human(r) -> str:
        f = r.filter
        filt = "unfiltered" if f["type"] == "none" else f"Gaussian filter {f['upr']:g} UPR (ISO 16610-21)"
        e = r.eccentricity
        top = sorted(range(len(r.amplitude)), key=lambda i: -r.amplitude[i])[:5]
        lines = [
            f"{file}: {r.n_points} points, {filt}, reference {r.reference}",
            _params_table(r.parameters),
            f"reference circle: centre ({r.center[0]:.6f}, {r.center[1]:.6f}) mm, radius {r.radius:.6f} mm",
            f"eccentricity: {_um(e['magnitude'])} um at {e['angle_deg']:.2f} deg (from the coordinate origin)",
            f"resampled at {r.samples} equal angles about the least-squares centre; largest gap {r.max_gap_deg:.3f} deg",
            "largest harmonics: " + ", ".join(f"{i + 1} UPR {_um(r.amplitude[i])} um" for i in top),
        ]
        if report is not None:
            lines.append(f"report: {report / 'report.html'}")
        return "\n".join(lines)

    emit(res, as_json, human)


def straightness_cmd(
    file: Path = typer.Argument(..., help="Profile points x,y (mm), in scan order along the line."),
    filter: str = typer.Option("none", "--filter", help="gaussian (ISO 16610-21), spline (ISO 16610-22), with --cutoff; or none."),
    cutoff: Optional[float] = typer.Option(None, "--cutoff", callback=_positive, help="Cut-off length, mm (e.g. 0.8, 2.5, 8)."),
    reference: str = typer.Option("LSLI", "--reference", help="Reference line: LSLI (least squares) or MZLI (minimum zone)."),
    step: Optional[float] = typer.Option(None, "--step", callback=_positive, help="Resampling step, mm (default: the mean spacing)."),
    units: Optional[str] = UNITS_OPTION,
    as_json: bool = JSON_OPTION,
) -> None:
    """Straightness parameters STRt, STRp, STRv, STRq (ISO 12780-1) of a 2-D profile; Gaussian
    filter: one cut-off dropped at each end; spline filter: nothing dropped."""
    from ..form.files import read_xy
    from ..form.parameters import straightness_parameters

    res = straightness_parameters(read_xy(file, units), filter, cutoff, reference, step=step)

    def human(r) -> str:
        f = r.filter
        filt = "unfiltered" if f["type"] == "none" else (
            f"Gaussian filter, cut-off {f['cutoff_mm']:g} mm (ends dropped)" if f["type"] == "gaussian"
            else f"cubic spline filter (ISO 16610-22), cut-off {f['cutoff_mm']:g} mm")
        return "\n".join([f"{file}: {r.n_points} points, {filt}, reference {r.reference}, {r.length:.4f} mm evaluated",
                          _params_table(r.parameters)])

    emit(res, as_json, human)


def flatness_cmd(
    file: Path = typer.Argument(..., help="Surface points x,y,z (mm; any file read_points reads)."),
    reference: str = typer.Option("LSPL", "--reference", help="Reference plane: LSPL (least squares) or MZPL (minimum zone)."),
    units: Optional[str] = UNITS_OPTION,
    as_json: bool = JSON_OPTION,
) -> None:
    """Flatness parameters FLTt, FLTp, FLTv, FLTq (ISO 12781-1), unfiltered; deviations positive
    along the reference normal turned towards +z."""
    from ..form.files import load_points
    from ..form.parameters import flatness_parameters

    res = flatness_parameters(load_points(file, units), reference)

    def human(r) -> str:
        return "\n".join([f"{file}: {r.n_points} points, unfiltered, reference {r.reference}", _params_table(r.parameters)])

    emit(res, as_json, human)


#: (command name, function) of this module, in help order.
COMMANDS = (("roundness", roundness_cmd), ("straightness", straightness_cmd), ("flatness", flatness_cmd))


def register(app: typer.Typer) -> None:
    """Add this module's commands to the ``form`` sub-application ``app``."""
    for name, fn in COMMANDS:
        app.command(name)(fn)
