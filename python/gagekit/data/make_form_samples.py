"""Simulated probe measurements of four features, the samples of the form commands' tour.

Each file is a feature of known nominal size and pose with a known form deviation (lobing,
the usual signature of turning and boring, Sec. 6.1) plus Gaussian probing noise, from a
fixed seed, so the commands' numbers can be checked against the truth below. Lengths mm.

``round.csv`` (2-D, ``x,y``): a turned diameter 50 circle about (10, -5), 90 points around
the full circle; 3 lobes of 4 um and 2 lobes of 2 um amplitude, noise 0.5 um.
``bore.csv`` (``x,y,z``): a bored hole of diameter 40, axis through (0, 0, 0) tilted 0.2
degrees from z towards x, 8 sections z = 5..40 of 36 points; 3 lobes of 5 um, a taper of
6 um over the length, noise 0.5 um.
``ball.csv``: a 25.4 mm reference ball about (100, 50, 20), 200 points on its upper
hemisphere (a probe cannot reach the stem side), 2 lobes of 0.3 um, noise 0.2 um.
``cone.csv``: a shaft cone with a full apex angle of 60 degrees, axis z through the origin,
apex at z = 40, 6 sections z = 5..30 of 30 points; noise 1 um normal to the surface (the
README's ``gagekit form fit cone`` lines: half angle 30 degrees to 1e-3, conicity about 5 um).
``program.nc``: a short 3-axis program for the example machine (``gagekit data path
machine``): a rapid to the start, then feed moves around a pocket, with the rotary table B
and the ram W fixed.

Run ``python -m gagekit.data.make_form_samples`` to rewrite the bundled files.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SEED = 20260125

PROGRAM = """%
O2201 (GAGEKIT SAMPLE POCKET, EXAMPLE MACHINE BXZYW)
N10 G21 G90 G17
N20 G0 B0 W-500 X-400 Y800 Z1500
N30 G1 Z1450 F800
N40 X400 F1500
N50 Y1400
N60 X-400
N70 Y800
N80 G0 Z1500
N90 M30
%
"""


def _write(path: Path, header: str, pts: np.ndarray) -> None:
    lines = [header] + [",".join(f"{v:.6f}" for v in p) for p in pts]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def round_points(rng: np.random.Generator) -> np.ndarray:
    t = np.linspace(0.0, 2 * math.pi, 90, endpoint=False)
    r = 25.0 + 0.004 * np.cos(3 * t + 0.3) + 0.002 * np.cos(2 * t + 1.1) + rng.normal(0, 0.0005, t.size)
    return np.column_stack([10.0 + r * np.cos(t), -5.0 + r * np.sin(t)])


def bore_points(rng: np.random.Generator) -> np.ndarray:
    t, z = np.meshgrid(np.linspace(0, 2 * math.pi, 36, endpoint=False), np.linspace(5.0, 40.0, 8))
    t, z = t.ravel(), z.ravel()
    r = 20.0 + 0.005 * np.cos(3 * t) + 0.006 * (z - 5.0) / 35.0 + rng.normal(0, 0.0005, t.size)
    a = math.radians(0.2)  # the axis leans towards +x
    p = np.column_stack([r * np.cos(t), r * np.sin(t), z])
    rot = np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])
    return p @ rot.T


def ball_points(rng: np.random.Generator) -> np.ndarray:
    n = 200
    k = np.arange(n) + 0.5
    polar = np.arccos(1.0 - k / n)  # equal areas on the upper hemisphere
    azim = math.pi * (1 + 5 ** 0.5) * k
    r = 12.7 + 0.0003 * np.cos(2 * azim) + rng.normal(0, 0.0002, n)
    d = np.column_stack([np.sin(polar) * np.cos(azim), np.sin(polar) * np.sin(azim), np.cos(polar)])
    return np.array([100.0, 50.0, 20.0]) + r[:, None] * d


def cone_points(rng: np.random.Generator) -> np.ndarray:
    t, z = np.meshgrid(np.linspace(0, 2 * math.pi, 30, endpoint=False), np.linspace(5.0, 30.0, 6))
    t, z = t.ravel(), z.ravel()
    half = math.radians(30.0)
    r = (40.0 - z) * math.tan(half) + rng.normal(0, 0.001, t.size) / math.cos(half)
    return np.column_stack([r * np.cos(t), r * np.sin(t), z])


def main() -> None:
    rng = np.random.default_rng(SEED)
    _write(HERE / "round.csv", "x,y", round_points(rng))
    _write(HERE / "bore.csv", "x,y,z", bore_points(rng))
    _write(HERE / "ball.csv", "x,y,z", ball_points(rng))
    _write(HERE / "cone.csv", "x,y,z", cone_points(rng))
    (HERE / "program.nc").write_text(PROGRAM, encoding="utf-8")


if __name__ == "__main__":
    main()
