"""Plain-text tables for terminals and report.txt files (the CLI and the demo print them)."""

from __future__ import annotations

from typing import Any

__all__ = ["table"]


def table(headers: list[str], rows: list[list[Any]]) -> str:
    """A plain aligned text table (numbers right-aligned)."""
    cells = [[str(h) for h in headers]] + [[_fmt(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    lines = []
    for k, r in enumerate(cells):
        lines.append("  ".join(c.rjust(w) if k and _is_num(c) else c.ljust(w) for c, w in zip(r, widths)).rstrip())
        if k == 0:
            lines.append("  ".join("-" * w for w in widths))
    return "\n".join(lines)


def fixed(v: float, decimals: int = 4) -> str:
    """``v`` with ``decimals`` decimals; a value that rounds to zero prints 0.000..., never
    -0.000... (for a column whose unit calls for another precision than the default 4)."""
    s = f"{v:.{decimals}f}"
    return s[1:] if s.startswith("-") and float(s) == 0.0 else s  # -1e-13 prints 0.0000, not -0.0000


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return fixed(v)
    return str(v)


def _is_num(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False
