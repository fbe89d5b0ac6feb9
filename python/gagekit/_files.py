"""Every file boundary of gagekit: typed errors for reads and writes, atomic outputs.

One place maps what the operating system, the decoders and SQLite raise onto the
:mod:`gagekit.errors` classes, so that a caller (and the CLI's one error line) never
sees an ``OSError``, ``UnicodeDecodeError`` or ``sqlite3`` traceback:

* :func:`input_file` checks an input path before anything opens it: it must exist
  and be a *regular* file (a folder, FIFO, socket or device is refused, so
  ``mkfifo f.toml; gagekit machine check f.toml`` cannot block);
* :func:`read_bytes` / :func:`read_text` read a whole input file with those checks
  (text is UTF-8; a leading byte-order mark is dropped);
* :func:`reading` is a context for third-party readers that open the file
  themselves: any ``OSError`` inside becomes a :class:`~gagekit.errors.FileAccessError`;
* :func:`output_file` checks an output path up front (its folder exists and is
  writable, the path is not a folder, an existing file is writable);
* :func:`atomic_path`, :func:`atomic_open`, :func:`write_text`, :func:`write_bytes`
  write outputs atomically: a temporary file in the same folder, flushed and fsynced,
  then :func:`os.replace` onto the final name. An interrupted or killed command
  leaves the old file or none, never a truncated one under the final name;
* :func:`atomic_dir` does the same for report folders: the folder is built under a
  temporary name beside it and renamed into place at the end;
* :func:`os_error` and :func:`sqlite_error` are the mappings themselves.

Writes follow POSIX rename semantics; on the same file system :func:`os.replace`
is atomic (POSIX ``rename(2)``).
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import signal
import stat
import tempfile
import threading
from pathlib import Path
from typing import IO, Iterator, Optional, Union

from .errors import FileAccessError, FileFormatError, GagekitError

PathLike = Union[str, os.PathLike]

__all__ = [
    "os_error",
    "sqlite_error",
    "decode_error",
    "input_file",
    "read_bytes",
    "read_text",
    "reading",
    "output_file",
    "output_dir",
    "atomic_path",
    "atomic_open",
    "write_text",
    "write_bytes",
    "atomic_dir",
    "REPORT_MARKER",
]

#: A file every report folder gagekit writes holds; only such folders are replaced.
REPORT_MARKER = ".gagekit-report"

_REASONS = {
    errno.ENOENT: "no such file or folder",
    errno.EACCES: "permission denied",
    errno.EPERM: "operation not permitted",
    errno.EISDIR: "is a folder, not a file",
    errno.ENOTDIR: "a part of the path is not a folder",
    errno.ENOSPC: "no space left on the device",
    errno.EROFS: "read-only file system",
    errno.EDQUOT: "disk quota exceeded",
    errno.ENAMETOOLONG: "file name too long",
    errno.ELOOP: "too many symbolic links",
    errno.EEXIST: "already exists",
    errno.EXDEV: "cannot rename across file systems",
    errno.EBUSY: "device or resource busy",
    errno.EIO: "input/output error",
    errno.ETXTBSY: "file busy",
    errno.EMFILE: "too many open files",
}


def os_error(exc: OSError, path: PathLike, action: str = "read") -> FileAccessError:
    """The typed error for an ``OSError`` met while doing ``action`` ("read", "write"...)
    on ``path``: one line naming the file and the reason, no errno jargon."""
    reason = _REASONS.get(exc.errno or 0) or (exc.strerror or type(exc).__name__).lower()
    return FileAccessError(f"{path}: cannot {action}: {reason}")


_BINARY_DATA = (".ply", ".e57", ".stl", ".las", ".laz", ".npy", ".npz", ".3mf", ".gz", ".zip", ".db", ".sqlite")
"""Suffixes of the scans, meshes and archives gagekit reads as binary data: one of them
where a text file was expected is most often two arguments given in the wrong order."""


def decode_error(exc: UnicodeDecodeError, path: PathLike, what: Optional[str] = None) -> FileFormatError:
    """A text file that is not UTF-8: name the byte offset (an editor finds it). When the
    caller expected a text ``what`` (:func:`read_text`) and got a scan, mesh or archive,
    that is said instead."""
    suffix = Path(path).suffix.lower()
    if what is not None and suffix in _BINARY_DATA:
        return FileFormatError(f"{path}: a binary {suffix} file where a text {what} was expected "
                               "(check the order of the arguments)")
    bad = exc.object[exc.start : exc.start + 1].hex() if isinstance(exc.object, (bytes, bytearray)) else "?"
    return FileFormatError(f"{path}: not UTF-8 text (byte 0x{bad} at offset {exc.start}); save it as UTF-8")


def sqlite_error(exc: BaseException, path: PathLike, what: str = "database") -> GagekitError:
    """Map a ``sqlite3`` error to a typed error: locked or busy, read-only, unreadable
    (not a database, corrupt), or anything else."""
    msg = str(exc).lower()
    if "locked" in msg or "busy" in msg:
        return FileAccessError(f"{path}: the {what} is locked by another process; try again when it has finished")
    if "readonly" in msg or "read-only" in msg or "read only" in msg:
        return FileAccessError(f"{path}: the {what} is read-only (file or folder permissions)")
    if "unable to open" in msg:
        return FileAccessError(f"{path}: cannot open the {what} (missing folder or permission denied)")
    if "not a database" in msg or "malformed" in msg or "file is encrypted" in msg:
        return FileFormatError(f"{path}: not a {what} (or a damaged one): {exc}")
    if "disk i/o" in msg or "full" in msg:
        return FileAccessError(f"{path}: cannot write the {what}: {exc}")
    return FileFormatError(f"{path}: {what} error: {exc}")


# ----------------------------------------------------------------------------- inputs

def input_file(path: PathLike, what: str = "file") -> Path:
    """Return ``path`` as a :class:`~pathlib.Path` if it names an existing regular file;
    :class:`FileAccessError` otherwise (missing, a folder, a FIFO/socket/device, no
    permission). ``stat`` never blocks, so a FIFO is refused before anything opens it."""
    p = Path(path)
    try:
        st = p.stat()
    except FileNotFoundError:
        raise FileAccessError(f"{p}: {what} not found (no such file)") from None
    except OSError as exc:
        raise os_error(exc, p, "read") from None
    why = not_regular(st, what)
    if why:
        raise FileAccessError(f"{p}: {why}")
    return p


def not_regular(st: os.stat_result, what: str = "file") -> Optional[str]:
    """Why a file with status ``st`` is not read (a folder, FIFO, socket or device), or None
    for a regular file: the one wording of every input check (single commands, batches)."""
    if stat.S_ISDIR(st.st_mode):
        return f"is a folder; expected a {what}"
    if not stat.S_ISREG(st.st_mode):
        kind = "a FIFO (named pipe)" if stat.S_ISFIFO(st.st_mode) else "not a regular file (a device or socket)"
        return f"is {kind}; gagekit reads regular files only"
    return None


def read_bytes(path: PathLike, what: str = "file") -> bytes:
    """The content of a regular input file; typed errors for every OS failure."""
    p = input_file(path, what)
    try:
        return p.read_bytes()
    except OSError as exc:
        raise os_error(exc, p, "read") from None


def read_text(path: PathLike, what: str = "file") -> str:
    """The UTF-8 text of a regular input file (a leading byte-order mark dropped);
    :class:`FileFormatError` naming the byte offset for other encodings."""
    p = Path(path)
    data = read_bytes(p, what)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise decode_error(exc, p, what) from None


def csv_rows(text: str, path: PathLike) -> Iterator[tuple[int, list[str]]]:
    """(line number, cells) of CSV ``text`` (read from ``path``); a line the csv module
    refuses (a field over its size limit, a NUL byte) is a FileFormatError naming it."""
    import csv
    import io

    reader = csv.reader(io.StringIO(text))
    while True:
        try:
            row = next(reader)
        except StopIteration:
            return
        except csv.Error as exc:
            raise FileFormatError(f"{path}, line {reader.line_num}: not a CSV line ({exc})") from None
        yield reader.line_num, row


@contextlib.contextmanager
def reading(path: PathLike, what: str = "file") -> Iterator[Path]:
    """Check ``path`` with :func:`input_file`, then map every ``OSError`` and
    ``UnicodeDecodeError`` raised inside the block (by a library that opens the file
    itself) to a typed error."""
    p = input_file(path, what)
    try:
        yield p
    except UnicodeDecodeError as exc:
        raise decode_error(exc, p) from None
    except OSError as exc:
        raise os_error(exc, p, "read") from None


# ---------------------------------------------------------------------------- outputs

def _check_folder(folder: Path, target: Path) -> None:
    try:
        st = folder.stat()
    except FileNotFoundError:
        raise FileAccessError(f"{target}: cannot write: the folder {folder} does not exist") from None
    except OSError as exc:
        raise os_error(exc, target, "write") from None
    if not stat.S_ISDIR(st.st_mode):
        raise FileAccessError(f"{target}: cannot write: {folder} is not a folder")
    if not _writable(folder, st):
        raise FileAccessError(f"{target}: cannot write: the folder {folder} is read-only")


def output_file(path: PathLike) -> Path:
    """Check an output file path before any work is done: its folder exists and is
    writable, the path is not a folder or special file, and an existing file there is
    writable (it will be replaced atomically). Returns the path."""
    p = Path(path)
    if str(path) == "" or p.name in ("", ".", ".."):
        raise FileAccessError(f"'{path}': not a file name")
    _check_folder(p.parent if str(p.parent) else Path("."), p)
    try:
        st = p.stat()
    except FileNotFoundError:
        return p
    except OSError as exc:
        raise os_error(exc, p, "write") from None
    if stat.S_ISDIR(st.st_mode):
        raise FileAccessError(f"{p}: cannot write: is a folder; give a file name")
    if not stat.S_ISREG(st.st_mode):
        raise FileAccessError(f"{p}: cannot write: not a regular file")
    if not _writable(p, st):
        raise FileAccessError(f"{p}: cannot write: the existing file is read-only (make it writable to replace it)")
    return p


def output_dir(path: PathLike) -> Path:
    """Check a report folder path before any work is done: its parent exists and is
    writable; the path is new, an empty folder, or a folder gagekit wrote before (it
    holds :data:`REPORT_MARKER`); a folder with other files is never replaced."""
    p = Path(path)
    if p.name in ("", ".", ".."):
        p = p.resolve()
    _check_folder(p.parent, p)
    try:
        st = p.stat()
    except FileNotFoundError:
        return p
    except OSError as exc:
        raise os_error(exc, p, "write") from None
    if not stat.S_ISDIR(st.st_mode):
        raise FileAccessError(f"{p}: cannot write a report folder: a file of that name exists")
    try:
        entries = [e.name for e in os.scandir(p)]
    except OSError as exc:
        raise os_error(exc, p, "write") from None
    if entries and REPORT_MARKER not in entries:
        raise FileAccessError(
            f"{p}: the folder exists and holds other files (not a gagekit report); give a new or empty folder"
        )
    if not _writable(p, st):
        raise FileAccessError(f"{p}: cannot write: the folder is read-only")
    return p


def _writable(p: Path, st: os.stat_result) -> bool:
    """Writable for this process, and not protected by its mode bits: a file or folder
    with no write bit at all counts as read-only even for root (who bypasses
    permissions), as a user who ran ``chmod a-w`` on a result means it."""
    return os.access(p, os.W_OK) and bool(st.st_mode & 0o222)


def _fsync_dir(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:  # pragma: no cover - platforms without directory fds
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover
        pass
    finally:
        os.close(fd)


#: The signals the command line turns into an exception (Ctrl-C, a timeout, a closed terminal).
_HELD = tuple(s for s in (getattr(signal, n, None) for n in ("SIGINT", "SIGTERM", "SIGHUP")) if s is not None)


@contextlib.contextmanager
def _signals_held() -> Iterator[None]:
    """Hold SIGINT, SIGTERM and SIGHUP back for the block (their handlers run when it ends): a
    signal's exception between creating a temporary file and recording its name would leave
    the file behind, one between moving the old output aside and the new one in would lose
    both. The Python-level handlers are swapped for one that only records the signal, then put
    back and called for what arrived. (Blocking the signal with ``pthread_sigmask`` is not
    enough: it blocks the calling thread only, so with any other thread alive, a Rust worker
    or a Dask thread, the kernel delivers the signal there and Python still raises it in the
    main thread at once.) Only the main thread runs Python's signal handlers, and only it may
    change them, so elsewhere the block runs as is."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list = []

    def record(signum, frame):  # noqa: ANN001 - signal handler signature
        caught.append((signum, frame))

    saved = {}
    for s in _HELD:
        h = signal.getsignal(s)
        if h is None:  # installed outside Python: leave it alone
            continue
        saved[s] = h
        signal.signal(s, record)
    try:
        yield
    finally:
        for s, h in saved.items():
            signal.signal(s, h)
        for signum, frame in caught:
            h = saved[signum]
            if callable(h):
                h(signum, frame)
            elif h == signal.SIG_DFL:
                signal.raise_signal(signum)


