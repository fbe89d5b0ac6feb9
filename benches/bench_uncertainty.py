"""Task-specific uncertainty (issue 26 Sec. 1): JCGM 101 Monte Carlo over the whole inspection
of the bundled bracket (20 callouts; datums, frames and zones re-evaluated on every simulated
scan), isotropic noise sigma = 1 um.

gagekit: :func:`gagekit.uncertainty.inspect_uncertainty` -- the feature regions are cut once
and only their points (the active set) are perturbed; the drawing is compiled once and each
block of trials is one kernel call running its trials in parallel on 2 threads
(``gagekit_gdt::plan``), each seeded by (seed, trial); each trial starts from the measured
evaluation (docs/uncertainty.md, "How a trial is evaluated fast"): the minimax cylinders run
the exact local method from the measured axis (the global search where it cannot decide:
counted), the least-squares cylinders start from the measured axis, the minimum-zone
sphere, flatness slabs and roundness sections run on active sets verified on every point;
with isotropic noise the planes A, B, C and top are evaluated on their blocks of points that
can be extreme, the others certified inside every zone (``gagekit_gdt::plan::sparse``).
The peer: what a user writes without it -- a loop of ``gagekit.inspect`` on a perturbed copy
of the whole scan (regions cut again every time), one trial after the other; timed on
``--peer-trials`` trials and scaled to the same number of trials (said on the line).

Goals of the issue: 1,000 trials in < 10 s at 29 k points, < 60 s at 2 M points on 2 cores.
Prints: case, gagekit time, peer time, ratio; the 2 M case runs ``--large-trials`` trials and
prints the time scaled to 1,000 beside it.
Run: python benches/bench_uncertainty.py [--trials 1000] [--peer-trials 10] [--large-trials 10]
[--large-peer-trials N] [--quick]
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import time

import numpy as np

from gagekit import read_points
from gagekit.inspect import inspect, load_part_spec
from gagekit.samples import data_path
from gagekit.uncertainty import inspect_uncertainty, measurement_model, trial_rng

SIGMA = 0.001


def generator():
    spec = importlib.util.spec_from_file_location("make_bracket", data_path("make_bracket.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def peer(pts: np.ndarray, spec, trials: int) -> float:
    model = measurement_model(sigma=SIGMA)
    t = time.perf_counter()
    for i in range(trials):
        inspect(model.perturb(pts, trial_rng(0, i)), spec)
    return time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--trials", type=int, default=1000)
    ap.add_argument("--peer-trials", type=int, default=10)
    ap.add_argument("--large-trials", type=int, default=10)
    ap.add_argument("--large-peer-trials", type=int, default=None,
                    help="peer trials of the 2 M case, scaled to --large-trials (default: a fifth of them)")
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    if a.quick:
        a.trials, a.peer_trials, a.large_trials = 20, 3, 0
    spec = load_part_spec(data_path("bracket.toml"))
    model = measurement_model(sigma=SIGMA)
    print(f"{'case':62s} {'gagekit s':>10s} {'peer s':>10s} {'ratio':>7s}")
    pts = read_points(data_path("bracket.ply"))
    t, c = time.perf_counter(), time.process_time()
    res = inspect_uncertainty(pts, spec, model, a.trials, seed=0, threads=2)
    t_g, c_g = time.perf_counter() - t, time.process_time() - c
    t_p = peer(pts, spec, a.peer_trials) * a.trials / a.peer_trials
    print(f"{f'bracket {len(pts)} pts, 20 callouts, {a.trials} trials (peer x{a.trials}/{a.peer_trials})':62s} "
          f"{t_g:10.2f} {t_p:10.2f} {t_p / t_g:7.1f}")
    worst = max(res.tolerances, key=lambda r: r.uncertainty["U"])
    print(f"#   largest U {worst.uncertainty['U']:.6f} mm ({worst.characteristic} of {worst.feature}); "
          f"per trial {t_g / a.trials * 1000:.0f} ms on 2 threads")
    w = res.monte_carlo.get("warm_starts", {})
    print(f"#   CPU {c_g:.2f} s in all threads ({c_g / a.trials * 1000:.1f} ms a trial); warm-started cylinder fits "
          f"{w.get('fits', 0)}, fallbacks to the global search {w.get('fallbacks', 0)}; load average "
          f"{os.getloadavg()[0]:.1f}")
    if a.large_trials:
        big = generator().make_bracket(70.0)
        t, c = time.perf_counter(), time.process_time()
        r = inspect_uncertainty(big, spec, model, a.large_trials, seed=0, threads=2)
        t_g, c_g = time.perf_counter() - t, time.process_time() - c
        t_m = r.seconds - r.monte_carlo["seconds"]  # the measured evaluation (once, not per trial)
        k = a.large_peer_trials if a.large_peer_trials else max(1, a.large_trials // 5)
        t_p = peer(big, spec, k) * a.large_trials / k
        print(f"{f'bracket {len(big)} pts, 20 callouts, {a.large_trials} trials':62s} {t_g:10.2f} {t_p:10.2f} {t_p / t_g:7.1f}")
        per = (t_g - t_m) / a.large_trials
        print(f"#   the measured evaluation {t_m:.1f} s once, then {per:.2f} s a trial: scaled to 1000 trials "
              f"{t_m + per * 1000:.0f} s (goal 60 s); CPU {c_g:.1f} s; load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
