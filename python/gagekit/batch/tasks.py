"""What a worker does with one scan: the single-scan command's computation, as JSON.

Runs in a local worker process or on a Dask worker; imports only what the task needs.
:func:`execute` never raises for a bad scan: a :class:`~gagekit.errors.GagekitError`
(unreadable file, infeasible problem, degenerate points) becomes an ``error`` outcome
with its message, as does an unexpected exception (named as an internal error), so the
batch goes on. Results are exactly the dictionaries the single-scan commands print with
``--json`` (``gage check``, ``form fit``, ``inspect``).
"""

from __future__ import annotations

import os
import socket
import time
import warnings
from dataclasses import dataclass
from datetime import datetime, timezone
from typing import Any, Callable, Mapping, Optional

__all__ = ["Outcome", "execute", "TASKS", "limit_threads", "limit_dask_worker_threads", "warm_up", "gagekit_version"]


@dataclass(frozen=True)
class Outcome:
    """What a worker returns for one scan (times in UTC, seconds of wall time)."""

    status: str  # "ok" | "error"
    result: Optional[dict]
    error: Optional[str]
    started: datetime
    finished: datetime
    seconds: float
    worker: Optional[str] = None


def limit_threads(threads: int) -> None:
    """Cap the kernels' threads in this worker process (Rayon, BLAS), so that N workers on
    N cores do not each start N threads (idle Rayon and OpenBLAS threads spin, taking
    the core another worker needs).

    The environment variables reach Rayon's pool, which starts at the first kernel call;
    the BLAS library was loaded with numpy before this runs (the worker imports gagekit
    to unpickle this very function), so its pool is resized at run time with
    threadpoolctl."""
    n = max(1, int(threads))
    for var in ("RAYON_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(n)
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=n)


