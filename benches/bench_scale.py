"""A scan far larger than the part's regions: `gage check` on 50 M, 200 M (and, with
--huge, 1 G) generated points, reading the whole file vs streaming it (issue 29).

The scan: the simulated casting of ``gagekit.data.make_castings`` (casting_ok: 3-2-1
locators, Table 5.1 gages, fixture error), sampled at about 2 M points, and written as
repeated passes of the scanner over the same part (each pass with its own seeded 5 um
Gaussian noise) until the file holds N points: a binary PLY, float64 x y z (24 bytes a
point: 200 M points = 4.8 GB). The gage file is the case's own.

Each case runs ``gagekit gage check SCAN GAGES --json --memory M`` in a child process,
in three reading modes: ``whole`` (--memory 64G: the file read whole, a no-copy map of
gagekit's own PLY layout), ``stream`` (--memory 2G: chunks of 5.6 M points, three buffers
of them: the next two are read while the last is classified) and ``stream-256M`` (chunks of
0.7 M points). A streamed check with a 3-2-1 alignment reads the file once when its
first chunk gives a 3-2-1 frame (this scan's does): the part-frame gage regions are cut
in the datum pass around the boxes that frame puts them at (hull vertices of a shrunk
core, every point of a thin shell) and joined once the file's frame is fitted; else
twice, the gage regions from the end of the file back (a file larger than the page
cache then starts its second pass on what the first left cached). Each chunk's regions
are taken in a thread while the next chunk is cut. Printed per case and mode: wall time, the
child's peak RSS (max resident set, from wait4), the objective of Eq. 5.11, and whether
the whole JSON result equals the whole read's (bit for bit), the CPU a point and the cores
used (CPU / wall). The file is written just before (a ``scan_NM.ply`` of the right size in
--dir, left there by a run with --keep, is reused instead), so it is read
from a warm page cache (the "warm" figures); --cold drops the page cache first (needs root).

The disk's read speed is measured in the same run, beside each streamed check, alternated
with it: an O_DIRECT read of the whole file (--ref-gb: its first GB) just before the check,
and just after it a buffered read of the whole file after dropping the cache (--cold) or a
second O_DIRECT read (warm: the cache is left as the check left it). O_DIRECT reads 16 MiB
blocks with two requests in flight, past the page cache: the device's own sequential speed,
with no copy and no cache bookkeeping. The buffered read after a cache drop is what any
program reading the file gets from the kernel's read-ahead. "The disk's read speed" of the
goal is the faster of the two reads beside the check (the stricter reference: the device has
been seen to read 408-773 MB/s within an hour on this VM, so only a reference read next to
the check, of the same file, compares like with like); each line prints the check's MB/s as
a fraction of it.

A size whose float64 points would take more than half the RAM (1 G points: 24 GB) skips
the whole read, which cannot run here, and compares the streamed modes with each other.

``--dask``: only the cluster line of issue 29 section 3: ``gage batch`` of 16 generated
scans of 50 M points (binary PLY, float32 x y z: 9.6 GB of disk) on a local Dask cluster
of 2 single-thread workers with ``memory_limit`` 3 GB each: the time, the workers' peak
RSS, whether a worker was lost, and the first scan's result against its whole read.

Goals: 200 M points under 30 s warm; a 1 G-point PLY (24 GB) with peak RSS under 4 GB,
at or above the disk's read speed; the Dask batch with no worker lost. Generated files are
deleted at the end (kept with --keep).

    python benches/bench_scale.py [--sizes 50,200] [--huge] [--dir /tmp] [--cold] [--repeat N] [--keep]
    python benches/bench_scale.py --dask [--dask-scans 16] [--dask-points 50] [--dask-memory 3GB]
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


def ply_header(n: int) -> bytes:
    """The PLY header of ``n`` float64 points, padded to a multiple of 8 bytes (the points
    then lie 8-byte aligned in the file)."""
    header = (f"ply\nformat binary_little_endian 1.0\ncomment gagekit bench_scale\nelement vertex {n}\n"
              "property double x\nproperty double y\nproperty double z\nend_header\n")
    pad = -len(header) % 8
    return header.replace("bench_scale", "bench_scale" + " " * pad).encode("ascii")


def write_scan(path: Path, n: int, base: np.ndarray, seed: int = 0) -> None:
    """The casting's points ``base`` (sampled once), then passes with fresh noise until
    ``n`` points."""
    rng = np.random.default_rng(seed)
    with open(path, "wb") as fh:
        fh.write(ply_header(n))
        left = n
        while left:
            k = min(left, len(base))
            block = base[:k] + rng.normal(0.0, 0.005, (k, 3))
            block.astype("<f8").tofile(fh)
            left -= k


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
    """MB/s of reading the whole of ``path`` sequentially in 16 MiB blocks through the page
    cache, after dropping it (the kernel's read-ahead keeps the disk busy between reads)."""
    drop_caches()
    t = time.perf_counter()
    with open(path, "rb", buffering=0) as fh:
        while fh.read(16 << 20):
            pass
    return path.stat().st_size / 1e6 / (time.perf_counter() - t)


def write_scans_fast(folder: Path, scans: int, n: int, base) -> list[str]:
    """``scans`` float32 PLY files of ``n`` points: the casting sample ``base`` plus, per pass
    over it, one of 8 pregenerated 5 um noise blocks (scan k's pass j takes block (j + 3 k)
    mod 8, and scan k is shifted by k um in x), so every file differs and the 16 x 50 M
    points take minutes, not an hour, to write on a shared machine."""
    pts, _ = base
    rng = np.random.default_rng(7)
    base32 = pts.astype("<f4")
    pool = [(rng.standard_normal(pts.shape, dtype=np.float32) * np.float32(0.005)) for _ in range(8)]
    header = (f"ply\nformat binary_little_endian 1.0\ncomment gagekit bench_scale\nelement vertex {n}\n"
              "property float x\nproperty float y\nproperty float z\nend_header\n")
    paths = []
    for k in range(scans):
        p = folder / f"scan_{k:02d}.ply"
        shifted = base32 + np.array([0.001 * k, 0, 0], dtype="<f4")
        with open(p, "wb") as fh:
            fh.write(header.encode("ascii"))
            left, j = n, 0
            while left:
                m = min(left, len(pts))
                (shifted[:m] + pool[(j + 3 * k) % 8][:m]).tofile(fh)
                left -= m
                j += 1
        paths.append(str(p))
    return paths


def disk_speed_direct(path: Path, limit: int = 0, inflight: int = 2) -> float:
    """MB/s of reading ``path`` (its first ``limit`` bytes; 0: the whole file) with O_DIRECT,
    past the page cache (nothing cached is used or evicted): 16 MiB blocks, ``inflight``
    threads each reading every ``inflight``-th block, so that many requests are in flight
    (one at a time leaves the device idle between requests, an underestimate)."""
    import mmap
    import threading

    size = path.stat().st_size if not limit else min(limit, path.stat().st_size)
    block = 16 << 20
    done = [0] * inflight

    def reader(k: int) -> None:
        buf = mmap.mmap(-1, block)  # page-aligned, as O_DIRECT needs
        fd = os.open(path, os.O_RDONLY | os.O_DIRECT)
        try:
            at = k * block
            while at < size and (got := os.preadv(fd, [buf], at)) > 0:
                done[k] += min(got, size - at)
                at += inflight * block
        finally:
            os.close(fd)
            buf.close()

    t = time.perf_counter()
    threads = [threading.Thread(target=reader, args=(k,)) for k in range(inflight)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    return sum(done) / 1e6 / (time.perf_counter() - t)


def dask_line(folder: str, scans: int, millions: int, memory_limit: str) -> None:
    """``gage batch`` of ``scans`` generated scans of ``millions`` M points each (binary PLY,
    float32 x y z: 12 bytes a point) on a local Dask cluster of 2 single-thread workers with
    ``memory_limit`` each (their nannies restart a worker that goes over it): the time, the
    workers' peak RSS (sampled every 0.2 s), whether a worker was lost (the worker set
    changed or a scan was resubmitted), and the first scan's objective against a whole read
    of it by ``gagekit gage check`` in a child process."""
    import threading

    import psutil
    from distributed import Client, LocalCluster

    from gagekit.batch import BatchSummary, DaskCluster, Job, run_batch
    from gagekit.store import ResultStore
    from gagekit._util import load_toml

    n = millions * 1_000_000
    with tempfile.TemporaryDirectory(dir=folder) as d:
        base = make_casting("casting_ok", density=BASE_DENSITY)
        t = time.perf_counter()
        paths = write_scans_fast(Path(d), scans, n, base)
        gages = Path(d) / "gages.toml"
        gages.write_text(to_toml(base[1], "bench_scale: casting_ok gages"))
        size = sum(os.path.getsize(p) for p in paths) / 1e9
        print(f"# Dask: {scans} scans of {millions} M points (float32 PLY, {size:.1f} GB in all), written in "
              f"{time.perf_counter() - t:.0f} s; load average {os.getloadavg()[0]:.1f}", flush=True)
        job = Job("gage", {"spec": load_toml(gages)}, {"groups": True}, source=str(gages), part="casting_ok")
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, memory_limit=memory_limit,
                          dashboard_address=None, host="127.0.0.1") as cluster, Client(cluster) as client:
            before = set(client.scheduler_info()["workers"])
            pids = list(client.run(os.getpid).values())
            peak = {p: 0 for p in pids}
            stop = threading.Event()

            def sample() -> None:
                while not stop.wait(0.2):
                    for p in pids:
                        try:
                            peak[p] = max(peak[p], psutil.Process(p).memory_info().rss)
                        except psutil.Error:
                            pass

            th = threading.Thread(target=sample, daemon=True)
            th.start()
            store = ResultStore(f"sqlite:///{Path(d) / 'results.db'}")
            summary = BatchSummary()
            ex = DaskCluster(cluster.scheduler_address)
            t = time.perf_counter()
            try:
                events = list(run_batch(job, paths, store, ex, summary=summary))
            finally:
                seconds = time.perf_counter() - t
                stop.set()
                th.join()
                ex.close()
                store.close()
            after = set(client.scheduler_info()["workers"])
        ok = [e for e in events if e.status == "ok"]
        lost = before != after  # a worker restarted by its nanny comes back at a new address
        first = next((e for e in ok if e.scan == paths[0]), None)
        _, _, rss_whole, whole = run_child(Path(paths[0]), gages, "64G")
        same = "no result" if first is None else "yes" if first.result == whole else \
            "objective only" if first.result["objective"] == whole["objective"] else "NO"
        print(f"{'case':<34}{'time s':>9}{'worker peak RSS MB':>20}{'ok':>5}  worker lost  objective (scan 0)"
              "       equal to whole read")
        print(f"{f'gage batch {scans} x {millions} M, Dask 2x{memory_limit}':<34}{seconds:>9.1f}"
              f"{max(peak.values()) / 2**20:>20.0f}{len(ok):>5}  {'YES' if lost else 'no':<11}  "
              f"{(first.result['objective'] if first else float('nan')):<24.15g}{same}"
              f"   (load {os.getloadavg()[0]:.1f}; the whole read's RSS {rss_whole:.0f} MB)", flush=True)


def scan_file(folder: str, millions: int, keep: bool):
    """(scan path, gage file path, seconds spent writing (None: reused), temporary directory
    or None): a scan ``scan_{millions}M.ply`` already in ``folder`` with the expected size is
    reused and left there (the generator is seeded: the same bytes; a run with --keep left
    it); else the scan is written, into ``folder`` itself with ``keep`` (kept at the end),
    or into a temporary directory there (deleted at the end)."""
    n = millions * 1_000_000
    base, doc = make_casting("casting_ok", density=BASE_DENSITY)
    text = to_toml(doc, "bench_scale: casting_ok gages")
    kept = Path(folder or tempfile.gettempdir()) / f"scan_{millions}M.ply"
    if kept.exists() and kept.stat().st_size == len(ply_header(n)) + 24 * n:
        gages = kept.parent / "gages.toml"
        gages.write_text(text)
        return kept, gages, None, None
    tmp = None if keep else tempfile.TemporaryDirectory(dir=folder)
    d = Path(tmp.name) if tmp else kept.parent
    scan, gages = d / kept.name, d / "gages.toml"
    t = time.perf_counter()
    write_scan(scan, n, base)
    gen = time.perf_counter() - t
    gages.write_text(text)
    return scan, gages, gen, tmp


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="50,200", help="millions of points, comma separated")
    ap.add_argument("--huge", action="store_true", help="also 1000 M points (24 GB of disk, many minutes)")
    ap.add_argument("--dir", default=None)
    ap.add_argument("--cold", action="store_true", help="drop the page cache before each run (root)")
    ap.add_argument("--modes", default=",".join(m for m, _ in MODES))
    ap.add_argument("--repeat", type=int, default=1, help="runs of each streamed mode, alternated with the disk reads")
    ap.add_argument("--keep", action="store_true",
                    help="keep the generated scans in --dir (scan_NM.ply; a scan found there is always reused)")
    ap.add_argument("--inflight", type=int, default=2,
                    help="O_DIRECT requests of 16 MiB in flight for the disk's speed (1: one at a time, as before)")
    ap.add_argument("--ref-gb", type=float, default=0.0,
                    help="read only the first GB of the file for the disk's speed (default: the whole file)")
    ap.add_argument("--dask", action="store_true",
                    help="only the Dask line: gage batch of 16 scans of 50 M points (float32 PLY, 9.6 GB of disk) "
                         "on a local cluster of 2 workers with a 3 GB memory limit each")
    ap.add_argument("--dask-scans", type=int, default=16)
    ap.add_argument("--dask-points", type=int, default=50, help="millions of points a scan")
    ap.add_argument("--dask-memory", default="3GB")
    args = ap.parse_args()
    if args.dask:
        dask_line(args.dir, args.dask_scans, args.dask_points, args.dask_memory)
        return
    # --huge adds 1000 once (``--sizes 1000 --huge`` does not write the 24 GB file twice)
    sizes = list(dict.fromkeys([int(s) for s in args.sizes.split(",") if s] + ([1000] if args.huge else [])))
    modes = [m for m in MODES if m[0] in args.modes.split(",")]
    limit = int(args.ref_gb * 1e9)
    print(f"# load average at start: {' '.join(f'{x:.1f}' for x in os.getloadavg())} ({os.cpu_count()} cores); "
          "cpu s: the child's user + system time (less sensitive to a shared machine than the wall time); "
          "cores: cpu s / time s")
    print(f"# disk: O_DIRECT reads of 16 MiB, {args.inflight} in flight; the disk's read speed, read beside each streamed run ({'just before and just after it' if not args.cold else 'O_DIRECT just before, buffered after a cache drop just after'}): "
          f"the faster of the plain sequential reads of the {'whole file' if not limit else f'first {args.ref_gb:g} GB'}")
    print(f"{'case':<22}{'mode':<13}{'time s':>9}{'cpu s':>9}{'peak RSS MB':>13}{'objective':>22}  "
          "equal to the first mode")
    for millions in sizes:
        n = millions * 1_000_000
        scan, gages, gen, tmp = scan_file(args.dir, millions, args.keep)
        try:
            size_gb = scan.stat().st_size / 1e9
            print(f"# {millions} M points, {size_gb:.1f} GB PLY, {'reused' if gen is None else f'written in {gen:.0f} s'}")
            ref = None
            ram = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
            for mode, memory in modes:
                if mode == "whole" and n * 24 > ram // 2:
                    print(f"# whole read skipped: {n * 24 / 1e9:.0f} GB of float64 points on a {ram / 2**30:.0f} GiB "
                          "machine; the streamed modes are compared with each other")
                    continue
                for _ in range(args.repeat if mode != "whole" else 1):
                    # the disk's speed next to the check: O_DIRECT just before it; after it,
                    # the buffered read after a cache drop (cold) or O_DIRECT again (warm:
                    # the cache is left as the check left it)
                    before = disk_speed_direct(scan, limit, args.inflight) if mode != "whole" else float("nan")
                    if args.cold:
                        drop_caches()
                    load = os.getloadavg()[0]
                    seconds, cpu, rss, res = run_child(scan, gages, memory)
                    load = max(load, os.getloadavg()[0])
                    ref = res if ref is None else ref
                    same = "yes" if res == ref else "NO"
                    speed = scan.stat().st_size / 1e6 / seconds
                    print(f"{millions:>4} M points{'':<10}{mode:<13}{seconds:>9.1f}{cpu:>9.1f}{rss:>13.0f}"
                          f"{res['objective']:>22.15g}  {same}   load {load:.1f}, {speed:.0f} MB/s of file, "
                          f"{cpu / n * 1e9:.0f} ns CPU a point, {cpu / seconds:.2f} cores{' (--cold)' if args.cold else ''}",
                          flush=True)
                    if mode == "whole":
                        continue
                    if args.cold and not limit:
                        after, how = disk_speed(scan), "buffered after a cache drop"
                    else:
                        after, how = disk_speed_direct(scan, limit, args.inflight), "O_DIRECT"
                    disk = max(before, after)
                    print(f"# disk: O_DIRECT {before:.0f} MB/s before, {how} {after:.0f} MB/s after: "
                          f"the check at {speed / disk:.2f} of the faster ({speed:.0f} / {disk:.0f} MB/s)", flush=True)
        finally:
            if tmp is not None:
                tmp.cleanup()


if __name__ == "__main__":
    main()
