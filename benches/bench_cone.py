"""Cone fits (issue 25 §3): gagekit vs what a user would write with SciPy.

One line per case: case, gagekit time, peer time, ratio (peer / gagekit), and the results
of both (radius at the reference section for MC / MI, zone width for MZ, in mm).

- MC / MI / MZ: gagekit's SLP on the minimax cone problem (axis offset, tilt, half angle,
  radii) from the least-squares cone with basin hops vs a multistart Nelder-Mead (scipy)
  on the same objective in the same 5 parameters (tilt 2, offset 2, half angle), started
  from gagekit's least-squares cone (the peer gets the start for free).

Data: the bundled sample ``cone`` (180 points) and a noisy 3-lobed cone of 2 * 10^4 points.
Run: python benches/bench_cone.py [--quick]
"""

from __future__ import annotations

import math
import sys

import numpy as np
from scipy.optimize import minimize

import gagekit
from gagekit.samples import sample_path
from _timing import timed


def _basis(a):
    u = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    return u, np.cross(a, u)


def scipy_cone(pts, crit, starts=8, seed=0):
    """Multistart Nelder-Mead on the cone's minimax objective from the least-squares cone."""
    ls = gagekit.fit_cone(pts)
    c = pts.mean(axis=0)
    a0 = np.array(ls.direction)
    u, v = _basis(a0)
    p0 = np.array(ls.point) - c
    q = pts - c

    def objective(x):
        a = a0 + x[0] * u + x[1] * v
        a /= np.linalg.norm(a)
        w = q - (p0 + x[2] * u + x[3] * v)
        z = w @ a  # from the axis point nearest the centroid (the reference section)
        rho = np.linalg.norm(w - np.outer(w @ a, a), axis=1)
        psi = ls.half_angle + x[4]
        if crit == "mz":
            d = rho * math.cos(psi) - z * math.sin(psi)
            return d.max() - d.min()
        e = rho - z * math.tan(psi)
        return e.max() if crit == "mc" else -e.min()

    rng = np.random.default_rng(seed)
    best, nfev = np.inf, 0
    for k in range(starts):
        x0 = np.zeros(5) if k == 0 else rng.normal(0, [1e-3, 1e-3, 1e-2, 1e-2, 1e-3])
        r = minimize(objective, x0, method="Nelder-Mead", options={"xatol": 1e-12, "fatol": 1e-14, "maxfev": 20000})
        best, nfev = min(best, r.fun), nfev + r.nfev
    return (abs(best), nfev)


def noisy_cone(n, seed=0):
    rng = np.random.default_rng(seed)
    t, z, psi = rng.uniform(0, 2 * np.pi, n), rng.uniform(0, 30, n), math.radians(15.0)
    d = 0.003 * np.cos(3 * t) + rng.normal(0, 0.001, n)
    rho, zz = 10 + z * math.tan(psi) + d * math.cos(psi), z - d * math.sin(psi)
    return np.column_stack([rho * np.cos(t), rho * np.sin(t), zz])


def main() -> None:
    quick = "--quick" in sys.argv
    sets = {"sample cone": np.loadtxt(sample_path("cone"), delimiter=",", skiprows=1),
            "noisy 2e4": noisy_cone(2000 if quick else 20000)}
    print(f"{'case':<20} {'gagekit_s':>10} {'peer_s':>10} {'ratio':>8}  gagekit_result / peer_result")
    for name, pts in sets.items():
        for crit in ("mz", "mc", "mi"):
            g_t, g = timed(lambda: gagekit.fit_cone(pts, crit), repeat=1 if len(pts) > 1000 else 3)
            gv = g.form_error if crit == "mz" else g.radius
            p_t, (p_v, p_n) = timed(lambda: scipy_cone(pts, crit, starts=8 if len(pts) <= 1000 else 2), repeat=1)
            print(f"{name + ' ' + crit:<20} {g_t:>10.5f} {p_t:>10.5f} {p_t / g_t:>8.1f}  "
                  f"{gv:.10f} (LPs {g.evaluations}, gap {g.gap:.1e}) / {p_v:.10f} (NM nfev {p_n})")


if __name__ == "__main__":
    main()
