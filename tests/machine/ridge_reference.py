"""The nested leave-one-cycle-out ridge of ``machine track`` as first written (dual form,
one solve per training set and strength: about C^5 operations): the reference the fast
implementation is checked against (tests/machine/test_track_speed.py) and the peer of
``benches/bench_track.py``."""

from __future__ import annotations

import numpy as np

from gagekit.machine.tracking.track import _LAMBDAS


def ridge(T: np.ndarray, P: np.ndarray, lam: float):
    tm, pm = T.mean(axis=0), P.mean(axis=0)
    sd = T.std(axis=0)
    sd = np.where(sd > 1e-9, sd, 1.0)
    X = (T - tm) / sd
    k = X @ X.T
    scale = max(float(np.trace(k)) / len(T), 1e-12)
    B = X.T @ np.linalg.solve(k + lam * scale * np.eye(len(T)), P - pm)
    return tm, sd, pm, B


def predict(fit, t):
    tm, sd, pm, B = fit
    return pm + ((t - tm) / sd) @ B


def residual(m, resid_c, g) -> float:
    return float(np.linalg.norm(resid_c - (m @ g).reshape(-1, 3), axis=1).mean())


def loo_errors(T, P, m, resid, idx) -> np.ndarray:
    out = []
    for lam in _LAMBDAS:
        err = 0.0
        for c in idx:
            keep = [i for i in idx if i != c]
            err += residual(m, resid[c], predict(ridge(T[keep], P[keep], lam), T[c]))
        out.append(err)
    return np.array(out)


def choose_lambda(T, P, m, resid, idx) -> float:
    best, best_err = _LAMBDAS[0], np.inf
    for lam, err in zip(_LAMBDAS, loo_errors(T, P, m, resid, idx)):
        if err < best_err - 1e-15:
            best, best_err = lam, err
    return best


def nested_loo(T, P, m, resid) -> list:
    """(lambda, mean residual) of each held-out cycle, as ``temperature_model`` reports them."""
    allc = list(range(len(P)))
    out = []
    for c in allc:
        keep = [i for i in allc if i != c]
        lam = choose_lambda(T, P, m, resid, keep)
        g = predict(ridge(T[keep], P[keep], lam), T[c])
        out.append((lam, float(np.linalg.norm(resid[c] - (m @ g).reshape(-1, 3), axis=1).mean())))
    return out
