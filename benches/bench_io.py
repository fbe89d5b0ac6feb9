"""Point-cloud reading speed: gagekit.read_points vs numpy on a 14M-point cloud.

Writes a noisy 14-million-point cloud as ASCII XYZ and as binary PLY to a
temporary directory, then reads each back. Prints one line per case:
case, gagekit time, peer time, ratio (peer / gagekit).

    python benches/bench_io.py [--n 14000000] [--dir /tmp]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

import gagekit
from _timing import timed


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--n", type=int, default=14_000_000)
    ap.add_argument("--dir", default=None)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    pts = np.column_stack(
        [rng.uniform(0, 200, args.n), rng.uniform(0, 150, args.n), rng.normal(0, 0.02, args.n)]
    ).round(4)
    with tempfile.TemporaryDirectory(dir=args.dir) as d:
        xyz, ply = Path(d) / "cloud.xyz", Path(d) / "cloud.ply"
        t_w, _ = timed(lambda: gagekit.write_points(xyz, pts))
        gagekit.write_points(ply, pts)
        print(f"# {args.n} points; XYZ {xyz.stat().st_size / 1e6:.0f} MB (written in {t_w:.2f} s), PLY {ply.stat().st_size / 1e6:.0f} MB")
        print(f"{'case':<28}{'gagekit s':>11}{'peer s':>10}{'ratio':>8}  peer")
        t_g, got = timed(lambda: gagekit.read_points(xyz))
        assert np.array_equal(got, pts)
        t_p, ref = timed(lambda: np.loadtxt(xyz))
        assert np.array_equal(ref, pts)
        print(f"{'ascii xyz read':<28}{t_g:>11.3f}{t_p:>10.3f}{t_p / t_g:>8.1f}  numpy.loadtxt")
        t_g, got = timed(lambda: gagekit.read_points(ply), repeat=2)
        assert np.array_equal(got, pts)
        t_p, _ = timed(lambda: np.fromfile(ply, dtype="<f8", offset=len(open(ply, "rb").read(200).split(b"end_header\n")[0]) + 11).reshape(-1, 3).copy(), repeat=2)
        print(f"{'binary ply read':<28}{t_g:>11.3f}{t_p:>10.3f}{t_p / t_g:>8.1f}  numpy.fromfile (raw copy, lower bound)")


if __name__ == "__main__":
    main()
