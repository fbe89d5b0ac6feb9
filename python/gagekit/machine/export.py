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
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence, Union

import numpy as np

from ..errors import ConfigError, FileFormatError, InvalidInputError
from ._files import write_files_atomically
from .errormotions import Twist, compose, element_twists, frames, transport
from .calibration import Calibration
from .predict import check_calibration, predict, predict_covariance, predict_uncertainty
from .model import JointSpec, Machine, ShapeSpec

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
ISO_LETTERS = ("X", "Y", "Z", "A", "B", "C")
DEFAULT_STEP = {"prismatic": 50.0, "rotary": 5.0}
LINUXCNC_MAX_LINES = 256
_ROT_NAMES = ("A", "B", "C")
_TRANS_NAMES = ("X", "Y", "Z")


@dataclass(frozen=True)
class Grid:
    """A regular grid over ``axes`` (node values per axis, file units); other joints ``fixed``."""

    axes: tuple[str, ...]
    values: tuple[np.ndarray, ...]
    fixed: dict

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(v) for v in self.values)

    def commands(self, machine: Machine) -> np.ndarray:
        """(N, J) commands at the nodes, C order of ``axes``."""
        mesh = np.meshgrid(*self.values, indexing="ij")
        n = mesh[0].size if mesh else 1
        c = np.empty((n, len(machine.joint_names)))
        for j, name in enumerate(machine.joint_names):
            if name in self.axes:
                c[:, j] = mesh[self.axes.index(name)].reshape(-1)
            else:
                c[:, j] = self.fixed[name]
        return c

    def random_commands(self, machine: Machine, n: int, seed: int) -> np.ndarray:
        """``n`` uniform random commands inside the grid (other joints fixed)."""
        rng = np.random.default_rng(seed)
        c = np.empty((n, len(machine.joint_names)))
        for j, name in enumerate(machine.joint_names):
            if name in self.axes:
                v = self.values[self.axes.index(name)]
                c[:, j] = rng.uniform(v[0], v[-1], n)
            else:
                c[:, j] = self.fixed[name]
        return c

    def to_dict(self) -> dict:
        return {
            "axes": list(self.axes),
            "points": list(self.shape),
            "start": [float(v[0]) for v in self.values],
            "end": [float(v[-1]) for v in self.values],
            "step": [float(v[1] - v[0]) if len(v) > 1 else 0.0 for v in self.values],
            "fixed": dict(self.fixed),
        }


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


# ----- grid ----------------------------------------------------------------------------------
def _per_axis(value: Any, axes: Sequence[str], what: str) -> dict:
    """A number for every axis, or {axis: number}; returns {axis: value or None}."""
    if value is None:
        return {a: None for a in axes}
    if isinstance(value, Mapping):
        unknown = [k for k in value if k not in axes]
        if unknown:
            raise InvalidInputError(f"{what}: '{unknown[0]}' is not one of the grid axes {', '.join(axes)}")
        return {a: value.get(a) for a in axes}
    return {a: value for a in axes}


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


