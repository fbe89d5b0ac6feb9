"""Command and observation CSV files (Sec. 3.2.1).

An observations file has a header with one column per joint (named as in the machine file,
commands in the file's units: mm, and ``angle_unit`` for rotary joints) and ``x``, ``y``,
``z``: the target measured in the tracker frame, mm. Columns may come in any order; lines
starting with ``#`` are comments. A commands file has the joint columns only (``x, y, z``
are allowed and ignored, so an observations file is also a commands file).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Sequence, Union

import numpy as np

from ..errors import DegenerateGeometryError, FileFormatError, InvalidInputError
from .model import Machine

__all__ = ["Observations", "read_observations", "read_commands", "write_csv"]

_XYZ = ("x", "y", "z")


@dataclass(frozen=True)
class Observations:
    """Commands (n, J) in machine-file units, columns ``joint_names``, and the measured
    target positions (n, 3) in the tracker frame, mm."""

    commands: np.ndarray
    measured: np.ndarray
    joint_names: tuple[str, ...]
    source: Optional[str] = None

    def __post_init__(self) -> None:
        c = np.asarray(self.commands, dtype=np.float64)
        q = np.asarray(self.measured, dtype=np.float64)
        if c.ndim != 2 or c.shape[1] != len(self.joint_names):
            raise InvalidInputError(f"observations: commands must be (n, {len(self.joint_names)}), got {c.shape}")
        if q.shape != (c.shape[0], 3):
            raise InvalidInputError(f"observations: measured positions must be ({c.shape[0]}, 3), got {q.shape}")
        for arr, what in ((c, "command"), (q, "measured coordinate")):
            bad = ~np.isfinite(arr)
            if bad.any():
                i = int(np.argwhere(bad)[0][0])
                raise InvalidInputError(f"{self.source or 'observations'}: point {i} has a non-finite {what}")
        object.__setattr__(self, "commands", np.ascontiguousarray(c))
        object.__setattr__(self, "measured", np.ascontiguousarray(q))

    def __len__(self) -> int:
        return int(self.commands.shape[0])

    def write(self, path: Union[str, Path]) -> None:
        write_csv(path, list(self.joint_names) + list(_XYZ), np.hstack([self.commands, self.measured]))


def _read_table(path: Union[str, Path]) -> tuple[list[str], np.ndarray]:
    from .._files import csv_rows, read_text

    p = Path(path)
    text = read_text(p, "CSV file")
    rows = []
    header: Optional[list[str]] = None
    for lineno, row in csv_rows(text, p):
        if not row or not "".join(row).strip() or row[0].lstrip().startswith("#"):
            continue
        cells = [c.strip() for c in row]
        if header is None:
            header = cells
            dup = {c for c in header if header.count(c) > 1}
            if dup:
                raise FileFormatError(f"{p}, line {lineno}: column '{sorted(dup)[0]}' appears twice in the header")
            continue
        if len(cells) != len(header):
            raise FileFormatError(f"{p}, line {lineno}: {len(cells)} values for {len(header)} columns")
        vals = []
        for name, c in zip(header, cells):
            try:
                vals.append(float(c))
            except ValueError:
                raise FileFormatError(f"{p}, line {lineno}: '{c}' in column {name} is not a number") from None
        rows.append(vals)
    if header is None:
        raise FileFormatError(f"{p}: empty file (expected a header line and data)")
    data = np.array(rows, dtype=np.float64).reshape(len(rows), len(header))
    bad = ~np.isfinite(data)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise InvalidInputError(f"{p}: data row {i + 1} has a non-finite value in column {header[j]}")
    return header, data


def _columns(header: list[str], machine: Machine, path, with_xyz: bool) -> list[int]:
    joints = machine.joint_names
    missing = [c for c in joints + (list(_XYZ) if with_xyz else []) if c not in header]
    if missing:
        raise FileFormatError(
            f"{path}: missing column(s) {', '.join(missing)} (expected {', '.join(joints + list(_XYZ if with_xyz else ()))})"
        )
    allowed = set(joints) | set(_XYZ)
    extra = [c for c in header if c not in allowed]
    if extra:
        raise FileFormatError(
            f"{path}: unknown column(s) {', '.join(extra)}: machine '{machine.name}' has joints {', '.join(joints)}"
        )
    return [header.index(c) for c in joints]


def read_observations(path: Union[str, Path], machine: Machine, warn_range: bool = False) -> Observations:
    """Read an observations CSV for ``machine``: exactly its joint columns and x, y, z.
    Missing or unknown columns, non-numbers and NaN are errors naming the line; with
    ``warn_range``, commands outside the joint ranges give a warning (identify, predict and
    compensate warn anyway)."""
    header, data = _read_table(path)
    idx = _columns(header, machine, path, with_xyz=True)
    if data.shape[0] == 0:
        raise DegenerateGeometryError(f"{path}: no observations")
    obs = Observations(
        commands=data[:, idx],
        measured=data[:, [header.index(c) for c in _XYZ]],
        joint_names=tuple(machine.joint_names),
        source=str(path),
    )
    if warn_range:
        machine.warn_out_of_range(obs.commands, what=str(path))
    return obs


def read_commands(path: Union[str, Path], machine: Machine, warn_range: bool = False) -> np.ndarray:
    """Read a commands CSV for ``machine`` (joint columns; x, y, z ignored)."""
    header, data = _read_table(path)
    idx = _columns(header, machine, path, with_xyz=False)
    if warn_range:
        machine.warn_out_of_range(data[:, idx], what=str(path))
    return np.ascontiguousarray(data[:, idx])


def write_csv(path: Union[str, Path], header: Sequence[str], data: np.ndarray) -> None:
    """Write a CSV with ``header`` and full-precision numbers, atomically."""
    from .._files import atomic_open

    with atomic_open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(list(header))
        for row in np.asarray(data, dtype=np.float64):
            w.writerow([repr(float(v)) for v in row])
