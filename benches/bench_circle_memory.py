"""Peak memory of the maximum-inscribed circle on large point sets (issue 12: 10^6
uniform points once peaked at 686 MB, 40 times the input).

Each case runs in a fresh process: the peak resident set size (ru_maxrss) after the fit
minus the one before it (points already made), against the size of the input array.
Cases: 10^6 points uniform in a square (the optimum lies outside the square, inside the
minimum circumscribed circle), uniform in a disk (an inner gap), and on a noisy ring.

    python benches/bench_circle_memory.py [--n 1000000]
"""

from __future__ import annotations

import argparse
import subprocess
import sys

CASE = r"""
import resource, sys, time
import numpy as np
import gagekit
kind, n = sys.argv[1], int(sys.argv[2])
rng = np.random.default_rng(0)
if kind == "square":
    p = rng.uniform(-1, 1, (n, 2))
elif kind == "disk":
    r, t = np.sqrt(rng.uniform(0, 1, n)), rng.uniform(0, 2 * np.pi, n)
    p = np.c_[r * np.cos(t), r * np.sin(t)]
else:
    t, r = rng.uniform(0, 2 * np.pi, n), 10 + rng.normal(0, 0.01, n)
    p = np.c_[r * np.cos(t), r * np.sin(t)]
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
t0 = time.perf_counter()
c = gagekit.fit_circle(p, "max-inscribed")
dt = time.perf_counter() - t0
after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(p.nbytes / 2**20, after - before, dt, c.radius)
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--n", type=int, default=1_000_000)
    args = ap.parse_args()
    print(f"{'case':<28}{'input MB':>9}{'peak+ MB':>10}{'x input':>9}{'time s':>8}  radius")
    for kind in ("square", "disk", "ring"):
        out = subprocess.run([sys.executable, "-c", CASE, kind, str(args.n)], capture_output=True, text=True, check=True)
        mb_in, extra, dt, radius = map(float, out.stdout.split())
        print(f"{'max-inscribed ' + kind + ' ' + format(args.n, '.0e'):<28}{mb_in:>9.1f}{extra:>10.1f}"
              f"{extra / mb_in:>9.1f}{dt:>8.2f}  {radius!r}")


if __name__ == "__main__":
    main()
