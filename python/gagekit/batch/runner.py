"""The batch loop: hash, skip what is stored, run the rest, record each result as it comes.

For every scan path, in order: its content is hashed; content already evaluated against
this spec (in the database) is *skipped* and its path recorded; content seen earlier in the
same batch is attached to that scan (processed once, both paths recorded); anything else
is submitted at once, so workers start while later files are still being hashed. Each
finished scan is written in its own transaction (:meth:`ResultStore.record`) before its
event is yielded, so an interrupted batch loses at most the scans in flight, and running
the same command again finishes it without duplicates.

A scan whose worker died is submitted again (at most :data:`MAX_ATTEMPTS` times); a scan
still lost after that is reported as an error but not stored, so a rerun tries it again.
Errors of the scan itself (unreadable, infeasible) are stored and not retried unless
``retry_failed``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Iterator, Optional, Sequence

from ..store.results import ResultStore, spec_hash
from .executors import WorkerLost
from .scans import FileIdentity, identify_file

MAX_ATTEMPTS = 3

__all__ = ["Job", "ScanEvent", "BatchSummary", "run_batch", "MAX_ATTEMPTS"]


@dataclass(frozen=True)
class Job:
    """What every scan of a batch is evaluated against.

    ``document`` and ``options`` define the spec hash (a changed drawing or option is a
    new spec); ``source`` (the spec file's path) and ``part`` are only recorded."""

    kind: str
    document: dict
    options: dict = field(default_factory=dict)
    source: Optional[str] = None
    part: Optional[str] = None

    @cached_property
    def hash(self) -> str:
        return spec_hash(self.kind, self.document, self.options)

    def task_args(self, path: str) -> tuple:
        return (self.kind, path, self.document, {**self.options, "source": self.source})


@dataclass(frozen=True)
class ScanEvent:
    """The outcome of one scan path: ``ok``, ``error`` or ``skipped`` (already stored)."""

    scan: str
    status: str
    result: Optional[dict] = None
    error: Optional[str] = None

    def to_dict(self) -> dict:
        """The ``--json`` line: ``{"scan", "status", "result"}`` or ``{"scan", "status", "error"}``."""
        if self.result is not None:
            return {"scan": self.scan, "status": self.status, "result": self.result}
        return {"scan": self.scan, "status": self.status, "error": self.error}


@dataclass
class BatchSummary:
    scans: int = 0
    ok: int = 0
    failed: int = 0
    skipped: int = 0
    seconds: float = 0.0
    write_seconds: float = 0.0
    executor: str = ""
    database: str = ""

    def count(self, event: ScanEvent) -> None:
        self.scans += 1
        if event.status == "ok":
            self.ok += 1
        elif event.status == "skipped":
            self.skipped += 1
        else:
            self.failed += 1

    def to_dict(self) -> dict:
        """The ``--json`` summary line's object."""
        return {"scans": self.scans, "ok": self.ok, "failed": self.failed, "skipped": self.skipped}


@dataclass
class _Pending:
    identity: FileIdentity
    paths: list
    attempts: int = 1


def run_batch(job: Job, paths: Sequence[str], store: ResultStore, executor: Any, *, retry_failed: bool = False,
              summary: Optional[BatchSummary] = None) -> Iterator[ScanEvent]:
    """Evaluate ``paths`` against ``job`` on ``executor``, recording into ``store``; yields
    one :class:`ScanEvent` per path as results arrive, and fills ``summary``."""
    summary = summary if summary is not None else BatchSummary()
    summary.executor = getattr(executor, "description", "")
    summary.database = store.url
    t_start = time.perf_counter()
    w0 = store.write_seconds
    spec_id = store.ensure_spec(job.kind, job.hash, job.document, job.source, job.part)
    if retry_failed:
        store.forget_errors(spec_id)
    stored = store.done(spec_id)
    pending: dict[Any, str] = {}  # future -> content hash
    jobs: dict[str, _Pending] = {}  # content hash -> scan in flight

    def emit(ev: ScanEvent) -> ScanEvent:
        summary.count(ev)
        return ev

    def finish(fut) -> Iterator[ScanEvent]:
        h = pending.pop(fut)
        p = jobs[h]
        try:
            out = executor.outcome(fut)
        except WorkerLost as exc:
            if p.attempts < MAX_ATTEMPTS:
                p.attempts += 1
                lost.append(h)
                return
            del jobs[h]
            msg = f"{p.paths[0]}: not evaluated, its worker was lost {MAX_ATTEMPTS} times ({exc}); run the batch again"
            for path in p.paths:
                yield emit(ScanEvent(path, "error", error=msg))
            return
        del jobs[h]
        store.record(job.kind, spec_id, h, p.identity.size, p.identity.modified, p.paths, out,
                     acquired=p.identity.acquired)
        for path in p.paths:
            yield emit(ScanEvent(path, out.status, out.result, out.error))

    def drain(timeout: Optional[float]) -> Iterator[ScanEvent]:
        if pending:
            for fut in executor.wait(pending, timeout):
                yield from finish(fut)
        if lost and not pending:  # a broken local pool has failed all its futures by now
            executor.recover()
            for h in lost:
                p = jobs[h]
                pending[executor.submit(job.task_args(p.paths[0]), _key(job, h, p.attempts))] = h
            lost.clear()

    lost: list[str] = []
    try:
        for path in paths:
            try:
                ident = identify_file(path)
            except OSError as exc:
                yield emit(ScanEvent(path, "error", error=f"{path}: {exc.strerror or exc}"))
                continue
            h = ident.content_hash
            if h in stored:
                s = stored[h]
                store.add_paths(h, ident.size, ident.modified, [path], acquired=ident.acquired)
                yield emit(ScanEvent(path, "skipped", s.result, s.error))
            elif h in jobs:
                jobs[h].paths.append(path)
            else:
                jobs[h] = _Pending(ident, [path])
                pending[executor.submit(job.task_args(path), _key(job, h, 1))] = h
                yield from drain(0)
        while pending or lost:
            yield from drain(None)
    finally:
        summary.seconds = time.perf_counter() - t_start
        summary.write_seconds = store.write_seconds - w0


def _key(job: Job, content_hash: str, attempt: int) -> str:
    return f"gagekit-{job.kind}-{content_hash[:24]}-{job.hash[:12]}-{attempt}"
