"""Helpers shared by the CLI sub-applications."""

from __future__ import annotations

from typing import Any, Callable

import typer

from .._util import dumps

JSON_OPTION = typer.Option(False, "--json", help="Print the result as JSON on stdout, and nothing else.")

UNITS_OPTION = typer.Option(
    None, "--units",
    help="Unit of the cloud file's coordinates: mm, cm, m, um, in or ft (default: the file's own: "
         "E57 m, LAS/LAZ its CRS unit, others mm). Everything is converted to mm.",
)


def read_cloud_cli(path: Any, units: Any = None, dim: int = 3) -> Any:
    """Read a cloud for a command (:func:`gagekit.cloud.read_cloud`), printing each reader
    warning as one ``gagekit: warning: ...`` line on stderr. Every command that reads a
    cloud takes ``units: Optional[str] = UNITS_OPTION`` and passes it here."""
    from ..cloud import read_cloud

    cloud = read_cloud(path, units=units, dim=dim)
    for w in cloud.warnings:
        typer.echo(f"gagekit: warning: {w}", err=True)
    return cloud


def emit(result: Any, as_json: bool, human: Callable[[Any], str]) -> None:
    """Print ``result`` as JSON or as the human-readable text ``human(result)``."""
    if as_json:
        typer.echo(dumps(result))
    else:
        typer.echo(human(result))


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


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.4f}"
    return str(v)


def _is_num(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False