def make_grid(
    machine: Machine,
    axes: Sequence[str],
    step: Any = None,
    points: Any = None,
    at: Optional[Mapping[str, float]] = None,
    limits: Optional[Mapping[str, tuple[float, float]]] = None,
) -> Grid:
    """A regular grid over ``axes`` inside the joint ranges; see the module docstring."""
    names = machine.joint_names
    spec = {j.name: j for j in machine.joints}
    axes = list(axes)
    if not axes:
        raise InvalidInputError("grid: no axes")
    for a in axes:
        if a not in spec:
            raise InvalidInputError(f"grid axis '{a}' is not a joint of machine '{machine.name}' ({', '.join(names)})")
    if len(set(axes)) != len(axes):
        raise InvalidInputError(f"grid axes repeat a joint: {', '.join(axes)}")
    if step is not None and points is not None:
        raise InvalidInputError("give --step or --points, not both")
    steps = _per_axis(step, axes, "--step")
    counts = _per_axis(points, axes, "--points")
    limits = dict(limits or {})
    for k in limits:
        if k not in axes:
            raise InvalidInputError(f"--limits: '{k}' is not one of the grid axes {', '.join(axes)}")
    values = []
    for a in axes:
        j = spec[a]
        lo, hi = j.range
        if a in limits:
            l0, l1 = (float(v) for v in limits[a])
            if not (math.isfinite(l0) and math.isfinite(l1) and l0 < l1):
                raise InvalidInputError(f"--limits {a}: need finite lo < hi, got {l0}:{l1}")
            if l0 < lo - 1e-9 or l1 > hi + 1e-9:
                raise InvalidInputError(f"--limits {a}={l0:g}:{l1:g} is outside the joint range [{lo:g}, {hi:g}]")
            lo, hi = l0, l1
        n = counts[a]
        if n is not None:
            if int(n) != n or n < 2:
                raise InvalidInputError(f"--points for {a} must be an integer >= 2, got {n}")
            n = int(n)
        else:
            s = steps[a] if steps[a] is not None else DEFAULT_STEP[j.kind]
            if not (isinstance(s, (int, float)) and math.isfinite(s) and s > 0):
                raise InvalidInputError(f"--step for {a} must be a positive number, got {s}")
            n = int(math.ceil((hi - lo) / s - 1e-9)) + 1
        if n > 100_000:
            raise InvalidInputError(f"grid axis {a}: {n} nodes is too many (raise --step)")
        values.append(np.linspace(lo, hi, n))
    fixed = {}
    at = dict(at or {})
    for k in at:
        if k not in spec:
            raise InvalidInputError(f"--at: '{k}' is not a joint of machine '{machine.name}' ({', '.join(names)})")
        if k in axes:
            raise InvalidInputError(f"--at: '{k}' is a grid axis; fix only the other joints")
    for name in names:
        if name in axes:
            continue
        lo, hi = spec[name].range
        v = at.get(name, 0.0 if lo <= 0.0 <= hi else 0.5 * (lo + hi))
        v = float(v)
        if not (math.isfinite(v) and lo <= v <= hi):
            raise InvalidInputError(f"--at {name}={v:g} is outside the joint range [{lo:g}, {hi:g}]")
        fixed[name] = v
    size = int(np.prod([len(v) for v in values]))
    if size > 5_000_000:
        raise InvalidInputError(f"the grid has {size} nodes; raise --step or lower --points")
    return Grid(tuple(axes), tuple(values), fixed)


# ----- model ---------------------------------------------------------------------------------
def calibration_parameters(machine: Machine, calibration: Calibration) -> np.ndarray:
    """The minimum-norm parameter vector (P,) with the calibration's group values (Eq. 3.14);
    raises ConfigError when the calibration is not this machine's (:func:`check_calibration`)."""
    c = check_calibration(machine, calibration)
    return np.linalg.pinv(c) @ np.array([g.value for g in calibration.groups])


def corrections(machine: Machine, commands: np.ndarray, errors: np.ndarray, joints: Sequence[str]) -> np.ndarray:
    """(n, k) first-order command corrections: c = -pinv(J[:, joints]) e (command Jacobian)."""
    idx = [machine.joint_names.index(j) for j in joints]
    n = commands.shape[0]
    out = np.empty((n, len(idx)))
    for s in range(0, n, 50_000):
        jac = machine.command_jacobian(commands[s : s + 50_000]).reshape(-1, 3, len(machine.joint_names))[:, :, idx]
        out[s : s + 50_000] = -np.einsum("nij,nj->ni", np.linalg.pinv(jac), errors[s : s + 50_000])
    return out


def correction_uncertainty(machine: Machine, calibration: Calibration, commands: np.ndarray, joints: Sequence[str]) -> np.ndarray:
    """(n, k) standard uncertainty (mm) of the corrections c = -pinv(J[:, joints]) e: with
    P = -pinv(J) and the prediction covariance C_e (:func:`predict_covariance`),
    u(c)^2 = diag(P C_e P^T) (GUM 5.1.2, exact: c is linear in the group values)."""
    st = machine.structure()
    idx = [machine.joint_names.index(j) for j in joints]
    n = commands.shape[0]
    out = np.empty((n, len(idx)))
    for s in range(0, n, 20_000):
        c = commands[s : s + 20_000]
        ce = predict_covariance(machine, calibration, c, structure=st)
        jac = machine.command_jacobian(c).reshape(-1, 3, len(machine.joint_names))[:, :, idx]
        pm = np.linalg.pinv(jac)
        var = np.einsum("nki,nij,nkj->nk", pm, ce, pm)
        out[s : s + 20_000] = np.sqrt(np.clip(var, 0.0, None))
    return out


