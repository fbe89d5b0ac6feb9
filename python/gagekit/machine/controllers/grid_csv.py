"""``grid-csv``, gagekit's reference table: header line, then one row per grid node in C order
of ``axes``: the joint columns (file units), ``ex, ey, ez`` (predicted volumetric error,
table frame, mm, Eq. 3.9), ``c<joint>`` for each prismatic grid joint (what to add to its
command so that the predicted error vanishes, first order through the command Jacobian,
mm), ``ux, uy, uz`` (standard uncertainty of the prediction, mm) and, with uncertainty,
``uc<joint>`` (u of each correction). Read back by multilinear interpolation."""

from __future__ import annotations

from pathlib import Path
from typing import Optional, Sequence, Union

import numpy as np

from ...errors import InvalidInputError
from ..calibration import Calibration
from ..grid import Grid, correction_uncertainty, corrections, grid_predictions, number_text
from ..model import Machine

__all__ = ["comp_joints", "table_text", "csv_text", "read_grid_csv"]


def comp_joints(machine: Machine, grid: Grid) -> list[str]:
    spec = {j.name: j for j in machine.joints}
    return [a for a in grid.axes if spec[a].kind == "prismatic"]


def table_text(machine: Machine, calibration: Calibration, grid: Grid, uncertainty: bool = False) -> tuple[str, Optional[np.ndarray]]:
    """The grid-csv text, and with ``uncertainty`` the (n, k) u of the corrections (columns ``uc<joint>``)."""
    cmds = grid.commands(machine)
    e, u = grid_predictions(machine, calibration, cmds)
    comp = comp_joints(machine, grid)
    cj = corrections(machine, cmds, e, comp) if comp else np.zeros((len(cmds), 0))
    header = machine.joint_names + ["ex", "ey", "ez"] + [f"c{j}" for j in comp] + ["ux", "uy", "uz"]
    blocks = [cmds, e, cj, u]
    uc = None
    if uncertainty and comp:
        uc = correction_uncertainty(machine, calibration, cmds, comp)
        header += [f"uc{j}" for j in comp]
        blocks.append(uc)
    data = np.hstack(blocks)
    if not np.isfinite(data).all():
        raise InvalidInputError("grid-csv: non-finite prediction (calibration values out of range?)")
    return csv_text(header, data), (uc if uc is not None else u)


def csv_text(header: Sequence[str], data: np.ndarray) -> str:
    lines = [",".join(header)]
    lines += [",".join(number_text(v) for v in row) for row in data]
    return "\n".join(lines) + "\n"


def read_grid_csv(path: Union[str, Path], machine: Machine):
    """Read a grid-csv back: (Grid, {column: (n, ...) array in C order})."""
    text = Path(path).read_text(encoding="utf-8").splitlines()
    header = text[0].split(",")
    data = np.array([[float(v) for v in line.split(",")] for line in text[1:] if line])
    cols = {h: data[:, i] for i, h in enumerate(header)}
    varying = [j for j in machine.joint_names if len(np.unique(cols[j])) > 1]
    # C order: the first axis changes least often between consecutive rows
    axes = sorted(varying, key=lambda j: int((np.diff(cols[j]) != 0).sum()))
    values = tuple(np.unique(cols[a]) for a in axes)
    fixed = {j: float(cols[j][0]) for j in machine.joint_names if j not in axes}
    grid = Grid(tuple(axes), values, fixed)
    shape = grid.shape
    return grid, {h: cols[h].reshape(shape) for h in header}
