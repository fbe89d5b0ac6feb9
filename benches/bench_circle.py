"""Benchmark of the 2-D circle fits against what a user would write with SciPy.

One line per case: case, gagekit time, peer time, ratio (peer / gagekit), and both
results (radius for lsq/mc/mi, zone width for mz), so accuracy is compared too.
Peers: ``scipy.optimize.least_squares`` for lsq; Nelder-Mead on the min-max objective
(Eq. 6.1 for mc, Eq. 6.4 restricted to MC for mi, Eq. 6.5 for mz) from the centroid,
the heuristic style of commercial zone fits.

Usage: python benches/bench_circle.py [--sizes 1000 10000 100000 1000000] [--noise 0.01]
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.optimize import least_squares, minimize

from gagekit import fit_circle
from _timing import timed


def noisy_circle(n: int, noise: float, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    a = rng.uniform(0.0, 2.0 * np.pi, n)
    r = 50.0 + rng.uniform(-noise / 2, noise / 2, n)
    return np.c_[120.0 + r * np.cos(a), -40.0 + r * np.sin(a)]


def _dist(pts: np.ndarray, c: np.ndarray) -> np.ndarray:
    return np.hypot(pts[:, 0] - c[0], pts[:, 1] - c[1])


def peer(pts: np.ndarray, crit: str) -> float:
    c0 = pts.mean(axis=0)
    opts = {"xatol": 1e-10, "fatol": 1e-12, "maxiter": 4000}
    if crit == "lsq":
        r0 = _dist(pts, c0).mean()
        res = least_squares(lambda x: _dist(pts, x[:2]) - x[2], [*c0, r0], xtol=1e-15, ftol=1e-15)
        return float(res.x[2])
    if crit == "mc":
        res = minimize(lambda c: _dist(pts, c).max(), c0, method="Nelder-Mead", options=opts)
        return float(res.fun)
    if crit == "mz":
        def f(c):
            d = _dist(pts, c)
            return d.max() - d.min()
        res = minimize(f, c0, method="Nelder-Mead", options=opts)
        return float(res.fun)
    # mi: maximise min distance, constrained within MC (Eq. 6.2) by a penalty
    cmc = minimize(lambda c: _dist(pts, c).max(), c0, method="Nelder-Mead", options=opts)
    rmc = cmc.fun

    def g(c):
        return -min(_dist(pts, c).min(), rmc - np.hypot(*(c - cmc.x)))

    res = minimize(g, cmc.x, method="Nelder-Mead", options=opts)
    return float(-res.fun)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000, 100000, 1000000])
    ap.add_argument("--noise", type=float, default=0.01, help="peak-to-valley radial noise, mm (radius 50 mm)")
    ap.add_argument("--no-peer", action="store_true")
    args = ap.parse_args()
    print(f"{'case':<14}{'gagekit':>12}{'peer':>12}{'ratio':>9}   gagekit result       peer result")
    for n in args.sizes:
        pts = noisy_circle(n, args.noise)
        for crit in ("lsq", "mc", "mi", "mz"):
            rep = 3 if n <= 100000 else 1
            tg, fit = timed(lambda: fit_circle(pts, crit), rep)
            val = fit.form_error if crit == "mz" else fit.radius
            if args.no_peer:
                tp, pv = float("nan"), float("nan")
            else:
                tp, pv = timed(lambda: peer(pts, crit), 1)
            print(f"{crit + ' ' + format(n, '.0e'):<14}{tg * 1e3:>10.1f}ms{tp * 1e3:>10.1f}ms{tp / tg:>9.1f}"
                  f"   {val:<20.12f} {pv:<20.12f}", flush=True)


if __name__ == "__main__":
    main()
