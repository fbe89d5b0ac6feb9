"""Best-of-N wall time, shared by the benchmark scripts (run them as `python benches/X.py`)."""

from __future__ import annotations

import time
from typing import Any, Callable


def timed(fn: Callable[[], Any], repeat: int = 1) -> tuple[float, Any]:
    """Run ``fn`` ``repeat`` times; return (best wall time in s, the last result). The previous
    result is dropped before each run, so a large output is never held twice."""
    best, out = float("inf"), None
    for _ in range(max(1, repeat)):
        out = None
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out