@contextlib.contextmanager
def atomic_path(path: PathLike) -> Iterator[Path]:
    """Yield a temporary path in the folder of ``path`` (same suffix, so writers that
    choose the format by extension still work); when the block ends without an
    exception the temporary file is fsynced and renamed onto ``path``, otherwise it is
    removed (also on Ctrl-C). ``OSError`` inside the block becomes a typed error."""
    p = output_file(path)
    tmp: Optional[Path] = None
    try:
        with _signals_held():  # the file and its name together (see _signals_held)
            fd, tmp_name = tempfile.mkstemp(prefix=f".{p.stem}.", suffix=f".gk-tmp{p.suffix}",
                                            dir=p.parent if str(p.parent) else ".")
            os.close(fd)
            tmp = Path(tmp_name)
        try:
            yield tmp
            if not tmp.exists():
                raise FileAccessError(f"{p}: the writer produced no file")
            with open(tmp, "rb+") as fh:
                os.fsync(fh.fileno())
            try:
                mode = stat.S_IMODE(os.stat(p).st_mode)
            except OSError:
                umask = os.umask(0)
                os.umask(umask)
                mode = 0o666 & ~umask
            os.chmod(tmp, mode)
            os.replace(tmp, p)
        except OSError as exc:
            raise os_error(exc, p, "write") from None
        _fsync_dir(p.parent if str(p.parent) else Path("."))
    finally:
        if tmp is not None:
            with contextlib.suppress(OSError):
                tmp.unlink()


