"""Statistical process control of individual measurements (one value per part).

Capability (ISO 22514-2:2017, Secs. 6-7; AIAG *Statistical Process Control*, 2nd ed. 2005,
Ch. IV), with specification limits LSL and/or USL:

* overall (long-term) spread: the sample standard deviation ``s`` (n - 1 in the
  denominator); performance indices ``Pp = (USL - LSL) / 6 s`` and
  ``Ppk = min(USL - mean, mean - LSL) / 3 s``;
* within (short-term) spread of an individuals chart: ``sigma = MRbar / d2`` with
  ``d2 = 1.128`` for moving ranges of two; capability indices ``Cp`` and ``Cpk`` as above
  with ``sigma``. With one limit only, Cp and Pp do not exist and Cpk, Ppk are the
  one-sided ``Cpl = (mean - LSL) / 3 sigma`` or ``Cpu = (USL - mean) / 3 sigma``.

Individuals / moving-range chart (AIAG Ch. II; Montgomery, *Introduction to Statistical
Quality Control*, 7th ed., Sec. 6.4): centre ``mean``, limits ``mean +- 3 MRbar / d2``
(``+- 2.660 MRbar``); MR chart centre ``MRbar``, upper limit ``D4 MRbar = 3.267 MRbar``.

Western Electric rules (*Statistical Quality Control Handbook*, Western Electric, 1956,
Sec. 1B), with the zones of the individuals chart's sigma:

1. one point beyond 3 sigma;
2. two of three consecutive points beyond 2 sigma on the same side;
3. four of five consecutive points beyond 1 sigma on the same side;
4. eight consecutive points on the same side of the centre line.

A signal is reported at the point that completes the pattern.

Resolution. Every result is a float computed from measured points; an LP that places a
face exactly on its limit returns +-1e-14 mm, not 0. A characteristic carries a resolution
(:data:`RESOLUTION`: 1e-9 mm for lengths, 1e-12 rad for angles, 1e-9 mm over a 1 m lever):
a value within it of a limit is on the limit, and a characteristic whose values spread no
more than it has no variation to speak of: no capability index, no control chart, a note.

Capability rules (AIAG *SPC* manual, 2nd ed., Ch. II-IV; ISO 22514-2): indices exist only
against specification limits, and from :data:`MIN_CAPABILITY_VALUES` = 25 values: the
AIAG manual asks for 25 subgroups before control limits and capability are computed
(with individuals, 25 values); below, each index comes with a warning that states n and
the one-sided 95 % lower confidence bound of Cpk (Bissell, *Applied Statistics* 39, 1990:
``Cpk - 1.645 sqrt(1/(9n) + Cpk^2/(2(n-1)))``): at n = 10 a Cpk of 1.33 may be 0.79.

Measurement variance (ISO 22514-7:2021; ISO 22514-2 Annex on measurement; AIAG MSA 4th ed.
Ch. I-B): every observed value is the process's value plus the measurement's error, and the two
are independent, so ``sigma_obs^2 = sigma_process^2 + u^2`` with ``u`` the standard uncertainty
of the measurement (k = 1). Given ``u`` (``--measurement-uncertainty``, or the uncertainties
stored with the results), :func:`capability` reports the indices of the observed spread (the
``cp``/``cpk``/``pp``/``ppk`` keys, unchanged) and those of the process with the measurement
variance removed, ``sigma_process = sqrt(sigma_obs^2 - u^2)`` for the within and the overall
spread (``measurement.process``); where ``u^2 >= sigma_obs^2`` the measuring system does not
resolve the process spread and no process index is given (a note says so). Removing the
measurement variance can only raise an index: observed indices are the conservative ones.
With two limits the capability ratio of the measurement process ``Q_MP = 2 U / T`` (U = 2 u,
k = 2; ISO 22514-7 and VDA 5 accept at most 30 %) is given too.

Trends need time: a slope over less than :data:`MIN_TREND_DAYS` (one day) of data is not
reported (8 scans written within milliseconds are not 792 mm/day).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional, Sequence

import numpy as np

from .._util import LENGTH_RESOLUTION_MM
from ..errors import InvalidInputError

D2 = 1.128  #: d2 for moving ranges of two observations
D4 = 3.267  #: D4 for moving ranges of two observations
RESOLUTION = {"mm": LENGTH_RESOLUTION_MM, "rad": LENGTH_RESOLUTION_MM * 1e-3}  #: default resolution of results by unit
MIN_CAPABILITY_VALUES = 25  #: AIAG: a capability study needs at least 25 values
MIN_TREND_DAYS = 1.0  #: no trend over less than a day of data

RULES = {
    1: "one point beyond 3 sigma",
    2: "two of three points beyond 2 sigma, same side",
    3: "four of five points beyond 1 sigma, same side",
    4: "eight points in a row on one side of the centre line",
}

__all__ = ["D2", "D4", "RULES", "RESOLUTION", "MIN_CAPABILITY_VALUES", "MIN_TREND_DAYS", "on_limits", "Capability", "measurement_split", "ImrChart", "Signal", "capability", "imr_chart", "western_electric",
           "trend_per_day"]


@dataclass(frozen=True)
class Signal:
    """A Western Electric rule broken at the point ``index`` (0-based, in time order)."""

    index: int
    rule: int

    def to_dict(self) -> dict:
        return {"index": self.index, "rule": self.rule, "description": RULES[self.rule]}


@dataclass(frozen=True)
class ImrChart:
    """Individuals and moving-range chart limits, and the rule violations."""

    center: float
    ucl: float
    lcl: float
    sigma: float
    mr_center: float
    mr_ucl: float
    signals: tuple[Signal, ...] = field(default=())

    def to_dict(self) -> dict:
        return {"center": self.center, "ucl": self.ucl, "lcl": self.lcl, "sigma": self.sigma,
                "mr_center": self.mr_center, "mr_ucl": self.mr_ucl, "signals": [s.to_dict() for s in self.signals]}


@dataclass(frozen=True)
class Capability:
    """Summary statistics and capability of one characteristic against its limits.

    Indices that do not exist for the data (one value, no spread above the resolution,
    no limits) are absent from :meth:`to_dict` and ``None`` here, with the reason in
    ``notes``; ``warnings`` say when an index exists but rests on too few values.
    ``on_limit`` counts the values within the resolution of a limit (they count as on it:
    a margin of zero)."""

    n: int
    mean: float
    minimum: float
    maximum: float
    lower: Optional[float]
    upper: Optional[float]
    sd: Optional[float] = None
    sigma_within: Optional[float] = None
    min_margin: Optional[float] = None
    cp: Optional[float] = None
    cpk: Optional[float] = None
    pp: Optional[float] = None
    ppk: Optional[float] = None
    notes: tuple[str, ...] = ()
    resolution: float = 0.0
    on_limit: int = 0
    warnings: tuple[str, ...] = ()
    #: with a measurement uncertainty: ISO 22514-7 split of the observed variance (see the module doc)
    measurement: Optional[dict] = None

    @property
    def varies(self) -> bool:
        """Whether the values spread more than the resolution."""
        return self.n >= 2 and self.maximum - self.minimum > self.resolution

    def to_dict(self) -> dict:
        d = {"n": self.n, "mean": self.mean, "min": self.minimum, "max": self.maximum, "resolution": self.resolution}
        for k in ("lower", "upper", "sd", "sigma_within", "min_margin", "cp", "cpk", "pp", "ppk"):
            v = getattr(self, k)
            if v is not None:
                d[k] = v
        if self.lower is not None or self.upper is not None:
            d["on_limit"] = self.on_limit
        if self.measurement is not None:
            d["measurement"] = self.measurement
        if self.notes:
            d["notes"] = list(self.notes)
        if self.warnings:
            d["warnings"] = list(self.warnings)
        return d


def _index(spread: Optional[float], mean: float, lower: Optional[float], upper: Optional[float]):
    """(C, Ck) for a spread: two-sided or one-sided (ISO 22514-2, AIAG)."""
    if spread is None or spread <= 0:
        return None, None
    c = (upper - lower) / (6 * spread) if lower is not None and upper is not None else None
    sides = [x for x in ((upper - mean) if upper is not None else None, (mean - lower) if lower is not None else None)
             if x is not None]
    ck = min(sides) / (3 * spread) if sides else None
    return c, ck


def on_limits(values: Sequence[float], lower: Optional[float], upper: Optional[float], resolution: float) -> np.ndarray:
    """``values`` with every value within ``resolution`` of a limit set to that limit."""
    x = np.array(values, dtype=np.float64)
    for limit in (lower, upper):
        if limit is not None:
            x[np.abs(x - limit) <= resolution] = limit
    return x


def _fmt(v: float) -> str:
    return f"{v:.3g}"


def cpk_lower_bound(cpk: float, n: int, z: float = 1.645) -> float:
    """One-sided lower confidence bound of Cpk (Bissell 1990; z = 1.645: 95 %)."""
    return cpk - z * math.sqrt(1.0 / (9.0 * n) + cpk * cpk / (2.0 * (n - 1)))


def capability(values: Sequence[float], lower: Optional[float] = None, upper: Optional[float] = None, *,
               resolution: float = 0.0, unit: str = "", measurement_u: Optional[float] = None,
               measurement_source: str = "given") -> Capability:
    """n, mean, sd, the smallest margin to a limit, Cp/Cpk (within) and Pp/Ppk (overall).

    Values within ``resolution`` of a limit are on the limit (see the module doc); with a
    spread of at most ``resolution`` there is no capability index. ``measurement_u``: the
    standard uncertainty of a measured value (k = 1, the values' unit): the indices with the
    measurement variance removed as well (ISO 22514-7, see the module doc)."""
    if not (math.isfinite(resolution) and resolution >= 0):
        raise ValueError(f"the resolution must be a finite number >= 0, got {resolution}")
    if measurement_u is not None and not (isinstance(measurement_u, (int, float)) and math.isfinite(measurement_u)
                                          and measurement_u >= 0):
        raise InvalidInputError(f"the measurement uncertainty must be a finite number >= 0, got {measurement_u}")
    x = np.asarray(values, dtype=np.float64)
    if x.ndim != 1 or len(x) == 0:
        raise ValueError("capability needs at least one value")
    if lower is not None and upper is not None and not lower < upper:
        raise ValueError(f"the lower limit {lower} must be below the upper limit {upper}")
    x = on_limits(x, lower, upper, resolution)
    n, mean = len(x), float(x.mean())
    notes: list[str] = []
    warns: list[str] = []
    margins = [m for m in ((x - lower).min() if lower is not None else None, (upper - x).min() if upper is not None else None)
               if m is not None]
    min_margin = float(min(margins)) if margins else None
    on_limit = int(sum(int(np.sum(x == lim)) for lim in (lower, upper) if lim is not None))
    limits = lower is not None or upper is not None
    if not limits:
        notes.append("no specification limits: no capability indices")
    sd = sigma = None
    spread = float(x.max() - x.min())
    u = f" {unit}" if unit else ""
    if n < 2:
        notes.append("one value: no spread, no capability indices")
    elif spread <= resolution:
        notes.append(f"no variation above the resolution ({resolution:g}{u}): the values spread {_fmt(spread)}{u}; "
                     "no capability index and no control chart")
    else:
        sd = float(x.std(ddof=1))
        sigma = float(np.abs(np.diff(x)).mean() / D2)
    cp = cpk = pp = ppk = None
    if limits:
        cp, cpk = _index(sigma, mean, lower, upper)
        pp, ppk = _index(sd, mean, lower, upper)
        if sigma == 0.0 and sd and sd > 0:
            notes.append("no point-to-point variation (MRbar = 0): no Cp/Cpk; see Pp/Ppk")
        if (cpk is not None or ppk is not None) and n < MIN_CAPABILITY_VALUES:
            k = cpk if cpk is not None else ppk
            warns.append(f"only {n} values: a capability study needs at least {MIN_CAPABILITY_VALUES} (AIAG SPC manual); "
                         f"with {n} the 95 % lower confidence bound of {'Cpk' if cpk is not None else 'Ppk'} "
                         f"{k:.2f} is {cpk_lower_bound(k, n):.2f} (Bissell)")
    if on_limit:
        warns.append(f"{on_limit} of {n} values on a limit (within {resolution:g}{u}): conforming, but nothing is left "
                     "for measurement noise or fixturing")
    meas = None
    if measurement_u is not None:
        meas = measurement_split(float(measurement_u), mean, lower, upper, sigma, sd, cp, cpk, pp, ppk, unit,
                                 measurement_source)
    return Capability(n, mean, float(x.min()), float(x.max()), lower, upper, sd, sigma, min_margin,
                      cp, cpk, pp, ppk, tuple(notes), resolution, on_limit, tuple(warns), meas)


def _removed(spread: Optional[float], u: float) -> Optional[float]:
    """sqrt(spread^2 - u^2), or None when the measurement variance is at least the observed one."""
    if spread is None or spread <= u:
        return None
    return math.sqrt(spread * spread - u * u)


def measurement_split(u: float, mean: float, lower: Optional[float], upper: Optional[float],
                      sigma: Optional[float], sd: Optional[float], cp, cpk, pp, ppk, unit: str = "",
                      source: str = "given") -> dict:
    """The ISO 22514-7 account of a characteristic's spread for a measurement standard
    uncertainty ``u``: observed = process + measurement variance; the indices of both."""
    sig_p, sd_p = _removed(sigma, u), _removed(sd, u)
    cp_p, cpk_p = _index(sig_p, mean, lower, upper)
    pp_p, ppk_p = _index(sd_p, mean, lower, upper)
    obs = {k: v for k, v in (("sigma_within", sigma), ("sd", sd), ("cp", cp), ("cpk", cpk), ("pp", pp), ("ppk", ppk))
           if v is not None}
    proc = {k: v for k, v in (("sigma_within", sig_p), ("sd", sd_p), ("cp", cp_p), ("cpk", cpk_p), ("pp", pp_p),
                              ("ppk", ppk_p)) if v is not None}
    d: dict = {
        "u": u, "k": 1, "source": source,
        "model": "observed variance = process variance + measurement variance u^2 (ISO 22514-7)",
        "observed": obs, "process": proc,
    }
    if sd:
        d["share_of_observed_variance"] = min(u * u / (sd * sd), 1.0) if sd > 0 else 1.0
    if lower is not None and upper is not None:
        d["q_mp_pct"] = 100.0 * 2.0 * (2.0 * u) / (upper - lower)
    notes = []
    un = f" {unit}" if unit else ""
    if (sigma is not None and sig_p is None) or (sd is not None and sd_p is None):
        notes.append(f"the measurement uncertainty u = {u:.3g}{un} is at least the observed spread "
                     f"(sd {sd:.3g}{un}): this measuring system does not resolve the process; no process index")
    if "q_mp_pct" in d and d["q_mp_pct"] > 30.0:
        notes.append(f"Q_MP = 2U/T = {d['q_mp_pct']:.0f} % > 30 %: the measurement process is not capable for "
                     "this tolerance (ISO 22514-7, VDA 5)")
    if notes:
        d["notes"] = notes
    return d


def western_electric(x: Sequence[float], center: float, sigma: float) -> list[Signal]:
    """The points completing each Western Electric pattern (rules 1-4, see module doc)."""
    z = (np.asarray(x, dtype=np.float64) - center) / sigma if sigma > 0 else np.zeros(len(x))
    out = []
    for i in range(len(z)):
        if abs(z[i]) > 3:
            out.append(Signal(i, 1))
        for rule, (count, window, k) in ((2, (2, 3, 2.0)), (3, (4, 5, 1.0))):
            if i + 1 >= window:
                w = z[i + 1 - window:i + 1]
                side = math.copysign(1.0, z[i]) if z[i] != 0 else 0.0
                if side and abs(z[i]) > k and np.sum(w * side > k) >= count:
                    out.append(Signal(i, rule))
        if i >= 7:
            w = z[i - 7:i + 1]
            if np.all(w > 0) or np.all(w < 0):
                out.append(Signal(i, 4))
    return out


def imr_chart(x: Sequence[float], resolution: float = 0.0) -> Optional[ImrChart]:
    """Individuals / moving-range chart of ``x`` in time order (None below two values, or
    when they spread no more than ``resolution``: a chart of rounding noise says nothing)."""
    x = np.asarray(x, dtype=np.float64)
    if len(x) < 2 or float(x.max() - x.min()) <= resolution:
        return None
    center = float(x.mean())
    mr = float(np.abs(np.diff(x)).mean())
    sigma = mr / D2
    return ImrChart(center, center + 3 * sigma, center - 3 * sigma, sigma, mr, D4 * mr,
                    tuple(western_electric(x, center, sigma)) if sigma > 0 else ())


def trend_per_day(days: Sequence[float], values: Sequence[float], min_days: float = MIN_TREND_DAYS) -> Optional[float]:
    """Least-squares slope of ``values`` against time in days (None over less than
    ``min_days`` of data: minutes of data extrapolated to a day are not a trend)."""
    t = np.asarray(days, dtype=np.float64)
    y = np.asarray(values, dtype=np.float64)
    if len(t) < 2 or np.ptp(t) == 0 or np.ptp(t) < min_days:
        return None
    tc = t - t.mean()
    return float((tc * (y - y.mean())).sum() / (tc * tc).sum())
