"""Batches of scans on local worker processes or a Dask cluster, recorded in the results
database (:mod:`gagekit.store`), restartable by content hash and spec hash.

Importing :mod:`gagekit` does not import this package.
"""

from .executors import DaskCluster, LocalPool, WorkerLost, default_workers
from .runner import BatchSummary, Job, ScanEvent, run_batch
from .scans import SCAN_SUFFIXES, FileIdentity, expand_scans, identify_file
from .tasks import TASKS, Outcome, execute

__all__ = [
    "BatchSummary",
    "DaskCluster",
    "FileIdentity",
    "Job",
    "LocalPool",
    "Outcome",
    "SCAN_SUFFIXES",
    "ScanEvent",
    "TASKS",
    "WorkerLost",
    "default_workers",
    "execute",
    "expand_scans",
    "identify_file",
    "run_batch",
]
