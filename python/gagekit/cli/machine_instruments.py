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
    machine_file: Optional[Path] = typer.Option(None, "--machine", help="Machine file: name the groups behind squareness and scale mismatch (with --at)."),
    at: Optional[str] = typer.Option(None, "--at", help="With --machine: the circle centre's joint positions, e.g. B=0,X=0,Z=1500,Y=1400,W=-500."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Circular test with a ballbar, ISO 230-4:2022: G, F, H and the diagnostics with their share of G."""
    from .._files import atomic_dir, output_dir
    from ..machine.ballbar import analyse_ballbar, read_ballbar

    if report is not None:
        output_dir(report)
    res = analyse_ballbar(read_ballbar(run), plane, radius, feed=feed, pitch=pitch)
    groups = None
    if machine_file is not None or at is not None:
        from ..errors import InvalidInputError
        from ..machine import load_machine
        from ..machine.ballbar import group_sensitivities
        from ._common import number_option as _number, parse_assignments

        if machine_file is None or at is None:
            raise InvalidInputError("--machine and --at go together (the circle centre's joint positions)")
        fixed = {k: _number(v, f"--at {k}") for k, v in parse_assignments(at, "--at").items()}
        groups = group_sensitivities(load_machine(machine_file), plane, radius, fixed)
    if report is not None:
        from ..report import Report
        from ..report.ballbar import add_ballbar

        rep = Report(f"Ballbar test: {run.name}", f"ISO 230-4:2022, plane {res.plane}, radius {res.radius_mm:g} mm")
        add_ballbar(rep, res)
        with atomic_dir(report) as tmp:
            rep.write(tmp)

    if groups is not None:
        result = {**res.to_dict(), "groups_per_unit": groups}
    else:
        result = res

    def human(r) -> str:
        d = r if isinstance(r, dict) else r.to_dict()
        g = d["circular_deviation_um"]
        axes = d["axes"]
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
            ax1, ax2 = axes
            lines.append(
                f"cyclic error, pitch {c['pitch_mm']:.3f} mm ({c['pitch_source']}): {ax1} {c[ax1]['amplitude']:.3f}, "
                f"{ax2} {c[ax2]['amplitude']:.3f} um"
            )
        c = d["centre_offset_um"]["both"]
        lines.append(f"centre offset x {c['x']:.3f}, y {c['y']:.3f} um; residual RMS {d['residual_rms_um']:.3f} um")
        for key, label in (("squareness_um_per_m", "squareness"), ("scale_mismatch_um_per_m", "scale mismatch")):
            if "groups_per_unit" in d:
                terms = ", ".join(f"{v:+.4g} x ({k})" for k, v in d["groups_per_unit"][key].items())
                lines.append(f"{label} (um/m) = {terms}")
        return "\n".join(lines)

    emit(result, as_json, human)


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


def export_kinematics_cmd(m, cal, out, at, stamp, as_json, uncertainty: bool = False) -> None:
    """`machine export --format kinematics`: three controller files (four with --uncertainty), all or nothing."""
    from ..machine.export_kinematics import export_kinematics

    res = export_kinematics(m, cal, out, at=at, stamp=stamp, uncertainty=uncertainty)

    def human(r) -> str:
        lines = [f"wrote {', '.join(r.files)}"]
        for a in r.axes:
            moved = ", ".join(f"{k} {a.point[k]:.4f} (nominal {a.nominal_point[k]:.4f})" for k in a.point)
            lines.append(f"{a.joint} axis line: {moved}; direction {', '.join(f'{v:.7f}' for v in a.direction)}")
        return "\n".join(lines)

    emit(res, as_json, human)


def design_instrument_cmd(m, instrument, points, criterion, sphere, at, radius, seed, out, as_json) -> None:
    """`machine design --instrument sphere|rtest|ballbar`: an optimal probing or circle plan."""
    import numpy as np

    from .._files import write_text
    from ..errors import InvalidInputError
    from ..machine.instrument_design import design_instrument
    from ._common import number_option as _number, parse_assignments

    fixed = {k: _number(v, f"--at {k}") for k, v in parse_assignments(at, "--at").items()}
    s = None
    if sphere is not None:
        parts = sphere.split(",")
        if len(parts) != 3:
            raise InvalidInputError(f"--sphere: expected x,y,z in mm, got {sphere!r}")
        s = np.array([_number(v, "--sphere") for v in parts])
    d = design_instrument(m, instrument.lower(), points, criterion, sphere=s, at=fixed, radius=radius, seed=seed)
    if "commands" in d:
        rows = [",".join(d["joint_names"])] + [",".join(repr(float(v)) for v in row) for row in d["commands"]]
        lines = [f"# kind = {d['instrument']}", f"# {d['criterion']}-optimal probing positions of {d['joint']}, sphere at {d['sphere']} (table frame, mm)"]
        write_text(out, "\n".join(lines + rows) + "\n")
        result = {k: v for k, v in d.items() if k not in ("commands", "joint_names")}
    else:
        head = "plane," + ",".join(m.joint_names)
        rows = [f"{c['plane']}," + ",".join(repr(c["centre"][j]) for j in m.joint_names) for c in d["circles"]]
        write_text(out, f"# {d['criterion']}-optimal ballbar circles, radius {d['radius']} mm\n" + "\n".join([head] + rows) + "\n")
        result = dict(d)
    result["out"] = str(out)

    def human(r) -> str:
        if "positions" in r:
            return (f"{r['criterion']}-optimal {r['instrument']} plan: {r['joint']} at {', '.join(f'{v:g}' for v in r['positions'])} "
                    f"(unknowns {', '.join(r['unknowns'])}; trace {r['trace']:.4g}, condition {r['condition_number']:.3g}) -> {r['out']}")
        circles = "; ".join(f"{c['plane']} about " + ", ".join(f"{k} {v:.1f}" for k, v in c["centre"].items()) for c in r["circles"])
        return (f"{r['criterion']}-optimal ballbar plan ({r['combinations_seen']} of {r['groups']} group combinations seen): "
                f"{circles} -> {r['out']}")

    emit(result, as_json, human)


def track_sphere_cmd(m, cycles_csv, history, report, as_json) -> None:
    """`machine track` on sphere-probing cycles: location errors per cycle, drift, trend."""
    from .._util import dumps
    from ..errors import InvalidInputError
    from ..machine.instruments import track_sphere

    if history is not None:
        raise InvalidInputError("--history stores tracker cycles of the full model; sphere-probing cycles are reported (--json, --report) only")
    res = track_sphere(m, cycles_csv)
    if report is not None:
        from .._files import atomic_dir, write_text

        with atomic_dir(report) as tmp:
            write_text(tmp / "track.json", dumps(res))
        res["report"] = str(report / "track.json")

    def human(r) -> str:
        names = [k for k, v in r["cycles"][0]["location_errors"].items() if "value" in v]
        head = f"{'cycle':>6} " + " ".join(f"{k:>16}" for k in names) + "   (um / urad, +/- std)"
        lines = [f"sphere-probing cycles: {len(r['cycles'])}, rotary-axis location errors per cycle", head]
        for c in r["cycles"]:
            cells = []
            for k in names:
                v = c["location_errors"][k]
                s = 1e3 if k[1] in "XYZ" else 1e6
                cells.append(f"{s * v['value']:8.2f}+/-{s * v['std']:5.2f}" if "value" in v else f"{'-':>16}")
            lines.append(f"{c['cycle']:>6} " + " ".join(cells))
        for k, t in r["trend"].items():
            s, u = (1e3, "um") if k[1] in "XYZ" else (1e6, "urad")
            lines.append(f"trend {k}: {s * t['slope']:+.3f} {u} per {t['per']}")
        return "\n".join(lines)

    emit(res, as_json, human)
