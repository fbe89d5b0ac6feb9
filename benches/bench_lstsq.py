"""Dense least squares and SVD of large design matrices (Eq. 3.13; 10^5-10^6 commands x 52
parameters of the example machine): nalgebra (gagekit-kinematics' lstsq, the shipped kernel)
vs faer (thin SVD of the same column-equilibrated matrix, and column-pivoted QR least
squares), in the Rust peer binary benches/peers. One line per size: case, nalgebra time,
faer times, ratios, relative differences of the singular values and of x.

    python benches/bench_lstsq.py [--quick]
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path


def main() -> None:
    sizes = ["10000", "100000"] if "--quick" in sys.argv else ["100000", "1000000"]
    manifest = Path(__file__).parent / "peers" / "Cargo.toml"
    subprocess.run(["cargo", "run", "--quiet", "--release", "--manifest-path", str(manifest), "--", "lstsq", *sizes],
                   check=True)


if __name__ == "__main__":
    main()
