"""Generate ``roundness_profile.csv`` and ``straightness_profile.csv``, the bundled traces of
``gagekit form roundness`` / ``gagekit form straightness`` (``gagekit data path roundness``,
``gagekit data path straightness``).

Roundness: a turned shaft of radius 25 mm traced as a roundness instrument traces it, 3600
points at equal angles about the spindle axis (the origin), the part's centre 12 um off the
axis at 30 degrees; radial form: 3 lobes of 1.5 um (a three-jaw chuck), an oval of 0.8 um,
chatter of 0.3 um at 45 UPR, 0.08 um at 180 UPR (tool marks) and 0.05 um (1 sigma) of white
noise. The 50 UPR Gaussian filter keeps 3 lobes, oval and eccentricity, about 57 % of the
chatter amplitude and nothing of the rest.

Straightness: a 40 mm trace along x, 4001 points, with a 2 um, 20 mm wave, 0.5 um at 0.5 mm
and 0.05 um of noise, on a line tilted by 1e-4 rad.

Run ``python -m gagekit.data.make_roundness_samples [FOLDER]`` (default: this folder).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

SEED = 20261125
RADIUS, SAMPLES = 25.0, 3600
OFFSET_UM, OFFSET_DEG = 12.0, 30.0
#: (UPR, amplitude um, phase rad)
HARMONICS = ((2, 0.8, 0.4), (3, 1.5, 1.1), (45, 0.3, 0.0), (180, 0.08, 2.0))
NOISE_UM = 0.05


def roundness_rows(seed: int = SEED) -> list[str]:
    """The CSV lines of the roundness trace (header first), x,y in mm."""
    rng = np.random.default_rng(seed)
    t = 2 * np.pi * np.arange(SAMPLES) / SAMPLES  # angles about the spindle
    e = 1e-3 * OFFSET_UM * np.array([np.cos(np.radians(OFFSET_DEG)), np.sin(np.radians(OFFSET_DEG))])
    # the part's surface, by angle phi about the part's centre, seen from the spindle at angle t
    phi = t.copy()
    for _ in range(6):  # fixed point: the ray from the spindle at t meets the surface at phi
        r = RADIUS + 1e-3 * sum(a * np.cos(k * phi + p) for k, a, p in HARMONICS)
        x, y = e[0] + r * np.cos(phi), e[1] + r * np.sin(phi)
        phi = phi - (np.arctan2(y, x) - t + np.pi) % (2 * np.pi) + np.pi
    r = RADIUS + 1e-3 * sum(a * np.cos(k * phi + p) for k, a, p in HARMONICS) + 1e-3 * rng.normal(0.0, NOISE_UM, SAMPLES)
    x, y = e[0] + r * np.cos(phi), e[1] + r * np.sin(phi)
    return ["x,y"] + [f"{a:.7f},{b:.7f}" for a, b in zip(x, y)]


def straightness_rows(seed: int = SEED) -> list[str]:
    """The CSV lines of the straightness trace (header first), x,y in mm."""
    rng = np.random.default_rng(seed + 1)
    x = np.linspace(0.0, 40.0, 4001)
    z = 1e-3 * (2.0 * np.sin(2 * np.pi * x / 20.0) + 0.5 * np.sin(2 * np.pi * x / 0.5) + rng.normal(0.0, 0.05, x.size))
    y = 1e-4 * x + z
    return ["x,y"] + [f"{a:.7f},{b:.7f}" for a, b in zip(x, y)]


def main(folder: Path) -> None:
    (folder / "roundness_profile.csv").write_text("\n".join(roundness_rows()) + "\n", encoding="utf-8")
    (folder / "straightness_profile.csv").write_text("\n".join(straightness_rows()) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent)
