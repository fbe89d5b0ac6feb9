"""Accuracy and repeatability of positioning of a numerically controlled axis, ISO 230-2:2014.

Input: laser-interferometer runs, one row per reading, CSV header ``target,direction,cycle,
measured`` (``direction`` ``+`` or ``-``, also ``up``/``down``; ``measured`` the actual
position, mm). The positional deviation is x_ij = measured - target (ISO 230-2 3.1).

Per target i (clause 3): mean unidirectional positional deviations x_i(up), x_i(down) (the
means over the n cycles); mean bidirectional positional deviation x_i = (x_i(up) +
x_i(down)) / 2; reversal value B_i = x_i(up) - x_i(down); estimators of the unidirectional
standard uncertainty s_i = sqrt(sum_j (x_ij - x_i)^2 / (n - 1)); unidirectional
repeatability R_i = 4 s_i; bidirectional repeatability R_i = max(2 s_i(up) + 2 s_i(down) +
|B_i|, R_i(up), R_i(down)).

Axis: B = max |B_i|; mean reversal value B_mean = sum B_i / m; R_up, R_down = max R_i(up),
max R_i(down); R = max R_i; E_up = max x_i(up) - min x_i(up) (E_down likewise); E = max over
both directions - min over both; M = max x_i - min x_i; A_up = max(x_i(up) + 2 s_i(up)) -
min(x_i(up) - 2 s_i(up)) (A_down likewise); A = max(x_i(up) + 2 s_i(up), x_i(down) + 2
s_i(down)) - min(x_i(up) - 2 s_i(up), x_i(down) - 2 s_i(down)). All in mm.

The standard's test has five cycles in each direction; any n >= 2 is accepted (reported as
``cycles``). A target measured in one direction only, unequal cycle counts, repeated
(target, direction, cycle) readings or fewer than two targets are errors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Union

import numpy as np

from ..errors import FileFormatError, InvalidInputError

__all__ = ["Iso230Result", "TargetFigures", "iso230_2", "read_runs"]

_UP = {"+", "up", "u", "forward", "fwd", "\u2191"}
_DOWN = {"-", "down", "d", "backward", "bwd", "\u2193"}


@dataclass(frozen=True)
class TargetFigures:
    """The per-target figures of ISO 230-2 (mm)."""

    target: float
    mean_up: float
    mean_down: float
    mean: float
    s_up: float
    s_down: float
    R_up: float
    R_down: float
    R: float
    B: float

    def to_dict(self) -> dict:
        return dict(self.__dict__)


@dataclass(frozen=True)
class Iso230Result:
    """The axis figures of ISO 230-2:2014 (mm) and the per-target table."""

    targets: tuple[TargetFigures, ...]
    cycles: int
    A: float
    A_up: float
    A_down: float
    E: float
    E_up: float
    E_down: float
    M: float
    R: float
    R_up: float
    R_down: float
    B: float
    B_mean: float
    deviations_up: np.ndarray
    deviations_down: np.ndarray

    def to_dict(self) -> dict:
        keys = ("A", "A_up", "A_down", "E", "E_up", "E_down", "M", "R", "R_up", "R_down", "B", "B_mean")
        return {
            "standard": "ISO 230-2:2014",
            "unit": "mm",
            "n_targets": len(self.targets),
            "cycles": self.cycles,
            **{k: getattr(self, k) for k in keys},
            "targets": [t.to_dict() for t in self.targets],
        }


def read_runs(path: Union[str, Path]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(targets (m,), deviations up (m, n), deviations down (m, n)) from a runs CSV."""
    from .._files import csv_rows, read_text

    p = Path(path)
    text = read_text(p, "interferometer runs")
    rows = [r for _, r in csv_rows(text, p) if r and "".join(r).strip() and not r[0].lstrip().startswith("#")]
    if not rows:
        raise FileFormatError(f"{p}: empty file (expected the header target,direction,cycle,measured)")
    header = [h.strip().lower() for h in rows[0]]
    want = ["target", "direction", "cycle", "measured"]
    missing = [c for c in want if c not in header]
    if missing:
        raise FileFormatError(f"{p}: missing column(s) {', '.join(missing)} (header must be target,direction,cycle,measured)")
    idx = [header.index(c) for c in want]
    readings: dict = {}
    for lineno, r in enumerate(rows[1:], start=2):
        if len(r) != len(header):
            raise FileFormatError(f"{p}, data row {lineno - 1}: {len(r)} values for {len(header)} columns")
        t, d, c, v = (r[i].strip() for i in idx)
        try:
            target, measured = float(t), float(v)
            cycle = float(c)
        except ValueError:
            raise FileFormatError(f"{p}, data row {lineno - 1}: target, cycle and measured must be numbers") from None
        if not (math.isfinite(target) and math.isfinite(measured)) or cycle != int(cycle) or cycle < 1:
            raise InvalidInputError(f"{p}, data row {lineno - 1}: non-finite value or a cycle that is not 1, 2, ...")
        dl = d.lower()
        if dl in _UP:
            direction = "+"
        elif dl in _DOWN:
            direction = "-"
        else:
            raise FileFormatError(f"{p}, data row {lineno - 1}: direction must be + or -, got {d!r}")
        key = (target, direction, int(cycle))
        if key in readings:
            raise InvalidInputError(f"{p}: target {target:g}, direction {direction}, cycle {int(cycle)} is read twice")
        readings[key] = measured - target
    return _arrange(readings, str(p))


