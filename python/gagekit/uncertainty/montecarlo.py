"""Propagation of distributions by the Monte Carlo method (JCGM 101:2008, GUM Supplement 1).

``monte_carlo(evaluate, points, model)`` draws simulated measurements of ``points`` from the
:class:`~gagekit.uncertainty.model.MeasurementModel`, re-runs the whole evaluation
``evaluate`` on each (for an inspection: datums, alignment and every zone, so their share of
the uncertainty is counted) and summarises each output quantity by JCGM 101 Sec. 7:

- ``u``: the standard deviation of the trials' values (Sec. 7.6);
- ``interval``: the probabilistically symmetric 95 % coverage interval [y_(r), y_(r+q)] of
  the sorted values, q = pM and r = (M - q)/2 rounded as in Sec. 7.7;
- ``U``: half its width (the expanded uncertainty), ``k = U / u``;
- ``bias``: the mean of the trials minus the measured value. A minimum-zone form error of
  noisy points (flatness, roundness, cylindricity, sphericity) is biased upward: the
  simulation's bias says by how much, beside U, instead of hiding it.

Trials run on ``threads`` threads (the Rust kernels release the GIL; a compiled inspection
runs a whole block of trials in one kernel call, ``block``); trial ``i``'s draws come from
a generator keyed by (seed, i) alone (:meth:`MeasurementModel.simulate`), so the same seed
gives the same values on any number of threads.

Adaptive stopping (JCGM 101 Sec. 7.9.4): batches of ``batch`` trials until, with h >= 2
batches, twice the standard deviation of the h batch means of y, u and both interval
endpoints is at most the numerical tolerance delta = 10^l / 2 of u written with
``digits`` significant digits (u = c x 10^l, Sec. 7.9.2), for every output; or
``max_trials``. A fixed number of trials is checked the same way (batches of ``batch``)
and reports whether it reached the tolerance (``stabilized``).
"""

from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Optional, Union

import numpy as np

from ..errors import GagekitError, InvalidInputError, NumericalError
from .model import MeasurementModel

__all__ = ["Uncertainty", "MonteCarlo", "monte_carlo", "parse_trials", "MIN_TRIALS", "METHOD", "coverage_interval",
           "numerical_tolerance"]

#: The smallest number of trials accepted (a 95 % interval from fewer is meaningless).
MIN_TRIALS = 10
#: The method string of every result.
METHOD = "JCGM 101:2008 Monte Carlo"
#: Two-sided 95 % normal coverage factor (k when u = 0).
K95 = 1.959963984540054


@dataclass(frozen=True)
class Uncertainty:
    """The uncertainty of one measured quantity (JSON: u, U, k, coverage, interval, bias,
    method, trials)."""

    value: float
    u: float
    U: float
    k: float
    coverage: float
    interval: tuple[float, float]
    bias: float
    trials: int
    method: str = METHOD

    def to_dict(self) -> dict[str, Any]:
        return {"u": self.u, "U": self.U, "k": self.k, "coverage": self.coverage, "interval": list(self.interval),
                "bias": self.bias, "method": self.method, "trials": self.trials}


@dataclass(frozen=True)
class MonteCarlo:
    """The outcome of :func:`monte_carlo`: the measured ``values``, each key's
    :class:`Uncertainty`, and how it was run."""

    values: dict[str, float]
    uncertainties: dict[str, Uncertainty]
    trials: int
    seed: int
    adaptive: bool
    stabilized: bool
    digits: int
    numerical_tolerance: dict[str, float]
    model: MeasurementModel
    threads: int
    seconds: float = 0.0
    samples: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)), repr=False)
    #: Fits the trials started from the measured ones, and how many needed the global search.
    warm_starts: Optional[dict[str, Any]] = None
    #: How each trial was evaluated (a compiled inspection, or why not).
    evaluation: Optional[str] = None

    def __getitem__(self, key: str) -> Uncertainty:
        return self.uncertainties[key]

    def settings(self) -> dict[str, Any]:
        """How the simulation ran (the JSON ``monte_carlo`` object)."""
        return {"method": METHOD, "trials": self.trials, "seed": self.seed,
                "stopping": ("adaptive (JCGM 101 7.9.4)" if self.adaptive else "fixed number of trials"),
                "significant_digits": self.digits, "stabilized": self.stabilized,
                "numerical_tolerance": dict(self.numerical_tolerance), "coverage": 0.95,
                "interval": "probabilistically symmetric (JCGM 101 7.7)", "model": self.model.to_dict(),
                "seconds": self.seconds, **({} if self.warm_starts is None else {"warm_starts": dict(self.warm_starts)}),
                **({} if self.evaluation is None else {"evaluation": self.evaluation})}

    def to_dict(self) -> dict[str, Any]:
        return {k: v.to_dict() for k, v in self.uncertainties.items()}


