"""Optimal designs for any linear model (Sec. 4.1, Eqs. 4.1-4.8).

The model is given as a function ``rows(X)`` that maps an (m, d) array of design
variables to the (m, r, k) design-matrix rows those points produce (Eq. 4.9;
r = 3 for a tracker point, r = 1 for a scalar response). The search is a
multistart point exchange over quasi-random candidates (``gagekit._core``; for D,
I, K and E each start's local optimum is then perturbed and re-optimised a few
times, keeping only improvements), followed by a continuous pattern-search refinement of each point inside its
bounds and zone: ``rows`` is evaluated here, in Python, on the candidates and on
the refinement moves; the combinatorial search runs in Rust on the stacked rows.

Criteria (all minimised):

* ``A``: tr((M^T M)^-1), Eq. 4.4;
* ``D``: det((M^T M)^-1), Eq. 4.3 (searched as its logarithm);
* ``K``: kappa(M) = s_max / s_min, Eq. 4.5 (singular values; ERRATA item 2);
* ``E``: 1 / l_min(M^T M), the worst-determined parameter combination;
* ``I``: average prediction variance over the design space,
  tr(W (M^T M)^-1) with W the mean of B(x)^T B(x) over quasi-random x.

References: dissertation Ch. 4, Eqs. 4.3-4.5 (criteria), 4.7 (design problem),
4.8 (zone constraints); ERRATA items 2 and 7 (Table 4.1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Optional, Sequence

import numpy as np

from .. import _core
from .._util import check_finite
from ..errors import InfeasibleError, InvalidInputError

CRITERIA = ("A", "D", "K", "E", "I")

#: Default number of quasi-random candidates over the whole design space.
DEFAULT_CANDIDATES = 4096
#: Independent starts of the exchange search.
DEFAULT_STARTS = 8

RowsFn = Callable[[np.ndarray], Any]


@dataclass(frozen=True, eq=False)
class DesignResult:
    """An optimal design and its figures (Table 4.1 / 4.2 columns).

    ``trace`` is tr((M^T M)^-1), ``det`` is det((M^T M)^-1) and ``log_det`` its
    natural logarithm (use it when ``det`` underflows), ``condition_number`` is
    kappa(M) = s_max / s_min. ``zone[i]`` is the zone of point i (-1: free).
    """

    points: np.ndarray
    criterion: str
    trace: float
    det: float
    log_det: float
    condition_number: float
    objective: float
    lambda_min: float
    zone: np.ndarray
    n_candidates: int
    start_objectives: tuple = field(default=())

    def to_dict(self) -> dict:
        return {
            "criterion": self.criterion,
            "n_points": int(len(self.points)),
            "points": self.points.tolist(),
            "trace": self.trace,
            "det": self.det,
            "log_det": self.log_det,
            "condition_number": self.condition_number,
            "objective": self.objective,
            "lambda_min": self.lambda_min,
            "zone": [int(z) for z in self.zone],
            "n_candidates": self.n_candidates,
            "start_objectives": list(self.start_objectives),
        }


def optimal_design(
    rows: RowsFn,
    bounds: Any,
    n_points: int,
    criterion: str,
    zones: Optional[Sequence[Any]] = None,
    candidates: Any = None,
    seed: int = 0,
) -> DesignResult:
    """Optimal n-point design for the linear model ``rows`` (Eqs. 4.7, 4.8).

    Parameters
    ----------
    rows
        ``rows(X)`` maps an (m, d) array to the (m, r, k) design-matrix rows
        (an (m, k) result means r = 1).
    bounds
        (d, 2) array of lower and upper bounds of the design variables.
    n_points
        Number of design points (repeats allowed).
    criterion
        ``"A"``, ``"D"``, ``"K"``, ``"E"`` or ``"I"`` (see the module docstring).
    zones
        Optional list of ``(lower, upper, count)``: ``count`` points must lie in
        the box [lower, upper] (Eq. 4.8); the counts may not exceed ``n_points``
        and the remaining points are free.
    candidates
        Optional (m, d) array of allowed points. Given candidates are used as
        they are (no continuous refinement); by default quasi-random candidates
        are generated and the best plan is refined continuously.
    seed
        Seed of the candidates and of the multistart search; the same seed gives
        the same design on any number of threads.

    Returns
    -------
    DesignResult

    Examples
    --------
    Table 4.1: y = p1 x + p2 on [0, 1] with four points.

    >>> r = optimal_design(lambda X: np.stack([X[:, 0], np.ones(len(X))], 1)[:, None, :],
    ...                    [[0.0, 1.0]], 4, "A")
    >>> sorted(r.points[:, 0].tolist()), round(r.trace, 3)
    ([0.0, 0.0, 1.0, 1.0], 1.5)
    """
    return search_design(rows, bounds, n_points, criterion, zones=zones, candidates=candidates, seed=seed)


def search_design(
    rows: RowsFn,
    bounds: Any,
    n_points: int,
    criterion: str,
    zones: Optional[Sequence[Any]] = None,
    candidates: Any = None,
    seed: int = 0,
    *,
    starts: int = DEFAULT_STARTS,
    n_candidates: int = DEFAULT_CANDIDATES,
    feasible: Optional[Callable[[np.ndarray], np.ndarray]] = None,
    refine: Optional[bool] = None,
    average_over: Optional[np.ndarray] = None,
) -> DesignResult:
    """:func:`optimal_design` with the search settings exposed.

    ``feasible(X)`` returns a boolean mask of usable points (for instance to keep
    a plan away from commands a tracker cannot reach); it filters the candidates
    and the refinement moves. ``refine`` defaults to True for generated
    candidates and False for given ones. ``average_over``: a boolean mask of the
    candidates whose mean B^T B defines the I criterion (default: the quasi-random
    sample over the whole design space, or all given candidates).
    """
    crit = _criterion(criterion)
    lo, hi = _bounds(bounds)
    d = len(lo)
    n = _count(n_points, "n_points")
    if n < 1:
        raise InvalidInputError("a plan needs at least one point (n_points >= 1)")
    seed = _count(seed, "seed")
    zone_boxes = _zones(zones, lo, hi, n)

    if candidates is None:
        cand, global_mask = _generate(lo, hi, zone_boxes, max(16, int(n_candidates)), seed)
        do_refine = True if refine is None else bool(refine)
    else:
        cand = _user_candidates(candidates, lo, hi)
        global_mask = np.ones(len(cand), bool)
        do_refine = bool(refine)
    if average_over is not None:
        global_mask = np.asarray(average_over, bool).copy()
        if global_mask.shape != (len(cand),):
            raise InvalidInputError("average_over must be a boolean mask of the candidates")
    if feasible is not None:
        keep = np.asarray(feasible(cand), bool)
        cand, global_mask = cand[keep], global_mask[keep]
    if len(cand) == 0:
        raise InfeasibleError("no candidate point is left in the design space")

    blocks = _blocks(rows, cand, "candidates")
    m, r, k = blocks.shape
    weights = None
    if crit == "I":
        g = blocks[global_mask] if global_mask.any() else blocks
        weights = np.ascontiguousarray(np.einsum("mrk,mrl->kl", g, g) / len(g))

    groups, point_group, zone_of_point = _groups(cand, zone_boxes, n)
    out = _core.design.search(
        np.ascontiguousarray(blocks.reshape(m * r, k)), r, groups, point_group, crit,
        weights=weights, starts=max(1, int(starts)), max_sweeps=50, seed=seed,
    )
    design = np.asarray(out.design, dtype=np.int64)
    points = cand[design].copy()
    point_blocks = blocks[design].copy()
    if do_refine:
        points, point_blocks = _refine(rows, points, point_blocks, zone_of_point, zone_boxes, lo, hi,
                                       crit, weights, feasible, len(cand) ** (1.0 / d))
    met = _core.design.metrics(np.ascontiguousarray(point_blocks.reshape(n * r, k)), weights=weights)
    return _result(points, crit, met, zone_of_point, len(cand), out.start_objectives)


# ----------------------------------------------------------------------------- parsing

def _criterion(criterion: Any) -> str:
    c = str(criterion).strip().upper()
    if c not in CRITERIA:
        raise InvalidInputError(f"unknown design criterion {criterion!r}; choose one of A, D, K, E, I")
    return c


def _count(v: Any, what: str) -> int:
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
        raise InvalidInputError(f"{what} must be an integer, got {v!r}")
    return int(v)


def _bounds(bounds: Any) -> tuple[np.ndarray, np.ndarray]:
    try:
        b = np.asarray(bounds, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"bounds: cannot be read as numbers ({exc})") from None
    if b.ndim == 1 and b.shape == (2,):
        b = b[None, :]
    if b.ndim != 2 or b.shape[1] != 2 or b.shape[0] == 0:
        raise InvalidInputError(f"bounds: expected a (d, 2) array of [lower, upper], got shape {b.shape}")
    if not np.isfinite(b).all():
        raise InvalidInputError("bounds: every bound must be a finite number")
    bad = np.nonzero(b[:, 0] > b[:, 1])[0]
    if len(bad):
        i = int(bad[0])
        raise InvalidInputError(f"bounds: variable {i} has lower {b[i, 0]} > upper {b[i, 1]}")
    return b[:, 0].copy(), b[:, 1].copy()


def _zones(zones: Any, lo: np.ndarray, hi: np.ndarray, n: int) -> list[tuple[np.ndarray, np.ndarray, int]]:
    """Zones clipped to the bounds (zones with count 0 are kept but take no point)."""
    if zones is None:
        return []
    d = len(lo)
    out = []
    total = 0
    for z, spec in enumerate(zones):
        hole = None
        try:
            if len(spec) == 4:  # internal: (lower, upper, count, (hole_lower, hole_upper))
                zl, zu, cnt, hole = spec
            else:
                zl, zu, cnt = spec
        except (TypeError, ValueError):
            raise InvalidInputError(f"zone {z}: expected (lower, upper, count), got {spec!r}") from None
        try:
            zl = np.broadcast_to(np.asarray(zl, dtype=np.float64), (d,)).copy()
            zu = np.broadcast_to(np.asarray(zu, dtype=np.float64), (d,)).copy()
        except (TypeError, ValueError):
            raise InvalidInputError(f"zone {z}: lower and upper must each have {d} numbers") from None
        cnt = _count(cnt, f"zone {z} count")
        if cnt < 0:
            raise InvalidInputError(f"zone {z}: negative count {cnt}")
        if not (np.isfinite(zl).all() and np.isfinite(zu).all()):
            raise InvalidInputError(f"zone {z}: bounds must be finite")
        cl, cu = np.maximum(zl, lo), np.minimum(zu, hi)
        if (cl > cu).any():
            raise InfeasibleError(
                f"zone {z} [{_fmt(zl)}, {_fmt(zu)}] does not overlap the design space [{_fmt(lo)}, {_fmt(hi)}]"
            )
        total += cnt
        if hole is not None:
            hole = (np.asarray(hole[0], dtype=np.float64), np.asarray(hole[1], dtype=np.float64))
        out.append((cl, cu, cnt, hole))
    if total > n:
        raise InvalidInputError(f"the zones ask for {total} points but the plan has only {n}")
    return out


def _fmt(v: np.ndarray) -> str:
    return "(" + ", ".join(f"{x:g}" for x in v) + ")"


def _user_candidates(candidates: Any, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    d = len(lo)
    try:
        c = np.asarray(candidates, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"candidates: cannot be read as numbers ({exc})") from None
    if c.ndim == 1 and d == 1:
        c = c[:, None]
    if c.ndim != 2 or c.shape[1] != d:
        raise InvalidInputError(f"candidates: expected an (m, {d}) array, got shape {c.shape}")
    if len(c) == 0:
        raise InvalidInputError("candidates: the array is empty")
    check_finite(c, "candidates")
    tol = 1e-12 * np.maximum(1.0, np.abs(np.concatenate([lo, hi])).max())
    out = ((c < lo - tol) | (c > hi + tol)).any(axis=1)
    if out.any():
        i = int(np.argmax(out))
        raise InvalidInputError(f"candidates: point {i} {_fmt(c[i])} lies outside the bounds")
    return np.ascontiguousarray(np.clip(c, lo, hi))


def _corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    d = len(lo)
    if d > 10:
        return np.empty((0, d))
    bits = (np.arange(2**d)[:, None] >> np.arange(d)) & 1
    return np.where(bits == 1, hi, lo)


def _scaled(n: int, lo: np.ndarray, hi: np.ndarray, seed: int) -> np.ndarray:
    u = np.asarray(_core.design.halton(n, len(lo), seed))
    return lo + u * (hi - lo)


def _generate(lo, hi, zone_boxes, n_cand, seed) -> tuple[np.ndarray, np.ndarray]:
    """Quasi-random candidates over the bounds and inside each zone, plus box corners.

    Returns the candidates and a mask of those spread over the whole design space
    (the sample that defines the I criterion's average).
    """
    parts = [_scaled(n_cand, lo, hi, seed + 1), _corners(lo, hi)]
    used = sum(1 for z in zone_boxes if z[2] > 0)
    per_zone = max(256, n_cand // max(1, 2 * used))
    for z, (zl, zu, cnt, _) in enumerate(zone_boxes):
        if cnt == 0:
            continue
        parts.append(_scaled(per_zone, zl, zu, seed + 2 + z))
        parts.append(_corners(zl, zu))
    cand = np.ascontiguousarray(np.concatenate(parts))
    mask = np.zeros(len(cand), bool)
    mask[:n_cand] = True
    return cand, mask


def _blocks(rows: RowsFn, X: np.ndarray, what: str) -> np.ndarray:
    """``rows(X)`` as a finite float64 (m, r, k) array."""
    out = rows(X)
    try:
        b = np.asarray(out, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"rows(X) did not return numbers ({exc})") from None
    if b.ndim == 2:
        b = b[:, None, :]
    if b.ndim != 3 or b.shape[0] != len(X):
        raise InvalidInputError(
            f"rows(X) must return an (m, r, k) array for m = {len(X)} points, got shape {b.shape}"
        )
    if b.shape[1] == 0 or b.shape[2] == 0:
        raise InvalidInputError(f"rows(X) returned an empty block of shape {b.shape[1:]}")
    bad = ~np.isfinite(b).all(axis=(1, 2))
    if bad.any():
        i = int(np.argmax(bad))
        raise InvalidInputError(f"rows(X) is not finite at {what} point {i} {_fmt(X[i])}")
    return np.ascontiguousarray(b)


def _inside(X: np.ndarray, zl: np.ndarray, zu: np.ndarray) -> np.ndarray:
    tol = 1e-12 * np.maximum(1.0, np.abs(np.concatenate([zl, zu])).max())
    return ((X >= zl - tol) & (X <= zu + tol)).all(axis=1)


def _in_zone(X: np.ndarray, zone) -> np.ndarray:
    """Inside the zone's box and not strictly inside its hole (if any)."""
    zl, zu, _, hole = zone
    m = _inside(X, zl, zu)
    if hole is not None:
        m &= ~((X > hole[0]) & (X < hole[1])).all(axis=1)
    return m


def _groups(cand: np.ndarray, zone_boxes, n: int):
    groups, point_group, zone_of_point = [], [], []
    for z, (zl, zu, cnt, hole) in enumerate(zone_boxes):
        if cnt == 0:
            continue
        members = np.nonzero(_in_zone(cand, zone_boxes[z]))[0].astype(np.int64)
        if len(members) == 0:
            raise InfeasibleError(f"zone {z} [{_fmt(zl)}, {_fmt(zu)}] contains no usable candidate point")
        groups.append(members)
        point_group += [len(groups) - 1] * cnt
        zone_of_point += [z] * cnt
    free = n - len(point_group)
    if free:
        groups.append(np.arange(len(cand), dtype=np.int64))
        point_group += [len(groups) - 1] * free
        zone_of_point += [-1] * free
    return groups, point_group, np.asarray(zone_of_point, dtype=np.int64)


# ----------------------------------------------------------------------------- refinement

#: The refinement stops when the last STALL_ROUNDS rounds improved the criterion by less than
#: its stall tolerance (relative). The last rounds of a compass search creep: on the 80-point
#: machine plans a tolerance of 1e-6 took 2-5 times as long for gains under 0.05 %.
STALL_ROUNDS = 10


def _stall_tol(crit: str) -> float:
    """Relative stall tolerance: 1e-5 for the smooth criteria (A, D, I: the points still reach
    interior optima to ~1e-4 of the range), 1e-4 for K and E, which depend on the extreme
    eigenvalues only and creep longest."""
    return 1e-4 if crit in ("K", "E") else 1e-5


def _refine_sweeps(crit: str) -> int:
    """Exchange sweeps per refinement round. For K and E, re-sweeping within a round chases
    whichever extreme eigenvalue is active; one sweep, then a new compass step, reached lower
    values 3-5 times faster on the machine plans. A, D and I sweep to the round's optimum."""
    return 1 if crit in ("K", "E") else 50


def _refine(rows, points, blocks, zone_of_point, zone_boxes, lo, hi, crit, weights, feasible, per_axis):
    """Compass search of every point inside its box (bounds or zone).

    Each round proposes x_i +/- h_i e_j for every active point and variable (clipped
    to the point's box), evaluates ``rows`` on all proposals at once and lets the Rust
    exchange move each point to its best proposal. Each point has its own step: it
    doubles (up to the initial step) when the point moved and halves when it did not,
    and a point whose step is below the resolution stops proposing. The search stops
    when the last STALL_ROUNDS rounds together improved the criterion by less than
    its stall tolerance (relative, see `_stall_tol`).
    """
    n, d = points.shape
    r, k = blocks.shape[1:]
    box_lo = np.array([zone_boxes[z][0] if z >= 0 else lo for z in zone_of_point])
    box_hi = np.array([zone_boxes[z][1] if z >= 0 else hi for z in zone_of_point])
    span = hi - lo
    h0 = np.minimum(0.25, 2.0 / max(per_axis, 1.0)) * span
    h_min = 1e-7 * np.maximum(span, 1e-300)
    scale = np.ones(n)  # step of point i: scale[i] * h0
    active = ~(h0 <= h_min).all() & np.ones(n, bool)
    history: list[float] = []
    for _ in range(400):
        if not active.any():
            break
        if len(history) > STALL_ROUNDS and history[-STALL_ROUNDS - 1] - history[-1] <= _stall_tol(crit) * abs(history[-1]):
            break
        act = np.nonzero(active)[0]
        steps = np.concatenate([np.diag(h0), -np.diag(h0)])  # (2d, d)
        prop = points[act, None, :] + scale[act, None, None] * steps[None]
        prop = np.clip(prop, box_lo[act, None, :], box_hi[act, None, :])
        owner = np.repeat(act, 2 * d)
        prop = prop.reshape(-1, d)
        keep = (np.abs(prop - points[owner]) > 0).any(axis=1)
        for z, zone in enumerate(zone_boxes):
            if zone[3] is not None:
                sel = keep & (zone_of_point[owner] == z)
                keep[sel] = _in_zone(prop[sel], zone)
        if feasible is not None and keep.any():
            keep[keep] = np.asarray(feasible(prop[keep]), bool)
        prop, owner = prop[keep], owner[keep]
        moved = np.zeros(n, bool)
        if len(prop):
            pb = _blocks(rows, prop, "refinement")
            all_blocks = np.concatenate([blocks, pb])
            order = np.argsort(owner, kind="stable")
            starts_at = np.searchsorted(owner[order], np.arange(n + 1))
            groups = [np.concatenate([[i], n + order[starts_at[i]:starts_at[i + 1]]]).astype(np.int64)
                      for i in range(n)]
            out = _core.design.search(
                np.ascontiguousarray(all_blocks.reshape(-1, k)), r, groups, list(range(n)), crit,
                weights=weights, starts=1, max_sweeps=_refine_sweeps(crit), seed=0, initial=list(range(n)),
            )
            chosen = np.asarray(out.design)
            moved = chosen != np.arange(n)
            history.append(float(out.objective))
            if moved.any():
                allp = np.concatenate([points, prop])
                points, blocks = allp[chosen].copy(), all_blocks[chosen].copy()
        scale[~moved] /= 2
        scale[moved] = np.minimum(2 * scale[moved], 1.0)  # a point on the move speeds up
        active &= ~((scale[:, None] * h0[None]) <= h_min[None]).all(axis=1)
    return points, blocks


def det_from_log(log_det: float) -> float:
    """det((M^T M)^-1) from its logarithm: 0 or inf where it under- or overflows."""
    return math.exp(log_det) if math.isfinite(log_det) and log_det < 700 else (math.inf if log_det > 0 else 0.0)


def _result(points, crit, met, zone_of_point, n_cand, start_objectives) -> DesignResult:
    log_det = float(met.log_det)
    det = det_from_log(log_det)
    return DesignResult(
        points=points,
        criterion=crit,
        trace=float(met.trace),
        det=det,
        log_det=log_det,
        condition_number=float(met.condition_number),
        objective=float(met.objective(crit)),
        lambda_min=float(met.lambda_min),
        zone=zone_of_point,
        n_candidates=int(n_cand),
        start_objectives=tuple(float(v) for v in start_objectives),
    )