def limit_dask_worker_threads(threads_on_host: dict, dask_worker: Any = None) -> int:
    """On a Dask worker (through ``Client.run``, which hands the worker in as
    ``dask_worker``): cap the kernels' threads at this host's cores shared by the threads
    of every Dask worker on the host (``threads_on_host``: worker address -> total Dask
    threads on its host). Returns the cap. Rayon's pool is sized at its first use, so a
    worker that has already run kernels keeps its size."""
    w = dask_worker
    total = max(1, int(threads_on_host.get(w.address, w.state.nthreads)))
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    n = max(1, cores // total)
    limit_threads(n)
    return n


def warm_up(seconds: float = 0.2) -> int:
    """Import the kernels and hold the worker briefly (so that N calls land on N workers);
    returns the process id. Used to start workers before timing them."""
    from .. import gage  # noqa: F401  (the heavy imports: numpy, the Rust extension)

    time.sleep(seconds)
    return os.getpid()


def gagekit_version(dask_worker: Any = None, dask_scheduler: Any = None) -> str:
    """The gagekit version this process runs (on a Dask worker or scheduler, through
    ``Client.run`` / ``Client.run_on_scheduler``: unpickling this very function proves that
    gagekit can be imported there)."""
    from .. import __version__

    return __version__


def _read(path: str, units: Optional[str]):
    from ..cloud import read_points

    with warnings.catch_warnings():  # reader warnings (unit guesses, dropped points) would go to the worker's stderr
        warnings.simplefilter("ignore")
        return read_points(path, units=units)


def _stream(path: str, units: Optional[str]):
    """The scan as a :class:`~gagekit.cloud.stream.CloudStream` when its whole read would not
    fit this worker's budget (a quarter of a Dask worker's ``memory_limit``, else the
    default share of the RAM), else None: the same streaming path as the single-scan
    commands, with the same results."""
    from ..cloud.stream import memory_budget, open_cloud, should_stream

    memory = None
    try:
        from distributed import get_worker

        limit = get_worker().memory_manager.memory_limit
        memory = max(64 << 20, int(limit) // 4) if limit else None
    except (ImportError, ValueError, AttributeError):
        pass
    budget = memory_budget(memory)
    return open_cloud(path, units, memory=budget) if should_stream(path, budget) else None


def _monte_carlo(options: Mapping[str, Any]) -> Optional[dict]:
    """The keyword arguments of the uncertainty functions from a batch's ``uncertainty``
    option ({trials, model (the MeasurementModel's fields), seed, threads, rule}), or None."""
    unc = options.get("uncertainty")
    if unc is None:
        return None
    from ..uncertainty.model import MeasurementModel

    return {"model": MeasurementModel(**unc["model"]), "trials": unc["trials"], "seed": int(unc["seed"]),
            "threads": int(unc["threads"]), "rule": unc["rule"]}


def _gage(path: str, document: Mapping[str, Any], options: Mapping[str, Any]) -> dict:
    from .._util import to_jsonable
    from ..gage import GageSpec, check_gages
    from ..gage.analysis import check_gages_stream

    with warnings.catch_warnings():  # the batch printed the spec's warnings once
        warnings.simplefilter("ignore")
        spec = GageSpec.from_dict(document["spec"], options.get("source") or "gage spec")
    groups = options.get("groups", True)
    stream = _stream(path, options.get("units"))
    mc = _monte_carlo(options)
    if mc is not None:
        from ..gage.uncertainty import check_gages_uncertainty

        scan = stream if stream is not None else _read(path, options.get("units"))
        return to_jsonable(check_gages_uncertainty(scan, spec, mc["model"], mc["trials"], seed=mc["seed"],
                                                   threads=mc["threads"], rule=mc["rule"], groups=groups,
                                                   stream=stream is not None))
    if stream is not None:
        return to_jsonable(check_gages_stream(stream, spec, groups=groups))
    pts = _read(path, options.get("units"))
    return to_jsonable(check_gages(pts, spec, groups=groups))


def _form(path: str, document: Mapping[str, Any], options: Mapping[str, Any]) -> dict:
    from .._util import to_jsonable
    from ..form.files import fit_file

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return to_jsonable(fit_file(document["shape"], path, document["criterion"], seed=int(document.get("seed", 0)),
                                    units=options.get("units")))


def _inspect(path: str, document: Mapping[str, Any], options: Mapping[str, Any]) -> dict:
    """What ``gagekit inspect SCAN PART.toml --json`` prints (the drawing is ``document["part"]``)."""
    from .._util import check_finite_result, to_jsonable
    from ..inspect import inspect, inspect_stream, part_spec_from_dict

    spec = part_spec_from_dict(document["part"], options.get("source") or "part spec")
    stream = _stream(path, options.get("units")) if getattr(spec, "cad", None) is None else None
    mc = _monte_carlo(options)
    if mc is not None:
        from ..uncertainty import inspect_uncertainty

        scan = stream if stream is not None else _read(path, options.get("units"))
        result = inspect_uncertainty(scan, spec, mc["model"], mc["trials"], seed=mc["seed"], threads=mc["threads"],
                                     rule=mc["rule"], stream=stream is not None)
    else:
        result = inspect_stream(stream, spec) if stream is not None else inspect(_read(path, options.get("units")), spec)
    check_finite_result(result)
    return to_jsonable(result)


#: the kinds of batch and their worker functions
TASKS: dict[str, Callable[[str, Mapping[str, Any], Mapping[str, Any]], dict]] = {
    "gage": _gage, "form": _form, "inspect": _inspect}


def execute(kind: str, path: str, document: Mapping[str, Any], options: Mapping[str, Any]) -> Outcome:
    """Evaluate one scan; every failure of the scan itself is an ``error`` outcome."""
    from ..errors import GagekitError

    started = datetime.now(timezone.utc)
    t0 = time.perf_counter()
    worker = f"{socket.gethostname()}:{os.getpid()}"
    try:
        result = TASKS[kind](path, document, options)
        status, error = "ok", None
    except GagekitError as exc:
        result, status, error = None, "error", str(exc)
    except MemoryError:
        result, status, error = None, "error", f"{path}: out of memory"
    except Exception as exc:  # a bug: recorded so the batch goes on, named as such
        result, status, error = None, "error", f"internal error ({type(exc).__name__}): {exc}"
    return Outcome(status, result, error, started, datetime.now(timezone.utc), time.perf_counter() - t0, worker)
