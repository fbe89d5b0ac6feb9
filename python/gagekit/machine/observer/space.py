"""The design space of a machine's error observer (Sec. 4.2): design variables, bounds and
scaled model rows.

The design variables are the joint commands; the model is the identifiable groups of
Eq. 3.14 (``Machine.structure()``), one tracker point giving three rows (Eq. 4.9). Columns
are scaled to a common unit: the column of a group whose parameter is in mm/L^p (p = 0 mm,
1 rad, 2 rad/mm) is divided by L^p, L = the machine's length scale (RMS target distance
from the table origin plus tool length): every group is then measured in "mm of error at
the lever arm L", and the columns are of order 1.

When the machine has two parallel prismatic joints (Z and W in the example), their sum is a
design variable ("Z+W": the target's height) and the first of them is implied; zones and
exclusions may use the sum.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from ... import _core
from ...design.optimal import det_from_log
from ..model import Machine, ModelStructure

__all__ = ["ObserverSpace"]


@dataclass(frozen=True, eq=False)
class ObserverSpace:
    """Design variables, bounds and scaled model rows of a machine's observer design."""

    machine: Machine
    structure: ModelStructure
    names: tuple[str, ...]
    pair: Optional[tuple[int, int, float]]  # (replaced joint, other joint, sign)
    length_scale: float
    column_scale: np.ndarray = field(repr=False)

    @classmethod
    def of(cls, machine: Machine, structure: Optional[ModelStructure] = None) -> "ObserverSpace":
        st = structure if structure is not None else machine.structure()
        joints = machine.joints
        names = [j.name for j in joints]
        pair = None
        for a in range(len(joints)):
            for b in range(a + 1, len(joints)):
                ja, jb = joints[a], joints[b]
                if ja.kind == jb.kind == "prismatic":
                    d = float(np.dot(ja.axis, jb.axis))
                    if abs(abs(d) - 1.0) < 1e-9 and pair is None:
                        pair = (a, b, math.copysign(1.0, d))
                        names[a] = f"{ja.name}+{jb.name}" if d > 0 else f"{ja.name}-{jb.name}"
        length = machine.length_scale(machine.sample_commands(2000, seed=0))
        powers = np.array(machine.parameter_length_powers, dtype=float)[list(st.leaders)]
        return cls(machine, st, tuple(names), pair, float(length), length ** (-powers))

    # ---- variables -------------------------------------------------------------------------
    def to_u(self, commands: Any) -> np.ndarray:
        c = self.machine.commands_array(commands)
        u = c.copy()
        if self.pair:
            a, b, s = self.pair
            u[:, a] = c[:, a] + s * c[:, b]
        return u

    def to_commands(self, u: np.ndarray) -> np.ndarray:
        c = np.array(u, dtype=np.float64, copy=True)
        if self.pair:
            a, b, s = self.pair
            c[:, a] = u[:, a] - s * u[:, b]
        return c

    @property
    def bounds(self) -> np.ndarray:
        r = self.machine.ranges.copy()
        if self.pair:
            a, b, s = self.pair
            lo = r[a, 0] + min(s * r[b, 0], s * r[b, 1])
            hi = r[a, 1] + max(s * r[b, 0], s * r[b, 1])
            r[a] = [lo, hi]
        return r

    def in_range(self, u: np.ndarray) -> np.ndarray:
        c = self.to_commands(u)
        r = self.machine.ranges
        tol = 1e-9 * (r[:, 1] - r[:, 0] + 1.0)
        return ((c >= r[:, 0] - tol) & (c <= r[:, 1] + tol)).all(axis=1)

    def columns(self, u: np.ndarray) -> dict:
        """Every name usable in zones and exclusions -> its values (joints and the sum)."""
        c = self.to_commands(u)
        out = {n: c[:, j] for j, n in enumerate(self.machine.joint_names)}
        out.update({n: u[:, j] for j, n in enumerate(self.names)})
        return out

    # ---- model -----------------------------------------------------------------------------
    def rows(self, u: np.ndarray) -> np.ndarray:
        """Scaled design-matrix rows (m, 3, rank) of the groups at design points ``u``."""
        c = self.to_commands(np.atleast_2d(u))
        m = self.structure.reduce(self.machine.design_matrix(c)) * self.column_scale
        return m.reshape(len(c), 3, -1)

    def figures(self, commands: Any) -> dict:
        """tr, log det, det of (M^T M)^-1 and kappa(M) of a plan (scaled columns)."""
        b = self.rows(self.to_u(commands))
        met = _core.design.metrics(np.ascontiguousarray(b.reshape(-1, b.shape[2])))
        ld = float(met.log_det)
        return {
            "points": int(len(b)),
            "trace": float(met.trace),
            "log_det": ld,
            "det": det_from_log(ld),
            "condition_number": float(met.condition_number),
        }

    @property
    def scaling(self) -> dict:
        return {
            "length_scale_mm": self.length_scale,
            "rule": "group column divided by L^p (p = 0 mm, 1 rad, 2 rad/mm): groups in mm of error at lever arm L",
            "groups": len(self.structure.groups),
        }

