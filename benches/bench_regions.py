"""Region classification (Sec. 5.4.1 sampling volumes): 14M points against 30 oriented boxes.

Prints points x boxes per second for gagekit.classify (one parallel pass in Rust) and, side
by side, for a vectorised numpy version (chunked, box by box); the index sets are compared.

    python benches/bench_regions.py [--quick]
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

import gagekit
from gagekit.cloud.regions import Box


def rotation(rv: np.ndarray) -> np.ndarray:
    theta = np.linalg.norm(rv)
    if theta == 0:
        return np.eye(3)
    k = rv / theta
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(theta) * kx + (1 - np.cos(theta)) * kx @ kx


def numpy_classify(points: np.ndarray, boxes: list[Box], chunk: int = 1 << 19) -> list[np.ndarray]:
    """Vectorised numpy: per chunk of points (columns made contiguous once), per box,
    the three local coordinates by column arithmetic and one combined mask."""
    parts: list[list[np.ndarray]] = [[] for _ in boxes]
    frames = [(np.asarray(b.center), rotation(np.asarray(b.rotation)), np.asarray(b.size) / 2) for b in boxes]
    for s in range(0, len(points), chunk):
        x, y, z = (np.ascontiguousarray(points[s : s + chunk, k]) for k in range(3))
        for k, (c, r, half) in enumerate(frames):
            dx, dy, dz = x - c[0], y - c[1], z - c[2]
            mask = np.abs(dx * r[0, 0] + dy * r[1, 0] + dz * r[2, 0]) <= half[0]
            mask &= np.abs(dx * r[0, 1] + dy * r[1, 1] + dz * r[2, 1]) <= half[1]
            mask &= np.abs(dx * r[0, 2] + dy * r[1, 2] + dz * r[2, 2]) <= half[2]
            parts[k].append(s + np.flatnonzero(mask))
    return [np.concatenate(p) for p in parts]


def main() -> None:
    n = 1_400_000 if "--quick" in sys.argv else 14_000_000
    rng = np.random.default_rng(0)
    # a part of about 1.5 m x 1.5 m x 0.5 m, and 30 boxes of 50-300 mm with random rotations
    points = rng.uniform([0, 0, 0], [1500, 1500, 500], size=(n, 3))
    boxes = [
        Box(
            center=tuple(rng.uniform([100, 100, 50], [1400, 1400, 450])),
            size=tuple(rng.uniform(50, 300, 3)),
            rotation=tuple(rng.normal(0, 0.5, 3)),
            name=f"box{i}",
        )
        for i in range(30)
    ]
    gagekit.classify(points[:100_000], boxes)  # warm-up
    times = []
    for _ in range(3):
        t = time.perf_counter()
        got = gagekit.classify(points, boxes)
        times.append(time.perf_counter() - t)
    t_gk = min(times)
    t = time.perf_counter()
    ref = numpy_classify(points, boxes)
    t_np = time.perf_counter() - t
    agree = all(np.array_equal(a, b) for a, b in zip(got, ref))
    work = n * len(boxes)
    print(f"# {n:,} points x {len(boxes)} boxes, {os.cpu_count()} cores, "
          f"{sum(map(len, got)):,} memberships")
    print(f"{'case':<22} {'gagekit':>9} {'numpy':>9} {'ratio':>7} {'gagekit pts*boxes/s':>20} {'numpy pts*boxes/s':>18}  agree")
    case = f"classify {n / 1e6:g}M x {len(boxes)}"
    print(f"{case:<22} {t_gk:8.2f}s {t_np:8.2f}s {t_np / t_gk:6.1f}x {work / t_gk:20.3g} {work / t_np:18.3g}  {agree}")


if __name__ == "__main__":
    main()
