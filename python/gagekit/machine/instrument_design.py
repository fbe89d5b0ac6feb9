"""Optimal plans for the instruments other than the tracker (``machine design --instrument``),
by the optimal-design criteria of Ch. 4 (Eqs. 4.3-4.8; I by default) through
:func:`gagekit.optimal_design`.

- ``sphere`` / ``rtest``: the rotary positions at which to probe a sphere fixed at ``sphere``
  (table frame, mm) or to read the R-test nest, for the location errors each rotary axis shows
  there; candidates every ``step`` degrees over the joint's range. The design rows of a
  position are those of :mod:`.instruments` (the location errors and the sphere's position,
  which is unknown too).
- ``ballbar``: which circles: candidate circle centres (quasi-random over the joint ranges
  shrunk by the radius) in each of the planes XY, YZ, ZX, each circle a block of rows (readings
  every 10 deg, both directions averaged, plus the ballbar length), for the identifiable
  groups; the design picks ``points`` circles. A circle enters the search by its 8 strongest
  directions (the search takes at most 8 rows per point).
"""

from __future__ import annotations

import math
from typing import Optional

import numpy as np

from ..errors import InvalidInputError
from .model import Machine

__all__ = ["design_instrument"]


def _rotary(machine: Machine, joint: Optional[str]) -> int:
    rot = [i for i, j in enumerate(machine.joints) if j.kind == "rotary"]
    if not rot:
        raise InvalidInputError(f"machine '{machine.name}' has no rotary axis to probe")
    if joint is None:
        return rot[0]
    if joint not in machine.joint_names or machine.joint_names.index(joint) not in rot:
        raise InvalidInputError(f"--joint {joint}: not a rotary joint of machine '{machine.name}'")
    return machine.joint_names.index(joint)


def design_instrument(
    machine: Machine,
    instrument: str,
    points: int,
    criterion: str = "I",
    sphere: Optional[np.ndarray] = None,
    at: Optional[dict] = None,
    joint: Optional[str] = None,
    step: float = 5.0,
    radius: float = 150.0,
    seed: int = 0,
) -> dict:
    """The plan: for sphere/rtest the rotary positions and their commands, for ballbar the
    circles (plane, centre commands); with the design figures."""
    from ..design import optimal_design

    if points < 1:
        raise InvalidInputError(f"--points must be at least 1, got {points}")
    machine.check_joint_names(at or {}, "--at")
    if instrument in ("sphere", "rtest"):
        return _design_sphere(machine, instrument, points, criterion, sphere, at or {}, joint, step, seed, optimal_design)
    if instrument == "ballbar":
        return _design_ballbar(machine, points, criterion, at or {}, radius, seed, optimal_design)
    raise InvalidInputError(f"--instrument must be sphere, rtest or ballbar, got {instrument!r}")


