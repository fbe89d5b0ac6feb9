"""The ``gagekit`` command line.

One sub-application per capability (``cloud``, ``form``, ``gage``, ``machine``)
plus ``demo``. Every command that computes something takes ``--json``: the
machine-readable result alone on stdout. Errors are printed as one line on
stderr with exit status 2; nothing is printed to stdout then.
"""

from __future__ import annotations

import os
import sys
from typing import Optional

import typer

from .. import __version__
from ..errors import GagekitError
from . import (batch, cloud, compare, db, demo, form, gage, machine, machine_export, machine_instruments, machine_observer,
               qif, stats, studio)
from . import data  # gagekit data list / path
from . import form_params  # gagekit form roundness / straightness / flatness
from ._common import warn
from . import inspect as inspect_cmd
from . import grr as grr_cmd  # gagekit stats grr
from . import schema as schema_cmd  # gagekit schema KIND

app = typer.Typer(
    name="gagekit",
    help="Machining accuracy: machine-tool error models and virtual gages for scanned parts.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
# Every sub-application and command is registered here, explicitly (no registration by import).
machine_observer.register(machine.app)  # machine design, evaluate-plan, track, history, simulate-cycles
machine_export.register(machine.app)  # machine export, compensate-nc, iso230-2
machine_instruments.register(machine.app)  # machine ballbar
form_params.register(form.app)  # form roundness, straightness, flatness
app.add_typer(cloud.app, name="cloud")
app.add_typer(form.app, name="form")
app.add_typer(gage.app, name="gage")
app.add_typer(machine.app, name="machine")
app.add_typer(db.app, name="db")
app.add_typer(qif.app, name="qif")
app.add_typer(data.app, name="data")
stats_app = typer.Typer(add_completion=False)  # `gagekit stats --db URL` (SPC), `gagekit stats grr` (gage R&R)
stats_app.callback(invoke_without_command=True)(stats.stats)
stats_app.command("grr")(grr_cmd.grr)
app.add_typer(stats_app, name="stats")
gage.app.command("batch")(batch.gage_batch)
form.app.command("batch")(batch.form_batch)
app.command("demo")(demo.demo)
inspect_cmd.app.command("scan")(inspect_cmd.inspect)
inspect_cmd.app.command("batch")(batch.inspect_batch)
app.add_typer(inspect_cmd.app, name="inspect")
app.command("studio")(studio.studio)
app.command("compare")(compare.compare)
app.command("schema")(schema_cmd.schema)


def _plain_help(t: typer.Typer) -> None:
    """Help as plain text, for every command: Rich markup would read the TOML table names of
    the help texts (`[[region]]`, `[[feature]]`) as style tags and drop them, and Rich's
    panels print a `<bool>` metavar after every flag."""
    t.rich_markup_mode = None
    for group in t.registered_groups:
        if group.typer_instance is not None:
            _plain_help(group.typer_instance)


_plain_help(app)


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
    """Entry point of the console script.

    Every failure ends the same way: one line ``gagekit: error: ...`` on stderr and exit
    status 2 (130 after Ctrl-C), nothing on stdout. That covers gagekit's own errors,
    bad arguments (click's usage errors, which Typer would print as a framed box) and
    an interrupt. Python warnings raised while a command runs (numpy's "Mean of empty
    slice"...) are held back: printed as ``gagekit: warning: ...`` lines after a
    successful run, dropped when the command fails, so the error line is never buried.
    """
    import signal
    import warnings

    usage_error, no_args_help, exit_exc, abort_exc = _click_classes()
    args = list(sys.argv[1:] if argv is None else argv)
    code = 0
    with warnings.catch_warnings(record=True) as caught:
        try:
            # Python's handler (KeyboardInterrupt) from here on, inside the `try` that turns
            # it into the one line: Ctrl-C at any moment gives the same answer
            if getattr(signal.getsignal(signal.SIGINT), "__name__", "") == "_stop":  # set while gagekit imported
                signal.signal(signal.SIGINT, signal.default_int_handler)
            _terminate_as_interrupt(signal)
            command = typer.main.get_command(app)
            with command.make_context("gagekit", args) as ctx:
                command.invoke(ctx)
        except GagekitError as exc:
            code = _fail(str(exc))
        except no_args_help as exc:  # `gagekit machine` alone: its help, exit 0
            typer.echo(exc.ctx.get_help() if exc.ctx is not None else str(exc))
        except exit_exc as exc:
            code = exc.exit_code
        except abort_exc:
            code = _fail("interrupted", 130)
        except usage_error as exc:  # bad or missing arguments, unknown options
            code = _fail(exc.format_message())
        except _Terminated as exc:
            code = _fail(f"interrupted ({exc.name})", 128 + exc.signum)
        except KeyboardInterrupt:
            code = _fail("interrupted", 130)
        except RecursionError:
            code = _fail("the input is nested too deeply to be read")
        except MemoryError:
            code = _fail("out of memory: the input is too large for this computer")
        except BrokenPipeError:  # `gagekit ... | head`: the reader went away
            code = 0
            try:
                sys.stdout = open(os.devnull, "w")
            except OSError:  # pragma: no cover
                pass
        if code == 0:
            for line in dict.fromkeys(str(w.message) for w in caught):
                warn(line)
    sys.exit(code)  # always, as click's standalone mode does (callers of main() expect SystemExit)


class _Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP (a timeout, systemd, ``docker stop``, a closed terminal), handled
    as Ctrl-C: every temporary file and folder is removed on the way out; exit 128 + signal."""

    def __init__(self, signum: int, name: str) -> None:
        super().__init__(name)
        self.signum, self.name = signum, name


def _terminate_as_interrupt(signal) -> None:
    """Raise :class:`_Terminated` on SIGTERM and SIGHUP, as Python raises KeyboardInterrupt
    on SIGINT (the kernels stop for them too: ``rust/py/src/sigint.rs``). A signal the
    caller ignores (``nohup``: SIGHUP) or handles itself is left alone."""

    def handler(signum, frame):
        raise _Terminated(signum, signal.Signals(signum).name)

    for name in ("SIGTERM", "SIGHUP"):
        sig = getattr(signal, name, None)
        if sig is not None and signal.getsignal(sig) is signal.SIG_DFL:
            try:
                signal.signal(sig, handler)
            except (ValueError, OSError):  # pragma: no cover - not the main thread
                pass


def _click_classes() -> tuple:
    """The argument-parsing exception classes: Typer >= 0.20 vendors click as
    ``typer._click`` and has its own Exit/Abort; older Typer uses click's."""
    try:
        from typer._click import exceptions as ce
        from typer import exceptions as te

        return ((ce.ClickException, te.TyperException), ce.NoArgsIsHelpError, te.Exit, te.Abort)
    except ImportError:  # pragma: no cover - Typer with click as a dependency
        import click

        nah = getattr(click.exceptions, "NoArgsIsHelpError", ())
        return (click.ClickException, nah, click.exceptions.Exit, click.exceptions.Abort)


def _fail(message: str, code: int = 2) -> int:
    """Print the one error line (newlines folded: one line, always)."""
    line = " ".join(str(message).split())
    print(f"gagekit: error: {line}", file=sys.stderr)
    return code
