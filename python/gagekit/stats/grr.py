"""Is the measuring system good enough? Gage R&R and the Type-1 gage study.

Crossed ANOVA gage R&R (AIAG *Measurement Systems Analysis*, 4th ed. 2010, Ch. III,
Sec. B "Analysis of Variance (ANOVA) Method"; Montgomery & Runger, *Quality Engineering*
5, 1993), a balanced study of ``p`` parts x ``o`` appraisers x ``r`` trials, ``y[i, j, k]``:

* sums of squares ``SS_P = o r sum_i (ybar_i - ybar)^2``, ``SS_A = p r sum_j (ybar_j -
  ybar)^2``, ``SS_PA = r sum_ij (ybar_ij - ybar_i - ybar_j + ybar)^2``, ``SS_E = sum_ijk
  (y_ijk - ybar_ij)^2``, degrees of freedom ``p-1``, ``o-1``, ``(p-1)(o-1)``, ``p o (r-1)``;
* F tests of the random-effects model: parts and appraisers against the interaction,
  the interaction against repeatability. AIAG (and the usual practice it follows) pools
  the interaction into the error term when its p-value exceeds :data:`POOL_ALPHA` = 0.25;
  then parts and appraisers are tested against the pooled mean square;
* variance components (expected mean squares): ``s2_E = MS_E``, ``s2_PA = (MS_PA - MS_E)
  / r``, ``s2_A = (MS_A - MS_PA) / (p r)``, ``s2_P = (MS_P - MS_PA) / (o r)`` (pooled:
  MS_PA and MS_E replaced by the pooled mean square, no interaction); a negative
  estimate is set to 0 (AIAG);
* standard deviations: repeatability ``EV = sqrt(s2_E)``, appraiser ``AV = sqrt(s2_A)``,
  interaction ``INT = sqrt(s2_PA)``, reproducibility ``sqrt(AV^2 + INT^2)``, ``GRR =
  sqrt(EV^2 + AV^2 + INT^2)``, part variation ``PV = sqrt(s2_P)``, total ``TV =
  sqrt(GRR^2 + PV^2)``; every ratio is of standard deviations (AIAG 4th ed.: one sigma,
  not the 5.15 sigma of the 3rd edition, which cancels in the ratios);
* ``%GRR`` of the total variation ``100 GRR / TV`` and of the tolerance ``100 GRR /
  (tolerance / 6)`` (AIAG: the tolerance spans six standard deviations), the number of
  distinct categories ``ndc = 1.41 PV / GRR`` truncated to an integer (AIAG; >= 5 wanted);
* AIAG acceptance: ``%GRR < 10`` acceptable, ``10 <= %GRR <= 30`` may be acceptable
  depending on the application (``conditional``), ``> 30`` unacceptable.

Each variance component carries a 95 % confidence interval: ``s2_E`` exactly from the
chi-square distribution with ``p o (r-1)`` degrees of freedom, the others (linear
combinations of mean squares) by Satterthwaite's approximation (Burdick, Borror &
Montgomery, *Design and Analysis of Gauge R&R Studies*, SIAM 2005, Ch. 3), omitted for a
component estimated as 0.

Type-1 gage study (VDA 5, 2nd ed. 2010; Bosch, *Booklet 10: Capability of Measurement
and Test Processes*, 2019), ``n`` repeated measurements of one reference part with value
``x_ref`` and a characteristic tolerance ``T``: ``Cg = 0.2 T / (6 s)``, ``Cgk = (0.1 T -
|xbar - x_ref|) / (3 s)``; the convention is 20 % of the tolerance against 6 standard
deviations, and both indices >= 1.33 make the gage capable. At least
:data:`MIN_TYPE1_VALUES` = 25 measurements are asked for (Bosch: 50); fewer give a warning.

The F distribution's upper tail is the regularized incomplete beta function, the
chi-square quantiles invert the regularized incomplete gamma function, both written here
with :mod:`math` (Numerical Recipes, 3rd ed., Secs. 6.2, 6.4: series and Lentz continued
fractions to 1e-15), so the study needs only numpy.
"""

from __future__ import annotations

import math
import re
from typing import Iterable, Optional, Sequence

import numpy as np

from ..errors import InvalidInputError

