"""Which files a batch reads (files, folders, glob patterns) and what each one holds.

A scan is identified by the SHA-256 of its bytes, not by its path: the same file copied
under two names is evaluated once and both paths are recorded; a file renamed since the
last run is not evaluated again.
"""

from __future__ import annotations

import errno
import glob
import hashlib
import os
import threading
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Iterable, Optional

from ..cloud.acquisition import acquisition_time
from ..cloud.io import ASCII_SUFFIXES
from ..errors import InvalidInputError

#: file suffixes a folder is searched for (every format ``read_points`` reads)
SCAN_SUFFIXES = frozenset(ASCII_SUFFIXES | {".ply", ".npy", ".las", ".laz", ".e57"})
_CHUNK = 1 << 20

__all__ = ["SCAN_SUFFIXES", "FileIdentity", "expand_scans", "identify_file"]


def _is_pattern(arg: str) -> bool:
    return any(c in arg for c in "*?[")


def expand_scans(args: Iterable[str]) -> list[str]:
    """The scan paths named by ``args``, in order, each once.

    A folder stands for its scan files (by suffix, recursively, sorted); a glob pattern
    (``*``, ``?``, ``[...]``, ``**``) for its matches (sorted), and a pattern matching
    nothing is an error; any other argument is a file (a missing one is reported by the
    batch as a failed scan). No scans at all is an error."""
    out: list[str] = []
    seen: set[str] = set()

    def add(p: str) -> None:
        key = os.path.abspath(p)
        if key not in seen:
            seen.add(key)
            out.append(p)

    for arg in args:
        arg = str(arg)
        if _is_pattern(arg) and not Path(arg).exists():
            matches = sorted(m for m in glob.glob(arg, recursive=True) if os.path.isfile(m))
            if not matches:
                raise InvalidInputError(f"{arg}: the pattern matches no file")
            for m in matches:
                add(m)
        elif Path(arg).is_dir():
            files = sorted(str(p) for p in Path(arg).rglob("*") if p.is_file() and p.suffix.lower() in SCAN_SUFFIXES)
            if not files:
                raise InvalidInputError(f"{arg}: the folder holds no scan files ({', '.join(sorted(SCAN_SUFFIXES))})")
            for f in files:
                add(f)
        else:
            add(arg)
    if not out:
        raise InvalidInputError("no scans given")
    return out


@dataclass(frozen=True)
class FileIdentity:
    """A scan file's content hash (SHA-256, hex), size (bytes), modification time (UTC)
    and, where its header records one, acquisition time (UTC, :mod:`gagekit.cloud.acquisition`)."""

    content_hash: str
    size: int
    modified: datetime
    acquired: Optional[datetime] = None


def identify_file(path: str) -> FileIdentity:
    """Hash a file's bytes; OSError when it cannot be read.

    The batch's parent process hashes every scan while the workers compute, so this
    reads into one reused buffer (unbuffered ``readinto``: no new 4 MB object, and its
    page faults, per chunk) - half the CPU time of ``read()`` in chunks."""
    from .._files import not_regular

    why = not_regular(os.stat(path), "scan file")  # stat never blocks: a FIFO is refused, not opened
    if why:
        raise OSError(errno.EINVAL, why)
    h = hashlib.sha256()
    buf = _buffer()
    view = memoryview(buf)
    with open(path, "rb", buffering=0) as fh:
        st = os.fstat(fh.fileno())
        while True:
            n = fh.readinto(buf)
            if not n:
                break
            h.update(view[:n])
    return FileIdentity(h.hexdigest(), int(st.st_size), datetime.fromtimestamp(st.st_mtime, timezone.utc),
                        acquisition_time(path))


_local = threading.local()


def _buffer() -> bytearray:
    buf = getattr(_local, "buf", None)
    if buf is None:
        buf = _local.buf = bytearray(_CHUNK)
    return buf
