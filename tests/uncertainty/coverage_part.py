"""A simulated part with known true values for the coverage test: a block with datum faces
A (bottom), B (front), C (left), a top face and a hole whose true axis is off its nominal
position; scans are the true surfaces plus isotropic Gaussian noise (seeded)."""

from __future__ import annotations

import math

import numpy as np

SIGMA = 0.005  # mm per coordinate
RADIUS = 5.0
HOLE = (30.0 + 0.03, 20.0 - 0.04)  # the true axis; nominal (30, 20)
HEIGHT = 20.0

#: the true values (ISO definitions on the noise-free surfaces)
TRUE = {"diameter": 2 * RADIUS, "position": 2 * math.hypot(0.03, 0.04), "distance": HEIGHT}


def part_toml(datum_fit: str = "least-squares") -> str:
    return f"""
[part]
name = "coverage-block"
datum_fit = "{datum_fit}"

[[feature]]
name = "A"
shape = "plane"
region = {{ center = [30, 20, 0], size = [58, 38, 0.5] }}
outward = [0, 0, -1]

[[feature]]
name = "B"
shape = "plane"
region = {{ center = [30, 0, 10], size = [58, 0.5, 18] }}
outward = [0, -1, 0]

[[feature]]
name = "C"
shape = "plane"
region = {{ center = [0, 20, 10], size = [0.5, 38, 18] }}
outward = [-1, 0, 0]

[[feature]]
name = "top"
shape = "plane"
region = {{ center = [45, 20, 20], size = [28, 38, 0.5] }}
outward = [0, 0, 1]

[[feature]]
name = "hole"
shape = "cylinder"
kind = "hole"
direction = [0, 0, 1]
region = {{ center = [30, 20, 10], size = [11, 11, 16] }}

[datums]
A = "A"
B = "B"
C = "C"

[[tolerance]]
name = "diameter"
feature = "hole"
characteristic = "size"
modifier = "GG"
nominal = 10.0
upper = 0.05
lower = -0.05

[[tolerance]]
name = "position"
feature = "hole"
characteristic = "position"
tolerance = 0.2
datums = ["A", "B", "C"]
nominal = {{ point = [30, 20, 0], direction = [0, 0, 1] }}

[[tolerance]]
name = "distance"
feature = "A"
characteristic = "distance"
to = "top"
nominal = 20.0
tolerance = 0.1
"""


def true_surfaces(n: int = 1) -> np.ndarray:
    """The noise-free surface points (a fixed grid; ``n`` scales its density)."""
    g = np.linspace
    A = np.array([(x, y, 0.0) for x in g(2, 58, 12 * n) for y in g(2, 38, 8 * n)
                  if math.hypot(x - HOLE[0], y - HOLE[1]) > RADIUS + 0.5])
    B = np.array([(x, 0.0, z) for x in g(2, 58, 12 * n) for z in g(2, 18, 4 * n)])
    C = np.array([(0.0, y, z) for y in g(2, 38, 8 * n) for z in g(2, 18, 4 * n)])
    T = np.array([(x, y, HEIGHT) for x in g(33, 58, 6 * n) for y in g(2, 38, 8 * n)])
    t = np.linspace(0, 2 * math.pi, 24 * n, endpoint=False)
    H = np.array([(HOLE[0] + RADIUS * math.cos(a), HOLE[1] + RADIUS * math.sin(a), z) for z in g(3, 17, 4 * n) for a in t])
    return np.vstack([A, B, C, T, H])


def scan(rng: np.random.Generator, n: int = 1) -> np.ndarray:
    p = true_surfaces(n)
    return p + rng.normal(0.0, SIGMA, p.shape)