__all__ = ["POOL_ALPHA", "MIN_TYPE1_VALUES", "DEFAULT_PATTERN", "anova_grr", "type1_study", "f_sf", "chi2_ppf", "acceptance",
           "read_study_csv", "study_rows_from_db", "studies",
           "study_table", "name_parser"]

POOL_ALPHA = 0.25  #: AIAG: pool the interaction into repeatability when its p-value exceeds this
MIN_TYPE1_VALUES = 25  #: a Type-1 study wants at least this many repeated measurements
_EPS = 1e-15
_TINY = 1e-300


# ------------------------------------------------------------------ special functions

def _betacf(a: float, b: float, x: float) -> float:
    """Continued fraction of the incomplete beta function (modified Lentz)."""
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c, d = 1.0, 1.0 - qab * x / qap
    d = 1.0 / (d if abs(d) > _TINY else _TINY)
    h = d
    for m in range(1, 10000):
        m2 = 2 * m
        aa = m * (b - m) * x / ((qam + m2) * (a + m2))
        d = 1.0 + aa * d
        d = 1.0 / (d if abs(d) > _TINY else _TINY)
        c = 1.0 + aa / c
        c = c if abs(c) > _TINY else _TINY
        h *= d * c
        aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2))
        d = 1.0 + aa * d
        d = 1.0 / (d if abs(d) > _TINY else _TINY)
        c = 1.0 + aa / c
        c = c if abs(c) > _TINY else _TINY
        de = d * c
        h *= de
        if abs(de - 1.0) < _EPS:
            return h
    return h


