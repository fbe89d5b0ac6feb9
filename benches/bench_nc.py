"""Throughput of `gagekit machine compensate-nc` (issue 15: at least 200,000 lines/s on a
1 M-line program): the Rust kernel (interpret, correct every point through the inverse error
model, subdivide, write) against a straightforward Python implementation written here (regex
words, the package's `compensate` - itself the Rust inverse kernel - and string writing, no
subdivision), timed on the first 50,000 lines: the ratio is the cost of parsing and writing in
Python. The first line also gives CPU-seconds, since the wall time depends on the machine's load.

    python benches/bench_nc.py [--lines 1000000] [--peer-lines 50000]

The program is a finishing raster of the example machine's table (0.5 mm G1 steps in X, a
0.5 mm step-over in Y, comments, block numbers, feed words). Prints: case, gagekit time,
peer time, ratio (peer / gagekit); the peer time of the full program is extrapolated from
its throughput on the first lines (marked).
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

import gagekit
from _timing import timed
from gagekit.machine import Truth, compensate, identify, simulate
from gagekit.machine.nc import compensate_nc


def program(lines: int) -> bytes:
    """A raster finishing program of about ``lines`` lines."""
    out = ["%", "O2000 (RASTER FINISH)", "N1 G21 G90 G17", "N2 G0 B0 W-500 X-1000 Y500 Z1500 S8000 M3"]
    x, y, d, n = -1000.0, 500.0, 1, 3
    while len(out) < lines - 2:
        x += 0.5 * d
        if not -1000.0 <= x <= 1000.0:
            d, x, y = -d, x - 0.5 * d, y + 0.5
            out.append(f"N{n} G1 Y{y:.3f} F2000 (step over)")
        else:
            out.append(f"N{n} G1 X{x:.3f}")
        n += 1
        if n % 1000 == 0:
            out.append(f"; pass {n // 1000}")
    out += [f"N{n} M30", "%"]
    return ("\n".join(out) + "\n").encode()


_WORD = re.compile(r"([A-Z])\s*([-+]?[0-9.]+)")


def python_peer(machine, cal, text: bytes) -> bytes:
    """Parse with regular expressions, correct with the package's `compensate`, write."""
    names = machine.joint_names
    pos = dict.fromkeys(names, 0.0)
    blocks, points = [], []
    for raw in text.decode().split("\n"):
        body = raw.split(";", 1)[0]
        body = re.sub(r"\([^)]*\)", "", body)
        words = _WORD.findall(body.upper())
        moved = False
        for letter, value in words:
            if letter in pos:
                pos[letter] = float(value)
                moved = True
        blocks.append((raw, moved))
        if moved:
            points.append([pos[k] for k in names])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        corrected, _ = compensate(machine, cal, np.array(points)) if points else (np.zeros((0, len(names))), None)
    out, k = [], 0
    for raw, moved in blocks:
        if moved:
            c = corrected[k]
            k += 1
            out.append(_WORD.sub(lambda m: f"{m.group(1)}{c[names.index(m.group(1))]:.4f}" if m.group(1) in names else m.group(0), raw))
        else:
            out.append(raw)
    return "\n".join(out).encode()


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--lines", type=int, default=1_000_000)
    ap.add_argument("--peer-lines", type=int, default=50_000)
    ap.add_argument("--repeat", type=int, default=2)
    a = ap.parse_args()
    m = gagekit.load_machine(gagekit.machine.example_machine_path())
    truth = Truth.random(m, seed=1)
    cal = identify(m, simulate(m, truth, m.sample_commands(290, seed=1), seed=2))
    text = program(a.lines)
    head = b"\n".join(text.split(b"\n")[: a.peer_lines]) + b"\n"
    with tempfile.TemporaryDirectory() as d:
        src, dst = Path(d) / "in.nc", Path(d) / "out.nc"
        src.write_bytes(text)
        r0 = resource.getrusage(resource.RUSAGE_SELF)
        tg, res = timed(lambda: compensate_nc(m, cal, src, dst), a.repeat)
        r1 = resource.getrusage(resource.RUSAGE_SELF)
        cpu = (r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime) / a.repeat
        src.write_bytes(head)
        tgh, _ = timed(lambda: compensate_nc(m, cal, src, dst), a.repeat)
    tp, _ = timed(lambda: python_peer(m, cal, head), 1)
    n_head = head.count(b"\n")
    print(f"# threads: RAYON_NUM_THREADS={os.environ.get('RAYON_NUM_THREADS', 'all')} of {os.cpu_count()} cores; "
          f"{res.lines} lines, {res.moves} moves, {res.inserted} inserted points; gagekit {res.lines / tg:,.0f} lines/s wall, "
          f"{cpu:.2f} CPU-s ({res.lines / cpu:,.0f} lines per CPU-second); load average {os.getloadavg()[0]:.1f}")
    print(f"{'case':<46} {'gagekit [s]':>12} {'python [s]':>12} {'ratio':>8}")
    print(f"{f'compensate-nc {n_head} lines':<46} {tgh:12.4f} {tp:12.4f} {tp / tgh:8.1f}")
    tpx = tp * res.lines / n_head
    print(f"{f'compensate-nc {res.lines} lines (python extrapolated)':<46} {tg:12.4f} {tpx:12.4f} {tpx / tg:8.1f}")
    if res.lines / tg < 200_000:
        print(f"# below the goal of 200,000 lines/s: {res.lines / tg:,.0f}", file=sys.stderr)


if __name__ == "__main__":
    main()
