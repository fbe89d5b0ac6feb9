"""Helpers shared by the CLI sub-applications."""

from __future__ import annotations

from typing import Any, Callable

import typer

from .._util import dumps
from ..report.text import table

__all__ = ["JSON_OPTION", "emit", "table"]

JSON_OPTION = typer.Option(False, "--json", help="Print the result as JSON on stdout, and nothing else.")


def emit(result: Any, as_json: bool, human: Callable[[Any], str]) -> None:
    """Print ``result`` as JSON or as the human-readable text ``human(result)``."""
    if as_json:
        typer.echo(dumps(result))
    else:
        typer.echo(human(result))
