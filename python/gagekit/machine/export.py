"""Compensation tables for controllers from an identified error model (Sec. 7.1.1 (3)).

``export(machine, calibration, fmt, out, ...)`` writes one of four formats and reads it back
the way the controller interpolates it, at random commands inside the grid, reporting how
far the interpolated table is from the model (``readback``, um). Parameters: the
minimum-norm parameter vector with the identified group values (Eq. 3.14,
:meth:`ModelStructure.params_from_groups`); any other vector with the same group values has
the same volumetric error everywhere, so the tables do not depend on that choice (the
individual ISO 230-1 error motions of ``isg-csv`` do: they are one of many equivalent
decompositions).

Grid: the named joints (``axes``) over their ranges (or ``limits`` inside them) in equal steps
no longer than ``step`` (default 50 mm, 5 deg) or with ``points`` nodes; every other joint
fixed at ``at`` (default 0 when inside its range, else mid-range).

Formats (units and sources in ``docs/controller-tables.md``):

``grid-csv`` (gagekit's reference)
    Header line, then one row per grid node in C order of ``axes``: the joint columns (file
    units), ``ex, ey, ez`` (predicted volumetric error, table frame, mm, Eq. 3.9), ``c<joint>``
    for each prismatic grid joint (what to add to its command so that the predicted error
    vanishes, first order through the command Jacobian, mm), ``ux, uy, uz`` (standard
    uncertainty of the prediction, mm). Read back by multilinear interpolation.
``isg-csv``
    ISG kernel / Beckhoff TF5280 volumetric compensation, ``ISG_CSV`` file format (Beckhoff
    Information System, TF5280 "ISG CSV format", "Units of measure", "List of parameters
    supported"): whitespace-separated columns under a header line, ``//`` comments, ``#``
    between blocks; offsets in mm, angles in rad, arguments in mm (linear) or degrees
    (rotary); GRID interpolation is linear. One block of location errors (``X0J Y0J Z0J A0J
    B0J C0J`` per exported axis J: the constant errors of the structure between the previous
    exported axis and J, as a small motion in the frame just before J), then one block per
    axis of ISO 230-1 component errors ``EXJ EYJ EZJ EAJ EBJ ECJ`` over its travel (the joint's
    own error motion, Eq. 3.3 / 3.5: in the moving frame of a linear axis, in the fixed frame
    of a rotary axis; constants beyond the last axis are added to its table). Only joints
    named X, Y, Z, A, B or C can be exported (the ISO letters the kernel knows).
``fanuc-3d``
    FANUC three-dimensional error compensation: compensation vectors (X, Y, Z amounts to add
    to the axes) at the nodes of a regular grid over three linear axes, interpolated
    trilinearly from the 8 corners of the cell holding the position (FANUC Series 30i-A
    "Three-dimensional error compensation", A-79351E, calculation of compensation). Written as
    an ISO punch tape (``%`` ... ``%``, comments in parentheses) of integer amounts in
    detection units (default 0.001 mm, IS-B).
``linuxcnc``
    One file per linear axis for ``[JOINT_n] COMP_FILE`` with ``COMP_FILE_TYPE = 1``: lines
    ``nominal forward-trim reverse-trim`` in machine units (mm), ascending, at most 256 lines,
    no comments (LinuxCNC stops reading at the first line that is not three numbers,
    ``usrmotLoadComp``); between lines the motion controller interpolates linearly. The trim
    is the joint's own correction along a line through the ``at`` point (other joints fixed):
    a per-axis table cannot carry the cross-axis terms, which the readback shows.

Uncertainty (``uncertainty=True``, ``--uncertainty``): every table entry is linear in the
identified group values g (e = M_L g, Eq. 3.14; a correction c = -pinv(J) e; the ISO 230-1
error motions of the minimum-norm parameters pinv(C) g), so its standard uncertainty is the
exact law of propagation of the identification's group covariance Sigma (GUM, JCGM 100:2008,
5.1.2; the covariance terms of 5.2.2 Eq. 13): u^2 = a^T Sigma a with a = d entry / d g. Groups
the tracker frame takes (a rigid motion) and groups no instrument saw carry no uncertainty.
Where it goes:

* ``grid-csv``: extra columns ``uc<joint>`` (u of each correction; ``ux, uy, uz`` are always
  written);
* ``isg-csv``, ``fanuc-3d``, ``linuxcnc`` (controller formats with no room for it): a companion
  CSV ``<OUT stem>_u.csv`` beside the table, written in the same all-or-nothing step:
  ``isg-csv``: ``block,axis,argument,name,value,u`` (one row per entry of the file, values as
  written, u in the entry's unit); ``fanuc-3d``: ``node,<axes>,c<axis>...,uc<axis>...`` (mm,
  nodes numbered as on the tape); ``linuxcnc``: ``joint,nominal,trim,u_trim`` (mm).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence, Union

import numpy as np

from ..errors import InvalidInputError
from ._files import write_files_atomically
from .calibration import Calibration
from .controllers import fanuc, grid_csv, isg, linuxcnc
from .controllers.fanuc import read_fanuc_3d
from .controllers.grid_csv import read_grid_csv
from .controllers.isg import ISO_LETTERS, isg_entries, isg_twists, isg_uncertainty, read_isg_csv  # noqa: F401  (re-exported)
from .controllers.linuxcnc import LINUXCNC_MAX_LINES, linuxcnc_paths, read_linuxcnc  # noqa: F401  (re-exported)
from .errormotions import compose
from .grid import (  # noqa: F401  (DEFAULT_STEP, multilinear: re-exported for callers)
    DEFAULT_STEP,
    Grid,
    calibration_parameters,
    correction_uncertainty,
    corrections,
    grid_predictions,
    interpolate_grid,
    make_grid,
    multilinear,
)
from .model import Machine

__all__ = [
    "FORMATS",
    "Grid",
    "ExportResult",
    "make_grid",
    "calibration_parameters",
    "grid_predictions",
    "export",
    "read_grid_csv",
    "read_isg_csv",
    "read_fanuc_3d",
    "read_linuxcnc",
    "correction_uncertainty",
    "isg_uncertainty",
    "companion_path",
]

FORMATS = ("grid-csv", "isg-csv", "fanuc-3d", "linuxcnc")


@dataclass(frozen=True)
class ExportResult:
    """What :func:`export` wrote and how well the file, read back as the controller reads it,
    reproduces the model: ``readback`` max and RMS deviation (um) over ``n`` random commands."""

    format: str
    files: tuple[str, ...]
    grid: Grid
    readback: dict
    parameters: str = "minimum-norm parameter vector of the identified groups (Eq. 3.14)"
    notes: tuple[str, ...] = ()
    #: with ``uncertainty=True``: where it was written and its summary (see the module doc)
    uncertainty: Optional[dict] = None

    def to_dict(self) -> dict:
        d = {
            "format": self.format,
            "files": list(self.files),
            "grid": self.grid.to_dict(),
            "readback": dict(self.readback),
            "parameters": self.parameters,
            "notes": list(self.notes),
        }
        if self.uncertainty is not None:
            d["uncertainty"] = dict(self.uncertainty)
        return d


def default_axes(machine: Machine, fmt: str) -> list[str]:
    """Default grid axes: ``isg-csv`` every joint named with an ISO letter; otherwise, per
    direction x, y, z, the first prismatic joint along it (a redundant axis such as W stays
    fixed: two tables correcting the same direction would add up)."""
    joints = machine.joints
    if fmt == "isg-csv":
        return [j.name for j in joints if j.name in ISO_LETTERS]
    out = []
    for d in range(3):
        for j in joints:
            if j.kind == "prismatic" and abs(j.axis[d]) > 0.999 and j.name not in out:
                out.append(j.name)
                break
    return out


def export(
    machine: Machine,
    calibration: Calibration,
    fmt: str,
    out: Union[str, Path],
    axes: Optional[Sequence[str]] = None,
    step: Any = None,
    points: Any = None,
    at: Optional[Mapping[str, float]] = None,
    limits: Optional[Mapping[str, tuple[float, float]]] = None,
    increment: float = 0.001,
    stamp: str = "",
    check_points: int = 2000,
    seed: int = 0,
    uncertainty: bool = False,
) -> ExportResult:
    """Write a compensation table (see the module docstring) and read it back at
    ``check_points`` random commands inside the grid (seeded); with ``uncertainty`` also
    each entry's standard uncertainty (columns or a companion CSV, see the module doc)."""
    if fmt not in FORMATS:
        raise InvalidInputError(f"unknown format {fmt!r} (choose {', '.join(FORMATS)})")
    if not (math.isfinite(increment) and increment > 0):
        raise InvalidInputError(f"--increment must be a positive number of mm, got {increment}")
    from .._files import output_file

    params = calibration_parameters(machine, calibration)
    grid = make_grid(machine, axes if axes else default_axes(machine, fmt), step, points, at, limits)
    companion = companion_path(out) if uncertainty and fmt != "grid-csv" else None
    targets = linuxcnc_paths(out, grid.axes) if fmt == "linuxcnc" else [Path(out)]
    for p in targets + ([companion] if companion is not None else []):
        output_file(p)  # a bad output path fails before any work
    if companion is not None and companion in targets:
        raise InvalidInputError(f"--out {out}: the uncertainty file {companion} would overwrite the table")
    stamp = stamp or "undated"
    notes: list[str] = []
    extra = None
    if fmt == "grid-csv":
        text, u = grid_csv.table_text(machine, calibration, grid, uncertainty)
        files = {Path(out): text}
        if uncertainty:
            comp = grid_csv.comp_joints(machine, grid)
            cols = [f"uc{j}" for j in comp] if comp else ["ux", "uy", "uz"]
            extra = _u_summary(grid, machine, u, str(out), "columns " + ", ".join(cols),
                               "corrections c" if comp else "predicted error e")
    elif fmt == "isg-csv":
        files = {Path(out): isg.isg_text(machine, calibration, grid, params, stamp)}
        notes.append("ISO 230-1 error motions are one decomposition of the identified groups (minimum-norm parameters)")
        if uncertainty:
            keys, vals, u = isg_uncertainty(machine, calibration, grid)
            files[companion] = isg.companion_text(keys, vals, u)
            lin = np.array([(k[3][1] if k[0] == "component" else k[3][0]) in "XYZ" for k in keys], dtype=bool)
            extra = {"file": str(companion), "quantity": "ISO 230-1 error motions of the file",
                     "columns": "block,axis,argument,name,value,u",
                     "max_mm": float(u[lin].max(initial=0.0)), "max_rad": float(u[~lin].max(initial=0.0))}
            notes.append("the uncertainty of each ISO 230-1 error motion is that of the minimum-norm decomposition")
    elif fmt == "fanuc-3d":
        tape, comp_text, u = fanuc.tape_text(machine, calibration, grid, stamp, increment, uncertainty)
        files = {Path(out): tape}
        if uncertainty:
            files[companion] = comp_text
            extra = _u_summary(grid, machine, u, str(companion), "node,<axes>,c<axis>,uc<axis>", "compensation amounts c")
    else:
        texts, comp_text, u = linuxcnc.axis_texts(machine, calibration, grid, uncertainty)
        files = dict(zip(targets, texts))
        notes.append("per-axis tables hold each joint's own correction along a line through the fixed point")
        if uncertainty:
            files[companion] = comp_text
            extra = {"file": str(companion), "quantity": "own-axis trims", "columns": "joint,nominal,trim,u_trim",
                     "max_mm": float(u.max(initial=0.0)), "rms_mm": float(np.sqrt((u**2).mean())) if len(u) else 0.0}
    if extra is not None:
        extra.update(_U_COMMON)
        left_out = [g.name for g in calibration.groups if g.std is None]
        if left_out:
            extra["not_included"] = left_out
    write_files_atomically(files)
    readback = _readback(machine, calibration, grid, fmt, list(files), check_points, seed)
    return ExportResult(fmt, tuple(str(p) for p in files), grid, readback, notes=tuple(notes), uncertainty=extra)