def _design_sphere(machine, instrument, points, criterion, sphere, at, joint, step, seed, optimal_design) -> dict:
    from .instruments import InstrumentObservations, _rows, location_matrix
    from .simulate_instruments import simulate_sphere

    rj = _rotary(machine, joint)
    name = machine.joint_names[rj]
    lo, hi = machine.joints[rj].range
    if not (math.isfinite(step) and step > 0):
        raise InvalidInputError(f"--step must be a positive angle, got {step}")
    full_turn = hi - lo >= (359.999 if machine.angle_unit == "deg" else 2 * math.pi - 1e-6)
    cand = np.arange(lo, hi + (0 if full_turn else 0.5 * step), step)
    if full_turn:
        cand = cand[cand < lo + (360.0 if machine.angle_unit == "deg" else 2 * math.pi) - 1e-9]
    s = np.asarray(sphere if sphere is not None else [150.0, 400.0, 250.0], dtype=np.float64)
    fixed = {k: v for k, v in at.items() if k != name}
    cmds = simulate_sphere(machine, name, cand, s, fixed, {})
    lmat = location_matrix(machine)
    cols = [k for k in range(lmat.shape[1]) if k // 6 == [i for i, j in enumerate(machine.joints) if j.kind == "rotary"].index(rj)]
    obs = InstrumentObservations(instrument, cmds, np.zeros((len(cmds), 3)) if instrument == "rtest" else None,
                                 np.zeros(len(cmds), int) if instrument == "sphere" else None,
                                 np.eye(3) if instrument == "rtest" else None, 0.001)
    blk = _rows(machine, obs, 0)
    a = np.hstack([blk.n, blk.a @ lmat[:, cols]])  # the sphere (unknown, first) and this axis's location errors
    # keep the columns the instrument can see over all candidates (the others have no effect)
    from .instruments import RANK_RTOL

    norms = np.linalg.norm(a, axis=0)
    keep = []
    for j in range(a.shape[1]):
        trial = a[:, keep + [j]] / np.where(norms[keep + [j]] > 0, norms[keep + [j]], 1.0)
        sv = np.linalg.svd(trial, compute_uv=False)
        if norms[j] > 0 and sv[-1] > 1e3 * RANK_RTOL * sv[0]:
            keep.append(j)
    rows3 = (a[:, keep] / norms[keep]).reshape(len(cand), 3, len(keep))
    index = {float(v): i for i, v in enumerate(cand)}

    def rows(x: np.ndarray) -> np.ndarray:
        return rows3[[index[float(v)] for v in x[:, 0]]]

    res = optimal_design(rows, [[float(cand[0]), float(cand[-1])]], points, criterion, candidates=cand[:, None], seed=seed)
    pos = np.sort(res.points[:, 0])
    chosen = cmds[[index[float(v)] for v in pos]]
    from .instruments import location_names

    unknowns = [["sphere x", "sphere y", "sphere z"][j] if j < 3 else location_names(machine)[cols[j - 3]] for j in keep]
    return {
        "instrument": instrument, "joint": name, "criterion": res.criterion, "positions": pos.tolist(),
        "commands": chosen, "joint_names": machine.joint_names, "sphere": s.tolist(), "unknowns": unknowns,
        "trace": res.trace, "condition_number": res.condition_number, "n_candidates": int(len(cand)),
    }


def _design_ballbar(machine, points, criterion, at, radius, seed, optimal_design) -> dict:
    from .ballbar import PLANES, circle_commands, radial_rows

    if not (math.isfinite(radius) and radius > 0):
        raise InvalidInputError(f"--radius must be positive, got {radius}")
    st = machine.structure()
    names = machine.joint_names
    planes = [p for p, (a, b) in PLANES.items() if a in names and b in names]
    if not planes:
        raise InvalidInputError(f"machine '{machine.name}' has no pair of joints named X, Y, Z for a ballbar circle")
    joints = machine.joints
    r = machine.ranges.copy()
    lo, hi = r[:, 0].copy(), r[:, 1].copy()
    for p in planes:
        for axis in PLANES[p]:
            j = names.index(axis)
            lo[j], hi[j] = r[j, 0] + radius, r[j, 1] - radius
    if np.any(lo > hi):
        raise InvalidInputError(f"--radius {radius} mm does not fit in the joint ranges")
    for k, v in at.items():
        if k in names:
            lo[names.index(k)] = hi[names.index(k)] = v
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x6264]))
    n_cand = 40
    cand = []
    for pi, p in enumerate(planes):
        u = rng.random((n_cand, len(names)))
        c = lo + u * (hi - lo)
        for k, j in enumerate(joints):
            if j.kind == "rotary" and names[k] not in at:
                c[:, k] = 0.0
        cand.append(np.hstack([np.full((n_cand, 1), pi), c]))
    cand = np.vstack(cand)
    t = np.radians(np.arange(0, 360, 10.0))

    def circle_rows(row: np.ndarray) -> np.ndarray:
        cmds = circle_commands(machine, planes[int(row[0])], radius, row[1:], t)
        g, _ = radial_rows(machine, cmds, st.reduce(machine.design_matrix(cmds)))
        g = np.hstack([g, np.ones((len(t), 1))])  # the ballbar length is unknown too
        # the design search takes at most 8 rows per point: the circle's 8 strongest
        # directions (S V^T of its SVD), which carry most of its information
        _, sv, vt = np.linalg.svd(g, full_matrices=False)
        return sv[:8, None] * vt[:8]

    table = np.array([circle_rows(row) for row in cand])
    norms = np.sqrt((table**2).sum(axis=(0, 1)))
    norms[norms == 0] = 1.0
    table = table / norms
    # circles see combinations of the groups only: design for the combinations any circle
    # can see (the row space of all candidates together)
    _, sv, vt = np.linalg.svd(table.reshape(-1, table.shape[2]), full_matrices=False)
    visible = vt[: int((sv > 1e-6 * sv[0]).sum())]
    table = table @ visible.T
    index = {tuple(row): i for i, row in enumerate(cand)}

    def rows(x: np.ndarray) -> np.ndarray:
        return table[[index[tuple(v)] for v in x]]

    res = optimal_design(rows, np.stack([cand.min(axis=0), cand.max(axis=0)], axis=1), points, criterion, candidates=cand, seed=seed)
    circles = [{"plane": planes[int(v[0])], "centre": dict(zip(names, map(float, v[1:])))} for v in res.points]
    return {"instrument": "ballbar", "criterion": res.criterion, "radius": radius, "circles": circles,
            "combinations_seen": int(visible.shape[0]), "groups": int(st.rank),
            "trace": res.trace, "condition_number": res.condition_number, "n_candidates": int(len(cand))}