def _arrange(readings: dict, source: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    targets = sorted({k[0] for k in readings})
    if len(targets) < 2:
        raise InvalidInputError(f"{source}: {len(targets)} target position(s); ISO 230-2 needs several along the axis")
    cycles = {}
    for t in targets:
        for d in "+-":
            cs = sorted(k[2] for k in readings if k[0] == t and k[1] == d)
            if not cs:
                other = "up (+)" if d == "-" else "down (-)"
                raise InvalidInputError(f"{source}: target {t:g} is measured {other} only; both directions are needed")
            cycles[(t, d)] = cs
    counts = {len(v) for v in cycles.values()}
    if len(counts) != 1:
        detail = ", ".join(f"{t:g}{d}: {len(v)}" for (t, d), v in cycles.items())
        raise InvalidInputError(f"{source}: inconsistent runs, unequal numbers of cycles per target and direction ({detail})")
    n = counts.pop()
    if n < 2:
        raise InvalidInputError(f"{source}: {n} cycle per target and direction; at least 2 are needed (the standard uses 5)")
    up = np.array([[readings[(t, "+", c)] for c in cycles[(t, "+")]] for t in targets])
    down = np.array([[readings[(t, "-", c)] for c in cycles[(t, "-")]] for t in targets])
    return np.array(targets), up, down


def iso230_2(targets, deviations_up, deviations_down) -> Iso230Result:
    """ISO 230-2:2014 figures from deviations (m targets x n cycles) in each direction, mm."""
    t = np.asarray(targets, dtype=np.float64)
    up = np.asarray(deviations_up, dtype=np.float64)
    dn = np.asarray(deviations_down, dtype=np.float64)
    if up.ndim != 2 or up.shape != dn.shape or up.shape[0] != t.shape[0]:
        raise InvalidInputError(f"deviations: expected two (m, n) arrays for {t.shape[0]} targets, got {up.shape} and {dn.shape}")
    m, n = up.shape
    if m < 2 or n < 2:
        raise InvalidInputError(f"need at least 2 targets and 2 cycles, got {m} and {n}")
    if not (np.isfinite(t).all() and np.isfinite(up).all() and np.isfinite(dn).all()):
        raise InvalidInputError("deviations: non-finite values")
    mu, md = up.mean(axis=1), dn.mean(axis=1)
    su, sd = up.std(axis=1, ddof=1), dn.std(axis=1, ddof=1)
    mean = 0.5 * (mu + md)
    b = mu - md
    ru, rd = 4.0 * su, 4.0 * sd
    r = np.maximum(2.0 * su + 2.0 * sd + np.abs(b), np.maximum(ru, rd))
    rows = tuple(
        TargetFigures(float(t[i]), float(mu[i]), float(md[i]), float(mean[i]), float(su[i]), float(sd[i]),
                      float(ru[i]), float(rd[i]), float(r[i]), float(b[i]))
        for i in range(m)
    )
    hi_u, lo_u = mu + 2.0 * su, mu - 2.0 * su
    hi_d, lo_d = md + 2.0 * sd, md - 2.0 * sd
    return Iso230Result(
        targets=rows,
        cycles=n,
        A=float(max(hi_u.max(), hi_d.max()) - min(lo_u.min(), lo_d.min())),
        A_up=float(hi_u.max() - lo_u.min()),
        A_down=float(hi_d.max() - lo_d.min()),
        E=float(max(mu.max(), md.max()) - min(mu.min(), md.min())),
        E_up=float(mu.max() - mu.min()),
        E_down=float(md.max() - md.min()),
        M=float(mean.max() - mean.min()),
        R=float(r.max()),
        R_up=float(ru.max()),
        R_down=float(rd.max()),
        B=float(np.abs(b).max()),
        B_mean=float(b.mean()),
        deviations_up=up,
        deviations_down=dn,
    )
