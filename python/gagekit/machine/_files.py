"""Atomic output files for the machine exports: every file is written to a temporary file in
the same folder and renamed over the target only when all of a command's files are complete,
so an error leaves nothing half written."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Mapping, Union

from ..errors import InvalidInputError

__all__ = ["write_files_atomically"]

_UMASK = os.umask(0)
os.umask(_UMASK)


def write_files_atomically(files: Mapping[Union[str, Path], Union[str, bytes]]) -> None:
    """Write ``{path: text or bytes}``; all or nothing (temporary files, then renames)."""
    temps = []
    try:
        for path, text in files.items():
            p = Path(path)
            folder = p.parent if str(p.parent) else Path(".")
            if not folder.is_dir():
                raise InvalidInputError(f"{p}: folder {folder} does not exist")
            fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=folder)
            temps.append((tmp, p))
            os.chmod(tmp, 0o666 & ~_UMASK)
            if isinstance(text, bytes):
                with os.fdopen(fd, "wb") as fb:
                    fb.write(text)
            else:
                with os.fdopen(fd, "w", encoding="utf-8", newline="") as f:
                    f.write(text)
        for tmp, p in temps:
            os.replace(tmp, p)
        temps = []
    except OSError as exc:
        raise InvalidInputError(f"cannot write {exc.filename or 'the output'}: {exc.strerror}") from None
    finally:
        for tmp, _ in temps:
            try:
                os.unlink(tmp)
            except OSError:
                pass
