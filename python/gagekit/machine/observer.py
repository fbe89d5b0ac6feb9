"""Optimal error observers for a machine tool (Sec. 4.2, 4.3.1) and their simulated worth.

The design variables are the joint commands; the model is the identifiable groups of
Eq. 3.14 (``Machine.structure()``), one tracker point giving three rows (Eq. 4.9). Columns
are scaled to a common unit: the column of a group whose parameter is in mm/L^p (p = 0 mm,
1 rad, 2 rad/mm) is divided by L^p, L = the machine's length scale (RMS target distance
from the table origin plus tool length): every group is then measured in "mm of error at
the lever arm L", and the columns are of order 1.

When the machine has two parallel prismatic joints (Z and W in the example), their sum is a
design variable ("Z+W": the target's height) and the first of them is implied; zones and
exclusions may use the sum. The ``dissertation-8`` zones (Fig. 4.3) cut the box of commanded
(X, Y, Z+W) into 4 equal slices along Y and each slice into a central block (the middle
1/sqrt(2) of the X and Z+W ranges, half the slice's volume) and the annulus around it.

References: Eqs. 4.3-4.5, 4.7-4.10; Tables 4.2, 4.3; Sec. 4.3.1 (4 of 80 points unreachable).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional, Sequence, Union

import numpy as np

from .. import _core, _progress
from ..design.optimal import CRITERIA, search_design
from ..errors import ConfigError, DegenerateGeometryError, FileFormatError, InvalidInputError
from .identify import frame_columns, identify, predict
from .model import Machine, ModelStructure, halton
from .observations import write_csv
from .simulate import TRACKER_SIGMA, Truth, simulate

try:  # Python 3.11+
    import tomllib
except ModuleNotFoundError:  # pragma: no cover
    import tomli as tomllib

__all__ = [
    "ObserverSpace",
    "ObserverPlan",
    "PlanEvaluation",
    "design_observer",
    "evaluate_plan",
    "dissertation_zones",
    "read_zones",
    "read_exclusions",
    "DEFAULT_CRITERION",
    "DEFAULT_ZONES",
]

#: The criterion and zones that predicted best in the simulation study (see README):
#: I (average prediction variance over the workspace), no zones.
DEFAULT_CRITERION = "I"
DEFAULT_ZONES = "none"
#: The quasi-random identification set of Sec. 3.2.1.
FULL_SET = 290


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
        met = _core.design_metrics(np.ascontiguousarray(b.reshape(-1, b.shape[2])))
        ld = float(met["log_det"])
        return {
            "points": int(len(b)),
            "trace": float(met["trace"]),
            "log_det": ld,
            "det": math.exp(ld) if math.isfinite(ld) and ld < 700 else (0.0 if ld < 0 else math.inf),
            "condition_number": float(met["condition_number"]),
        }

    @property
    def scaling(self) -> dict:
        return {
            "length_scale_mm": self.length_scale,
            "rule": "group column divided by L^p (p = 0 mm, 1 rad, 2 rad/mm): groups in mm of error at lever arm L",
            "groups": len(self.structure.groups),
        }


# ------------------------------------------------------------------------------------- zones

Zone = tuple  # (lower (d,), upper (d,), count, hole or None)


def _interval(val: Any, what: str) -> tuple[float, float]:
    """``[lower, upper]``: two finite numbers, lower <= upper (a reversed or NaN box would
    silently select nothing)."""
    if not isinstance(val, (list, tuple)) or len(val) != 2 or any(isinstance(v, (bool, str)) for v in val):
        raise ConfigError(f"{what} must be [lower, upper], got {val!r}")
    try:
        a, z = (float(v) for v in val)
    except (TypeError, ValueError):
        raise ConfigError(f"{what} must be [lower, upper], got {val!r}") from None
    if not (math.isfinite(a) and math.isfinite(z)):
        raise ConfigError(f"{what} = {val!r}: the bounds must be finite numbers")
    if a > z:
        raise ConfigError(f"{what} = {val!r} is reversed: give [lower, upper]")
    return a, z


def _named_box(space: ObserverSpace, spec: dict, what: str) -> tuple[np.ndarray, np.ndarray]:
    b = space.bounds
    lo, hi = b[:, 0].copy(), b[:, 1].copy()
    for key, val in spec.items():
        if key in ("count",):
            continue
        if key not in space.names:
            raise ConfigError(f"{what}: unknown variable '{key}' (use {', '.join(space.names)})")
        a, z = _interval(val, f"{what}: '{key}'")
        j = space.names.index(key)
        lo[j], hi[j] = a, z
    return lo, hi


def dissertation_zones(space: ObserverSpace, points: int) -> list[Zone]:
    """The 8 equal-volume zones of Fig. 4.3, ``points / 8`` each (the remainder to the first)."""
    names = space.names
    ys = [n for n in names if n == "Y"]
    if not ys or space.pair is None or "X" not in names:
        raise ConfigError(
            "dissertation-8 zones need joints X and Y and a redundant pair (Z and W): "
            f"this machine has {', '.join(space.machine.joint_names)}; give a zones file instead"
        )
    iy, ix, iz = names.index("Y"), names.index("X"), space.pair[0]
    b = space.bounds
    counts = [points // 8 + (1 if k < points % 8 else 0) for k in range(8)]
    zones = []
    edges = np.linspace(b[iy, 0], b[iy, 1], 5)
    for s in range(4):
        lo, hi = b[:, 0].copy(), b[:, 1].copy()
        lo[iy], hi[iy] = edges[s], edges[s + 1]
        clo, chi = lo.copy(), hi.copy()
        for j in (ix, iz):
            mid, half = 0.5 * (b[j, 0] + b[j, 1]), 0.5 * (b[j, 1] - b[j, 0]) / math.sqrt(2.0)
            clo[j], chi[j] = mid - half, mid + half
        hole_lo = np.full(len(names), -np.inf)
        hole_hi = np.full(len(names), np.inf)
        hole_lo[[ix, iz]], hole_hi[[ix, iz]] = clo[[ix, iz]], chi[[ix, iz]]
        zones.append((clo, chi, counts[2 * s], None))
        zones.append((lo, hi, counts[2 * s + 1], (hole_lo, hole_hi)))
    return zones


def _toml(path: Union[str, Path], what: str) -> dict:
    from .._files import read_text

    p = Path(path)
    text = read_text(p, f"{what} file (TOML)")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise FileFormatError(f"{p}: not valid TOML ({exc})") from None


def read_zones(path: Union[str, Path], space: ObserverSpace) -> list[Zone]:
    """Zones file: ``[[zone]]`` tables with ``count`` and ``NAME = [lower, upper]`` per variable
    (joint names or the redundant sum, e.g. ``"Z+W"``); unnamed variables span their range."""
    doc = _toml(path, "zones")
    items = doc.get("zone")
    if not isinstance(items, list) or not items:
        raise ConfigError(f"{path}: expected one or more [[zone]] tables")
    zones = []
    for k, z in enumerate(items):
        if not isinstance(z, dict) or "count" not in z:
            raise ConfigError(f"{path}: zone {k + 1} needs a count")
        cnt = z["count"]
        if isinstance(cnt, bool) or not isinstance(cnt, int) or cnt < 0:
            raise ConfigError(f"{path}: zone {k + 1}: count must be a non-negative integer")
        lo, hi = _named_box(space, z, f"{path}: zone {k + 1}")
        zones.append((lo, hi, cnt, None))
    return zones


@dataclass(frozen=True)
class Exclusions:
    """Boxes (over joints or the redundant sum) and single commands a plan must avoid."""

    boxes: tuple = ()
    commands: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    tolerance: float = 0.01

    def mask(self, space: ObserverSpace, u: np.ndarray) -> np.ndarray:
        """True where a design point is usable (not excluded)."""
        ok = np.ones(len(u), bool)
        cols = space.columns(u)
        for box in self.boxes:
            inside = np.ones(len(u), bool)
            for name, (a, z) in box.items():
                inside &= (cols[name] >= a) & (cols[name] <= z)
            ok &= ~inside
        if len(self.commands):
            c = space.to_commands(u)
            r = space.machine.ranges
            half = self.tolerance * (r[:, 1] - r[:, 0])
            for cmd in self.commands:
                ok &= ~(np.abs(c - cmd) <= half).all(axis=1)
        return ok


def read_exclusions(path: Union[str, Path], space: ObserverSpace) -> Exclusions:
    """Exclusions file: ``[[box]]`` tables of ``NAME = [lower, upper]``; and/or
    ``commands = [[...], ...]`` (joint order of the machine file) to avoid, each with a
    margin of ``tolerance`` (fraction of every joint range, default 0.01)."""
    doc = _toml(path, "exclusions")
    boxes = []
    items = doc.get("box", [])
    if isinstance(items, dict):  # a single [box] table
        items = [items]
    if not isinstance(items, list):
        raise ConfigError(f"{path}: box must be given as [[box]] tables, got {items!r}")
    for k, bx in enumerate(items):
        if not isinstance(bx, dict) or not bx:
            raise ConfigError(f"{path}: box {k + 1} is empty")
        spec = {}
        valid = set(space.names) | set(space.machine.joint_names)
        for key, val in bx.items():
            if key not in valid:
                raise ConfigError(f"{path}: box {k + 1}: unknown variable '{key}' (use {', '.join(sorted(valid))})")
            spec[key] = _interval(val, f"{path}: box {k + 1}: '{key}'")
        boxes.append(spec)
    cmds = doc.get("commands", [])
    nj = len(space.machine.joint_names)
    rows_msg = f"{path}: commands must be a list of [{', '.join(space.machine.joint_names)}] rows"
    if not isinstance(cmds, list) or not all(isinstance(r, list) and len(r) == nj for r in cmds):
        raise ConfigError(rows_msg)
    try:
        cmd_arr = np.asarray(cmds, dtype=np.float64).reshape(-1, nj) if cmds else np.empty((0, nj))
    except (TypeError, ValueError):
        raise ConfigError(rows_msg) from None
    if not np.isfinite(cmd_arr).all():
        raise ConfigError(f"{path}: commands must be finite numbers")
    tol = doc.get("tolerance", 0.01)
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not (0 <= tol < 0.5):
        raise ConfigError(f"{path}: tolerance must be a fraction of the joint ranges in [0, 0.5)")
    if not boxes and not len(cmd_arr):
        raise ConfigError(f"{path}: no [[box]] tables and no commands to exclude")
    return Exclusions(tuple(boxes), cmd_arr, float(tol))


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


# ---------------------------------------------------------------------------------- evaluation

@dataclass(frozen=True, eq=False)
class PlanEvaluation:
    """RMS prediction error of the volumetric error over the workspace (um), per plan."""

    plans: dict
    seeds: int
    noise: float
    test_points: int

    def to_dict(self) -> dict:
        return {"plans": self.plans, "seeds": self.seeds, "noise_mm": self.noise, "test_points": self.test_points}


def prediction_rms(machine: Machine, commands: np.ndarray, truths: Sequence[Truth], noise: float, test: np.ndarray,
                   seed: int = 0, structure: Optional[ModelStructure] = None) -> np.ndarray:
    """For each truth: identify from noisy simulated readings at ``commands`` and return the
    RMS (um) over ``test`` of predicted minus true volumetric error, after removing the best
    rigid motion of the table frame (which part set-up takes up and the tracker cannot see)."""
    st = structure if structure is not None else machine.structure()
    p_nom = machine.nominal(test)
    frame = frame_columns(p_nom)
    out = []
    for k, truth in enumerate(truths):
        obs = simulate(machine, truth, commands, noise=noise, seed=seed + 7919 * (k + 1))
        cal = identify(machine, obs, structure=st)
        diff = (predict(machine, cal, test, structure=st) - (machine.positions(test, truth.parameters) - p_nom)).reshape(-1)
        coef, *_ = np.linalg.lstsq(frame, diff, rcond=None)
        res = (diff - frame @ coef).reshape(-1, 3)
        out.append(1000.0 * math.sqrt(float((res**2).sum(axis=1).mean())))
    return np.array(out)


def evaluate_plan(
    machine: Machine,
    plan: Any,
    seeds: int = 20,
    noise: float = TRACKER_SIGMA,
    test_points: int = 2000,
    seed: int = 0,
    compare: bool = True,
) -> PlanEvaluation:
    """Simulation study (issue 7): random machines (Table 3.3 magnitudes), noisy tracker
    readings at the plan's commands, identification, and the RMS prediction error of the
    volumetric error over ``test_points`` quasi-random commands; with ``compare``, the same
    for quasi-random plans of the same size and of 290 points."""
    cmds = machine.commands_array(plan, "plan")
    if isinstance(seeds, bool) or not isinstance(seeds, int) or seeds < 1:
        raise InvalidInputError(f"--seeds must be a positive integer, got {seeds!r}")
    st = machine.structure()
    if len(cmds) < st.rank:
        raise InvalidInputError(
            f"the plan has {len(cmds)} points; identification of the {st.rank} groups needs at least {st.rank} points"
        )
    test = machine.sample_commands(int(test_points), seed=seed + 101)
    truths = [Truth.random(machine, seed=seed + 1000 + s) for s in range(seeds)]

    def summary(c: np.ndarray, label: str) -> dict:
        rms = prediction_rms(machine, c, truths, noise, test, seed=seed, structure=st)
        return {"label": label, "points": int(len(c)), "rms_um": float(np.mean(rms)), "rms_um_std": float(np.std(rms)),
                "rms_um_max": float(np.max(rms))}

    plans = {"plan": summary(cmds, "plan")}
    if compare:
        plans["quasi_random_same_size"] = summary(machine.sample_commands(len(cmds), seed=seed + 3), "quasi-random, same size")
        plans[f"quasi_random_{FULL_SET}"] = summary(machine.sample_commands(FULL_SET, seed=seed + 3), f"quasi-random, {FULL_SET} points")
    return PlanEvaluation(plans=plans, seeds=seeds, noise=noise, test_points=int(test_points))
