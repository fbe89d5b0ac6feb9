"""`gagekit form`: Form of lines, planes, circles, spheres and cylinders (Ch. 6)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Optional

import numpy as np
import typer

from ._common import JSON_OPTION, UNITS_OPTION, emit, seed_option, table
from ._uncertainty import MEASUREMENT_OPTION, NOISE_OPTION, THREADS_OPTION, UNCERTAINTY_OPTION, uncertainty_settings

app = typer.Typer(help="Form of lines, planes, circles, spheres and cylinders (Ch. 6).", no_args_is_help=True)


# circles ------------------------------------------------------------------------------


def _read_xy(path: Path, units: Optional[str] = None) -> np.ndarray:
    from ..form.files import read_xy

    return read_xy(path, units)


@app.command("circle")
def circle(
    file: Path = typer.Argument(..., help="Points: any file read_points reads (NIST .ds too); 2-D, or 3-D in any pose."),
    criterion: str = typer.Option("lsq", "--criterion", "-c",
                                  help="lsq, mc (min circumscribed), mi (max inscribed), mz (min zone), any name "
                                       "of the criterion table, or all."),
    units: Optional[str] = UNITS_OPTION,
    as_json: bool = JSON_OPTION,
) -> None:
    """Fit a circle (Sec. 6.2): least squares, MC, MI or minimum zone (roundness); points in
    space are fitted in their least-squares plane."""
    from ..form.circle import fit_circle
    from ..form.criteria import CIRCLE_CRITERIA

    pts = _read_xy(file, units)
    crits = list(CIRCLE_CRITERIA.values()) if criterion.strip().lower() == "all" else [criterion]
    fits = [fit_circle(pts, c) for c in crits]
    result = fits[0] if len(fits) == 1 else {f.to_dict()["criterion"]: f for f in fits}

    def human(_: object) -> str:
        xyz = ["x", "y", "z"][: len(fits[0].center)]
        rows = [[f.criterion, *f.center, f.radius, f.form_error,
                 " ".join(map(str, f.control_points))] for f in fits]
        text = table(["criterion", *xyz, "radius", "form error", "control points"], rows)
        return "\n".join([f"{file}: {fits[0].n_points} points", text])

    emit(result, as_json, human, warnings=[w for f in fits for w in f.warnings])


# end circles --------------------------------------------------------------------------


# 3-D fits ------------------------------------------------------------------

def _load_points(path: Path, units: Optional[str] = None) -> np.ndarray:
    from ..form.files import load_points

    return load_points(path, units)


def _fmt_vec(v: Any) -> str:
    return "(" + ", ".join(f"{x:.9g}" for x in v) + ")"


def _human(r: Any) -> str:
    d = r.to_dict()
    rows = []
    for key in ("radius", "inner_radius", "outer_radius", "form_error", "theta", "phi", "tilt_deg", "distance", "apex_angle",
                "half_angle_deg", "gap"):
        if d.get(key) is not None:
            rows.append([key, f"{d[key]:.9f}"])
    for key in ("center", "normal", "point", "direction", "axis_point", "axis_direction", "apex"):
        if key in d:
            rows.append([key, _fmt_vec(d[key])])
    if d.get("control_points"):
        rows.append(["control_points", " ".join(str(i) for i in d["control_points"])])
    cert = d["certificate"]
    rows.append(["min_distance", f"{cert['min_distance']:.9f}"])
    rows.append(["max_distance", f"{cert['max_distance']:.9f}"])
    head = f"{d['shape']} ({d['criterion']}), {d['n_points']} points"
    return "\n".join([head, table(["quantity", "value (mm, rad)"], rows)])


def _axis(text: Optional[str]) -> Optional[tuple[float, ...]]:
    """``--axis X,Y,Z`` as three numbers (the kernels check length and finiteness)."""
    from ..errors import ConfigError

    if text is None:
        return None
    parts = [p for p in text.replace(";", ",").replace(" ", ",").split(",") if p]
    try:
        vals = tuple(float(p) for p in parts)
    except ValueError:
        vals = ()
    if len(vals) != 3:
        raise ConfigError(f"--axis: expected three numbers X,Y,Z, got {text!r}")
    return vals


AXIS_OPTION = typer.Option(None, "--axis", help="Nominal axis X,Y,Z of cylinders and 3-D lines (default: the least-squares axis)")
TILT_OPTION = typer.Option(10.0, "--max-tilt", help="Chebyshev fits search axes within DEG of the axis (0: fixed, 90: all)")


@app.command("fit")
def fit(
    shape: str = typer.Argument(..., help="circle (circle3d: alias), line, plane, sphere, cylinder or cone"),
    file: Path = typer.Argument(..., help="Points: any file read_points reads (XYZ/CSV/TXT, NIST .ds, PLY, .npy, ...)"),
    criterion: str = typer.Option(
        "least-squares", "--criterion", "-c",
        help="least-squares (lsq), min-circumscribed (mc), max-inscribed (mi) or minimum-zone (mz); "
             "lines and planes: least-squares or minimum-zone"),
    seed: int = seed_option(help="Seed of the particle swarm (cylinders, 3-D lines)"),
    axis: Optional[str] = AXIS_OPTION,
    max_tilt: float = TILT_OPTION,
    angle: Optional[float] = typer.Option(None, "--angle", help="Cones: fix the half apex angle to DEG, in (0, 90) (default: free)"),
    units: Optional[str] = UNITS_OPTION,
    as_json: bool = JSON_OPTION,
    uncertainty: Optional[str] = UNCERTAINTY_OPTION,
    noise: Optional[str] = NOISE_OPTION,
    measurement: Optional[Path] = MEASUREMENT_OPTION,
    threads: Optional[int] = THREADS_OPTION,
) -> None:
    """Fit a feature to the points of FILE and report its form error and certificate; with
    --uncertainty, the JCGM 101 uncertainty of each result (the swarm's --seed seeds the trials too)."""
    from ..form.files import fit_file, load_points, normalize_shape

    mc = uncertainty_settings(uncertainty, noise, measurement)
    ax = _axis(axis)
    if mc is None:
        r = fit_file(shape, file, criterion, seed=seed, units=units, axis=ax, max_tilt=max_tilt, angle=angle)
        emit(r, as_json, _human, warnings=getattr(r, "warnings", ()))
        return
    from ..uncertainty import fit_uncertainty

    pts = _read_xy(file, units) if normalize_shape(shape) == "circle" else load_points(file, units)
    r, res = fit_uncertainty(lambda p: fit_file(shape, file, criterion, seed=seed, points=p, axis=ax, max_tilt=max_tilt,
                                                       angle=angle),
                             pts, mc[1], mc[0], seed=seed, threads=threads)
    out = {**r.to_dict(), "uncertainty": res.to_dict(), "monte_carlo": res.settings()}

    def human(_: object) -> str:
        rows = [[k, f"{u.value:.9f}", f"{u.u:.9f}", f"{u.U:.9f}", f"[{u.interval[0]:.9f}, {u.interval[1]:.9f}]", f"{u.bias:+.9f}"]
                for k, u in res.uncertainties.items()]
        s = res.settings()
        return "\n".join([_human(r), "", table(["quantity", "value", "u", "U (95 %)", "95 % interval", "MC bias"], rows),
                          f"uncertainty: {s['method']}, {s['trials']} trials, seed {s['seed']}, {s['stopping']}; noise "
                          f"sigma {s['model']['sigma']:.6g} mm" + (f" ({s['model']['sigma_source']})" if "sigma_source" in s["model"] else "")])

    emit(out, as_json, human, warnings=getattr(r, "warnings", ()))


@app.command("cylinder")
def cylinder(
    file: Path = typer.Argument(..., help="Points: any file read_points reads (XYZ/CSV/TXT, NIST .ds, PLY, .npy, ...)"),
    criterion: str = typer.Option(
        "least-squares", "--criterion", "-c", help="least-squares (lsq), mcc, mic or mzc"
    ),
    seed: int = seed_option(help="Seed of the particle swarm"),
    axis: Optional[str] = AXIS_OPTION,
    max_tilt: float = TILT_OPTION,
    units: Optional[str] = UNITS_OPTION,
    as_json: bool = JSON_OPTION,
) -> None:
    """Fit a cylinder (least squares, min circumscribed, max inscribed, minimum zone)."""
    from .. import form

    r = form.fit_cylinder(_load_points(file, units), criterion, seed=seed, axis=_axis(axis), max_tilt=max_tilt)
    emit(r, as_json, _human, warnings=r.warnings)
