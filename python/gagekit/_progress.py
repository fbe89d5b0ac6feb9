"""Progress bars for long work, on stderr, silent when stderr is not a terminal.

``quiet()`` turns them off for the whole process (the CLI's ``--quiet`` and
``--json`` do this), so machine-readable output is never mixed with them.
"""

from __future__ import annotations

import sys
from contextlib import contextmanager
from typing import Iterable, Iterator, Optional, TypeVar

T = TypeVar("T")
_QUIET = False


def set_quiet(value: bool = True) -> None:
    global _QUIET
    _QUIET = value


def enabled() -> bool:
    return not _QUIET and sys.stderr.isatty()


def track(iterable: Iterable[T], description: str, total: Optional[int] = None) -> Iterator[T]:
    """Iterate with a progress bar on stderr when :func:`enabled`."""
    if not enabled():
        yield from iterable
        return
    from rich.console import Console
    from rich.progress import track as rich_track

    yield from rich_track(iterable, description=description, total=total, console=Console(stderr=True), transient=True)


@contextmanager
def status(description: str) -> Iterator[None]:
    """A spinner on stderr around a step without a known length."""
    if not enabled():
        yield
        return
    from rich.console import Console

    with Console(stderr=True).status(description):
        yield
