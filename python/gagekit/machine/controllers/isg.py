"""``isg-csv``: ISG kernel / Beckhoff TF5280 volumetric compensation, ``ISG_CSV`` file format
(Beckhoff Information System, TF5280 "ISG CSV format", "Units of measure", "List of
parameters supported"): whitespace-separated columns under a header line, ``//`` comments,
``#`` between blocks; offsets in mm, angles in rad, arguments in mm (linear) or degrees
(rotary); GRID interpolation is linear. One block of location errors (``X0J Y0J Z0J A0J B0J
C0J`` per exported axis J: the constant errors of the structure between the previous
exported axis and J, as a small motion in the frame just before J), then one block per axis
of ISO 230-1 component errors ``EXJ EYJ EZJ EAJ EBJ ECJ`` over its travel (the joint's own
error motion, Eq. 3.3 / 3.5: in the moving frame of a linear axis, in the fixed frame of a
rotary axis; constants beyond the last axis are added to its table). Only joints named X, Y,
Z, A, B or C can be exported (the ISO letters the kernel knows). The uncertainty goes to a
companion CSV ``block,axis,argument,name,value,u``."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Union

import numpy as np

from ...errors import FileFormatError, InvalidInputError
from ..calibration import Calibration
from ..errormotions import Twist, element_twists, frames, transport
from ..grid import Grid, number_text
from ..model import JointSpec, Machine
from ..predict import check_calibration

__all__ = ["ISO_LETTERS", "isg_tables", "isg_text", "isg_entries", "isg_uncertainty", "companion_text", "read_isg_csv",
           "isg_twists"]

ISO_LETTERS = ("X", "Y", "Z", "A", "B", "C")


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


def isg_text(machine: Machine, calibration: Calibration, grid: Grid, params: np.ndarray, stamp: str) -> str:
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
    from ..predict import _group_covariance

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


def companion_text(keys: list, vals: np.ndarray, u: np.ndarray) -> str:
    lines = ["block,axis,argument,name,value,u"]
    for (block, axis, arg, name), v, uu in zip(keys, vals, u):
        lines.append(f"{block},{axis},{'' if arg is None else repr(arg)},{name},{number_text(v)},{number_text(uu)}")
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
