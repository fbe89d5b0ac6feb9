"""`gagekit data`: the sample files bundled with gagekit (the tour and docs run on them)."""

from __future__ import annotations

import typer

from ._common import JSON_OPTION, emit, table

app = typer.Typer(help="The sample files bundled with gagekit: list them, print a path.", no_args_is_help=True)


@app.command("list")
def list_samples(as_json: bool = JSON_OPTION) -> None:
    """List every bundled sample: name, path, what it is."""
    from ..samples import SAMPLES, sample_path

    rows = [{"name": n, "path": str(sample_path(n)), "description": d} for n, (_, d) in SAMPLES.items()]
    emit({"samples": rows}, as_json, lambda r: table(["name", "path", "what"],
                                                     [[x["name"], x["path"], x["description"]] for x in r["samples"]]))


@app.command("path")
def path(name: str = typer.Argument(..., help="Sample name, as `gagekit data list` shows it (round, bore, machine, ...).")) -> None:
    """Print the path of the bundled sample NAME (for scripts: `gagekit form fit circle $(gagekit data path round)`)."""
    from ..samples import sample_path

    typer.echo(str(sample_path(name)))
