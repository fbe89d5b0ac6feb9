"""Simulated ballbar runs and probed-sphere cycles, written from the kinematic model.

Nothing here uses the identification or the ballbar analysis: a reading is computed from the
exact perturbed chain (:meth:`Machine.positions`, Eq. 3.7) or from the nominal chain and an
explicitly displaced rotary axis, so the tests that recover the errors check those codes
against geometry, not against themselves.

- :func:`simulate_ballbar`: a circular test (ISO 230-4) in the plane of two prismatic joints
  about the commands ``at``; the joints may have lost motion (backlash: the joint is b/2 behind
  its command in the direction of travel) and a servo lag (the joint follows its command dt
  late). The pivot is where the actual tool is at ``at``; a reading is the actual distance of
  the tool from the pivot minus the nominal radius.
- :func:`simulate_sphere`: the touch-probe cycle of a sphere fixed on a rotary table
  (KinematicsOpt, CYCLE996 style): for each rotary position, the commands at which the nominal
  tool sits at the sphere's centre when the rotary axis is displaced by ISO 230-7 location
  errors (EXOB, EYOB, EZOB offsets of the axis line, EAOB, EBOB, ECOB tilts), plus noise on the
  found linear commands.
"""

from __future__ import annotations

import math
from typing import Optional

import numpy as np

from .._rotation import rotation_from_vector
from ..errors import InvalidInputError
from .ballbar import PLANES, BallbarRun
from .model import Machine

__all__ = ["simulate_ballbar", "simulate_sphere"]


def _joint(machine: Machine, name: str) -> int:
    if name not in machine.joint_names:
        raise InvalidInputError(f"machine '{machine.name}' has no joint {name} (joints: {', '.join(machine.joint_names)})")
    j = machine.joint_names.index(name)
    if machine.joints[j].kind != "prismatic":
        raise InvalidInputError(f"joint {name} is not prismatic: a ballbar circle needs two linear axes")
    return j


def simulate_ballbar(
    machine: Machine,
    params: np.ndarray,
    plane: str,
    radius: float,
    at: np.ndarray,
    points: int = 720,
    backlash: Optional[dict] = None,
    lag: Optional[dict] = None,
    feed: float = 1000.0,
    noise_um: float = 0.0,
    seed: int = 0,
    directions: tuple = (1, -1),
) -> BallbarRun:
    """A ballbar run of ``points`` readings per direction (+1 ccw, -1 cw) on the machine with
    error parameters ``params``; ``backlash`` {joint: lost motion, mm}, ``lag`` {joint: s},
    ``feed`` mm/min, ``noise_um`` standard deviation of each reading."""
    a, b = (_joint(machine, n) for n in PLANES[plane.upper()])
    at = np.asarray(at, dtype=np.float64).reshape(-1)
    backlash = backlash or {}
    lag = lag or {}
    omega = feed / 60.0 / radius  # rad/s
    pivot = machine.positions(at[None, :], params)[0]
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x6262]))
    angles, devs, dirs = [], [], []
    for s in directions:
        th = 2.0 * math.pi * np.arange(points) / points
        cmds = np.repeat(at[None, :], points, axis=0)
        for j, trig, dtrig in ((a, np.cos, lambda t: -np.sin(t)), (b, np.sin, np.cos)):
            name = machine.joint_names[j]
            delay = lag.get(name, 0.0)
            t_eff = th - s * omega * delay  # where the command was dt ago
            cmds[:, j] = at[j] + radius * trig(t_eff)
            velocity = s * dtrig(th)
            cmds[:, j] -= 0.5 * backlash.get(name, 0.0) * np.sign(np.where(np.abs(velocity) < 1e-12, 0.0, velocity))
        p = machine.positions(cmds, params)
        d = np.linalg.norm(p - pivot, axis=1) - radius
        if noise_um > 0:
            d = d + rng.normal(scale=1e-3 * noise_um, size=d.shape)
        angles.append(np.degrees(th))
        devs.append(1e3 * d)
        dirs.append(np.full(points, s, dtype=np.int8))
    return BallbarRun(np.concatenate(angles), np.concatenate(devs), np.concatenate(dirs), "simulated")