def grid_predictions(machine: Machine, calibration: Calibration, commands: np.ndarray, with_uncertainty: bool = True):
    """Predicted error (n, 3) and its standard uncertainty (n, 3) (or None), mm, in chunks."""
    st = machine.structure()
    e = np.empty((commands.shape[0], 3))
    u = np.empty((commands.shape[0], 3)) if with_uncertainty else None
    for s in range(0, commands.shape[0], 20_000):
        c = commands[s : s + 20_000]
        e[s : s + 20_000] = predict(machine, calibration, c, structure=st)
        if with_uncertainty:
            u[s : s + 20_000] = predict_uncertainty(machine, calibration, c, structure=st)
    return e, u


def _fmt(v: float) -> str:
    return repr(float(v)) if v != 0.0 else "0.0"


# ----- grid-csv ------------------------------------------------------------------------------
def _comp_joints(machine: Machine, grid: Grid) -> list[str]:
    spec = {j.name: j for j in machine.joints}
    return [a for a in grid.axes if spec[a].kind == "prismatic"]


def _grid_csv(machine: Machine, calibration: Calibration, grid: Grid, uncertainty: bool = False) -> tuple[str, Optional[np.ndarray]]:
    """The grid-csv text, and with ``uncertainty`` the (n, k) u of the corrections (columns ``uc<joint>``)."""
    cmds = grid.commands(machine)
    e, u = grid_predictions(machine, calibration, cmds)
    comp = _comp_joints(machine, grid)
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
    return _csv_text(header, data), (uc if uc is not None else u)


def _csv_text(header: Sequence[str], data: np.ndarray) -> str:
    lines = [",".join(header)]
    lines += [",".join(_fmt(v) for v in row) for row in data]
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


def interpolate_grid(grid: Grid, table: np.ndarray, commands: np.ndarray, machine: Machine) -> np.ndarray:
    """Multilinear interpolation of a (shape..., k) table at commands (n, J): what a grid
    compensation (FANUC 3-D, trilinear) does between the nodes."""
    idx = [machine.joint_names.index(a) for a in grid.axes]
    return multilinear(grid.values, table, commands[:, idx])


