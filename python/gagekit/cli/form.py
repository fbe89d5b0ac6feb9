"""`gagekit form`: Form of lines, planes, circles, spheres and cylinders (Ch. 6)."""

from __future__ import annotations

from enum import Enum
from pathlib import Path
from typing import Any, Optional

import numpy as np
import typer

from ._common import JSON_OPTION, UNITS_OPTION, emit, seed_option, table

app = typer.Typer(help="Form of lines, planes, circles, spheres and cylinders (Ch. 6).", no_args_is_help=True)


# circles ------------------------------------------------------------------------------


class _CircleCriterion(str, Enum):
    lsq = "lsq"
    mc = "mc"
    mi = "mi"
    mz = "mz"
    all = "all"


def _read_xy(path: Path, units: Optional[str] = None) -> np.ndarray:
    from ..form.files import read_xy

    return read_xy(path, units)


@app.command("circle")
def circle(
    file: Path = typer.Argument(..., help="Points: any file read_points reads (NIST .ds too); 2 columns or planar 3-D."),
    criterion: _CircleCriterion = typer.Option(_CircleCriterion.lsq, "--criterion", "-c",
                                               help="lsq, mc (min circumscribed), mi (max inscribed), mz (min zone), or all."),
    units: Optional[str] = UNITS_OPTION,
    as_json: bool = JSON_OPTION,
) -> None:
    """Fit a 2-D circle (Sec. 6.2): least squares, MC, MI or minimum zone (roundness)."""
    from ..form.circle import fit_circle

    pts = _read_xy(file, units)
    crits = ["lsq", "mc", "mi", "mz"] if criterion.value == "all" else [criterion.value]
    fits = [fit_circle(pts, c) for c in crits]
    result = fits[0] if len(fits) == 1 else {f.to_dict()["criterion"]: f for f in fits}

    def human(_: object) -> str:
        rows = [[f.to_dict()["criterion"], f.center[0], f.center[1], f.radius, f.width,
                 " ".join(map(str, f.control_points))] for f in fits]
        text = table(["criterion", "x", "y", "radius", "form error", "control points"], rows)
        notes = [w for f in fits for w in f.warnings]
        return "\n".join([f"{file}: {fits[0].n_points} points", text, *[f"warning: {w}" for w in notes]])

    emit(result, as_json, human)


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
    for key in ("radius", "inner_radius", "outer_radius", "form_error", "theta", "phi", "distance", "apex_angle"):
        if d.get(key) is not None:
            rows.append([key, f"{d[key]:.9f}"])
    for key in ("center", "normal", "point", "direction", "axis_point", "axis_direction"):
        if key in d:
            rows.append([key, _fmt_vec(d[key])])
    if d.get("control_points"):
        rows.append(["control_points", " ".join(str(i) for i in d["control_points"])])
    cert = d["certificate"]
    rows.append(["min_distance", f"{cert['min_distance']:.9f}"])
    rows.append(["max_distance", f"{cert['max_distance']:.9f}"])
    head = f"{d['shape']} ({d['criterion']}), {d['n_points']} points"
    return head + "\n" + table(["quantity", "value (mm, rad)"], rows)


@app.command("fit")
def fit(
    shape: str = typer.Argument(..., help="circle, line, plane, sphere, circle3d, cylinder or cone"),
    file: Path = typer.Argument(..., help="Points: any file read_points reads (XYZ/CSV/TXT, NIST .ds, PLY, .npy, ...)"),
    criterion: str = typer.Option("least-squares", "--criterion", "-c", help="Fit criterion"),
    seed: int = seed_option(help="Seed of the particle swarm (cylinders)"),
    units: Optional[str] = UNITS_OPTION,
    as_json: bool = JSON_OPTION,
) -> None:
    """Fit a feature to the points of FILE and report its form error and certificate."""
    from ..form.files import fit_file

    emit(fit_file(shape, file, criterion, seed=seed, units=units), as_json, _human)


@app.command("cylinder")
def cylinder(
    file: Path = typer.Argument(..., help="Points: any file read_points reads (XYZ/CSV/TXT, NIST .ds, PLY, .npy, ...)"),
    criterion: str = typer.Option(
        "least-squares", "--criterion", "-c", help="least-squares (lsq), mcc, mic or mzc"
    ),
    seed: int = seed_option(help="Seed of the particle swarm"),
    units: Optional[str] = UNITS_OPTION,
    as_json: bool = JSON_OPTION,
) -> None:
    """Fit a cylinder (least squares, min circumscribed, max inscribed, minimum zone)."""
    from .. import form

    emit(form.fit_cylinder(_load_points(file, units), criterion, seed=seed), as_json, _human)
