"""`gagekit compare SCAN CAD`: signed deviations of a scan from its CAD model, with
best-fit, minimax or datum alignment, per-face statistics and a deviation map."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from ._common import JSON_OPTION, UNITS_OPTION, emit, read_cloud_cli, seed_option, table, warn
from ._uncertainty import MEASUREMENT_OPTION, NOISE_OPTION, THREADS_OPTION, UNCERTAINTY_OPTION, uncertainty_settings


def human(result) -> str:
    d = result.to_dict()
    s = d["deviations"]
    a = d["alignment"]
    lines = [
        f"{d['cad']['file']}: {d['cad']['faces']} faces, {d['cad']['triangles']} triangles ({d['cad']['unit']})",
        f"points {d['n_points']}, used {d['n_used']}, beyond --max-distance {d['n_beyond']}"
        + ("" if d["signed"] else "  (unsigned: the model is open)"),
        f"alignment {a['method']}: rms {a['rms_before']:.6f} -> {a['rms_after']:.6f} mm, {a['iterations']} iterations",
    ]
    if "certificate" in a:
        c = a["certificate"]
        lines.append(f"minimax certificate: largest |deviation| {c['max_abs_deviation']:.6f} mm, LP optimum {c['lp_optimum']:.6f} mm")
    lines.append(f"deviation mm: min {s['min']:+.6f}  max {s['max']:+.6f}  mean {s['mean']:+.6f}  sd {s['sd']:.6f}  "
                 f"rms {s['rms']:.6f}  profile {s['profile']:.6f}")
    rows = [[f["id"], f["name"] or "-", f["kind"], f["n"]] + ([f"{f['min']:+.4f}", f"{f['max']:+.4f}", f"{f['mean']:+.4f}", f"{f['rms']:.4f}"]
            if f["n"] else ["-", "-", "-", "-"]) for f in d["faces"]]
    return "\n".join(lines) + "\n\n" + table(["face", "name", "surface", "n", "min", "max", "mean", "rms"], rows)


def compare(
    scan: Path = typer.Argument(..., help="Scanned cloud: XYZ/CSV/TXT, NIST .ds, PLY, .npy, LAS/LAZ, E57."),
    cad: Path = typer.Argument(..., help="CAD model: STEP (.step/.stp, needs gagekit[cad]), STL, OBJ, PLY or 3MF mesh."),
    units: Optional[str] = UNITS_OPTION,
    cad_units: Optional[str] = typer.Option(None, "--cad-units", help="Unit of a mesh file (STL/OBJ/PLY carry none): mm (default), cm, m, um, in, ft. STEP and 3MF declare their own."),
    align: str = typer.Option("none", "--align", help="none (the scan is in CAD coordinates), best-fit, minimax or datums (needs --part)."),
    part: Optional[Path] = typer.Option(None, "--part", help="PART.toml: the drawing's datums (for --align datums)."),
    lock: Optional[str] = typer.Option(None, "--lock", help="Degrees of freedom to keep, e.g. z,rx,ry (of x,y,z,rx,ry,rz, in CAD axes)."),
    max_distance: Optional[float] = typer.Option(None, "--max-distance", help="Points farther from the model (mm) are counted apart (n_beyond), not used."),
    deviations: Optional[Path] = typer.Option(None, "--deviations", help="Write one deviation per input point: OUT.npy, OUT.csv or OUT.ply (a scalar field)."),
    report: Optional[Path] = typer.Option(None, "--report", help="Write report.html (the CAD coloured by deviation, histogram, per-face table, callouts) and result.json into DIR."),
    as_json: bool = JSON_OPTION,
    uncertainty: Optional[str] = UNCERTAINTY_OPTION,
    noise: Optional[str] = NOISE_OPTION,
    measurement: Optional[Path] = MEASUREMENT_OPTION,
    seed: int = seed_option(help="Seed of the Monte Carlo trials (--uncertainty)"),
    threads: Optional[int] = THREADS_OPTION,
) -> None:
    """Signed deviation of every scan point from the CAD surface (positive outside the
    material), after the chosen alignment; per-face statistics. With --uncertainty, the
    JCGM 101 uncertainty of every statistic (alignment re-run on each simulated scan).

    Exit status 0 when the comparison ran; 2 on errors.
    """
    from .._files import output_dir, output_file
    from ..cad import read_cad
    from ..cad import compare as run_compare
    from ..cad.compare import write_deviations
    from ..errors import ConfigError

    if align not in ("none", "best-fit", "minimax", "datums"):
        raise ConfigError(f"--align {align}: choose none, best-fit, minimax or datums")
    if align == "datums" and part is None:
        raise ConfigError("--align datums needs --part PART.toml (the drawing's datums)")
    if max_distance is not None and not (max_distance > 0 and max_distance < float("inf")):
        raise ConfigError(f"--max-distance must be a positive number, got {max_distance}")
    mc = uncertainty_settings(uncertainty, noise, measurement)
    if deviations is not None:
        output_file(deviations)
    if report is not None:
        output_dir(report)
    spec = None
    if part is not None:
        from ..inspect import load_part_spec

        spec = load_part_spec(part)
    model = read_cad(cad, cad_units)
    for w in model.warnings:
        warn(w)
    pts = read_cloud_cli(scan, units).points
    options = dict(align=align, lock=lock, max_distance=max_distance, part=spec)
    res = None
    if mc is not None:
        from ..uncertainty import compare_uncertainty

        result, res = compare_uncertainty(pts, model, mc[1], mc[0], seed=seed, threads=threads, **options)
    else:
        result = run_compare(pts, model, **options)
    if deviations is not None:
        write_deviations(deviations, result)
    if report is not None:
        from ..report.compare import write_report

        write_report(result, report)
    if res is None:
        emit(result, as_json, human)
        return
    out = {**result.to_dict(), "uncertainty": res.to_dict(), "monte_carlo": res.settings()}

    def human_mc(_: object) -> str:
        rows = [[k, f"{u.value:+.6f}", f"{u.U:.6f}", f"[{u.interval[0]:+.6f}, {u.interval[1]:+.6f}]", f"{u.bias:+.6f}"]
                for k, u in res.uncertainties.items() if k.startswith("deviations.")]
        s = res.settings()
        return "\n".join([human(result), "", table(["statistic", "value", "U (95 %)", "95 % interval", "MC bias"], rows),
                          f"uncertainty: {s['method']}, {s['trials']} trials, seed {s['seed']}, {s['stopping']}; noise "
                          f"sigma {s['model']['sigma']:.6g} mm (per-face figures in --json)"])

    emit(out, as_json, human_mc)
