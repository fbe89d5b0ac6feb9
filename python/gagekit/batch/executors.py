"""Where the scans run: local worker processes, or a Dask distributed cluster.

Both offer the same three calls to the batch runner: ``submit`` one scan, ``wait`` for the
first completions, and ``outcome`` of a finished one, which raises :class:`WorkerLost`
when the worker died or the cluster lost the task (the runner submits it again; a scan's
own errors never raise, see :func:`gagekit.batch.tasks.execute`).

* :class:`LocalPool` - ``concurrent.futures.ProcessPoolExecutor`` with spawned processes;
  each worker caps its kernel threads at cores / workers. A worker that dies breaks the
  whole pool (a property of the standard library), so the pool is started again and the
  unfinished scans resubmitted.
* :class:`DaskCluster` - ``dask.distributed.Client`` on ``tcp://host:8786``; each worker
  caps its kernel threads at its host's cores / the Dask threads on that host; the scheduler
  reschedules the tasks of a worker that dies (``distributed.scheduler.allowed-failures``)
  and a task that failed for other reasons is retried once. Workers must see the scan
  files at the same paths (a shared file system) and have gagekit installed.
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import os
import time
from typing import Any, Iterable, Optional

from ..errors import ClusterError, ConfigError, InvalidInputError
from .tasks import execute, gagekit_version, limit_dask_worker_threads, limit_threads, warm_up

__all__ = ["WorkerLost", "LocalPool", "DaskCluster", "default_workers"]


class WorkerLost(Exception):
    """The worker running a scan died or the cluster lost the task (not the scan's fault)."""


def default_workers() -> int:
    """One worker per core this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


class LocalPool:
    """``workers`` spawned processes on this machine."""

    def __init__(self, workers: Optional[int] = None):
        n = default_workers() if workers is None else int(workers)
        if n < 1:
            raise InvalidInputError(f"--workers must be at least 1, got {n}")
        self.workers = n
        self.threads = max(1, default_workers() // n)
        self.description = f"{n} local worker process{'es' if n != 1 else ''}"
        self._pool = self._start()
        self._broken = False

    def _start(self) -> cf.ProcessPoolExecutor:
        return cf.ProcessPoolExecutor(self.workers, mp_context=multiprocessing.get_context("spawn"),
                                      initializer=limit_threads, initargs=(self.threads,))

    def warm(self) -> None:
        """Start every worker now (the benchmark times batches without the start-up)."""
        list(self._pool.map(warm_up, [0.2] * self.workers))

    def submit(self, args: tuple, key: str) -> cf.Future:
        try:
            return self._pool.submit(execute, *args)
        except cf.process.BrokenProcessPool:
            self._broken = True
            self.recover()
            return self._pool.submit(execute, *args)

    def wait(self, futures: Iterable[cf.Future], timeout: Optional[float]) -> set:
        done, _ = cf.wait(list(futures), timeout=timeout, return_when=cf.FIRST_COMPLETED)
        return done

    def outcome(self, fut: cf.Future) -> Any:
        try:
            return fut.result()
        except (cf.process.BrokenProcessPool, cf.CancelledError) as exc:
            self._broken = True
            raise WorkerLost(f"a worker process died ({type(exc).__name__})") from None
        except Exception as exc:  # pickling of the outcome failed, or similar: not the scan's data
            raise WorkerLost(f"{type(exc).__name__}: {exc}") from None

    def recover(self) -> None:
        """Start a new pool after a worker died (the old one is broken for good)."""
        if self._broken:
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = self._start()
            self._broken = False

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)


class DaskCluster:
    """A client of the Dask scheduler at ``address`` (``tcp://host:8786``)."""

    def __init__(self, address: str, timeout: Optional[float] = None, wait_for_workers: float = 30.0):
        try:
            import dask.config
            from dask.utils import parse_timedelta
            from distributed import Client
        except ImportError:
            raise ConfigError("--scheduler needs dask.distributed: pip install 'gagekit[dask]'") from None
        self.address = address
        if timeout is None:  # Dask's own setting (DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT), 30 s by default
            timeout = parse_timedelta(dask.config.get("distributed.comm.timeouts.connect"), "s")
        try:
            self.client = Client(address, timeout=timeout)
        except (OSError, TimeoutError, ValueError) as exc:
            reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise ClusterError(f"cannot reach the Dask scheduler at {address}: {reason}") from None
        try:
            self.client.wait_for_workers(1, timeout=wait_for_workers)
        except (TimeoutError, OSError):
            self.client.close()
            raise ClusterError(f"the Dask scheduler at {address} has no workers (waited {wait_for_workers:g} s)") from None
        workers = self.client.scheduler_info().get("workers", {})
        n = len(workers)
        self.description = f"Dask scheduler {address} ({n} worker{'s' if n != 1 else ''})"
        try:
            self._check_environment()
        except ClusterError:
            self.client.close()
            raise
        self._limit_threads(workers)
        from distributed import as_completed

        self._completed = as_completed(loop=self.client.loop)
        self._ready: set = set()  # finished futures not yet asked for

    def _check_environment(self) -> None:
        """The scheduler (it unpickles every submitted task) and every worker must import
        the gagekit this client runs, in the same version (the same scan gives the same
        result on any node). Checked once at connect: a wrong deployment is one clear
        error, not every scan failing with Dask's deserialization message."""
        from .. import __version__ as mine

        problems = []
        try:
            theirs = self.client.run_on_scheduler(gagekit_version)
            if theirs != mine:
                problems.append(f"the scheduler runs gagekit {theirs}")
        except Exception as exc:
            problems.append(f"the scheduler cannot import gagekit ({_first_line(exc)})")
        try:
            found = self.client.run(gagekit_version, on_error="return")
        except Exception as exc:  # the scheduler could not even forward the call
            found = {"every worker": exc}
        for addr, theirs in sorted(found.items()):
            if isinstance(theirs, BaseException):
                problems.append(f"worker {addr} cannot import gagekit ({_first_line(theirs)})")
            elif theirs != mine:
                problems.append(f"worker {addr} runs gagekit {theirs}")
        if problems:
            more = f" and {len(problems) - 3} more" if len(problems) > 3 else ""
            raise ClusterError(f"the Dask cluster at {self.address} cannot run gagekit {mine}'s tasks: "
                               f"{'; '.join(problems[:3])}{more}; install gagekit {mine} on the scheduler and "
                               "every worker")

    def _limit_threads(self, workers: dict) -> None:
        """Workers sharing a host share its cores: each runs its kernels on
        cores / (Dask threads on the host) threads (Rayon and BLAS), as local workers do."""
        per_host: dict = {}
        for info in workers.values():
            per_host[info.get("host")] = per_host.get(info.get("host"), 0) + int(info.get("nthreads", 1))
        threads = {addr: per_host[info.get("host")] for addr, info in workers.items()}
        #: worker address -> the thread cap it took (empty when the workers could not run it)
        self.thread_caps: dict = {}
        try:
            self.thread_caps = self.client.run(limit_dask_worker_threads, threads)
        except Exception:  # a worker that left since the environment check: its scans go elsewhere
            pass

    def warm(self) -> None:
        """Import the kernels on every worker now, through the scheduler: it unpickles every
        submitted task, so its first gagekit task imports gagekit there too (0.4 s once per
        scheduler; the benchmark times batches without it)."""
        workers = list(self.client.scheduler_info().get("workers", {}))
        self.client.gather([self.client.submit(warm_up, 0.0, pure=False, workers=[w]) for w in workers])

    def submit(self, args: tuple, key: str):
        fut = self.client.submit(execute, *args, key=key, pure=False, retries=1)
        self._completed.add(fut)
        return fut

    def wait(self, futures: Iterable[Any], timeout: Optional[float]) -> set:
        """The submitted futures that have finished since the last call (at least one
        unless ``timeout`` runs out). One ``as_completed`` follows every future through
        the client's event loop: a callback per future, where ``distributed.wait`` over
        the pending set would start a waiting task per pending future on every call."""
        futures = set(futures)
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            self._ready.update(self._completed.next_batch(block=False))
            done = self._ready & futures
            if done or not futures or (deadline is not None and time.monotonic() >= deadline):
                self._ready -= done
                return done
            with self._completed.thread_condition:  # notified by as_completed when a future finishes
                if not self._completed.has_ready():
                    left = 0.1 if deadline is None else min(0.1, max(0.0, deadline - time.monotonic()))
                    self._completed.thread_condition.wait(timeout=left)

    def outcome(self, fut) -> Any:
        try:
            return fut.result()
        except Exception as exc:  # KilledWorker, CancelledError, lost connections, missing gagekit on a worker
            raise WorkerLost(f"{type(exc).__name__}: {exc}") from None
        finally:
            fut.release()

    def recover(self) -> None:
        """Nothing to do: the scheduler replaces lost workers' tasks itself."""

    def close(self) -> None:
        self.client.close()


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return f"{type(exc).__name__}: {text.splitlines()[0]}" if text else type(exc).__name__
