"""`gagekit form`: Form of lines, planes, circles, spheres and cylinders (Ch. 6)."""

from __future__ import annotations

from enum import Enum
from pathlib import Path

import numpy as np
import typer

from ._common import JSON_OPTION, emit, table

app = typer.Typer(help="Form of lines, planes, circles, spheres and cylinders (Ch. 6).", no_args_is_help=True)


# circles ------------------------------------------------------------------------------


class _CircleCriterion(str, Enum):
    lsq = "lsq"
    mc = "mc"
    mi = "mi"
    mz = "mz"
    all = "all"


def _read_xy(path: Path) -> np.ndarray:
    """(n, 2) points from a text file of (n, 2) or (n, 3) rows, or a NIST .ds file.

    Temporary reader until ``gagekit.read_points`` lands. A 3-column file must lie in a
    plane parallel to a coordinate plane; the constant coordinate is dropped.
    """
    from ..errors import FileFormatError, InvalidInputError

    if not path.is_file():
        raise FileFormatError(f"{path}: no such file")
    try:
        if path.suffix.lower() == ".npy":
            arr = np.load(path, allow_pickle=False)
        else:
            arr = np.loadtxt(path, skiprows=1 if path.suffix.lower() == ".ds" else 0, ndmin=2,
                             delimiter="," if path.suffix.lower() == ".csv" else None)
    except (ValueError, OSError) as exc:
        raise FileFormatError(f"{path}: cannot read points ({exc})") from None
    arr = np.asarray(arr, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] not in (2, 3):
        raise FileFormatError(f"{path}: expected 2 or 3 columns, got shape {arr.shape}")
    if arr.shape[1] == 3:
        const = [k for k in range(3) if np.ptp(arr[:, k]) == 0.0] if len(arr) else [2]
        if not const:
            raise InvalidInputError(
                f"{path}: 3-D points do not lie in a plane parallel to a coordinate plane; "
                "a 2-D circle fit needs planar points"
            )
        arr = np.delete(arr, const[-1], axis=1)
    return np.ascontiguousarray(arr)


@app.command("circle")
def circle(
    file: Path = typer.Argument(..., help="Points: (n, 2) or planar (n, 3) text/.npy file, or NIST .ds."),
    criterion: _CircleCriterion = typer.Option(_CircleCriterion.lsq, "--criterion", "-c",
                                               help="lsq, mc (min circumscribed), mi (max inscribed), mz (min zone), or all."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Fit a 2-D circle (Sec. 6.2): least squares, MC, MI or minimum zone (roundness)."""
    from ..form.circle import fit_circle

    pts = _read_xy(file)
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
