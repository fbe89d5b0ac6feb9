"""`gagekit demo`: the whole product on bundled sample data."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from .. import _progress
from ._common import JSON_OPTION


def demo(
    out: Optional[Path] = typer.Option(None, "--out", help="Directory for report.html and the JSON of every step (default: a new temporary directory)."),
    quick: bool = typer.Option(False, "--quick", help="Smaller problem sizes: a smoke run in a few seconds."),
    quiet: bool = typer.Option(False, "--quiet", help="No progress bars."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Run the end-to-end demonstration on bundled sample data and write an HTML report."""
    from .._util import dumps
    from ..demo import run_demo

    if quiet or as_json:
        _progress.set_quiet()
    echo = (lambda s: typer.echo(s, err=True)) if as_json else typer.echo
    result = run_demo(out, quick=quick, echo=echo)
    if as_json:
        typer.echo(dumps({"out": str(result.out), "report": str(result.report),
                          "steps": [{"name": s.name, "title": s.title, "seconds": s.seconds} for s in result.steps]}))