def _axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    return rotation_from_vector(np.asarray(axis, dtype=np.float64) * angle)


def simulate_sphere(
    machine: Machine,
    rotary: str,
    positions_deg: np.ndarray,
    sphere: np.ndarray,
    at: dict,
    location: dict,
    noise_um: float = 0.0,
    seed: int = 0,
    params: Optional[np.ndarray] = None,
) -> np.ndarray:
    """Commands (n, J), file units, at which the probe finds the centre of a sphere fixed at
    ``sphere`` (table frame, mm) for each rotary position, the rotary axis being displaced by
    ``location`` {EXOB.., mm; EAOB.., rad} (ISO 230-7 names with O and the axis letter, e.g.
    EXOB, EZOB, EAOB, ECOB for a B axis). The other rotary joints stay at ``at``, prismatic
    joints not needed to reach the sphere (a redundant one) too. The linear axes are ideal;
    with ``params`` the whole machine has those error parameters instead (the exact chain,
    Eq. 3.7: the actual tool reaches the sphere) and ``location`` must be empty."""
    rj = machine.joint_names.index(rotary)
    spec = machine.joints[rj]
    if spec.kind != "rotary":
        raise InvalidInputError(f"{rotary} is not a rotary joint")
    letter = rotary.upper()
    off = np.array([location.get(f"E{c}O{letter}", 0.0) for c in "XYZ"])
    tilt = np.array([location.get(f"E{c}O{letter}", 0.0) for c in "ABC"])
    axis = np.asarray(spec.axis, dtype=np.float64)
    true_axis = _axis_rotation(tilt / max(np.linalg.norm(tilt), 1e-300), float(np.linalg.norm(tilt))) @ axis if np.any(tilt) else axis
    unit = math.pi / 180.0 if machine.angle_unit == "deg" else 1.0
    base = np.array([at.get(n, 0.5 * (j.range[0] + j.range[1])) for n, j in zip(machine.joint_names, machine.joints)])
    free = [k for k, j in enumerate(machine.joints) if j.kind == "prismatic" and machine.joint_names[k] not in at]
    if len(free) != 3:
        raise InvalidInputError(f"give --at for all but three prismatic joints (free now: {[machine.joint_names[k] for k in free]})")
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x7370]))
    out = []
    if params is not None and location:
        raise InvalidInputError("give either location errors or error parameters, not both")
    for b in np.asarray(positions_deg, dtype=np.float64):
        if params is not None:
            c = base.copy()
            c[rj] = b
            for _ in range(20):  # Newton on the free prismatic joints, exact perturbed chain
                p = machine.positions(c[None, :], params)[0]
                jac = machine.command_jacobian(c[None, :])[:, free]
                step = np.linalg.lstsq(jac, np.asarray(sphere) - p, rcond=None)[0]
                c[free] += step
                if np.abs(step).max() < 1e-13:
                    break
            if noise_um > 0:
                c[free] += rng.normal(scale=1e-3 * noise_um, size=3)
            out.append(c)
            continue
        # a table point S lies, at rotary angle b, where the nominal kinematics at rotary 0
        # would put it: p_base = R_true(-b) (S - e) + e (rotation about the true axis line)
        rot = _axis_rotation(true_axis, -b * unit)
        target = rot @ (np.asarray(sphere) - off) + off
        c = base.copy()
        c[rj] = 0.0
        for _ in range(20):  # Newton on the free prismatic joints, nominal chain at rotary 0
            p = machine.nominal(c[None, :])[0]
            jac = machine.command_jacobian(c[None, :])[:, free]
            step = np.linalg.lstsq(jac, target - p, rcond=None)[0]
            c[free] += step
            if np.abs(step).max() < 1e-13:
                break
        c[rj] = b
        if noise_um > 0:
            c[free] += rng.normal(scale=1e-3 * noise_um, size=3)
        out.append(c)
    return np.array(out)
