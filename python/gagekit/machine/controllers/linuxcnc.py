"""``linuxcnc``: one file per linear axis for ``[JOINT_n] COMP_FILE`` with ``COMP_FILE_TYPE =
1``: lines ``nominal forward-trim reverse-trim`` in machine units (mm), ascending, at most 256
lines, no comments (LinuxCNC stops reading at the first line that is not three numbers,
``usrmotLoadComp``); between lines the motion controller interpolates linearly. The trim is
the joint's own correction along a line through the ``at`` point (other joints fixed): a
per-axis table cannot carry the cross-axis terms, which the readback shows. The uncertainty
goes to a companion CSV ``joint,nominal,trim,u_trim`` (mm)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional, Sequence, Union

import numpy as np

from ...errors import InvalidInputError
from ..calibration import Calibration
from ..grid import Grid, correction_uncertainty, corrections, grid_predictions, number_text
from ..model import Machine

__all__ = ["LINUXCNC_MAX_LINES", "linuxcnc_paths", "axis_texts", "line_commands", "read_linuxcnc"]

LINUXCNC_MAX_LINES = 256


def linuxcnc_paths(out: Union[str, Path], axes: Sequence[str]) -> list[Path]:
    """One file per axis: OUT's stem + '_' + joint + suffix (``comp.txt`` -> ``comp_X.txt``)."""
    p = Path(out)
    return [p.with_name(f"{p.stem}_{a}{p.suffix}") for a in axes]


def axis_texts(machine: Machine, calibration: Calibration, grid: Grid,
               uncertainty: bool = False) -> tuple[list[str], Optional[str], Optional[np.ndarray]]:
    """One text per axis, and with ``uncertainty`` the companion CSV and every line's u(trim)."""
    spec = {j.name: j for j in machine.joints}
    bad = [a for a in grid.axes if spec[a].kind != "prismatic"]
    if bad:
        raise InvalidInputError(f"linuxcnc: joint '{bad[0]}' is not prismatic (COMP_FILE tables are for linear axes)")
    centre = {a: float(np.median(v)) for a, v in zip(grid.axes, grid.values)}
    texts = []
    rows = ["joint,nominal,trim,u_trim"]
    us = []
    for a, qs in zip(grid.axes, grid.values):
        if len(qs) > LINUXCNC_MAX_LINES:
            raise InvalidInputError(f"linuxcnc: {len(qs)} lines for {a}, LinuxCNC reads at most {LINUXCNC_MAX_LINES} (raise --step)")
        cmds = line_commands(machine, grid, a, qs, centre)
        e, _ = grid_predictions(machine, calibration, cmds, with_uncertainty=False)
        trim = corrections(machine, cmds, e, [a])[:, 0]
        texts.append("".join(f"{q:.6f} {t:.9f} {t:.9f}\n" for q, t in zip(qs, trim)))
        if uncertainty:
            u = correction_uncertainty(machine, calibration, cmds, [a])[:, 0]
            us.append(u)
            rows += [f"{a},{q:.6f},{t:.9f},{number_text(uu)}" for q, t, uu in zip(qs, trim, u)]
    if not uncertainty:
        return texts, None, None
    return texts, "\n".join(rows) + "\n", np.concatenate(us)


def line_commands(machine: Machine, grid: Grid, axis: str, qs: np.ndarray, centre: dict) -> np.ndarray:
    """Commands along ``axis`` with every other joint at ``grid.fixed`` or its grid centre."""
    c = np.empty((len(qs), len(machine.joint_names)))
    for j, name in enumerate(machine.joint_names):
        c[:, j] = grid.fixed.get(name, centre.get(name, 0.0))
    c[:, machine.joint_names.index(axis)] = qs
    return c


def read_linuxcnc(path: Union[str, Path]) -> np.ndarray:
    """(n, 3) triplets as LinuxCNC reads them (stops at the first line that is not three numbers)."""
    rows = []
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        parts = line.split()
        try:
            if len(parts) < 3:
                break
            rows.append([float(parts[0]), float(parts[1]), float(parts[2])])
        except ValueError:
            break
    return np.array(rows, dtype=np.float64).reshape(-1, 3)
