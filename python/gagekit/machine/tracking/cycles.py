"""Repeated measurements of one observer plan (Sec. 4.3.2): the cycles CSV and its reader."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Union

import numpy as np

from ...errors import FileFormatError, InvalidInputError
from ..model import Machine
from ..observations import _read_table

__all__ = ["Cycles", "read_cycles", "XYZ"]

#: The tracker-reading columns of a cycles file.
XYZ = ("x", "y", "z")
_XYZ = XYZ

@dataclass(frozen=True, eq=False)
class Cycles:
    """Repeated measurements of one plan: commands (n, J), measured (C, n, 3) tracker frame."""

    cycle_ids: tuple
    commands: np.ndarray
    measured: np.ndarray
    joint_names: tuple
    time: Optional[np.ndarray] = None
    temperatures: dict = field(default_factory=dict)  # sensor -> (C,) cycle means
    source: Optional[str] = None


def read_cycles(path: Union[str, Path], machine: Machine) -> Cycles:
    """CSV with ``cycle``, the joint columns, ``x, y, z`` and optional ``time`` and ``temp_*``."""
    header, data = _read_table(path)
    joints = machine.joint_names
    need = ["cycle", *joints, *_XYZ]
    missing = [c for c in need if c not in header]
    if missing:
        raise FileFormatError(f"{path}: missing column(s) {', '.join(missing)} (expected {', '.join(need)}, optional time, temp_*)")
    extra = [c for c in header if c not in need and c != "time" and not c.startswith("temp_")]
    if extra:
        raise FileFormatError(f"{path}: unknown column(s) {', '.join(extra)}")
    if len(data) == 0:
        raise FileFormatError(f"{path}: no data rows")
    col = {c: data[:, header.index(c)] for c in header}
    cyc = col["cycle"]
    if not np.allclose(cyc, np.round(cyc)):
        raise FileFormatError(f"{path}: the cycle column must hold whole numbers")
    ids = sorted({int(round(v)) for v in cyc})
    cmds_all = np.column_stack([col[j] for j in joints])
    xyz = np.column_stack([col[c] for c in _XYZ])
    first = np.round(cyc) == ids[0]
    c0 = cmds_all[first]
    tol = 1e-6 * (np.ptp(machine.ranges, axis=1) + 1.0)
    meas, times, temps = [], [], {s: [] for s in header if s.startswith("temp_")}
    for cid in ids:
        sel = np.round(cyc) == cid
        c = cmds_all[sel]
        if c.shape != c0.shape or not (np.abs(c - c0) <= tol).all():
            raise InvalidInputError(
                f"{path}: cycle {cid} measures different commands from cycle {ids[0]} "
                f"({len(c)} vs {len(c0)} points): every cycle must repeat the same plan in the same order"
            )
        meas.append(xyz[sel])
        if "time" in col:
            times.append(float(col["time"][sel].mean()))
        for s in temps:
            temps[s].append(float(col[s][sel].mean()))
    return Cycles(
        cycle_ids=tuple(ids),
        commands=np.ascontiguousarray(c0),
        measured=np.stack(meas),
        joint_names=tuple(joints),
        time=np.array(times) if times else None,
        temperatures={s: np.array(v) for s, v in temps.items()},
        source=str(path),
    )
