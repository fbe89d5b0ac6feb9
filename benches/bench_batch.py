"""Batch throughput: local worker processes and a Dask LocalCluster, database write share.

Scans: ``--scans`` castings of about ``--points`` points each (the casting generator,
gagekit/data/make_castings.py, each with its own seed and its own pose on the spacers),
written once as binary PLY into ``--cache`` and checked against the bundled
``casting_ok.toml`` (Table 5.1 gages, Eq. 5.11). Every case runs the whole batch
(``gagekit.batch.run_batch``: hashing, scheduling, reading, the virtual-gage check, one
SQLite transaction per scan) into a fresh database. Workers are started before the clock
starts (a process start with its imports costs 1-3 s here, the same for every case; a
plant's cluster is long-lived).

Lines (case, gagekit time, peer time, ratio):

* ``2 local workers vs 1``: ratio = speed-up (goal >= 1.7);
* ``Dask scheduler + 2 workers vs local pool 2``: ratio = Dask time / pool time (goal <= 1.15).
  The cluster is deployed as a plant runs one: ``dask scheduler`` in its own process and two
  ``dask worker --nthreads 1 --no-nanny`` processes. A ``LocalCluster`` (its scheduler
  inside the batch's own process, a nanny process per worker polling memory) is printed
  for reference: on 2 cores those extra threads compete with the workers (1.25x here);
* ``database writes vs batch``: write time, batch time, share in % (goal < 2 %).

    python benches/bench_batch.py [--scans 64] [--points 1000000] [--cache DIR]
"""

from __future__ import annotations

import argparse
import contextlib
import os
import socket
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from gagekit.batch import BatchSummary, DaskCluster, Job, LocalPool, run_batch
from gagekit.data.make_castings import make_casting, write_ply
from gagekit.demo import data_path
from gagekit.store import ResultStore
from gagekit._util import load_toml

BASE_POINTS = 120_000  # casting_ok at density 1.5 points / mm^2


def _one(args):
    k, density, folder = args
    rng = np.random.default_rng(5000 + k)
    pts, _ = make_casting("casting_ok", density=density, seed=300 + k, shift=tuple(rng.uniform(1.5, 4.0, 2)),
                          tilt=float(rng.uniform(-0.02, 0.02)))
    p = Path(folder) / f"casting_{k:03d}.ply"
    tmp = p.with_suffix(".part")
    write_ply(tmp, pts)
    os.replace(tmp, p)
    return len(pts)


def make_scans(folder: Path, n: int, points: int) -> list[str]:
    folder.mkdir(parents=True, exist_ok=True)
    density = 1.5 * points / BASE_POINTS
    todo = [(k, density, str(folder)) for k in range(n) if not (folder / f"casting_{k:03d}.ply").exists()]
    if todo:
        with ProcessPoolExecutor(2) as pool:
            list(pool.map(_one, todo))
    return [str(folder / f"casting_{k:03d}.ply") for k in range(n)]


def run(job, paths, executor, db) -> BatchSummary:
    executor.warm()
    store = ResultStore(f"sqlite:///{db}")
    s = BatchSummary()
    try:
        events = list(run_batch(job, paths, store, executor, summary=s))
    finally:
        executor.close()
        store.close()
    bad = [e for e in events if e.status != "ok"]
    if bad:
        raise SystemExit(f"{len(bad)} scans failed, first: {bad[0].error}")
    return s


def line(case, tg, tp, ratio, note):
    print(f"{case:<42}{tg:>10.3f}{tp:>10.3f}{ratio:>8.2f}  {note}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scans", type=int, default=64)
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--cache", type=Path, default=Path(tempfile.gettempdir()) / "gagekit-bench-batch")
    a = ap.parse_args()
    folder = a.cache / f"{a.scans}x{a.points}"
    t = time.perf_counter()
    paths = make_scans(folder, a.scans, a.points)
    sizes = [os.path.getsize(p) for p in paths]
    print(f"# {len(paths)} scans, {np.mean(sizes) / 12 / 1e6:.2f} M points each on average "
          f"(generated or found in {time.perf_counter() - t:.0f} s in {folder})")
    gages = data_path("casting_ok.toml")
    job = Job("gage", {"spec": load_toml(gages)}, {"groups": True}, source=str(gages), part="casting_ok")
    work = Path(tempfile.mkdtemp(prefix="gagekit-bench-db-"))
    one = run(job, paths, LocalPool(1), work / "one.db")
    two = run(job, paths, LocalPool(2), work / "two.db")
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, host="127.0.0.1",
                      env={"RAYON_NUM_THREADS": "1"}) as cluster:
        local_cluster = run(job, paths, DaskCluster(cluster.scheduler_address), work / "dask-local.db")
    with dask_services(2) as address:
        dask = run(job, paths, DaskCluster(address), work / "dask.db")
    print(f"{'case':<42}{'gagekit':>10}{'peer':>10}{'ratio':>8}")
    line("2 local workers vs 1", two.seconds, one.seconds, one.seconds / two.seconds,
         "speed-up (goal >= 1.7)")
    line("Dask scheduler + 2 workers vs local pool 2", dask.seconds, two.seconds, dask.seconds / two.seconds,
         "Dask / pool (goal <= 1.15)")
    line("  Dask LocalCluster 2x1 (nannies, scheduler", local_cluster.seconds, two.seconds,
         local_cluster.seconds / two.seconds, "in this process), for reference")
    for name, s in (("1 worker", one), ("2 workers", two), ("Dask", dask), ("LocalCluster", local_cluster)):
        line(f"database writes vs batch ({name})", s.write_seconds, s.seconds, 100 * s.write_seconds / s.seconds,
             "% of batch time (goal < 2)" if name != "LocalCluster" else "% of batch time")


@contextlib.contextmanager
def dask_services(workers: int):
    """A plant's cluster as it is deployed: ``dask scheduler`` in a process of its own and
    ``dask worker`` processes (one thread each, no nanny) connected to it, on loopback."""
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    py = sys.executable
    procs = [subprocess.Popen([py, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port",
                               str(port), "--no-dashboard"], env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)]
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise SystemExit("the Dask scheduler did not start")
                time.sleep(0.2)
        procs += [subprocess.Popen([py, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1",
                                    "--no-dashboard", "--no-nanny"], env=env, stdout=subprocess.DEVNULL,
                                   stderr=subprocess.DEVNULL) for _ in range(workers)]
        from distributed import Client

        with Client(address, timeout=60) as c:
            c.wait_for_workers(workers, timeout=60)
        yield address
    finally:
        for p in reversed(procs):  # workers first, then their scheduler
            p.terminate()
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


if __name__ == "__main__":
    main()
