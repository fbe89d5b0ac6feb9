"""A scan far larger than the part's regions: `gage check` on 50 M, 200 M (and, with
--huge, 1 G) generated points, reading the whole file vs streaming it (issue 29).

The scan: the simulated casting of ``gagekit.data.make_castings`` (casting_ok: 3-2-1
locators, Table 5.1 gages, fixture error), sampled at about 2 M points, and written as
repeated passes of the scanner over the same part (each pass with its own seeded 5 um
Gaussian noise) until the file holds N points: a binary PLY, float64 x y z (24 bytes a
point: 200 M points = 4.8 GB). The gage file is the case's own.

Each case runs ``gagekit gage check SCAN GAGES --json --memory M`` in a child process,
in three reading modes: ``whole`` (--memory 64G: the file read whole, a no-copy map of
gagekit's own PLY layout), ``stream`` (--memory 2G: chunks of 5.6 M points) and
``stream-256M`` (chunks of 0.7 M points). Printed per case and mode: wall time, the
child's peak RSS (max resident set, from wait4), the objective of Eq. 5.11, and whether
the whole JSON result equals the whole read's (bit for bit). The file is written just
before, so it is read from a warm page cache (the "warm" figures); --cold drops the page
cache first (needs root) for the disk-speed figures. The disk's sequential read speed
is measured with dd-like reads of the same file after dropping the cache (--cold).

Goals: 200 M points under 30 s warm; a 1 G-point PLY (24 GB) with peak RSS under 4 GB,
at disk speed. Generated files are deleted at the end.

    python benches/bench_scale.py [--sizes 50,200] [--huge] [--dir /tmp] [--cold] [--keep]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from gagekit.data.make_castings import make_casting, to_toml

BASE_DENSITY = 24.0  # points per mm^2 of the casting sample (about 2 M points)
MODES = [("whole", "64G"), ("stream", "2G"), ("stream-256M", "256M")]


def write_scan(path: Path, n: int, seed: int = 0) -> str:
    """The casting sampled once, then passes with fresh noise until ``n`` points; returns
    the gage file text."""
    base, doc = make_casting("casting_ok", density=BASE_DENSITY)
    rng = np.random.default_rng(seed)
    header = (f"ply\nformat binary_little_endian 1.0\ncomment gagekit bench_scale\nelement vertex {n}\n"
              "property double x\nproperty double y\nproperty double z\nend_header\n")
    pad = -len(header) % 8
    header = header.replace("bench_scale", "bench_scale" + " " * pad)
    with open(path, "wb") as fh:
        fh.write(header.encode("ascii"))
        left = n
        while left:
            k = min(left, len(base))
            block = base[:k] + rng.normal(0.0, 0.005, (k, 3))
            block.astype("<f8").tofile(fh)
            left -= k
    return to_toml(doc, "bench_scale: casting_ok gages")


def run_child(scan: Path, gages: Path, memory: str) -> tuple[float, float, float, dict]:
    """(wall s, CPU s (user + system), peak RSS MB, result) of one child process."""
    t = time.perf_counter()
    pid = os.fork()
    if pid == 0:  # the child: exec gagekit with stdout into a temp file
        fd = os.open(str(scan) + f".{memory}.json", os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        os.dup2(fd, 1)
        os.execv(sys.executable, [sys.executable, "-m", "gagekit", "gage", "check", str(scan), str(gages), "--json",
                                  "--memory", memory])
    _, status, usage = os.wait4(pid, 0)
    seconds = time.perf_counter() - t
    out = Path(str(scan) + f".{memory}.json")
    text = out.read_text()
    out.unlink()
    if status != 0:
        raise SystemExit(f"gagekit gage check --memory {memory} failed (status {status})")
    return seconds, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0, json.loads(text)


def drop_caches() -> bool:
    try:
        os.sync()
        Path("/proc/sys/vm/drop_caches").write_text("3\n")
        return True
    except OSError:
        return False


def disk_speed(path: Path) -> float:
    """MB/s of reading ``path`` sequentially in 16 MiB blocks (after dropping the cache)."""
    drop_caches()
    t = time.perf_counter()
    with open(path, "rb", buffering=0) as fh:
        while fh.read(16 << 20):
            pass
    return path.stat().st_size / 1e6 / (time.perf_counter() - t)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="50,200", help="millions of points, comma separated")
    ap.add_argument("--huge", action="store_true", help="also 1000 M points (24 GB of disk, many minutes)")
    ap.add_argument("--dir", default=None)
    ap.add_argument("--cold", action="store_true", help="drop the page cache before each run (root)")
    ap.add_argument("--modes", default=",".join(m for m, _ in MODES))
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",") if s] + ([1000] if args.huge else [])
    modes = [m for m in MODES if m[0] in args.modes.split(",")]
    print(f"# load average at start: {' '.join(f'{x:.1f}' for x in os.getloadavg())} ({os.cpu_count()} cores); "
          "cpu s: the child's user + system time (less sensitive to a shared machine than the wall time)")
    print(f"{'case':<22}{'mode':<13}{'time s':>9}{'cpu s':>9}{'peak RSS MB':>13}{'objective':>22}  equal to whole")
    for millions in sizes:
        n = millions * 1_000_000
        with tempfile.TemporaryDirectory(dir=args.dir) as d:
            scan, gages = Path(d) / "scan.ply", Path(d) / "gages.toml"
            t = time.perf_counter()
            gages.write_text(write_scan(scan, n))
            gen = time.perf_counter() - t
            size_gb = scan.stat().st_size / 1e9
            print(f"# {millions} M points, {size_gb:.1f} GB PLY, written in {gen:.0f} s")
            ref = None
            for mode, memory in modes:
                if args.cold:
                    drop_caches()
                seconds, cpu, rss, res = run_child(scan, gages, memory)
                ref = res if ref is None else ref
                same = "yes" if res == ref else "NO"
                print(f"{millions:>4} M points{'':<10}{mode:<13}{seconds:>9.1f}{cpu:>9.1f}{rss:>13.0f}"
                      f"{res['objective']:>22.15g}  {same}", flush=True)
            if args.cold:
                print(f"# disk: sequential read of the file after dropping the cache: {disk_speed(scan):.0f} MB/s")


if __name__ == "__main__":
    main()