_U_COMMON = {
    "k": 1,
    "method": "exact linear propagation of the identification's group covariance (GUM 5.1.2, 5.2.2 Eq. 13)",
    "excludes": "groups the tracker frame takes (a rigid motion) and groups no instrument saw (not_included)",
}


def companion_path(out: Union[str, Path]) -> Path:
    """The uncertainty CSV beside a controller table: ``COMP.tap`` -> ``COMP_u.csv``."""
    p = Path(out)
    return p.with_name(f"{p.stem}_u.csv")


def _u_summary(grid: Grid, machine: Machine, u: np.ndarray, file: str, columns: str, quantity: str) -> dict:
    """Largest and RMS u over the nodes, and the node where it is largest (mm)."""
    worst = np.linalg.norm(u, axis=1)
    i = int(np.argmax(worst)) if len(worst) else 0
    node = grid.commands(machine)[i]
    return {"file": file, "quantity": quantity, "columns": columns, "max_mm": float(u.max(initial=0.0)),
            "rms_mm": float(np.sqrt((u**2).mean())) if u.size else 0.0,
            "largest_at": {a: float(node[machine.joint_names.index(a)]) for a in grid.axes}}


def _stats(diff: np.ndarray) -> dict:
    d = np.linalg.norm(np.atleast_2d(diff), axis=1) * 1000.0
    return {"n": int(len(d)), "max_um": float(d.max()), "rms_um": float(np.sqrt((d**2).mean()))}


