"""Helpers shared by the CLI sub-applications."""

from __future__ import annotations

from typing import Any, Callable

import typer

from .._util import dumps
from ..report.text import table

__all__ = ["JSON_OPTION", "emit", "table"]

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
