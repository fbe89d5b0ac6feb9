"""Cylinder fits: gagekit vs what a user would write with SciPy.

One line per case: case, gagekit time, peer time, ratio (peer / gagekit), and the
results of both (radius or zone width; iterations where the method has them).

- least squares: gagekit's Levenberg-Marquardt vs scipy.optimize.least_squares on the
  same orthogonal distances (5 parameters, started from the principal axis).
- MCC / MIC / MZC: gagekit's projection model (PSO + refinement + exact 2-D fits) vs a
  multistart Nelder-Mead on the same 5-parameter objective (Eqs. 6.9-6.11).

Data: the dissertation's data sets 1 and 3 and 10^5 points of a noisy cylinder.
Run: python benches/bench_form3d.py [--quick]
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares, linprog, minimize

import gagekit
from gagekit.samples import data_path
from _timing import timed

REF = data_path("cylinders")


def axis_dist(pts, x):
    """Distances to the axis with direction (sin t cos f, sin t sin f, cos t) through (x0, y0, z=0)."""
    t, f, x0, y0 = x[:4]
    a = np.array([np.sin(t) * np.cos(f), np.sin(t) * np.sin(f), np.cos(t)])
    d = pts - np.array([x0, y0, 0.0])
    return np.linalg.norm(np.cross(d, a), axis=1)


def scipy_lsq(pts):
    c = pts.mean(0)
    q = pts - c
    w, v = np.linalg.eigh(q.T @ q)
    best, nfev = None, 0
    for k in ([0, 1, 2] if len(q) <= 1000 else [2]):  # each principal axis (small sets), as gagekit does
        a = v[:, k] * np.sign(v[2, k] or 1.0)
        rad = np.sqrt((w.sum() - w[k]) / len(q))
        x0 = [np.arccos(a[2]), np.arctan2(a[1], a[0]), 0.0, 0.0, rad]
        r = least_squares(lambda x: axis_dist(q, x) - x[4], x0, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15)
        nfev += r.nfev
        if best is None or r.cost < best.cost:
            best = r
    return abs(best.x[4]), nfev, best.x


def scipy_minimax(pts, crit, starts=8, seed=0, maxfev=20000):
    """Multistart Nelder-Mead on Eqs. 6.9-6.11 from the least-squares cylinder."""
    q = pts - pts.mean(0)
    _, _, x_ls = scipy_lsq(pts)
    t0, f0 = x_ls[0], x_ls[1]
    scale = abs(x_ls[4])
    rng = np.random.default_rng(seed)

    def obj(x):
        d = axis_dist(q, x)
        return {"mcc": d.max(), "mic": -d.min(), "mzc": d.max() - d.min()}[crit]

    best, nfev = None, 0
    for k in range(starts):
        x0 = [t0, f0, *x_ls[2:4]] if k == 0 else [t0 + rng.normal(0, 0.01), f0 + rng.normal(0, 0.01), *(x_ls[2:4] + rng.normal(0, 0.01 * scale, 2))]
        r = minimize(obj, x0, method="Nelder-Mead", options=dict(xatol=1e-12, fatol=1e-14, maxiter=maxfev, maxfev=maxfev))
        nfev += r.nfev
        if best is None or r.fun < best.fun:
            best = r
    val = -best.fun if crit == "mic" else best.fun
    return val, nfev


def scipy_flatness(pts):
    """Vertical Chebyshev zone in the least-squares frame by linprog (HiGHS): min w s.t.
    0 <= h - a x - b y - c <= w, reported as the orthogonal width w / sqrt(1 + a^2 + b^2)."""
    q = pts - pts.mean(0)
    _, v = np.linalg.eigh(q.T @ q)
    x, y, h = q @ v[:, 2], q @ v[:, 1], q @ v[:, 0]
    n = len(q)
    A = np.block([[-np.column_stack([x, y]), -np.ones((n, 1)), -np.ones((n, 1))],
                  [np.column_stack([x, y]), np.ones((n, 1)), np.zeros((n, 1))]])
    b = np.concatenate([-h, h])
    r = linprog([0, 0, 0, 1], A_ub=A, b_ub=b, bounds=[(None, None)] * 4, method="highs")
    a_, b_ = r.x[:2]
    return r.x[3] / np.sqrt(1 + a_ * a_ + b_ * b_), r.nit


def noisy_plane(n, seed=0):
    rng = np.random.default_rng(seed)
    xy = rng.uniform(-100, 100, (n, 2))
    z = 0.01 * np.sin(xy[:, 0] / 20) + rng.normal(0, 0.003, n)
    return np.column_stack([xy, z + 0.01 * xy[:, 0]]) + [500.0, -200.0, 50.0]


def noisy_cylinder(n, seed=0):
    rng = np.random.default_rng(seed)
    t = rng.uniform(0, 2 * np.pi, n)
    z = rng.uniform(0, 80, n)
    r = 25 + 0.005 * np.sin(3 * t) + rng.normal(0, 0.002, n)
    pts = np.column_stack([r * np.cos(t), r * np.sin(t), z])
    a, b = 0.02, -0.03
    ry = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    rx = np.array([[1, 0, 0], [0, np.cos(b), -np.sin(b)], [0, np.sin(b), np.cos(b)]])
    return pts @ (ry @ rx).T + [100.0, -50.0, 10.0]


def main() -> None:
    quick = "--quick" in sys.argv
    sets = {
        "set1": np.loadtxt(REF / "set1.csv", delimiter=",", skiprows=1),
        "set3": np.loadtxt(REF / "set3.csv", delimiter=",", skiprows=1),
        "noisy1e5": noisy_cylinder(10**4 if quick else 10**5),
    }
    print(f"{'case':<22} {'gagekit_s':>10} {'peer_s':>10} {'ratio':>8}  gagekit_result / peer_result")
    for name, pts in sets.items():
        g_t, g = timed(lambda: gagekit.fit_cylinder(pts, "least-squares"))
        p_t, (p_r, p_n, _) = timed(lambda: scipy_lsq(pts), repeat=1 if len(pts) > 1000 else 3)
        print(f"{name + ' lsq':<22} {g_t:>10.5f} {p_t:>10.5f} {p_t / g_t:>8.1f}  r={g.radius:.9f} / r={p_r:.9f} (scipy nfev {p_n})")
        for crit in ("mcc", "mic", "mzc"):
            g_t, g = timed(lambda: gagekit.fit_cylinder(pts, crit, seed=0), repeat=1 if len(pts) > 1000 else 3)
            gv = g.form_error if crit == "mzc" else g.radius
            if len(pts) > 1000:
                p_t, p_v, p_n = float("nan"), float("nan"), 0
                if not quick:
                    p_t, (p_v, p_n) = timed(lambda: scipy_minimax(pts, crit, starts=2, maxfev=3000), repeat=1)
            else:
                p_t, (p_v, p_n) = timed(lambda: scipy_minimax(pts, crit), repeat=1)
            print(
                f"{name + ' ' + crit:<22} {g_t:>10.5f} {p_t:>10.5f} {p_t / g_t:>8.1f}  "
                f"{gv:.10f} (PSO it {g.iterations}, evals {g.evaluations}) / {p_v:.10f} (NM nfev {p_n})"
            )
    flatness_cases(quick)


def flatness_cases(quick: bool) -> None:
    for n in (10**4,) if quick else (10**4, 10**5):
        pts = noisy_plane(n)
        g_t, g = timed(lambda: gagekit.fit_plane(pts, "minimum-zone"))
        p_t, (p_w, p_it) = timed(lambda: scipy_flatness(pts), repeat=1)
        print(f"{'flatness ' + str(n):<22} {g_t:>10.5f} {p_t:>10.5f} {p_t / g_t:>8.1f}  {g.form_error:.10f} / {p_w:.10f} (HiGHS it {p_it})")


if __name__ == "__main__":
    main()
