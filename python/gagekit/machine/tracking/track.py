"""Thermal error tracking over repeated measurement cycles (Sec. 4.3.2-4.3.4).

The same plan is measured in every cycle. The tracker frame T0 is fitted in cycle 1 (Eq. 4.11;
with the frame correction of ERRATA item 6) and kept; then, per cycle j:

* ``full``: the groups re-identified from cycle j (Eqs. 4.12-4.14, Table 4.4);
* ``static``: cycle 1's groups used unchanged (Eq. 4.15, Table 4.5);
* ``drift_only``: cycle 1's groups plus a fitted translation of the workspace (Eqs. 4.16-4.18,
  Table 4.6);
* ``observed``: the errors left after the tracker placement (the "Observed" columns).

With temperature columns, a ridge model from the cycle-mean temperatures to each group
(Sec. 7.2, item 4), its strength chosen by leave-one-cycle-out, and its nested
leave-one-cycle-out prediction residuals (``temperature_model.leave_one_cycle_out_mean``, mm,
beside the full, static and drift-only residuals of each cycle). The nested search refits the
ridge C^2 times per strength; each training set is decomposed once (thin SVD) and reused
across the 25 strengths, and the residuals are linear in the groups, so a year of daily
cycles (365 x 80 points) tracks in seconds (``benches/bench_track.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from ... import _core, _progress
from ...errors import DegenerateGeometryError
from ..identify import identify
from ..model import Machine, ModelStructure
from ..observations import Observations
from .cycles import Cycles

__all__ = ["TrackResult", "track"]


def _stats(res: np.ndarray, observed: dict) -> dict:
    """mean/max of per-point residual norms (mm) and % decrease against the observed errors."""
    n = np.linalg.norm(res, axis=1)
    d = {"mean": float(n.mean()), "max": float(n.max())}
    if observed:
        d["decrease_mean_pct"] = 100.0 * (1 - d["mean"] / observed["mean"]) if observed["mean"] > 0 else 0.0
        d["decrease_max_pct"] = 100.0 * (1 - d["max"] / observed["max"]) if observed["max"] > 0 else 0.0
    return d


@dataclass(frozen=True, eq=False)
class TrackResult:
    """Per-cycle statistics (mm) of Tables 4.4-4.6, group values per cycle, temperature model."""

    machine: str
    cycles: list
    groups: dict
    group_units: dict
    temperature_model: Optional[dict]
    residuals: dict = field(repr=False)  # mode -> (C, n) residual norms, mm
    frame: dict = field(default_factory=dict)
    #: RMS over the plan's points of |d(error)/d(group)|, mm per group unit (for the drift plot)
    group_effect: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        d = {"machine": self.machine, "cycles": self.cycles, "groups": self.groups, "group_units": self.group_units,
             "frame": self.frame}
        if self.temperature_model is not None:
            d["temperature_model"] = self.temperature_model
        return d


def track(machine: Machine, cycles: Cycles, structure: Optional[ModelStructure] = None) -> TrackResult:
    """Track the error model over the cycles (Eqs. 4.11-4.18)."""
    st = structure if structure is not None else machine.structure()
    cmds = cycles.commands
    n = len(cmds)
    if n < st.rank:
        raise DegenerateGeometryError(
            f"the plan has {n} points; re-identifying the {st.rank} groups each cycle needs at least {st.rank}"
        )
    p_nom = machine.nominal(cmds)
    m = st.reduce(machine.design_matrix(cmds))
    sv = np.linalg.svd(m, compute_uv=False)
    if sv[-1] <= 1e-10 * sv[0]:
        raise DegenerateGeometryError("the plan cannot identify all groups (its design matrix is rank deficient): design it with `machine design`")
    cal1 = identify(machine, Observations(cmds, cycles.measured[0], cycles.joint_names), structure=st)
    frame = cal1.frame  # Eq. 4.11, kept for all cycles
    resid = [frame.to_table(q) - p_nom for q in cycles.measured]  # observed errors, table frame
    pinv = np.linalg.pinv(m)
    params = [pinv @ r.reshape(-1) for r in resid]  # Eqs. 4.12, 4.13
    p1 = params[0]
    rows, modes = [], {"full": [], "static": [], "drift_only": []}
    for j, (cid, r) in enumerate(_progress.track(list(zip(cycles.cycle_ids, resid)), "tracking cycles")):
        obs = _stats(r, {})
        full = r - (m @ params[j]).reshape(-1, 3)  # Eq. 4.14
        static = r - (m @ p1).reshape(-1, 3)  # Eq. 4.15
        drift = static - static.mean(axis=0)  # Eqs. 4.16-4.18: best translation of the workspace
        row = {"cycle": cid, "observed": obs, "full": _stats(full, obs), "static": _stats(static, obs),
               "drift_only": _stats(drift, obs), "drift_translation_mm": static.mean(axis=0).tolist()}
        if cycles.time is not None:
            row["time"] = float(cycles.time[j])
        if cycles.temperatures:
            row["temperatures"] = {s: float(v[j]) for s, v in cycles.temperatures.items()}
        rows.append(row)
        for key, arr in (("full", full), ("static", static), ("drift_only", drift)):
            modes[key].append(np.linalg.norm(arr, axis=1))
    names = [g.name for g in st.groups]
    units = machine.parameter_units()
    groups = {name: [float(p[i]) for p in params] for i, name in enumerate(names)}
    temp_model = _temperature_model(cycles, params, names, m, resid) if cycles.temperatures else None
    effect = np.sqrt((m.reshape(n, 3, -1) ** 2).sum(axis=1).mean(axis=0))  # RMS |column| over the plan
    return TrackResult(
        machine=machine.name,
        cycles=rows,
        groups=groups,
        group_units={name: units[st.leaders[i]] for i, name in enumerate(names)},
        temperature_model=temp_model,
        residuals={k: np.array(v) for k, v in modes.items()},
        frame=frame.to_dict(),
        group_effect={name: float(effect[i]) for i, name in enumerate(names)},
    )


#: Ridge strengths tried, relative to the mean squared norm of the standardised temperatures.
_LAMBDAS = tuple(float(v) for v in np.logspace(-3, 3, 25))


def _ridge_parts(T: np.ndarray, P: np.ndarray):
    """What every ridge strength shares for training cycles T (..., k, S), P (..., k, G)
    (leading axes: a batch of training sets): the temperature means and scales, the group
    means, the thin SVD X = U diag(s) V^T of the standardised temperatures, U^T (P - mean)
    and the scale of the strengths (mean squared norm of the rows of X)."""
    tm, pm = T.mean(axis=-2), P.mean(axis=-2)
    sd = T.std(axis=-2)
    sd = np.where(sd > 1e-9, sd, 1.0)
    X = (T - tm[..., None, :]) / sd[..., None, :]
    U, sv, Vt = np.linalg.svd(X, full_matrices=False)
    UtY = np.swapaxes(U, -1, -2) @ (P - pm[..., None, :])
    scale = np.maximum((sv**2).sum(axis=-1) / T.shape[-2], 1e-12)
    return tm, sd, pm, sv, Vt, UtY, scale


def _ridge(T: np.ndarray, P: np.ndarray, lam: float):
    """Ridge regression of group values P (C, G) on temperatures T (C, S): standardised
    temperatures, strength lam times the mean squared norm of their rows; through the thin
    SVD of the standardised temperatures, so more sensors than cycles is fine. Returns
    (T mean, T scale, P mean, coefficients (S, G) per standardised unit)."""
    tm, sd, pm, sv, Vt, UtY, scale = _ridge_parts(T, P)
    # X^T (X X^T + mu I)^-1 Y = V diag(s / (s^2 + mu)) U^T Y
    B = Vt.T @ ((sv / (sv**2 + lam * scale))[:, None] * UtY)
    return tm, sd, pm, B


def _predict_groups(fit, t: np.ndarray) -> np.ndarray:
    tm, sd, pm, B = fit
    return pm + ((t - tm) / sd) @ B


def _loo_errors(T, P, m, resid, idx) -> np.ndarray:
    """Leave-one-cycle-out mean residual over the cycles ``idx`` for every strength of
    ``_LAMBDAS`` (sum over the held-out cycles of the mean residual length, mm).

    Each training set is decomposed once and every strength then costs a rescaling of the
    spectrum; the model's residuals are linear in the predicted groups. With fewer sensors
    than training cycles, the Rust kernel (``gagekit_kinematics::ridge``: the primal form
    (X^T X + mu I)^-1 X^T Y from the sums over all cycles minus the held-out one, S x S per
    set, in parallel over the held-out cycles); otherwise the thin SVD of each set's X."""
    idx = np.asarray(idx)
    k, S = len(idx), T.shape[1]
    n = resid[0].shape[0]
    R = np.ascontiguousarray(np.stack([resid[c].reshape(-1) for c in idx]))  # (k, 3n)
    if S < k - 1:
        return np.array(_core.kinematics.tracking_loo_errors(np.ascontiguousarray(T[idx], dtype=np.float64),
                                                  np.ascontiguousarray(P[idx], dtype=np.float64), R,
                                                  np.ascontiguousarray(m, dtype=np.float64), list(_LAMBDAS)))
    Ti = T[idx] - T[idx].mean(axis=0)  # the ridge is invariant to a shift of the temperatures
    return _loo_errors_dual(Ti, P[idx], R, np.ascontiguousarray(m.T), n)


