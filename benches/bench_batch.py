"""Batch throughput: local worker processes and a Dask LocalCluster, database write share.

Scans: ``--scans`` castings of about ``--points`` points each (the casting generator,
gagekit/data/make_castings.py, each with its own seed and its own pose on the spacers),
written once as binary PLY into ``--cache`` and checked against the bundled
``casting_ok.toml`` (Table 5.1 gages, Eq. 5.11). Every case runs the whole batch
(``gagekit.batch.run_batch``: hashing, scheduling, reading, the virtual-gage check, one
SQLite transaction per scan) into a fresh database. Workers are started before the clock
starts (a process start with its imports costs 1-3 s here, the same for every case; a
plant's cluster is long-lived).

Every case runs ``--rounds`` times, each round starting one case later (with 4 rounds every case
runs once in every position), and the best run of each case is kept: this machine's speed drifts by
10-20 % between runs of the same case. Lines (case, gagekit time, peer time, ratio):

* ``2 local workers vs 1``: ratio = speed-up (goal >= 1.7);
* ``... vs local pool 2``: ratio = Dask time / pool time (goal <= 1.15), two deployments:

  - ``Dask scheduler + 2 workers (no nanny)``: as a plant runs a cluster, ``dask scheduler``
    in its own process and two ``dask worker --nthreads 1 --no-nanny`` processes;
  - ``Dask LocalCluster 2x1``: ``LocalCluster(n_workers=2, threads_per_worker=1)``, Dask's
    defaults: its scheduler and the workers' nannies run in the batch's own process, on the
    same 2 cores as the workers;
* ``database writes vs batch``: write time (wall clock, in the batch's parent process, while
  the workers keep both cores busy), batch time, share in % (goal < 2 %).

    python benches/bench_batch.py [--scans 64] [--points 1000000] [--rounds 4] [--cache DIR]
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
from gagekit.samples import data_path
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
    print(f"{case:<56}{tg:>9.3f}{tp:>9.3f}{ratio:>8.2f}  {note}")


def local_cluster():
    from distributed import LocalCluster

    return LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, host="127.0.0.1",
                        env={"RAYON_NUM_THREADS": "1"})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scans", type=int, default=64)
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--rounds", type=int, default=4, help="rounds of every case, interleaved; the best of each is kept")
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
    runs: dict[str, list[BatchSummary]] = {}

    def case(name, executor, r):
        runs.setdefault(name, []).append(run(job, paths, executor, work / f"{name}-{r}.db"))

    def dask_case(r):
        with dask_services(2) as address:
            case("dask", DaskCluster(address), r)

    def local_cluster_case(r):
        with local_cluster() as cluster:
            case("local-cluster", DaskCluster(cluster.scheduler_address), r)

    order = [lambda r: case("one", LocalPool(1), r), lambda r: case("two", LocalPool(2), r), dask_case,
             local_cluster_case]
    for r in range(a.rounds):  # each round starts one case later: every case runs in every position
        for k in range(len(order)):
            order[(k + r) % len(order)](r)
            time.sleep(1.0)  # the last case's processes are gone before the next starts
    best = {k: min(v, key=lambda s: s.seconds) for k, v in runs.items()}
    spread = {k: f"{min(s.seconds for s in v):.2f}-{max(s.seconds for s in v):.2f} s" for k, v in runs.items()}
    one, two, dask = best["one"], best["two"], best["dask"]
    print(f"# best of {a.rounds} interleaved rounds per case (all rounds: "
          + ", ".join(f"{k} {v}" for k, v in spread.items()) + f"); load average {os.getloadavg()[0]:.1f}")
    print(f"{'case':<56}{'gagekit':>9}{'peer':>9}{'ratio':>8}")
    line("2 local workers vs 1", two.seconds, one.seconds, one.seconds / two.seconds, "speed-up (goal >= 1.7)")
    for key, name in (("dask", "Dask scheduler + 2 workers (no nanny)"), ("local-cluster", "Dask LocalCluster 2x1")):
        s = best[key]
        line(f"{name} vs local pool 2", s.seconds, two.seconds, s.seconds / two.seconds, "Dask / pool (goal <= 1.15)")
    for key, name in (("one", "1 worker"), ("two", "2 workers"), ("dask", "Dask"), ("local-cluster", "LocalCluster")):
        s = best[key]
        line(f"database writes vs batch ({name})", s.write_seconds, s.seconds, 100 * s.write_seconds / s.seconds,
             "% of batch time (goal < 2)")


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
    try:  # the workers and the client below retry until the scheduler listens
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