def multilinear(values: tuple[np.ndarray, ...], table: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Multilinear interpolation on a regular (rectilinear) grid: ``values`` the ascending
    node coordinates per axis, ``table`` (len(values[0]), ..., len(values[-1]), k...), ``points``
    (n, d) inside the grid. Each point blends the 2^d vertices of its cell with the interior
    division ratios (the trilinear rule of FANUC's A-79351E for d = 3); an axis with one node
    holds that node's value. Points outside the grid are refused."""
    pts = np.asarray(points, dtype=float).reshape(len(points), len(values))
    table = np.asarray(table, dtype=float)
    lo_idx, frac = [], []
    for d, v in enumerate(values):
        v = np.asarray(v, dtype=float)
        x = pts[:, d]
        if np.any((x < v[0]) | (x > v[-1])) or not np.all(np.isfinite(x)):
            raise InvalidInputError(f"interpolation: a point lies outside the grid on axis {d} [{v[0]:g}, {v[-1]:g}]")
        if len(v) == 1:
            lo_idx.append(np.zeros(len(x), dtype=np.intp))
            frac.append(np.zeros(len(x)))
            continue
        i = np.clip(np.searchsorted(v, x, side="right") - 1, 0, len(v) - 2)
        lo_idx.append(i)
        frac.append((x - v[i]) / (v[i + 1] - v[i]))
    out = np.zeros((len(pts),) + table.shape[len(values):])
    for corner in range(1 << len(values)):
        weight = np.ones(len(pts))
        index = []
        for d, v in enumerate(values):
            up = (corner >> d) & 1
            index.append(np.minimum(lo_idx[d] + up, len(v) - 1))
            weight = weight * (frac[d] if up else 1.0 - frac[d])
        out += weight.reshape((-1,) + (1,) * (out.ndim - 1)) * table[tuple(index)]
    return out


# ----- isg-csv -------------------------------------------------------------------------------
def _constant_transform(machine: Machine, command: np.ndarray, start: int, stop: int):
    """Rotation and translation of A_{start+1} ... A_{stop} (elements start..stop-1, 0-based)."""
    fr, _ = frames(machine, command[None, :])
    r0, o0 = fr[start][0][0], fr[start][1][0]
    r1, o1 = fr[stop][0][0], fr[stop][1][0]
    return r0.T @ r1, r0.T @ (o1 - o0)


def isg_tables(machine: Machine, params: np.ndarray, grid: Grid) -> tuple[dict, dict]:
    """ISO 230-1 location errors {axis: 6 values} and component tables {axis: (q (n,), (n, 6))}
    of the exported ``grid.axes`` (values: X, Y, Z in mm then A, B, C in rad)."""
    spec = {j.name: j for j in machine.joints}
    for a in grid.axes:
        if a not in ISO_LETTERS:
            raise InvalidInputError(
                f"isg-csv: joint '{a}' has no ISO 230-1 letter (X, Y, Z, A, B, C); fix it with --at {a}=VALUE"
            )
    index = {e.name: k for k, e in enumerate(machine.elements) if isinstance(e, JointSpec)}
    exported = sorted(grid.axes, key=lambda a: index[a])
    ref = grid.commands(machine)[0]
    tw = element_twists(machine, params, ref[None, :])
    location = {a: np.zeros(6) for a in exported}
    trailing = []  # constant twists after the last exported joint: (frame index, values)
    last = index[exported[-1]]
    for t in tw:
        el = machine.elements[t.index]
        if isinstance(el, JointSpec) and el.name in grid.axes:
            continue
        f = t.index + 1 if t.side == "after" else t.index
        if f > last:
            trailing.append((f, t.values[0]))
            continue
        owner = next(a for a in exported if f <= index[a])
        k = index[owner]
        q, c = _constant_transform(machine, ref, f, k)  # F_k = F_f T, twist at F_f -> F_k: T^-1
        location[owner] += transport(t.values[0], q.T, -q.T @ c)
    components = {}
    for a in exported:
        j = grid.axes.index(a)
        qs = grid.values[j]
        cmds = np.repeat(ref[None, :], len(qs), axis=0)
        cmds[:, machine.joint_names.index(a)] = qs
        own = element_twists(machine, params, cmds)[index[a]].values.copy()
        if a == exported[-1] and trailing:
            after = index[a] + 1
            fr, _ = frames(machine, cmds)
            for f, v in trailing:
                # twist at F_f expressed in F_after (moving frame of the last axis)
                r0, o0 = fr[after]
                r1, o1 = fr[f]
                qm = np.einsum("nji,njk->nik", r0, r1)
                cm = np.einsum("nji,nj->ni", r0, o1 - o0)
                v_after = transport(np.broadcast_to(v, (len(qs), 6)), qm, cm)
                if spec[a].kind == "prismatic":
                    own += v_after
                else:
                    # rotary component tables act before the joint: through A_joint(q)
                    r_b, o_b = fr[index[a]]
                    qj = np.einsum("nji,njk->nik", r_b, r0)
                    cj = np.einsum("nji,nj->ni", r_b, o0 - o_b)
                    own += transport(v_after, qj, cj)
        components[a] = (qs, own)
    return location, components


def _isg_text(machine: Machine, calibration: Calibration, grid: Grid, params: np.ndarray, stamp: str) -> str:
    location, components = isg_tables(machine, params, grid)
    spec = {j.name: j for j in machine.joints}
    out = [
        f"// gagekit ISG_CSV volumetric compensation for machine '{machine.name}'",
        f"// calibration: {stamp}; parameters: minimum-norm vector of the identified groups (Eq. 3.14)",
        "// offsets mm, angles rad; arguments mm (linear) and degrees (rotary); GRID (linear) interpolation",
        "// fixed joints: " + (", ".join(f"{k}={v:g}" for k, v in grid.fixed.items()) or "none"),
        "// location errors: constant structure errors before each axis, small motion in the frame before it",
    ]
    head = []
    vals = []
    for a, v in location.items():
        for name, x in zip(("X", "Y", "Z", "A", "B", "C"), np.concatenate([v[3:], v[:3]])):
            head.append(f"{name}0{a}")
            vals.append(x)
    out.append("  ".join(head))
    out.append("  ".join(f"{x:.12e}" for x in vals))
    for a, (qs, tab) in components.items():
        deg = spec[a].kind == "rotary"
        factor = (180.0 / math.pi if machine.angle_unit == "rad" else 1.0) if deg else 1.0
        kind = "fixed frame (rotary)" if deg else "moving frame (linear)"
        out.append("#")
        out.append(f"// component errors of {a}: ISO 230-1 error motions, {kind}")
        out.append("  ".join([a] + [f"E{n}{a}" for n in ("X", "Y", "Z", "A", "B", "C")]))
        for q, row in zip(qs, tab):
            vals = np.concatenate([row[3:], row[:3]])
            out.append("  ".join([f"{q * factor:.10g}"] + [f"{x:.12e}" for x in vals]))
    return "\n".join(out) + "\n"


def isg_entries(machine: Machine, params: np.ndarray, grid: Grid) -> tuple[list, np.ndarray]:
    """Every number of the ISG_CSV file for ``params``, in the file's order: keys
    (block, axis, argument as written or None, name) and values (mm or rad)."""
    location, components = isg_tables(machine, params, grid)
    spec = {j.name: j for j in machine.joints}
    keys: list = []
    vals: list = []
    for a, v in location.items():
        for name, x in zip(("X", "Y", "Z", "A", "B", "C"), np.concatenate([v[3:], v[:3]])):
            keys.append(("location", a, None, f"{name}0{a}"))
            vals.append(x)
    for a, (qs, tab) in components.items():
        deg = spec[a].kind == "rotary"
        factor = (180.0 / math.pi if machine.angle_unit == "rad" else 1.0) if deg else 1.0
        for q, row in zip(qs, tab):
            for n, x in zip(("X", "Y", "Z", "A", "B", "C"), np.concatenate([row[3:], row[:3]])):
                keys.append(("component", a, float(f"{q * factor:.10g}"), f"E{n}{a}"))
                vals.append(x)
    return keys, np.array(vals, dtype=np.float64)


def isg_uncertainty(machine: Machine, calibration: Calibration, grid: Grid) -> tuple[list, np.ndarray, np.ndarray]:
    """(keys, values, u) of every ISG_CSV entry (:func:`isg_entries`). The entries are linear
    in the group values g through the minimum-norm parameters p = pinv(C) g, so column k of
    their Jacobian is the entries of pinv(C) e_k, and u^2 = diag(A Sigma A^T) (GUM 5.1.2)."""
    from .predict import _group_covariance

    st = machine.structure()
    coef = check_calibration(machine, calibration, st)
    cov = _group_covariance(calibration, st)
    basis = np.linalg.pinv(coef)
    keys, vals = isg_entries(machine, basis @ np.array([g.value for g in calibration.groups]), grid)
    live = [k for k in range(cov.shape[0]) if cov[k, k] > 0.0]
    jac = np.zeros((len(vals), len(live)))
    for col, k in enumerate(live):
        jac[:, col] = isg_entries(machine, basis[:, k], grid)[1]
    sub = cov[np.ix_(live, live)]
    var = np.einsum("ik,kl,il->i", jac, sub, jac) if live else np.zeros(len(vals))
    return keys, vals, np.sqrt(np.clip(var, 0.0, None))


def _isg_companion(keys: list, vals: np.ndarray, u: np.ndarray) -> str:
    lines = ["block,axis,argument,name,value,u"]
    for (block, axis, arg, name), v, uu in zip(keys, vals, u):
        lines.append(f"{block},{axis},{'' if arg is None else repr(arg)},{name},{_fmt(v)},{_fmt(uu)}")
    return "\n".join(lines) + "\n"


def read_isg_csv(path: Union[str, Path]) -> list[tuple[list[str], np.ndarray]]:
    """Blocks of an ISG_CSV file: (header names, (rows, columns) values); ``//`` comments and
    blank lines skipped, ``#`` starts a new block."""
    blocks: list = []
    header = None
    rows: list = []
    for lineno, raw in enumerate(Path(path).read_text(encoding="utf-8").splitlines(), start=1):
        line = raw.split("//", 1)[0].strip()
        if not line:
            continue
        if line.startswith("#"):
            if header is not None:
                blocks.append((header, np.array(rows, dtype=np.float64).reshape(len(rows), len(header))))
            header, rows = None, []
            continue
        cells = line.split()
        if header is None:
            header = cells
            continue
        if len(cells) != len(header):
            raise FileFormatError(f"{path}, line {lineno}: {len(cells)} values for {len(header)} columns")
        rows.append([float(c) for c in cells])
    if header is not None:
        blocks.append((header, np.array(rows, dtype=np.float64).reshape(len(rows), len(header))))
    return blocks


def isg_twists(machine: Machine, blocks, commands: np.ndarray) -> list[Twist]:
    """The twists an ISG_CSV file describes at ``commands`` (file units), interpolated
    linearly (GRID mode) along each axis."""
    index = {e.name: k for k, e in enumerate(machine.elements) if isinstance(e, JointSpec)}
    spec = {j.name: j for j in machine.joints}
    n = commands.shape[0]
    out = []
    for header, data in blocks:
        if all(re.fullmatch(r"[XYZABC]0[XYZABC]", h) for h in header):
            for a in {h[2] for h in header}:
                v = np.zeros(6)
                for h, x in zip(header, data[0]):
                    if h[2] == a:
                        k = "XYZABC".index(h[0])
                        v[k + 3 if k < 3 else k - 3] = x
                out.append(Twist(index[a], "before", np.broadcast_to(v, (n, 6))))
            continue
        a = header[0]
        q = commands[:, machine.joint_names.index(a)]
        if spec[a].kind == "rotary" and machine.angle_unit == "rad":
            q = np.degrees(q)
        v = np.zeros((n, 6))
        for h, col in zip(header[1:], data[:, 1:].T):
            k = "XYZABC".index(h[1])
            v[:, k + 3 if k < 3 else k - 3] = np.interp(q, data[:, 0], col)
        out.append(Twist(index[a], "before" if spec[a].kind == "rotary" else "after", v))
    return out


# ----- fanuc-3d ------------------------------------------------------------------------------
def _fanuc_text(machine: Machine, calibration: Calibration, grid: Grid, stamp: str, increment: float,
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
    rows = [",".join(header)] + [f"{k + 1}," + ",".join(_fmt(v) for v in row) for k, row in enumerate(data)]
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


# ----- linuxcnc ------------------------------------------------------------------------------
def linuxcnc_paths(out: Union[str, Path], axes: Sequence[str]) -> list[Path]:
    """One file per axis: OUT's stem + '_' + joint + suffix (``comp.txt`` -> ``comp_X.txt``)."""
    p = Path(out)
    return [p.with_name(f"{p.stem}_{a}{p.suffix}") for a in axes]


def _linuxcnc_texts(machine: Machine, calibration: Calibration, grid: Grid,
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
        cmds = _line_commands(machine, grid, a, qs, centre)
        e, _ = grid_predictions(machine, calibration, cmds, with_uncertainty=False)
        trim = corrections(machine, cmds, e, [a])[:, 0]
        texts.append("".join(f"{q:.6f} {t:.9f} {t:.9f}\n" for q, t in zip(qs, trim)))
        if uncertainty:
            u = correction_uncertainty(machine, calibration, cmds, [a])[:, 0]
            us.append(u)
            rows += [f"{a},{q:.6f},{t:.9f},{_fmt(uu)}" for q, t, uu in zip(qs, trim, u)]
    if not uncertainty:
        return texts, None, None
    return texts, "\n".join(rows) + "\n", np.concatenate(us)


def _line_commands(machine: Machine, grid: Grid, axis: str, qs: np.ndarray, centre: dict) -> np.ndarray:
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


# ----- export --------------------------------------------------------------------------------
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
        text, u = _grid_csv(machine, calibration, grid, uncertainty)
        files = {Path(out): text}
        if uncertainty:
            comp = _comp_joints(machine, grid)
            cols = [f"uc{j}" for j in comp] if comp else ["ux", "uy", "uz"]
            extra = _u_summary(grid, machine, u, str(out), "columns " + ", ".join(cols),
                               "corrections c" if comp else "predicted error e")
    elif fmt == "isg-csv":
        files = {Path(out): _isg_text(machine, calibration, grid, params, stamp)}
        notes.append("ISO 230-1 error motions are one decomposition of the identified groups (minimum-norm parameters)")
        if uncertainty:
            keys, vals, u = isg_uncertainty(machine, calibration, grid)
            files[companion] = _isg_companion(keys, vals, u)
            lin = np.array([(k[3][1] if k[0] == "component" else k[3][0]) in "XYZ" for k in keys], dtype=bool)
            extra = {"file": str(companion), "quantity": "ISO 230-1 error motions of the file",
                     "columns": "block,axis,argument,name,value,u",
                     "max_mm": float(u[lin].max(initial=0.0)), "max_rad": float(u[~lin].max(initial=0.0))}
            notes.append("the uncertainty of each ISO 230-1 error motion is that of the minimum-norm decomposition")
    elif fmt == "fanuc-3d":
        tape, comp_text, u = _fanuc_text(machine, calibration, grid, stamp, increment, uncertainty)
        files = {Path(out): tape}
        if uncertainty:
            files[companion] = comp_text
            extra = _u_summary(grid, machine, u, str(companion), "node,<axes>,c<axis>,uc<axis>", "compensation amounts c")
    else:
        texts, comp_text, u = _linuxcnc_texts(machine, calibration, grid, uncertainty)
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
        c = _line_commands(machine, grid, a, qs, centre)
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
