"""Generate ``grr_study.csv``, the bundled gage R&R study (``gagekit data path grr-study``).

A crossed study as AIAG MSA (4th ed., Ch. III, Sec. B) lays it out: 10 parts x 3 appraisers
x 3 trials, one row per measurement (columns ``part, appraiser, trial, value``, mm). Seeded
simulation with stated variance components: part sd 0.020 mm, appraiser sd 0.004 mm,
interaction sd 0.002 mm, repeatability sd 0.003 mm about a nominal of 20.000 mm, so
``gagekit stats grr --csv`` on it recovers them within their intervals.

Run ``python -m gagekit.data.make_grr_sample [FOLDER]`` (default: this folder).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

SEED = 20261125
PARTS, APPRAISERS, TRIALS = 10, ("A", "B", "C"), 3
SD_PART, SD_APPRAISER, SD_INTERACTION, SD_REPEAT = 0.020, 0.004, 0.002, 0.003


def study_rows(seed: int = SEED) -> list[str]:
    """The CSV lines of the study (header first)."""
    rng = np.random.default_rng(seed)
    part = rng.normal(0.0, SD_PART, PARTS)
    appraiser = rng.normal(0.0, SD_APPRAISER, len(APPRAISERS))
    inter = rng.normal(0.0, SD_INTERACTION, (PARTS, len(APPRAISERS)))
    rows = ["part,appraiser,trial,value"]
    for t in range(1, TRIALS + 1):
        for j, a in enumerate(APPRAISERS):
            for i in range(PARTS):
                value = 20.0 + part[i] + appraiser[j] + inter[i, j] + rng.normal(0.0, SD_REPEAT)
                rows.append(f"P{i + 1:02d},{a},{t},{value:.4f}")
    return rows


def main(folder: Path) -> None:
    (folder / "grr_study.csv").write_text("\n".join(study_rows()) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent)