def _readback(machine: Machine, calibration: Calibration, grid: Grid, fmt: str, files: list, n: int, seed: int) -> dict:
    """Interpolate the written file as the controller does and compare with the model."""
    cmds = grid.random_commands(machine, n, seed)
    e, _ = grid_predictions(machine, calibration, cmds, with_uncertainty=False)
    if fmt == "grid-csv":
        g, tab = read_grid_csv(files[0], machine)
        got = interpolate_grid(g, np.stack([tab["ex"], tab["ey"], tab["ez"]], axis=-1), cmds, machine)
        return {"quantity": "predicted error e", **_stats(got - e)}
    if fmt == "isg-csv":
        got = compose(machine, isg_twists(machine, read_isg_csv(files[0]), cmds), cmds)
        return {"quantity": "predicted error e", **_stats(got - e)}
    if fmt == "fanuc-3d":
        axes, values, amounts = read_fanuc_3d(files[0])
        got = interpolate_grid(Grid(tuple(axes), values, grid.fixed), amounts, cmds, machine)
        want = corrections(machine, cmds, e, axes)
        return {"quantity": "correction c", **_stats(got - want)}
    worst = {}
    centre = {a: float(np.median(v)) for a, v in zip(grid.axes, grid.values)}
    diffs = []
    rng = np.random.default_rng(seed)
    for a, path in zip(grid.axes, files):
        tab = read_linuxcnc(path)
        v = grid.values[grid.axes.index(a)]
        qs = rng.uniform(v[0], v[-1], max(n // len(grid.axes), 1))
        c = linuxcnc.line_commands(machine, grid, a, qs, centre)
        ee, _ = grid_predictions(machine, calibration, c, with_uncertainty=False)
        want = corrections(machine, c, ee, [a])[:, 0]
        got = np.interp(qs, tab[:, 0], tab[:, 1])
        diffs.append(got - want)
        worst[a] = float(np.abs(got - want).max() * 1000.0)
    d = np.concatenate(diffs)[:, None]
    # what per-axis tables leave of the volumetric error anywhere in the grid: e + J dc
    tables = {a: read_linuxcnc(path) for a, path in zip(grid.axes, files)}
    trims = np.stack([np.interp(cmds[:, machine.joint_names.index(a)], t[:, 0], t[:, 1]) for a, t in tables.items()], axis=1)
    idx = [machine.joint_names.index(a) for a in grid.axes]
    jac = machine.command_jacobian(cmds).reshape(-1, 3, len(machine.joint_names))[:, :, idx]
    left = e + np.einsum("nij,nj->ni", jac, trims)
    return {
        "quantity": "own-axis correction along the lines",
        **_stats(d),
        "max_um_per_axis": worst,
        "volumetric_error_left": {"before": _stats(e), "after": _stats(left)},
    }
