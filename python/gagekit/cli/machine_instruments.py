"""`gagekit machine ballbar`: instruments other than the laser tracker (ISO 230-4 ballbar).

Registered on the ``machine`` sub-application by :func:`register`, called in ``cli/__init__.py``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from ._common import JSON_OPTION, emit


def _positive(value: Optional[float]) -> Optional[float]:
    import math

    if value is not None and not (math.isfinite(value) and value > 0):
        raise typer.BadParameter(f"must be a positive number, got {value}")
    return value


def ballbar_cmd(
    run: Path = typer.Argument(..., help="Ballbar run CSV: angle_deg,deviation_um,direction (cw/ccw)."),
    plane: str = typer.Option(..., "--plane", help="XY, YZ or ZX (angle from the first axis towards the second)."),
    radius: float = typer.Option(..., "--radius", help="Nominal radius (ballbar length), mm.", callback=_positive),
    feed: Optional[float] = typer.Option(None, "--feed", help="Feed of the test, mm/min (servo mismatch in ms).", callback=_positive),
    pitch: Optional[float] = typer.Option(
        None, "--pitch", help="Pitch of the cyclic error, mm (default: the pitch that explains most).", callback=_positive
    ),
    report: Optional[Path] = typer.Option(None, "--report", help="Directory for report.html with the polar plot."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Circular test with a ballbar, ISO 230-4:2022: G, F, H and the diagnostics with their share of G."""
    from .._files import atomic_dir, output_dir
    from ..machine.ballbar import analyse_ballbar, read_ballbar

    if report is not None:
        output_dir(report)
    res = analyse_ballbar(read_ballbar(run), plane, radius, feed=feed, pitch=pitch)
    if report is not None:
        from ..report import Report
        from ..report.ballbar import add_ballbar

        rep = Report(f"Ballbar test: {run.name}", f"ISO 230-4:2022, plane {res.plane}, radius {res.radius_mm:g} mm")
        add_ballbar(rep, res)
        with atomic_dir(report) as tmp:
            rep.write(tmp)

    def human(r) -> str:
        d = r.to_dict()
        g = d["circular_deviation_um"]
        lines = [
            f"ballbar, plane {d['plane']}, radius {d['radius_mm']:g} mm, readings {d['n_readings']} (ISO 230-4:2022, um)",
            "G " + ", ".join(f"{k} {v:.3f}" for k, v in g.items())
            + f"; F max {d['radial_deviation_um']['max']:.3f}, min {d['radial_deviation_um']['min']:.3f}"
            + (f"; H {d['hysteresis_um']:.3f}" if "hysteresis_um" in d else ""),
            f"squareness {d['squareness_um_per_m']['value']:.2f} um/m ({100 * d['squareness_um_per_m']['fraction_of_G']:.0f} % of G; "
            f"{d['squareness_um_per_m']['sign']})",
            f"scale mismatch {d['scale_mismatch_um_per_m']['value']:.2f} um/m ({100 * d['scale_mismatch_um_per_m']['fraction_of_G']:.0f} % of G)",
        ]
        for ax, b in d["backlash_um"].items():
            vals = ", ".join(f"{k} {v:.3f}" for k, v in b.items() if k != "fraction_of_G")
            lines.append(f"backlash {ax}: {vals} um ({100 * b['fraction_of_G']:.0f} % of G)")
        if "servo_mismatch_ms" in d:
            s = d["servo_mismatch_ms"]
            lines.append(f"servo mismatch {s['value']:.3f} ms at {s['feed_mm_per_min']:g} mm/min ({100 * s['fraction_of_G']:.0f} % of G; {s['sign']})")
        if "cyclic_error_um" in d:
            c = d["cyclic_error_um"]
            ax1, ax2 = r.axes
            lines.append(
                f"cyclic error, pitch {c['pitch_mm']:.3f} mm ({c['pitch_source']}): {ax1} {c[ax1]['amplitude']:.3f}, "
                f"{ax2} {c[ax2]['amplitude']:.3f} um"
            )
        c = d["centre_offset_um"]["both"]
        lines.append(f"centre offset x {c['x']:.3f}, y {c['y']:.3f} um; residual RMS {d['residual_rms_um']:.3f} um")
        return "\n".join(lines)

    emit(res, as_json, human)


#: (command name, function) of this module, in help order.
COMMANDS = (("ballbar", ballbar_cmd),)


def register(app: typer.Typer) -> None:
    """Add this module's commands to the ``machine`` sub-application ``app``."""
    for name, fn in COMMANDS:
        app.command(name)(fn)


def check_observations(m, kinds_text: str, as_json: bool) -> None:
    """`machine check --observations KIND[,KIND]`: what each instrument sees."""
    from ..errors import InvalidInputError
    from ..machine.instruments import KINDS, instrument_view

    kinds = [k.strip().lower() for k in kinds_text.split(",") if k.strip()]
    bad = [k for k in kinds if k not in KINDS]
    if not kinds or bad:
        raise InvalidInputError(f"--observations: expected {', '.join(KINDS)} or a comma list of them, got {kinds_text!r}")
    view = instrument_view(m, list(dict.fromkeys(kinds)))
    result = {"machine": m.name, "instruments": view}

    def human(r) -> str:
        lines = []
        for label, v in r["instruments"].items():
            lines.append(f"{label}: sees {len(v['groups_seen'])} of {len(v['groups_seen']) + len(v['groups_not_seen'])} groups")
            lines += [f"  not seen: {g}" for g in v["groups_not_seen"]]
            lines.append(f"  rotary-axis location errors seen: {', '.join(v['location_errors_seen']) or 'none'}"
                         f"; not seen: {', '.join(v['location_errors_not_seen']) or 'none'}")
        return "\n".join(lines)

    emit(result, as_json, human)


def identify_mixed_cmd(m, observations, unknowns, out, test, residuals, as_json) -> None:
    """`machine identify` with several files or non-tracker kinds: one joint solve."""
    from ..errors import InvalidInputError
    from ..machine.instruments import identify_mixed

    if test is not None or residuals is not None:
        raise InvalidInputError("--test and --residuals apply to a single tracker file; mixed observations report each instrument's residual RMS")
    res = identify_mixed(m, observations, unknowns=unknowns)
    if out is not None:
        res.calibration.save(out)

    def human(r) -> str:
        d = r.to_dict()
        lines = [f"mixed identification ({d['unknowns']}), condition number {d['condition_number']:.1f}"]
        for i in d["instruments"]:
            lines.append(f"  {i['kind']:8s} {i['readings']:6d} readings, sigma {i['sigma_um']:.2f} um, residual RMS {i['residual_rms_um']:.2f} um  ({i['source']})")
        lines.append("rotary-axis location errors (ISO 230-7):")
        for n, v in d["location_errors"].items():
            if "value" in v:
                scale, unit = (1e3, "um") if v["unit"] == "mm" else (1e6, "urad")
                lines.append(f"  {n}  {scale * v['value']:10.3f} +/- {scale * v['std']:.3f} {unit}")
            else:
                lines.append(f"  {n}  not seen")
        seen = sum(1 for g in d["groups"].values() if "value" in g)
        lines.append(f"groups seen: {seen} of {len(d['groups'])}" + (f"; calibration written to {out}" if out else ""))
        return "\n".join(lines)

    emit(res, as_json, human)
