"""Rotary-axis location corrections as controllers' kinematics take them
(``gagekit machine export --format kinematics``; conventions in docs/controller-tables.md).

From a calibration (tracker, sphere, R-test or a mix) the location errors of each rotary axis
(ISO 230-7: EXOJ, EYOJ, EZOJ offsets of the axis line, EAOJ, EBOJ, ECOJ tilts; see
:mod:`.instruments`) give the axis line in machine coordinates: the joint positions at which
the nominal tool sits on the nominal axis origin (rotary joints at 0, the other joints at
``at`` or mid-range), moved by the command change that follows the location offset. Three files,
written all or nothing, ``OUT`` stem + suffix:

- ``_linuxcnc.hal``: ``setp`` lines for ``xyzbc-trt-kins`` (B and C) or ``xyzac-trt-kins`` (A
  and C), LinuxCNC ``src/emc/kinematics/trtfuncs.c``: the C axis passes through (x-rot-point,
  y-rot-point), the B axis through x = x-rot-point + x-offset, z = z-rot-point + z-offset +
  tool-offset (A: y = y-rot-point + y-offset, z likewise). trtkins assumes exactly perpendicular
  axes: tilts are listed as comments, not representable.
- ``_heidenhain.tab``: rows of a TNC kinematics description in the form KinematicsOpt
  maintains: per rotary axis a ``Trans`` row placing the axis (X, Y, Z mm, machine
  coordinates) and orienting it (SPA, SPB, SPC deg, spatial angles about x, y, z), then the axis
  row itself, then the ``Trans`` row back (the negated translation, angles negated: the
  displacement D of the axis is D Phi D^-1, see :mod:`.instruments`).
- ``_siemens.txt``: 5-axis transformation (TRAFO5) machine data: ``$MC_TRAFO5_PART_OFFSET_1``
  the axis point (mm, machine coordinates) of the table axis and ``$MC_TRAFO5_AXIS1_1`` (first
  rotary axis) / ``$MC_TRAFO5_AXIS2_1`` its unit direction vector, tilts included.

Only location errors the calibration determines are applied; the others are listed as unseen.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Optional, Union

import numpy as np

from .._rotation import rotation_from_vector
from ..errors import InvalidInputError
from .calibration import Calibration
from .model import Machine

__all__ = ["KinematicsExport", "export_kinematics", "rotary_axis_lines"]


@dataclass(frozen=True)
class AxisLine:
    """A rotary axis: nominal and corrected point (machine coordinates, mm), unit direction,
    and its location errors {name: (value, std)} (None for unseen)."""

    joint: str
    nominal_point: dict
    point: dict
    direction: tuple
    location: dict


@dataclass(frozen=True)
class KinematicsExport:
    files: tuple
    axes: tuple

    def to_dict(self) -> dict:
        return {
            "format": "kinematics",
            "files": list(self.files),
            "axes": [
                {"joint": a.joint, "nominal_point_mm": a.nominal_point, "point_mm": a.point, "direction": list(a.direction),
                 "location_errors": {k: ({"value": v[0], "std": v[1]} if v else {"seen": False}) for k, v in a.location.items()}}
                for a in self.axes
            ],
        }


def _location(machine: Machine, cal: Calibration) -> dict:
    from .instruments import _location_from_groups, location_matrix, location_names

    st = machine.structure()
    by_name = {g.name: g for g in cal.groups}
    missing = [g.name for g in st.groups if g.name not in by_name]
    if missing:
        raise InvalidInputError(f"calibration does not match machine '{machine.name}' (no group {missing[0]})")
    g = np.array([by_name[x.name].value for x in st.groups])
    seen = np.array([by_name[x.name].std is not None for x in st.groups])
    cov = np.asarray(cal.covariance) if cal.covariance is not None else np.diag([(by_name[x.name].std or 0.0) ** 2 for x in st.groups])
    vals, std, ok = _location_from_groups(st, location_matrix(machine), g, cov, seen)
    return {n: ((float(v), float(s)) if k else None) for n, v, s, k in zip(location_names(machine), vals, std, ok)}


def rotary_axis_lines(machine: Machine, cal: Calibration, at: Optional[Mapping[str, float]] = None) -> list[AxisLine]:
    """Each rotary axis line, nominal and corrected, in machine coordinates."""
    at = dict(at or {})
    loc = _location(machine, cal)
    joints = machine.joints
    names = machine.joint_names
    for k in at:
        if k not in names:
            raise InvalidInputError(f"--at: machine '{machine.name}' has no joint {k}")
    free = [i for i, j in enumerate(joints) if j.kind == "prismatic" and names[i] not in at][:3]
    if len(free) < 3:
        raise InvalidInputError("kinematics export: three prismatic joints must be free (leave them out of --at)")
    base = np.array([at.get(n, 0.0 if j.kind == "rotary" else 0.5 * (j.range[0] + j.range[1])) for n, j in zip(names, joints)])
    for i in free:
        base[i] = 0.5 * (joints[i].range[0] + joints[i].range[1])
    out = []
    for i, j in enumerate(joints):
        if j.kind != "rotary":
            continue
        c = base.copy()
        c[[r for r, jj in enumerate(joints) if jj.kind == "rotary"]] = 0.0
        for _ in range(30):  # joint positions that put the nominal tool on the axis origin
            p = machine.nominal(c[None, :])[0]
            jac = machine.command_jacobian(c[None, :])[:, free]
            step = np.linalg.lstsq(jac, -p, rcond=None)[0]
            c[free] += step
            if np.abs(step).max() < 1e-12:
                break
        jac = machine.command_jacobian(c[None, :])[:, free]
        e = np.array([(loc[f"E{a}O{j.name}"] or (0.0, 0.0))[0] for a in "XYZ"])
        w = np.array([(loc[f"E{a}O{j.name}"] or (0.0, 0.0))[0] for a in "ABC"])
        dc = np.linalg.lstsq(jac, e, rcond=None)[0]
        nominal = {names[f]: float(c[f]) for f in free}
        point = {names[f]: float(c[f] + d) for f, d in zip(free, dc)}
        direction = tuple(float(v) for v in rotation_from_vector(w) @ np.asarray(j.axis))
        mine = {k: v for k, v in loc.items() if k.endswith("O" + j.name)}
        out.append(AxisLine(j.name, nominal, point, direction, mine))
    if not out:
        raise InvalidInputError(f"machine '{machine.name}' has no rotary axis: nothing for a kinematics export")
    return out


def _fmt(v: float) -> str:
    return f"{v:.6f}"


def _um(loc: Optional[tuple], angle: bool) -> str:
    if loc is None:
        return "not seen"
    s = 1e6 if angle else 1e3
    return f"{s * loc[0]:.3f} +/- {s * loc[1]:.3f} {'urad' if angle else 'um'}"


def _linuxcnc(lines: list[AxisLine], stamp: str, machine: Machine) -> str:
    letters = {a.joint.upper() for a in lines}
    kins = "xyzac-trt-kins" if "A" in letters else "xyzbc-trt-kins"
    out = [f"# gagekit rotary-axis location corrections for LinuxCNC {kins} (trtfuncs.c), machine {machine.name}",
           f"# calibration: {stamp}", "# machine coordinates, mm; trtkins assumes perpendicular axes (tilts below are not applied)"]
    by = {a.joint.upper(): a for a in lines}
    c = by.get("C")
    if c is not None:
        out.append(f"# C axis line: x {c.point.get('X', 0.0):.6f}, y {c.point.get('Y', 0.0):.6f} (EXOC {_um(c.location.get('EXOC'), False)}, "
                   f"EYOC {_um(c.location.get('EYOC'), False)})")
        out.append(f"setp {kins}.x-rot-point {_fmt(c.point.get('X', 0.0))}")
        out.append(f"setp {kins}.y-rot-point {_fmt(c.point.get('Y', 0.0))}")
    xr = c.point.get("X", 0.0) if c is not None else 0.0
    yr = c.point.get("Y", 0.0) if c is not None else 0.0
    for letter, pins in (("B", ("X", "Z")), ("A", ("Y", "Z"))):
        a = by.get(letter)
        if a is None:
            continue
        for axis in pins:
            ref = {"X": xr, "Y": yr, "Z": 0.0}[axis]
            name = f"E{axis}O{a.joint}"
            out.append(f"# {letter} axis line {axis.lower()} = {axis.lower()}-rot-point + {axis.lower()}-offset"
                       f"{' + tool-offset' if axis == 'Z' else ''}: {a.point.get(axis, 0.0):.6f} (nominal {a.nominal_point.get(axis, 0.0):.6f}; "
                       f"{name} {_um(a.location.get(name), False)})")
            out.append(f"setp {kins}.{axis.lower()}-offset {_fmt(a.point.get(axis, 0.0) - ref)}")
    for a in lines:
        tilts = ", ".join(f"{k} {_um(v, True)}" for k, v in a.location.items() if k[1] in "ABC" and k[1] != a.joint.upper())
        out.append(f"# {a.joint} tilts (not representable in trtkins): {tilts}")
    out.append("# with z-rot-point 0: set tool-offset from the tool table as usual; z-offset above includes no tool length")
    return "\n".join(out) + "\n"


def _heidenhain(lines: list[AxisLine], stamp: str, machine: Machine) -> str:
    head = f"{'NR':>3} {'KEY':<6} {'X':>12} {'Y':>12} {'Z':>12} {'SPA':>12} {'SPB':>12} {'SPC':>12}  DOC"
    rows = [f"; gagekit rotary-axis location corrections, machine {machine.name}; calibration: {stamp}",
            "; TNC kinematics description rows (KinematicsOpt form): Trans places the axis, the axis row, Trans back",
            "; X Y Z mm (machine coordinates), SPA SPB SPC deg (spatial angles about x, y, z)", head]
    nr = 0
    for a in lines:
        loc = a.location
        ang = [math.degrees((loc.get(f"E{k}O{a.joint}") or (0.0, 0.0))[0]) for k in "ABC"]
        xyz = [a.point.get(k, 0.0) for k in "XYZ"]
        for key, sgn, doc in (("Trans", 1.0, f"{a.joint} axis position and orientation"), (a.joint, 0.0, f"{a.joint} rotary axis"),
                              ("Trans", -1.0, f"back from the {a.joint} axis")):
            vals = [sgn * v for v in xyz] + [sgn * v for v in ang] if sgn else [0.0] * 6
            rows.append(f"{nr:>3} {key:<6} " + " ".join(f"{v:>12.6f}" if k < 3 else f"{v:>12.7f}" for k, v in enumerate(vals)) + f"  {doc}")
            nr += 1
    return "\n".join(rows) + "\n"


def _siemens(lines: list[AxisLine], stamp: str, machine: Machine) -> str:
    out = [f"; gagekit rotary-axis location corrections, machine {machine.name}; calibration: {stamp}",
           "; 5-axis transformation TRAFO5: axis point (mm, machine coordinates) and unit direction of each table axis"]
    for k, a in enumerate(lines[:2]):
        if k == 0:
            for i, axis in enumerate("XYZ"):
                out.append(f"$MC_TRAFO5_PART_OFFSET_1[{i}]={a.point.get(axis, 0.0):.6f} ; {a.joint} axis point {axis}")
        for i, v in enumerate(a.direction):
            out.append(f"$MC_TRAFO5_AXIS{k + 1}_1[{i}]={v:.9f} ; {a.joint} axis direction")
    return "\n".join(out) + "\n"


def export_kinematics(machine: Machine, cal: Calibration, out: Union[str, Path], at: Optional[Mapping[str, float]] = None,
                      stamp: str = "", uncertainty: bool = False) -> KinematicsExport:
    """Write the three controller files (see the module's doc), all or nothing; with
    ``uncertainty`` a fourth, ``OUT`` stem + ``_u.csv``: ``joint,name,value,std,unit`` of every
    location error applied (std propagated from the group covariance, GUM 5.1.2)."""
    from ._files import write_files_atomically

    lines = rotary_axis_lines(machine, cal, at)
    p = Path(out)
    files = {
        p.with_name(f"{p.stem}_linuxcnc.hal"): _linuxcnc(lines, stamp or "undated", machine),
        p.with_name(f"{p.stem}_heidenhain.tab"): _heidenhain(lines, stamp or "undated", machine),
        p.with_name(f"{p.stem}_siemens.txt"): _siemens(lines, stamp or "undated", machine),
    }
    if uncertainty:
        rows = ["joint,name,value,std,unit"]
        for a in lines:
            for name, v in a.location.items():
                if v is not None:
                    rows.append(f"{a.joint},{name},{v[0]!r},{v[1]!r},{'mm' if name[1] in 'XYZ' else 'rad'}")
        files[p.with_name(f"{p.stem}_u.csv")] = "\n".join(rows) + "\n"
    write_files_atomically(files)
    return KinematicsExport(tuple(str(f) for f in files), tuple(lines))
