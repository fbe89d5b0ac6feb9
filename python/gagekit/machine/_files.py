"""Several output files written all or nothing, on the atomic writes of :mod:`gagekit._files`:
every file goes to a temporary file beside its target, and the renames happen only when all
of them are complete (the LinuxCNC export writes one file per axis)."""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import Mapping, Union

from .._files import atomic_path, output_file

__all__ = ["write_files_atomically"]


def write_files_atomically(files: Mapping[Union[str, Path], Union[str, bytes]]) -> None:
    """Write ``{path: text or bytes}``: all files or none."""
    for p in files:
        output_file(p)
    with contextlib.ExitStack() as stack:
        for p, data in files.items():
            tmp = stack.enter_context(atomic_path(p))
            if isinstance(data, bytes):
                tmp.write_bytes(data)
            else:
                tmp.write_text(data, encoding="utf-8", newline="")
