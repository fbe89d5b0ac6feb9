"""``fanuc-3d``: FANUC three-dimensional error compensation: compensation vectors (X, Y, Z
amounts to add to the axes) at the nodes of a regular grid over three linear axes,
interpolated trilinearly from the 8 corners of the cell holding the position (FANUC Series
30i-A "Three-dimensional error compensation", A-79351E, calculation of compensation).
Written as an ISO punch tape (``%`` ... ``%``, comments in parentheses) of integer amounts
in detection units (default 0.001 mm, IS-B). The uncertainty goes to a companion CSV
``node,<axes>,c<axis>...,uc<axis>...`` (mm, nodes numbered as on the tape)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Optional, Union

import numpy as np

from ...errors import FileFormatError, InvalidInputError
from ..calibration import Calibration
from ..grid import Grid, correction_uncertainty, corrections, grid_predictions, number_text
from ..model import Machine

__all__ = ["tape_text", "read_fanuc_3d"]


def tape_text(machine: Machine, calibration: Calibration, grid: Grid, stamp: str, increment: float,
              uncertainty: bool = False) -> tuple[str, Optional[str], Optional[np.ndarray]]:
    """The tape, and with ``uncertainty`` the companion CSV and the (n, 3) u of the amounts."""
    spec = {j.name: j for j in machine.joints}
    if len(grid.axes) != 3 or any(spec[a].kind != "prismatic" for a in grid.axes):
        raise InvalidInputError(f"fanuc-3d: needs three linear axes, got {', '.join(grid.axes)} (use --axes X,Y,Z)")
    cmds = grid.commands(machine)
    e, _ = grid_predictions(machine, calibration, cmds, with_uncertainty=False)
    c = corrections(machine, cmds, e, list(grid.axes))
    counts = np.rint(c / increment)
    if np.abs(counts).max(initial=0) > 32767:
        raise InvalidInputError(f"fanuc-3d: a compensation amount exceeds 32767 detection units of {increment:g} mm")
    lines = [
        "%",
        f"(GAGEKIT 3-D ERROR COMPENSATION FOR {machine.name.upper()})",
        f"(CALIBRATION {stamp.upper()})",
        f"(AXES {' '.join(grid.axes)} DETECTION UNIT {increment:g} MM)",
    ]
    for a, v in zip(grid.axes, grid.values):
        lines.append(f"({a} START {v[0]:.4f} INTERVAL {v[1] - v[0]:.4f} POINTS {len(v)})")
    lines.append("(FIXED " + " ".join(f"{k}{v:g}" for k, v in grid.fixed.items()) + ")")
    lines.append(f"(NODES IN C ORDER OF {' '.join(grid.axes)}: N NODE NUMBER, AMOUNTS TO ADD PER AXIS)")
    for k, row in enumerate(counts.astype(np.int64)):
        lines.append(f"N{k + 1}" + "".join(f"{a}{int(x)}" for a, x in zip(grid.axes, row)))
    lines.append("%")
    tape = "\n".join(lines) + "\n"
    if not uncertainty:
        return tape, None, None
    u = correction_uncertainty(machine, calibration, cmds, list(grid.axes))
    idx = [machine.joint_names.index(a) for a in grid.axes]
    header = ["node"] + [f"{a}" for a in grid.axes] + [f"c{a}" for a in grid.axes] + [f"uc{a}" for a in grid.axes]
    data = np.hstack([cmds[:, idx], np.round(counts * increment, 12), u])
    rows = [",".join(header)] + [f"{k + 1}," + ",".join(number_text(v) for v in row) for k, row in enumerate(data)]
    return tape, "\n".join(rows) + "\n", u


def read_fanuc_3d(path: Union[str, Path]):
    """(axes, node values per axis, amounts (shape..., 3) in mm) of a fanuc-3d tape."""
    text = Path(path).read_text(encoding="utf-8").splitlines()
    unit = None
    axes: list = []
    values = []
    rows = []
    for line in text:
        m = re.match(r"\(AXES (.*) DETECTION UNIT (\S+) MM\)", line)
        if m:
            axes = m.group(1).split()
            unit = float(m.group(2))
        m = re.match(r"\((\w+) START (\S+) INTERVAL (\S+) POINTS (\d+)\)", line)
        if m:
            s, d, n = float(m.group(2)), float(m.group(3)), int(m.group(4))
            values.append(s + d * np.arange(n))
        if line.startswith("N"):
            nums = re.findall(r"[A-Z](-?\d+)", line[1:].split(" ")[0] if False else re.sub(r"^N\d+", "", line))
            rows.append([int(v) for v in nums])
    if unit is None or len(values) != 3:
        raise FileFormatError(f"{path}: not a gagekit fanuc-3d tape")
    amounts = np.array(rows, dtype=np.float64).reshape(*[len(v) for v in values], 3) * unit
    return axes, tuple(values), amounts
