"""Optimal observer plans for a machine tool (Sec. 4.2, 4.3.1; Eqs. 4.3-4.5, 4.7-4.10;
Tables 4.2, 4.3; Sec. 4.3.1: 4 of 80 points unreachable)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Sequence, Union

import numpy as np

from ... import _progress
from ...design.optimal import CRITERIA, search_design
from ...errors import DegenerateGeometryError, InvalidInputError
from ..model import Machine, ModelStructure, halton
from ..observations import write_csv
from .space import ObserverSpace
from .zones import Exclusions, Zone, dissertation_zones

__all__ = ["ObserverPlan", "design_observer", "DEFAULT_CRITERION", "DEFAULT_ZONES", "FULL_SET"]

#: The criterion and zones that predicted best in the simulation study (see README):
#: I (average prediction variance over the workspace), no zones.
DEFAULT_CRITERION = "I"
DEFAULT_ZONES = "none"
#: The quasi-random identification set of Sec. 3.2.1.
FULL_SET = 290


# ------------------------------------------------------------------------------------- plans

@dataclass(frozen=True, eq=False)
class ObserverPlan:
    """An observer plan (Tables 4.2, 4.3): commands (n, J) in machine-file units."""

    machine: str
    joint_names: tuple[str, ...]
    commands: np.ndarray
    criterion: str
    zones: str
    figures: dict
    zone_counts: list
    scaling: dict
    quasi_random: dict
    n_candidates: int
    seed: int

    def write(self, path: Union[str, Path]) -> None:
        """PLAN.csv: one column per joint, one row per measurement point."""
        write_csv(path, list(self.joint_names), self.commands)

    def to_dict(self) -> dict:
        return {
            "machine": self.machine,
            "criterion": self.criterion,
            "zones": self.zones,
            "points": self.commands.tolist(),
            "joint_names": list(self.joint_names),
            **{k: self.figures[k] for k in ("trace", "log_det", "det", "condition_number")},
            "zone_counts": self.zone_counts,
            "column_scaling": self.scaling,
            "quasi_random": self.quasi_random,
            "n_candidates": self.n_candidates,
            "seed": self.seed,
        }


def _quasi_random(space: ObserverSpace, n: int, seed: int, ok=None) -> np.ndarray:
    """n quasi-random commands over the joint ranges, skipping excluded ones."""
    m = space.machine
    take = n
    for _ in range(8):
        c = m.sample_commands(take, seed=seed)
        if ok is not None:
            c = c[ok(space.to_u(c))]
        if len(c) >= n:
            return c[:n]
        take *= 2
    raise DegenerateGeometryError("the exclusions leave almost no commands in the workspace")


def design_observer(
    machine: Machine,
    points: int = 80,
    criterion: str = DEFAULT_CRITERION,
    zones: Union[None, str, Sequence[Zone]] = DEFAULT_ZONES,
    exclude: Optional[Exclusions] = None,
    candidates: int = 20000,
    seed: int = 0,
    starts: int = 4,
    structure: Optional[ModelStructure] = None,
) -> ObserverPlan:
    """An optimal observer plan for ``machine`` (Sec. 4.2): ``points`` commands minimising
    ``criterion`` (A, D, K, E, I) for the identifiable groups, with ``zones``
    (``"none"``, ``"dissertation-8"`` or a list from :func:`read_zones`) and ``exclude``."""
    space = ObserverSpace.of(machine, structure)
    crit = str(criterion).strip().upper()
    if crit not in CRITERIA:
        raise InvalidInputError(f"unknown design criterion {criterion!r}; choose one of A, D, K, E, I")
    if isinstance(points, bool) or not isinstance(points, (int, np.integer)) or points < 1:
        raise InvalidInputError(f"--points must be a positive integer, got {points!r}")
    need = space.structure.rank  # the rule of identify(): one point per identifiable group
    if points < need:
        raise InvalidInputError(
            f"a {points}-point plan cannot be identified: the {need} identifiable groups need a plan of "
            f"at least {need} points"
        )
    if zones is None or zones == "none":
        zone_list, zone_label = [], "none"
    elif zones == "dissertation-8":
        zone_list, zone_label = dissertation_zones(space, points), "dissertation-8"
    elif isinstance(zones, str):
        raise InvalidInputError(f"unknown zones {zones!r}: use none, dissertation-8 or a zones file")
    else:
        zone_list, zone_label = list(zones), "file"
    total = sum(z[2] for z in zone_list)
    if total > points:
        raise InvalidInputError(f"the zones ask for {total} points but the plan has only {points}")

    def ok(u: np.ndarray) -> np.ndarray:
        m = space.in_range(u)
        if exclude is not None:
            m &= exclude.mask(space, u)
        return m

    # Candidates: quasi-random commands over the joint ranges (all reachable by construction).
    n_cand = int(candidates)
    if n_cand < points:
        raise InvalidInputError(f"--candidates must be at least the number of points ({points})")
    u_cand = space.to_u(machine.sample_commands(n_cand, seed=seed + 1))
    extra = [u_cand]
    for k, (zl, zu, cnt, hole) in enumerate(zone_list):
        if cnt:
            per = max(256, n_cand // 16)
            extra.append(zl + halton(per, len(zl), seed + 11 + k) * (zu - zl))
    u_all = np.concatenate(extra)
    keep = ok(u_all)
    if exclude is not None and keep[: len(u_cand)].sum() < max(points, 0.01 * n_cand):
        raise DegenerateGeometryError(
            f"the exclusions leave {int(keep[: len(u_cand)].sum())} of {n_cand} candidate commands: "
            "too few to design from"
        )
    spread = np.zeros(len(u_all), bool)
    spread[: len(u_cand)] = True  # the I criterion averages over the workspace, not the zones' extras
    u_all, spread = u_all[keep], spread[keep]
    with _progress.status(f"searching a {points}-point {crit}-optimal plan over {len(u_all)} candidates"):
        res = search_design(
            space.rows, space.bounds, int(points), crit, zones=zone_list or None, candidates=u_all, seed=seed,
            starts=starts, feasible=ok, refine=True, average_over=spread,
        )
    r = machine.ranges
    commands = np.clip(space.to_commands(res.points), r[:, 0], r[:, 1])  # round-off of Z = (Z+W) - W
    zone_counts = [
        {"zone": z, "count": int((res.zone == z).sum()), "required": int(zone_list[z][2])}
        for z in range(len(zone_list))
    ]
    figures = space.figures(commands)
    qr = {
        "same_size": space.figures(_quasi_random(space, points, seed, ok)),
        f"full_{FULL_SET}": space.figures(_quasi_random(space, FULL_SET, seed, ok)),
    }
    return ObserverPlan(
        machine=machine.name,
        joint_names=tuple(machine.joint_names),
        commands=commands,
        criterion=crit,
        zones=zone_label,
        figures=figures,
        zone_counts=zone_counts,
        scaling=space.scaling,
        quasi_random=qr,
        n_candidates=int(len(u_all)),
        seed=seed,
    )

