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
    """(n, 2) points from any file ``read_points`` reads: 3-D points must lie in a plane
    parallel to a coordinate plane (as NIST's 2-D sets do); the constant coordinate is
    dropped. ASCII files of 2 columns are read as 2-D points."""
    from ..cloud import read_points
    from ..errors import FileFormatError, InvalidInputError

    try:
        arr = read_points(path, dim=3)
    except FileFormatError as exc3:
        if _text_columns(path) != 2:
            raise
        try:
            return read_points(path, dim=2)
        except (FileFormatError, InvalidInputError):
            raise exc3 from None
    const = [k for k in range(3) if np.ptp(arr[:, k]) == 0.0]
    if not const:
        raise InvalidInputError(
            f"{path}: 3-D points do not lie in a plane parallel to a coordinate plane; "
            "a 2-D circle fit needs planar points"
        )
    return np.ascontiguousarray(np.delete(arr, const[-1], axis=1))


def _text_columns(path: Path) -> int:
    """Number of numeric fields on the first data line of a text file (0 if none)."""
    import re

    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            for _, line in zip(range(1000), fh):
                fields = [f for f in re.split(r"[,;\s]+", line.strip()) if f]
                if not fields or fields[0].startswith("#"):
                    continue
                try:
                    [float(f) for f in fields]
                except ValueError:
                    continue  # a header line
                return len(fields)
    except OSError:
        return 0
    return 0


@app.command("circle")
def circle(
    file: Path = typer.Argument(..., help="Points: any file read_points reads (NIST .ds too); 2 columns or planar 3-D."),
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