def betainc(a: float, b: float, x: float) -> float:
    """Regularized incomplete beta function ``I_x(a, b)``."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    lbt = math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x) + b * math.log1p(-x)
    if x < (a + 1.0) / (a + b + 2.0):
        return math.exp(lbt) * _betacf(a, b, x) / a
    return 1.0 - math.exp(lbt) * _betacf(b, a, 1.0 - x) / b


def f_sf(f: float, d1: float, d2: float) -> float:
    """Upper tail ``P(F > f)`` of the F distribution with ``d1``, ``d2`` degrees of freedom."""
    if f <= 0.0:
        return 1.0
    if math.isinf(f):
        return 0.0
    return betainc(d2 / 2.0, d1 / 2.0, d2 / (d2 + d1 * f))


def gammainc(a: float, x: float) -> float:
    """Regularized lower incomplete gamma function ``P(a, x)``."""
    if x <= 0.0:
        return 0.0
    lg = a * math.log(x) - x - math.lgamma(a)
    if x < a + 1.0:
        ap, s = a, 1.0 / a
        term = s
        for _ in range(100000):
            ap += 1.0
            term *= x / ap
            s += term
            if abs(term) < abs(s) * _EPS:
                break
        return s * math.exp(lg)
    b = x + 1.0 - a
    c, d = 1.0 / _TINY, 1.0 / b
    h = d
    for i in range(1, 100000):
        an = -i * (i - a)
        b += 2.0
        d = an * d + b
        d = 1.0 / (d if abs(d) > _TINY else _TINY)
        c = b + an / c
        c = c if abs(c) > _TINY else _TINY
        de = d * c
        h *= de
        if abs(de - 1.0) < _EPS:
            break
    return 1.0 - math.exp(lg) * h


def chi2_ppf(q: float, df: float) -> float:
    """Quantile of the chi-square distribution (bisection on :func:`gammainc`, to 1e-13
    relative)."""
    lo, hi = 0.0, max(1.0, df)
    while gammainc(df / 2.0, hi / 2.0) < q:
        hi *= 2.0
    for _ in range(400):
        mid = 0.5 * (lo + hi)
        if gammainc(df / 2.0, mid / 2.0) < q:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-13 * hi:
            break
    return 0.5 * (lo + hi)


# ------------------------------------------------------------------ input

def study_table(parts: Sequence, appraisers: Sequence, values: Sequence[float]) -> tuple[np.ndarray, list, list]:
    """The array ``y[part, appraiser, trial]`` of a balanced crossed study from one row per
    measurement (the trial is the order of a part's measurements by an appraiser), with
    the part and appraiser labels in first-seen order. Refuses NaN, infinities, fewer than
    2 parts, 2 appraisers or 2 trials, and an unbalanced design (naming the cell)."""
    if not (len(parts) == len(appraisers) == len(values)):
        raise InvalidInputError("gage R&R: parts, appraisers and values differ in length")
    if len(values) == 0:
        raise InvalidInputError("gage R&R: no measurements")
    y = np.asarray(values, dtype=float)
    bad = np.flatnonzero(~np.isfinite(y))
    if bad.size:
        k = int(bad[0])
        raise InvalidInputError(f"gage R&R: measurement {k + 1} (part {parts[k]}, appraiser {appraisers[k]}) "
                                f"is {y[k]}: every value must be a finite number")
    plabels = list(dict.fromkeys(parts))
    alabels = list(dict.fromkeys(appraisers))
    if len(plabels) < 2:
        raise InvalidInputError(f"gage R&R: {len(plabels)} part; a study needs at least 2 parts (AIAG: 10)")
    if len(alabels) < 2:
        raise InvalidInputError(f"gage R&R: {len(alabels)} appraiser; a crossed study needs at least 2 "
                                "(with one, run a Type-1 study)")
    cells: dict = {}
    for pt, ap, v in zip(parts, appraisers, y):
        cells.setdefault((pt, ap), []).append(float(v))
    counts = {(pt, ap): len(cells.get((pt, ap), [])) for pt in plabels for ap in alabels}
    r = max(counts.values())
    if r < 2:
        raise InvalidInputError("gage R&R: one trial per part and appraiser; repeatability needs at least 2 trials")
    short = [(k, n) for k, n in counts.items() if n != r]
    if short:
        (pt, ap), n = short[0]
        raise InvalidInputError(f"gage R&R: unbalanced study: part {pt}, appraiser {ap} has {n} trials, others "
                                f"{r} ({len(short)} cells short); the ANOVA method needs every part measured "
                                "equally often by every appraiser")
    arr = np.array([[cells[(pt, ap)] for ap in alabels] for pt in plabels], dtype=float)
    return arr, plabels, alabels


def name_parser(pattern: str):
    """A function mapping a file name (stem) to ``{"part", "appraiser", "trial"}`` by a
    pattern such as ``{part}_{appraiser}_{trial}``; fields are non-empty and non-greedy,
    so separators must not occur inside a part id except in the last field."""
    names = re.findall(r"\{(\w+)\}", pattern)
    if not {"part", "appraiser"} <= set(names) or not set(names) <= {"part", "appraiser", "trial"}:
        raise InvalidInputError(f"--pattern {pattern!r}: needs {{part}} and {{appraiser}} (and optionally {{trial}}), "
                                "nothing else in braces")
    parts = re.split(r"(\{\w+\})", pattern)
    rx = "".join(f"(?P<{p[1:-1]}>.+?)" if re.fullmatch(r"\{\w+\}", p) else re.escape(p) for p in parts)
    compiled = re.compile(f"^{rx}$")

    def parse(stem: str) -> Optional[dict]:
        mt = compiled.match(stem)
        return None if mt is None else mt.groupdict()

    return parse


# ------------------------------------------------------------------ studies

#: Largest |value| a study takes: squared sums of larger values overflow double precision
#: (and no measured length or angle comes near it in any unit).
_MAX_VALUE = 1e100


def _check_values(y: np.ndarray, what: str) -> None:
    """NaN, infinity or a value beyond :data:`_MAX_VALUE` is an error (a huge value made the
    sums of squares overflow and the study read as "does not vary")."""
    if not np.all(np.isfinite(y)):
        raise InvalidInputError(f"{what} holds NaN or infinite values")
    big = float(np.max(np.abs(y)))
    if big > _MAX_VALUE:
        raise InvalidInputError(f"{what} holds a value of magnitude {big:.4g}, beyond {_MAX_VALUE:.0e}; check the units")


def acceptance(pct: float) -> str:
    """AIAG band of a %GRR: ``acceptable`` (< 10), ``conditional`` (10-30), ``unacceptable`` (> 30)."""
    return "acceptable" if pct < 10.0 else ("conditional" if pct <= 30.0 else "unacceptable")


def _ci(est: float, terms: Iterable[tuple[float, float, float]]) -> Optional[list]:
    """95 % interval of a variance component ``est = sum c MS`` from (c, MS, df) terms,
    Satterthwaite's degrees of freedom (exact for one term)."""
    if est <= 0.0:
        return None
    den = sum((c * ms) ** 2 / df for c, ms, df in terms)
    nu = est * est / den
    return [nu * est / chi2_ppf(0.975, nu), nu * est / chi2_ppf(0.025, nu)]


def anova_grr(y, *, tolerance: Optional[float] = None, pool_alpha: float = POOL_ALPHA,
              parts: Optional[list] = None, appraisers: Optional[list] = None) -> dict:
    """Crossed ANOVA gage R&R of ``y[part, appraiser, trial]`` (see the module text).

    ``tolerance`` (USL - LSL, > 0) adds %GRR, %EV, %AV, %PV of the tolerance. Returns a
    JSON-ready dict: ``design``, ``anova`` (rows with source, df, ss, ms, f, p), ``pooled``,
    ``components`` (variance, sd, ci95 of the variance), ``sd`` (EV, AV, interaction,
    reproducibility, GRR, PV, TV), ``percent_tv``, ``percent_tolerance``, ``ndc``,
    ``acceptance`` (by total variation and by tolerance)."""
    y = np.asarray(y, dtype=float)
    if y.ndim != 3:
        raise InvalidInputError(f"gage R&R: the study is an array part x appraiser x trial, got {y.ndim} dimensions")
    p, o, r = y.shape
    if p < 2 or o < 2 or r < 2:
        raise InvalidInputError(f"gage R&R: {p} parts x {o} appraisers x {r} trials; each needs at least 2")
    _check_values(y, "gage R&R: the study")
    if tolerance is not None and not (math.isfinite(tolerance) and tolerance > 0):
        raise InvalidInputError(f"gage R&R: tolerance {tolerance}: a positive number (USL - LSL)")
    gm = y.mean()
    yi = y.mean(axis=(1, 2))
    yj = y.mean(axis=(0, 2))
    yij = y.mean(axis=2)
    ss_p = o * r * float(np.sum((yi - gm) ** 2))
    ss_a = p * r * float(np.sum((yj - gm) ** 2))
    ss_pa = r * float(np.sum((yij - yi[:, None] - yj[None, :] + gm) ** 2))
    ss_e = float(np.sum((y - yij[:, :, None]) ** 2))
    ss_t = float(np.sum((y - gm) ** 2))
    df_p, df_a, df_pa, df_e = p - 1, o - 1, (p - 1) * (o - 1), p * o * (r - 1)
    ms_p, ms_a, ms_pa, ms_e = ss_p / df_p, ss_a / df_a, ss_pa / df_pa, ss_e / df_e
    if ss_e <= 1e-24 * max(gm * gm * y.size, _TINY) or ss_t <= 0.0:
        raise InvalidInputError("gage R&R: the repeated measurements do not vary: no repeatability to estimate "
                                "(resolution too coarse for the study?)")

    def _f(ms_num, ms_den, d1, d2):
        if ms_den <= 0.0:
            return None
        f = ms_num / ms_den
        return f, f_sf(f, d1, d2)

    f_pa = _f(ms_pa, ms_e, df_pa, df_e)
    p_pa = f_pa[1] if f_pa else 1.0
    pooled = p_pa > pool_alpha
    rows = []
    if pooled:
        df_r = df_pa + df_e
        ms_r = (ss_pa + ss_e) / df_r
        fp, fa = _f(ms_p, ms_r, df_p, df_r), _f(ms_a, ms_r, df_a, df_r)
        rows = [("part", df_p, ss_p, ms_p, fp), ("appraiser", df_a, ss_a, ms_a, fa),
                ("repeatability", df_r, ss_pa + ss_e, ms_r, None)]
        v_e, v_pa = ms_r, 0.0
        v_a = (ms_a - ms_r) / (p * r)
        v_p = (ms_p - ms_r) / (o * r)
        ci_e = _ci(v_e, [(1.0, ms_r, df_r)])
        ci_pa = None
        ci_a = _ci(v_a, [(1 / (p * r), ms_a, df_a), (-1 / (p * r), ms_r, df_r)])
        ci_p = _ci(v_p, [(1 / (o * r), ms_p, df_p), (-1 / (o * r), ms_r, df_r)])
    else:
        fp, fa = _f(ms_p, ms_pa, df_p, df_pa), _f(ms_a, ms_pa, df_a, df_pa)
        rows = [("part", df_p, ss_p, ms_p, fp), ("appraiser", df_a, ss_a, ms_a, fa),
                ("part x appraiser", df_pa, ss_pa, ms_pa, f_pa), ("repeatability", df_e, ss_e, ms_e, None)]
        v_e = ms_e
        v_pa = (ms_pa - ms_e) / r
        v_a = (ms_a - ms_pa) / (p * r)
        v_p = (ms_p - ms_pa) / (o * r)
        ci_e = _ci(v_e, [(1.0, ms_e, df_e)])
        ci_pa = _ci(v_pa, [(1 / r, ms_pa, df_pa), (-1 / r, ms_e, df_e)])
        ci_a = _ci(v_a, [(1 / (p * r), ms_a, df_a), (-1 / (p * r), ms_pa, df_pa)])
        ci_p = _ci(v_p, [(1 / (o * r), ms_p, df_p), (-1 / (o * r), ms_pa, df_pa)])
    rows.append(("total", p * o * r - 1, ss_t, None, None))
    anova = []
    for src, df, ss, ms, f in rows:
        row = {"source": src, "df": df, "ss": ss}
        if ms is not None:
            row["ms"] = ms
        if f is not None:
            row["f"], row["p"] = f
        anova.append(row)
    v_p, v_a, v_pa = max(v_p, 0.0), max(v_a, 0.0), max(v_pa, 0.0)
    ev, av, inter = math.sqrt(v_e), math.sqrt(v_a), math.sqrt(v_pa)
    repro = math.sqrt(v_a + v_pa)
    grr = math.sqrt(v_e + v_a + v_pa)
    pv = math.sqrt(v_p)
    tv = math.sqrt(grr * grr + pv * pv)
    comp = {}
    for name, v, ci in (("repeatability", v_e, ci_e), ("appraiser", v_a, ci_a), ("part x appraiser", v_pa, ci_pa),
                        ("part", v_p, ci_p)):
        if name == "part x appraiser" and pooled:
            continue
        c = {"variance": v, "sd": math.sqrt(v), "percent_contribution": 100.0 * v / (tv * tv)}
        if ci is not None:
            c["ci95"] = ci
        comp[name] = c
    sd = {"EV": ev, "AV": av, "interaction": inter, "reproducibility": repro, "GRR": grr, "PV": pv, "TV": tv}
    pct_tv = {k: 100.0 * sd[k] / tv for k in ("EV", "AV", "interaction", "GRR", "PV")}
    ndc = int(math.floor(1.41 * pv / grr))
    out = {
        "method": "ANOVA, crossed, random effects (AIAG MSA 4th ed.)",
        "design": {"parts": p, "appraisers": o, "trials": r, "measurements": p * o * r},
        "mean": float(gm),
        "anova": anova,
        "pooled": pooled,
        "pool_alpha": pool_alpha,
        "interaction_p": p_pa,
        "components": comp,
        "sd": sd,
        "percent_tv": pct_tv,
        "ndc": ndc,
        "acceptance": {"by_tv": acceptance(pct_tv["GRR"])},
        "notes": ["standard deviations at one sigma; %tolerance against tolerance / 6 (AIAG 4th ed.); "
                  f"interaction pooled into repeatability when its p-value > {pool_alpha:g}; negative variance "
                  "estimates set to 0; ci95: chi-square (repeatability) or Satterthwaite"],
    }
    if tolerance is not None:
        out["tolerance"] = tolerance
        out["percent_tolerance"] = {k: 100.0 * sd[k] / (tolerance / 6.0) for k in ("EV", "AV", "interaction", "GRR", "PV")}
        out["acceptance"]["by_tolerance"] = acceptance(out["percent_tolerance"]["GRR"])
    if ndc < 5:
        out.setdefault("warnings", []).append(f"ndc {ndc} < 5: the gage cannot tell enough part categories apart (AIAG)")
    if parts is not None:
        out["parts"] = [str(x) for x in parts]
    if appraisers is not None:
        out["appraisers"] = [str(x) for x in appraisers]
    return out


def type1_study(values: Sequence[float], reference: float, tolerance: float) -> dict:
    """Type-1 gage study of repeated measurements of one reference part: mean, s, bias,
    ``Cg = 0.2 T / 6 s``, ``Cgk = (0.1 T - |bias|) / 3 s`` (VDA 5, Bosch booklet 10),
    ``capable`` when both >= 1.33; a t-test of the bias (``bias_t``, ``bias_p``)."""
    x = np.asarray(values, dtype=float)
    if x.ndim != 1 or x.size < 2:
        raise InvalidInputError("Type-1 study: needs at least 2 repeated measurements (VDA 5: 25, Bosch: 50)")
    _check_values(x, "Type-1 study: the measurements")
    if not (math.isfinite(reference)):
        raise InvalidInputError("Type-1 study: the reference value must be finite")
    if not (math.isfinite(tolerance) and tolerance > 0):
        raise InvalidInputError(f"Type-1 study: tolerance {tolerance}: a positive number (USL - LSL)")
    n = int(x.size)
    mean = float(x.mean())
    s = float(x.std(ddof=1))
    if not s > 0.0:
        raise InvalidInputError("Type-1 study: the repeated measurements do not vary: no Cg (resolution too coarse?)")
    bias = mean - reference
    cg = 0.2 * tolerance / (6.0 * s)
    cgk = (0.1 * tolerance - abs(bias)) / (3.0 * s)
    t = bias / (s / math.sqrt(n))
    p_bias = betainc((n - 1) / 2.0, 0.5, (n - 1) / (n - 1 + t * t))  # two-sided t test
    out = {"method": "Type-1 gage study (VDA 5, Bosch booklet 10): Cg = 0.2 T / 6 s, Cgk = (0.1 T - |bias|) / 3 s",
           "n": n, "reference": float(reference), "tolerance": float(tolerance), "mean": mean, "sd": s, "bias": bias,
           "bias_t": t, "bias_p": p_bias, "cg": cg, "cgk": cgk, "capable": bool(cg >= 1.33 and cgk >= 1.33)}
    if n < MIN_TYPE1_VALUES:
        out["warnings"] = [f"{n} measurements, fewer than {MIN_TYPE1_VALUES}: Cg and Cgk are uncertain"]
    return out


# ------------------------------------------------------------------ studies from files and databases

#: default pattern of scan file names in a gage R&R study (the file name without its suffix)
DEFAULT_PATTERN = "{part}_{appraiser}_{trial}"
CSV_COLUMNS = ("part", "appraiser", "trial", "value")


def read_study_csv(path) -> list[dict]:
    """Rows ``{part, appraiser, trial, value, characteristic}`` of a study CSV with a header
    naming the columns ``part, appraiser, trial, value`` and optionally ``characteristic``
    (any order, case-insensitive). A bad line is a :class:`FileFormatError` naming it."""
    from .._files import csv_rows, read_text
    from ..errors import FileFormatError

    text = read_text(path, "study CSV")
    it = csv_rows(text, path)
    head = next(it, None)
    if head is None:
        raise FileFormatError(f"{path}: empty file; a study CSV has a header part,appraiser,trial,value")
    cols = [c.strip().lower() for c in head[1]]
    missing = [c for c in CSV_COLUMNS if c not in cols]
    if missing:
        raise FileFormatError(f"{path}, line {head[0]}: no column {', '.join(missing)} (header: part,appraiser,trial,"
                              "value[,characteristic])")
    idx = {c: cols.index(c) for c in (*CSV_COLUMNS, "characteristic") if c in cols}
    rows = []
    for line, cells in it:
        if not any(c.strip() for c in cells):
            continue
        if len(cells) < len(cols):
            raise FileFormatError(f"{path}, line {line}: {len(cells)} cells, the header has {len(cols)}")
        try:
            value = float(cells[idx["value"]])
        except ValueError:
            raise FileFormatError(f"{path}, line {line}: value {cells[idx['value']]!r} is not a number") from None
        if not math.isfinite(value):
            raise InvalidInputError(f"{path}, line {line}: value {cells[idx['value']]}: every value must be finite")
        rows.append({"part": cells[idx["part"]].strip(), "appraiser": cells[idx["appraiser"]].strip(),
                     "trial": cells[idx["trial"]].strip(), "value": value,
                     "characteristic": cells[idx["characteristic"]].strip() if "characteristic" in idx else "value"})
    if not rows:
        raise FileFormatError(f"{path}: a header and no measurements")
    return rows


def _trial_key(t: str):
    try:
        return (0, float(t), t)
    except ValueError:
        return (1, 0.0, t)


def study_rows_from_db(url: str, documents: Optional[list], pattern: str = DEFAULT_PATTERN) -> list[dict]:
    """Rows ``{part, appraiser, trial, value, characteristic, lower, upper, path}`` of the
    results database: every tolerance of every inspection (and the form error of every
    form fit) of the specs whose stored document is one of ``documents``, the part,
    appraiser and trial read from each scan's file name (without suffix) by ``pattern``.
    A file name the pattern does not match is an :class:`InvalidInputError` naming it."""
    from pathlib import PurePath

    import sqlalchemy as sa

    from ..errors import StoreError
    from ..store import models as m
    from ..store.schema import _reason, create_engine, ensure_schema, safe_url
    from .collect import _results

    parse = name_parser(pattern)
    engine = create_engine(url, must_exist=True)
    rows: list[dict] = []
    try:
        ensure_schema(engine, create=False)
        with engine.connect() as conn:
            for spec in conn.execute(sa.select(m.Spec.id, m.Spec.kind, m.Spec.document).order_by(m.Spec.id)):
                if documents is not None and spec.document not in documents:
                    continue
                if spec.kind == "inspect":
                    res = [(r[1], r[4], r[5], r[6], r[7]) for r in _results(
                        conn, spec.id, [m.InspectionResult.tolerance, m.InspectionResult.value,
                                        m.InspectionResult.lower, m.InspectionResult.upper], m.InspectionResult)]
                elif spec.kind == "form":
                    res = [(r[1], "form error", r[4], None, None)
                           for r in _results(conn, spec.id, [m.FormResult.form_error], m.FormResult)]
                else:
                    continue
                for path, name, value, lower, upper in res:
                    stem = PurePath(path).name.split(".")[0]
                    f = parse(stem)
                    if f is None:
                        raise InvalidInputError(f"{path}: the file name does not match --pattern {pattern!r}")
                    rows.append({"part": f["part"], "appraiser": f["appraiser"], "trial": f.get("trial", ""),
                                 "value": float(value), "characteristic": name, "lower": lower, "upper": upper,
                                 "path": path})
        return rows
    except sa.exc.SQLAlchemyError as exc:
        raise StoreError(f"cannot read {safe_url(engine.url)}: {_reason(exc)}") from None
    finally:
        engine.dispose()


def studies(rows: list[dict], *, tolerance: Optional[float] = None, reference: Optional[float] = None,
            part: Optional[str] = None, pool_alpha: float = POOL_ALPHA) -> list[dict]:
    """One study per characteristic of ``rows`` (see :func:`read_study_csv`): the crossed
    ANOVA gage R&R, or with ``reference`` the Type-1 study of the repeated measurements of
    one part (``part``, or the only one). The tolerance is ``tolerance``, else the
    characteristic's stored ``upper - lower`` (``upper`` alone: a geometric tolerance's zone
    from 0)."""
    by: dict[str, list[dict]] = {}
    for r in rows:
        by.setdefault(r["characteristic"], []).append(r)
    out = []
    for name, rs in by.items():
        tol = tolerance
        if tol is None:  # stored limits; a geometric tolerance (upper limit only) is the zone 0..t
            lo, up = rs[-1].get("lower"), rs[-1].get("upper")
            if up is not None and float(up) - float(lo or 0.0) > 0:
                tol = float(up) - float(lo or 0.0)
        entry: dict = {"characteristic": name}
        if reference is not None:
            if part is not None:
                rs = [r for r in rs if r["part"] == part]
                if not rs:
                    raise InvalidInputError(f"Type-1 study: no measurement of part {part} for {name}")
            parts = sorted({r["part"] for r in rs})
            if len(parts) != 1:
                raise InvalidInputError(f"Type-1 study of {name}: {len(parts)} parts ({', '.join(parts[:5])}); "
                                        "a Type-1 study measures one reference part (choose it with --part)")
            if tol is None:
                raise InvalidInputError(f"Type-1 study of {name}: no tolerance (give --tolerance, USL - LSL)")
            entry["part"] = parts[0]
            entry["type1"] = type1_study([r["value"] for r in rs], reference, tol)
        else:
            rs = sorted(rs, key=lambda r: _trial_key(str(r["trial"])))
            y, pl, al = study_table([r["part"] for r in rs], [r["appraiser"] for r in rs], [r["value"] for r in rs])
            entry["grr"] = anova_grr(y, tolerance=tol, pool_alpha=pool_alpha, parts=pl, appraisers=al)
        out.append(entry)
    return out