def parse_trials(value: Union[None, int, str]) -> Optional[int]:
    """``--uncertainty N`` or ``auto``: the number of trials (an int >= MIN_TRIALS) or None
    for adaptive stopping; anything else raises :class:`InvalidInputError`."""
    if value is None:
        return None
    if isinstance(value, str):
        t = value.strip().lower()
        if t in ("auto", "adaptive"):
            return None
        try:
            n = int(t)
        except ValueError:
            raise InvalidInputError(f"--uncertainty {value!r}: give a number of trials (>= {MIN_TRIALS}) or auto") from None
    elif isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise InvalidInputError(f"uncertainty trials must be an integer >= {MIN_TRIALS} or 'auto', got {value!r}")
    else:
        n = int(value)
    if n < MIN_TRIALS:
        raise InvalidInputError(f"uncertainty trials: at least {MIN_TRIALS} are needed for a 95 % interval, got {n}")
    if n > 10**7:
        raise InvalidInputError(f"uncertainty trials: at most 10**7, got {n}")
    return n


def coverage_interval(sorted_values: np.ndarray, p: float = 0.95) -> tuple[float, float]:
    """The probabilistically symmetric coverage interval of JCGM 101 Sec. 7.7 from M sorted
    values: q = pM (rounded half up when not an integer), r = (M - q)/2 likewise,
    [y_(r), y_(r+q)] (1-based order statistics)."""
    m = len(sorted_values)
    q = p * m
    q = int(q) if float(q).is_integer() else int(q + 0.5)
    r = (m - q) / 2
    r = int(r) if float(r).is_integer() else int(r + 0.5)
    r = max(r, 1)
    hi = min(r + q, m)
    return float(sorted_values[r - 1]), float(sorted_values[hi - 1])


def numerical_tolerance(u: float, digits: int) -> float:
    """delta = 10^l / 2 where u = c x 10^l and c has ``digits`` significant digits
    (JCGM 101 Sec. 7.9.2); 0 for u = 0."""
    if u <= 0:
        return 0.0
    l = math.floor(math.log10(u)) - digits + 1
    return 0.5 * 10.0 ** l


def _summary(col: np.ndarray) -> tuple[float, float, float, float]:
    s = np.sort(col)
    lo, hi = coverage_interval(s)
    return float(col.mean()), float(col.std(ddof=1)) if len(col) > 1 else 0.0, lo, hi


def _stable(samples: np.ndarray, batch: int, digits: int) -> tuple[bool, list[float]]:
    """JCGM 101 7.9.4 c-e over the complete batches of ``samples`` (trials x keys)."""
    h = len(samples) // batch
    deltas = [numerical_tolerance(float(samples[:, j].std(ddof=1)) if len(samples) > 1 else 0.0, digits)
              for j in range(samples.shape[1])]
    if h < 2:
        return False, deltas
    ok = True
    for j in range(samples.shape[1]):
        per = np.array([_summary(samples[b * batch:(b + 1) * batch, j]) for b in range(h)])
        s = per.std(axis=0, ddof=1) / math.sqrt(h)
        if not np.all(2.0 * s <= deltas[j]):
            ok = False
    return ok, deltas


def default_threads() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover
        return max(1, os.cpu_count() or 1)