def _loo_errors_dual(Ti, Pi, R, mt, n) -> np.ndarray:
    """:func:`_loo_errors` with at least as many sensors as training cycles: the thin SVD
    X = U diag(s) V^T of each training set, X^T (X X^T + mu I)^-1 Y = V diag(s/(s^2+mu)) U^T Y;
    held-out cycles in chunks of about 4 million numbers per array."""
    k, S = Ti.shape
    r = min(k - 1, S)
    chunk = max(1, 4_000_000 // max(1, (k - 1) * S + r * mt.shape[1] + len(_LAMBDAS) * mt.shape[1]))
    others = np.arange(k - 1)
    lam = np.asarray(_LAMBDAS)[None, :, None]
    err = np.zeros(len(_LAMBDAS))
    for lo in range(0, k, chunk):
        held = np.arange(lo, min(k, lo + chunk))
        rows = others[None, :] + (others[None, :] >= held[:, None])  # every cycle but the held-out one
        tm, sd, pm, sv, Vt, UtY, scale = _ridge_parts(Ti[rows], Pi[rows])
        a = (Vt @ ((Ti[held] - tm) / sd)[:, :, None])[:, :, 0]
        w = a[:, None, :] * sv[:, None, :] / (sv[:, None, :] ** 2 + lam * scale[:, None, None])
        err += _residual_sums(R[held] - pm @ mt, w, UtY @ mt, n)
    return err


def _residual_sums(base, w, mb, n) -> np.ndarray:
    """Sum over the held-out cycles of the mean residual length, per strength: residuals
    base - w @ mb, (h, L, 3n), of n points."""
    res = (base[:, None, :] - w @ mb).reshape(base.shape[0], w.shape[1], n, 3)
    return np.sqrt(np.einsum("hlpi,hlpi->hlp", res, res)).mean(axis=2).sum(axis=0)


def _choose_lambda(T, P, m, resid, idx) -> float:
    """Strength with the smallest leave-one-cycle-out mean residual over the cycles ``idx``
    (the first of equal ones)."""
    best, best_err = _LAMBDAS[0], np.inf
    for lam, err in zip(_LAMBDAS, _loo_errors(T, P, m, resid, idx)):
        if err < best_err - 1e-15:
            best, best_err = lam, float(err)
    return best


def _temperature_model(cycles: Cycles, params, names, m, resid) -> dict:
    """Ridge model group = a + b . (T - T_ref) over cycle-mean temperatures; its strength is
    chosen by leave-one-cycle-out on the training cycles, so the reported leave-one-cycle-out
    residuals are nested (the held-out cycle never chooses its own strength)."""
    sensors = list(cycles.temperatures)
    T = np.column_stack([cycles.temperatures[s] for s in sensors])  # (C, S)
    P = np.array(params)  # (C, G)
    C = len(P)
    if C < 4:
        return {"sensors": sensors, "fitted": False, "reason": "a temperature model needs at least 4 cycles (3 to choose its strength)"}
    allc = list(range(C))
    loo = []
    for c in allc:
        keep = [i for i in allc if i != c]
        lam = _choose_lambda(T, P, m, resid, keep)
        g = _predict_groups(_ridge(T[keep], P[keep], lam), T[c])
        res = np.linalg.norm(resid[c] - (m @ g).reshape(-1, 3), axis=1)
        loo.append({"cycle": cycles.cycle_ids[c], "mean": float(res.mean()), "max": float(res.max()), "lambda": lam})
    lam = _choose_lambda(T, P, m, resid, allc)
    tm, sd, pm, B = _ridge(T, P, lam)
    coef = B / sd[:, None]  # per C
    return {
        "fitted": True,
        "model": "ridge (standardised temperatures; strength by nested leave-one-cycle-out)",
        "lambda": lam,
        "sensors": sensors,
        "coefficients": {name: {s: float(coef[k, i]) for k, s in enumerate(sensors)} for i, name in enumerate(names)},
        "intercept": {name: float(pm[i]) for i, name in enumerate(names)},
        "reference_temperatures": {s: float(v) for s, v in zip(sensors, tm)},
        "leave_one_cycle_out": loo,
        "leave_one_cycle_out_mean": float(np.mean([x["mean"] for x in loo])),
    }
