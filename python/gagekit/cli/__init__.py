"""The ``gagekit`` command line.

One sub-application per capability (``cloud``, ``form``, ``gage``, ``machine``)
plus ``demo``. Every command that computes something takes ``--json``: the
machine-readable result alone on stdout. Errors are printed as one line on
stderr with exit status 2; nothing is printed to stdout then.
"""

from __future__ import annotations

import sys
from typing import Optional

import typer

from .. import __version__
from ..errors import GagekitError
from . import cloud, demo, form, gage, machine, machine_observer
from . import inspect as inspect_cmd

app = typer.Typer(
    name="gagekit",
    help="Machining accuracy: machine-tool error models and virtual gages for scanned parts.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
# Every sub-application and command is registered here, explicitly (no registration by import).
machine_observer.register(machine.app)  # machine design, evaluate-plan, track, history, simulate-cycles
app.add_typer(cloud.app, name="cloud")
app.add_typer(form.app, name="form")
app.add_typer(gage.app, name="gage")
app.add_typer(machine.app, name="machine")
app.command("demo")(demo.demo)
app.command("inspect")(inspect_cmd.inspect)


def _version_callback(value: bool) -> None:
    if value:
        typer.echo(f"gagekit {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Optional[bool] = typer.Option(
        None, "--version", callback=_version_callback, is_eager=True, help="Print the version and exit."
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bars (they go to stderr, and only on a terminal)."),
) -> None:
    """Machining accuracy: machine-tool error models and virtual gages for scanned parts."""
    from .. import _progress

    if quiet or "--json" in sys.argv:
        _progress.set_quiet()


def main(argv: Optional[list[str]] = None) -> None:
    """Entry point of the console script."""
    import warnings

    # library warnings (e.g. a LAS file's assumed unit) as one line each on stderr
    warnings.showwarning = lambda message, *_a, **_k: print(f"gagekit: warning: {message}", file=sys.stderr)
    try:
        app(args=argv, prog_name="gagekit", standalone_mode=True)
    except GagekitError as exc:
        print(f"gagekit: error: {exc}", file=sys.stderr)
        sys.exit(2)
