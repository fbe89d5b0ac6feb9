"""Convex-hull filter (Sec. 5.4.1) vs scipy.spatial.ConvexHull (Qhull).

One line per case: case, gagekit time, Qhull time, ratio (Qhull / gagekit), vertex count,
and whether the two vertex sets agree. Times are the best of several runs.
Goal (issue 2): at least 4x faster than Qhull on the 1M noisy patch.

    python benches/bench_hull.py [--quick] [--parry]

With ``--parry``, the same point sets (raw float64 files in a temporary folder) also go to
the Rust peer binary (benches/peers, parry3d-f64's quickhull next to gagekit-geometry's, plus
degenerate sets); it prints: case, gagekit time and vertices, parry3d time and vertices (or
its panic), ratio. parry3d never enters the shipped extension.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from scipy.spatial import ConvexHull

import gagekit
from _timing import timed


def noisy_patch(n: int, seed: int) -> np.ndarray:
    """A scanned face: 200 x 150 mm, 20 um Gaussian noise in z."""
    rng = np.random.default_rng(seed)
    return np.c_[rng.uniform(0, 200, n), rng.uniform(0, 150, n), rng.normal(0, 0.02, n)]


def ball(n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).normal(size=(n, 3))


def main() -> None:
    quick = "--quick" in sys.argv
    cases = [
        ("patch 1M", lambda: noisy_patch(1_000_000, 1), 7, 3),
        ("patch 5M", lambda: noisy_patch(5_000_000, 2), 3, 1),
        ("gaussian ball 1M", lambda: ball(1_000_000, 3), 7, 3),
    ]
    if quick:
        cases = [(name.replace("1M", "100k").replace("5M", "500k"), make, r, q) for name, make, r, q in cases]
    print(f"# gagekit {gagekit.__version__}, {os.cpu_count()} cores, "
          f"RAYON_NUM_THREADS={os.environ.get('RAYON_NUM_THREADS', 'all')}")
    print(f"{'case':<18} {'gagekit':>10} {'qhull':>10} {'ratio':>7} {'vertices':>9}  agree")
    for name, make, reps_gk, reps_qh in cases:
        pts = make()
        if quick:
            pts = pts[: len(pts) // 10]
        gagekit.convex_hull_indices(pts)  # warm-up (thread pool)
        t_gk, idx = timed(lambda: gagekit.convex_hull_indices(pts), reps_gk)
        t_qh, hull = timed(lambda: ConvexHull(pts), reps_qh)
        agree = np.array_equal(idx, np.sort(hull.vertices))
        print(f"{name:<18} {t_gk * 1e3:8.1f}ms {t_qh * 1e3:8.1f}ms {t_qh / t_gk:6.1f}x {len(idx):>9}  {agree}")


def parry(quick: bool) -> None:
    """The same patch and ball as above, hulled by gagekit-geometry and parry3d in Rust."""
    sets = [("patch-1M", noisy_patch(1_000_000, 1)), ("gaussian-ball-1M", ball(1_000_000, 3))]
    manifest = Path(__file__).parent / "peers" / "Cargo.toml"
    with tempfile.TemporaryDirectory() as tmp:
        files = []
        for name, pts in sets:
            if quick:
                pts = pts[: len(pts) // 10]
            f = Path(tmp) / f"{name}.f64"
            np.ascontiguousarray(pts, dtype="<f8").tofile(f)
            files.append(str(f))
        subprocess.run(["cargo", "run", "--quiet", "--release", "--manifest-path", str(manifest), "--", "hull", *files],
                       check=True)


if __name__ == "__main__":
    if "--parry" in sys.argv:
        parry("--quick" in sys.argv)
    else:
        main()