@contextlib.contextmanager
def atomic_open(path: PathLike, mode: str = "w", encoding: str = "utf-8", newline: Union[str, None] = None) -> Iterator[IO]:
    """``open()`` for writing, atomically: the data appears under ``path`` only when the
    block completes (see :func:`atomic_path`)."""
    if mode not in ("w", "wb", "wt"):
        raise ValueError(f"atomic_open: mode must be 'w' or 'wb', got {mode!r}")
    with atomic_path(path) as tmp:
        try:
            if "b" in mode:
                fh = open(tmp, mode)
            else:
                fh = open(tmp, mode, encoding=encoding, newline=newline)
        except OSError as exc:
            raise os_error(exc, path, "write") from None
        with fh:
            try:
                yield fh
            except OSError as exc:
                raise os_error(exc, path, "write") from None


def write_text(path: PathLike, text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically; returns the path."""
    with atomic_open(path, "w", encoding=encoding) as fh:
        fh.write(text)
    return Path(path)


def write_bytes(path: PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically; returns the path."""
    with atomic_open(path, "wb") as fh:
        fh.write(data)
    return Path(path)


@contextlib.contextmanager
def atomic_dir(path: PathLike) -> Iterator[Path]:
    """Yield a new temporary folder beside ``path``; fill it inside the block. On
    success it is renamed to ``path`` (an earlier gagekit report folder there is
    replaced, see :func:`output_dir`); on any exception it is deleted and ``path`` is
    left as it was. The folder receives :data:`REPORT_MARKER`."""
    p = output_dir(path)
    tmp: Optional[Path] = None
    old = None
    try:
        try:
            with _signals_held():  # the folder and its name together (see _signals_held)
                tmp = Path(tempfile.mkdtemp(prefix=f".{p.name}.", suffix=".gk-tmp", dir=p.parent))
        except OSError as exc:
            raise os_error(exc, p, "write") from None
        try:
            yield tmp
            (tmp / REPORT_MARKER).write_text("written by gagekit; this folder may be replaced by the next run\n")
            os.chmod(tmp, 0o777 & ~_umask())
            with _signals_held():  # never the old folder moved aside and the new one not in
                if p.exists():
                    if not any(True for _ in os.scandir(p)):
                        p.rmdir()
                    else:
                        old = p.parent / f".{p.name}.{os.getpid()}.gk-old"
                        os.replace(p, old)
                os.replace(tmp, p)
        except OSError as exc:
            raise os_error(exc, p, "write") from None
    finally:
        if tmp is not None and tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
        if old is not None and old.exists():
            shutil.rmtree(old, ignore_errors=True)


def _umask() -> int:
    m = os.umask(0)
    os.umask(m)
    return m