def monte_carlo(
    evaluate: Callable[[np.ndarray], Mapping[str, float]],
    points: Any,
    model: MeasurementModel,
    trials: Union[None, int, str] = None,
    *,
    seed: int = 0,
    threads: Optional[int] = None,
    digits: int = 1,
    batch: int = 100,
    max_trials: int = 10_000,
    values: Optional[Mapping[str, float]] = None,
    block: Optional[Callable[[int, int], np.ndarray]] = None,
) -> MonteCarlo:
    """Run the Monte Carlo propagation (see the module docstring).

    Parameters
    ----------
    evaluate
        The whole evaluation: (n, 3) points -> {key: value}; the same keys every call.
    points
        The measured points the evaluation needs (the "active set": e.g. only the points
        inside an inspection's feature regions), mm.
    model
        The :class:`MeasurementModel`.
    trials
        A number of trials (>= 10), or ``None`` / ``"auto"`` for adaptive stopping.
    seed, threads
        Trial i draws from a generator seeded by (seed, i); ``threads`` (default: the CPUs
        this process may use) only changes the speed.
    digits, batch, max_trials
        Adaptive stopping: significant digits of u, the batch size, the cap.
    values
        The measured values (``evaluate(points)`` when not given).
    block
        ``block(start, stop)``: the values of trials start .. stop - 1 as a (stop - start,
        len(values)) array, computed at once (a compiled inspection's kernel,
        :mod:`gagekit.uncertainty.plan`); ``evaluate`` then only gives the measured values.
    """
    import time

    t0 = time.perf_counter()
    n_fixed = parse_trials(trials)
    if not isinstance(model, MeasurementModel):
        raise InvalidInputError(f"monte_carlo: model must be a MeasurementModel, got {type(model).__name__}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= int(seed) < 2**64:
        raise InvalidInputError(f"monte_carlo: seed must be an integer from 0 to 2**64 - 1, got {seed!r}")
    if not isinstance(digits, int) or not 1 <= digits <= 4:
        raise InvalidInputError(f"monte_carlo: digits must be 1 to 4, got {digits!r}")
    if not isinstance(batch, int) or batch < MIN_TRIALS:
        raise InvalidInputError(f"monte_carlo: batch must be an integer >= {MIN_TRIALS}, got {batch!r}")
    if not isinstance(max_trials, int) or max_trials < 2 * batch:
        raise InvalidInputError(f"monte_carlo: max_trials must be an integer >= 2 x batch, got {max_trials!r}")
    nthreads = default_threads() if threads is None else int(threads)
    if nthreads < 1:
        raise InvalidInputError(f"monte_carlo: threads must be >= 1, got {threads!r}")
    pts = np.ascontiguousarray(np.asarray(points, dtype=float))
    if pts.ndim != 2 or pts.shape[1] not in (2, 3) or len(pts) == 0:
        raise InvalidInputError(f"monte_carlo: points must be a non-empty (n, 3) or (n, 2) array, got shape {pts.shape}")
    base = dict(values) if values is not None else dict(evaluate(pts))
    keys = list(base)
    if not keys:
        raise InvalidInputError("monte_carlo: the evaluation returned no values")

    def one(i: int) -> np.ndarray:
        try:
            out = evaluate(model.simulate(pts, int(seed), i))
        except GagekitError as exc:
            raise type(exc)(f"Monte Carlo trial {i} (a simulated measurement): {exc}") from None
        try:
            row = np.array([float(out[k]) for k in keys])
        except KeyError as exc:
            raise NumericalError(f"Monte Carlo trial {i}: the evaluation did not return {exc}") from None
        if not np.all(np.isfinite(row)):
            bad = keys[int(np.argmin(np.isfinite(row)))]
            raise NumericalError(f"Monte Carlo trial {i}: {bad} is not finite")
        return row

    rows: list[np.ndarray] = []
    pool = ThreadPoolExecutor(max_workers=nthreads) if nthreads > 1 and block is None else None

    def run(start: int, stop: int) -> None:
        if block is not None:
            got = np.asarray(block(start, stop), dtype=float)
            if got.shape != (stop - start, len(keys)) or not np.all(np.isfinite(got)):
                raise NumericalError(f"Monte Carlo trials {start} to {stop - 1}: the evaluation returned "
                                     f"{'non-finite values' if got.shape == (stop - start, len(keys)) else f'shape {got.shape}'}")
            rows.extend(got)
            return
        idx = range(start, stop)
        rows.extend(pool.map(one, idx) if pool is not None else map(one, idx))

    try:
        if n_fixed is not None:
            run(0, n_fixed)
            samples = np.array(rows)
            stabilized, deltas = _stable(samples, batch, digits)
        else:
            run(0, 2 * batch)
            while True:
                samples = np.array(rows)
                stabilized, deltas = _stable(samples, batch, digits)
                if stabilized or len(rows) >= max_trials:
                    break
                run(len(rows), min(len(rows) + batch, max_trials))
    finally:
        if pool is not None:
            pool.shutdown()
    m = len(samples)
    unc = {}
    for j, k in enumerate(keys):
        mean, u, lo, hi = _summary(samples[:, j])
        U = 0.5 * (hi - lo)
        unc[k] = Uncertainty(float(base[k]), u, U, (U / u) if u > 0 else K95, 0.95, (lo, hi), mean - float(base[k]), m)
    return MonteCarlo({k: float(base[k]) for k in keys}, unc, m, int(seed), n_fixed is None, bool(stabilized), digits,
                      dict(zip(keys, deltas)), model, nthreads, time.perf_counter() - t0, samples)
