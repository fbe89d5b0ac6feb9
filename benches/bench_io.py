"""Point-cloud reading speed: gagekit.read_points vs its peers on a 14M-point cloud.

Writes a noisy 14-million-point cloud as ASCII XYZ, binary PLY (float64 x y z, as
gagekit writes it; and float32 x y z + an intensity byte, as scanners write it) and E57
(written by pye57, double Cartesian), then reads each back. Prints one line per case:
case, gagekit time, peer time, ratio (peer / gagekit; above 1 gagekit is faster).

Goals (issues 13, 29): binary PLY within 1.2x of numpy.fromfile on the same file (ratio >=
0.83); ASCII XYZ at least 4x numpy.loadtxt (ratio >= 4) and within 2x of reading the
file's bytes alone (Python's ``open(...).read()``: ratio >= 0.5); E57 no slower than
pye57's read_scan_raw (ratio >= 1; pye57 is in the ``test`` extra: ``pip install
'gagekit[test]'``), whole and streamed data packet by data packet (``open_cloud``, the path
of ``gage check --memory``). Every read is checked against the written points.

What the peers do: for the float64 PLY, numpy.fromfile alone gives the (n, 3) float64
array gagekit returns. For the float32 + intensity PLY it gives records of float32
fields; the (n, 3) float64 array gagekit returns then takes one more step, which a
numpy user has to write too: the peer is numpy.fromfile plus the fastest such step we
know (an empty (n, 3) float64 array filled column by column from the x, y, z fields;
numpy.lib.recfunctions.structured_to_unstructured and column_stack(...).astype are
slower). The line "(records only)" prints fromfile without that step for reference.

    python benches/bench_io.py [--n 14000000] [--dir /tmp] [--repeat 3]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

import gagekit
from _timing import timed


def _body_offset(path: Path) -> int:
    with open(path, "rb") as fh:
        head = fh.read(4096)
    return head.index(b"end_header\n") + len(b"end_header\n")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--n", type=int, default=14_000_000)
    ap.add_argument("--dir", default=None)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--skip-loadtxt", action="store_true", help="numpy.loadtxt takes about a minute on 14M lines")
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    pts = np.column_stack(
        [rng.uniform(0, 200, args.n), rng.uniform(0, 150, args.n), rng.normal(0, 0.02, args.n)]
    ).round(4)
    row = "{:<30}{:>11.3f}{:>10.3f}{:>8.2f}  {}"
    with tempfile.TemporaryDirectory(dir=args.dir) as d:
        xyz, ply, ply32, e57 = (Path(d) / n for n in ("cloud.xyz", "cloud.ply", "cloud32.ply", "cloud.e57"))
        gagekit.write_points(xyz, pts)
        gagekit.write_points(ply, pts)
        rec = np.empty(args.n, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("intensity", "u1")])
        rec["x"], rec["y"], rec["z"], rec["intensity"] = pts[:, 0], pts[:, 1], pts[:, 2], 7
        with open(ply32, "wb") as fh:
            fh.write(f"ply\nformat binary_little_endian 1.0\nelement vertex {args.n}\nproperty float x\n"
                     "property float y\nproperty float z\nproperty uchar intensity\nend_header\n".encode())
            rec.tofile(fh)
        print(f"# {args.n} points; XYZ {xyz.stat().st_size / 1e6:.0f} MB, PLY {ply.stat().st_size / 1e6:.0f} MB, "
              f"PLY float32 {ply32.stat().st_size / 1e6:.0f} MB; best of {args.repeat}")
        print(f"{'case':<30}{'gagekit s':>11}{'peer s':>10}{'ratio':>8}  peer")

        t_g, got = timed(lambda: gagekit.read_points(ply), repeat=args.repeat)
        assert np.array_equal(got, pts)
        off = _body_offset(ply)
        t_p, ref = timed(lambda: np.fromfile(ply, dtype="<f8", offset=off).reshape(-1, 3), repeat=args.repeat)
        assert np.array_equal(ref, pts)
        print(row.format("binary ply read (float64)", t_g, t_p, t_p / t_g, "numpy.fromfile, same file"))

        t_g, got = timed(lambda: gagekit.read_points(ply32), repeat=args.repeat)
        assert np.array_equal(got, np.column_stack([rec["x"], rec["y"], rec["z"]]).astype(np.float64))
        off = _body_offset(ply32)

        def fromfile_float64():
            r = np.fromfile(ply32, dtype=rec.dtype, offset=off)
            out = np.empty((len(r), 3))
            out[:, 0], out[:, 1], out[:, 2] = r["x"], r["y"], r["z"]
            return out

        t_p, ref = timed(fromfile_float64, repeat=args.repeat)
        assert np.array_equal(ref, got)
        print(row.format("binary ply read (float32+i)", t_g, t_p, t_p / t_g, "numpy.fromfile + float64 (n, 3)"))
        t_r, _ = timed(lambda: np.fromfile(ply32, dtype=rec.dtype, offset=off), repeat=args.repeat)
        print(row.format("  (records only)", t_g, t_r, t_r / t_g, "numpy.fromfile, float32 records, no (n, 3)"))

        t_g, got = timed(lambda: gagekit.read_points(xyz), repeat=args.repeat)
        assert np.array_equal(got, pts)

        def raw_read():
            with open(xyz, "rb") as fh:
                return fh.read()

        t_r, _ = timed(raw_read, repeat=args.repeat)
        print(row.format("ascii xyz read (vs raw)", t_g, t_r, t_r / t_g, "open().read() of the same file"))
        if not args.skip_loadtxt:
            t_p, ref = timed(lambda: np.loadtxt(xyz))
            assert np.array_equal(ref, pts)
            print(row.format("ascii xyz read", t_g, t_p, t_p / t_g, "numpy.loadtxt"))
        else:
            print(f"{'ascii xyz read':<30}{t_g:>11.3f}")

        try:
            import pye57
        except ImportError:
            print("# E57: pye57 not installed, skipped (pip install 'gagekit[test]')")
            return
        w = pye57.E57(str(e57), mode="w")
        w.write_scan_raw({"cartesianX": pts[:, 0] / 1000, "cartesianY": pts[:, 1] / 1000, "cartesianZ": pts[:, 2] / 1000})
        w.close()
        t_g, got = timed(lambda: gagekit.read_points(e57), repeat=args.repeat)
        t_p, raw = timed(lambda: pye57.E57(str(e57)).read_scan_raw(0), repeat=args.repeat)
        # pye57 stores scaled integers (0.1 um): compare with what it reads back, in mm
        assert np.array_equal(got, np.column_stack([raw["cartesianX"], raw["cartesianY"], raw["cartesianZ"]]) * 1000.0)
        print(row.format("e57 read (double cartesian)", t_g, t_p, t_p / t_g, "pye57 read_scan_raw"))
        from gagekit.cloud.stream import open_cloud

        def streamed():  # what gage check does with the chunks: use each, keep none
            return sum(len(c) for c in open_cloud(e57, chunk=1 << 20))

        t_s, count = timed(streamed, repeat=args.repeat)
        assert count == len(got) and np.array_equal(np.vstack(list(open_cloud(e57, chunk=1 << 20))), got)
        print(row.format("e57 streamed (1 M chunks)", t_s, t_p, t_p / t_s, "pye57 read_scan_raw (whole)"))


if __name__ == "__main__":
    main()
