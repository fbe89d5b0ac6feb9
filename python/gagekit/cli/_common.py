"""Helpers shared by the CLI sub-applications."""

from __future__ import annotations

import math
import re
from typing import Any, Callable, Optional, Sequence

import typer

from .._util import check_finite_result, dumps
from ..errors import InvalidInputError
from ..report.text import table

__all__ = ["JSON_OPTION", "emit", "table", "warn"]

JSON_OPTION = typer.Option(False, "--json", help="Print the result as JSON on stdout, and nothing else.")

#: Seeds are unsigned 64-bit integers (the kernels' generators take a u64).
SEED_MAX = 2**64 - 1


def _seed(value: Any) -> Any:
    if value is not None and not 0 <= value <= SEED_MAX:
        raise typer.BadParameter(f"a seed is an integer from 0 to 2**64 - 1, got {value}")
    return value


def seed_option(help: str, flag: str = "--seed") -> Any:
    """A ``--seed`` option: an integer in [0, 2**64 - 1]; anything else is a usage error
    (one line, exit 2) instead of an OverflowError deep in numpy or the kernels. Checked by a
    callback, not an IntRange, so the help does not print the 20-digit bound."""
    return typer.Option(0, flag, metavar="SEED", callback=_seed, help=help)


def count_option(default: int, flag: str, help: str, min: int = 1, max: int = 10**9) -> Any:
    """A count option (points, candidates, starts, cycles...): an integer in [min, max]."""
    return typer.Option(default, flag, min=min, max=max, help=help)


def _finite(value: Any) -> Any:
    import math

    if value is not None and not math.isfinite(value):
        raise typer.BadParameter(f"must be a finite number, got {value}")
    return value


def _nonnegative(value: Any) -> Any:
    _finite(value)
    if value is not None and value < 0:
        raise typer.BadParameter(f"must be zero or positive, got {value}")
    return value


def float_option(default: float, flag: str, help: str, nonnegative: bool = True) -> Any:
    """A float option that refuses NaN and infinities (and, by default, negative values)."""
    return typer.Option(default, flag, help=help, callback=_nonnegative if nonnegative else _finite)


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
        warn(w)
    return cloud


MEMORY_OPTION = typer.Option(
    None, "--memory",
    help="Memory for points, e.g. 4G or 512M (default: an eighth of the RAM). A scan whose whole read "
         "needs more than half of it is streamed: read in chunks, keeping only the points inside regions.",
)
CHUNK_OPTION = typer.Option(None, "--chunk-points", hidden=True, min=1,
                            help="Stream in chunks of this many points (testing).")


def open_scan_cli(path: Any, units: Any = None, memory: Any = None, chunk: Any = None, whole: bool = False) -> Any:
    """The scan of a command that can stream (:mod:`gagekit.cloud.stream`): a
    :class:`~gagekit.cloud.stream.CloudStream` when ``chunk`` is given or the whole read
    would not fit half of ``memory`` (and ``whole`` is not asked), else the
    :class:`~gagekit.cloud.Cloud` of a whole read. Warnings as :func:`read_cloud_cli`."""
    from ..cloud.stream import memory_budget, open_cloud, should_stream

    budget = memory_budget(memory)
    if whole or (chunk is None and not should_stream(path, budget)):
        return read_cloud_cli(path, units)
    stream = open_cloud(path, units, chunk=chunk, memory=budget)
    for w in stream.warnings:
        warn(w)
    return stream


#: Python argument names the library's warnings may mention -> the command-line option
_OPTION_OF = {"max_tilt": "--max-tilt", "axis": "--axis"}
_ARGUMENT = re.compile(r"\b(" + "|".join(_OPTION_OF) + r")\s*=\s*(\.\.\.|[-+\w.]+)")


def cli_wording(message: str) -> str:
    """A library message as the command line says it: ``max_tilt=90`` -> ``--max-tilt 90``,
    ``axis=...`` -> ``--axis X,Y,Z``."""
    def option(m: "re.Match[str]") -> str:
        value = "X,Y,Z" if m.group(1) == "axis" and m.group(2) == "..." else m.group(2)
        return f"{_OPTION_OF[m.group(1)]} {value}"

    return _ARGUMENT.sub(option, " ".join(str(message).split()))


def warn(message: Any) -> None:
    """The one way the command line prints a warning: one line ``gagekit: warning: ...`` on
    stderr (never in the stdout table or JSON), in the command line's words."""
    typer.echo(f"gagekit: warning: {cli_wording(str(message))}", err=True)


def emit(result: Any, as_json: bool, human: Callable[[Any], str], warnings: Sequence[str] = ()) -> None:
    """Print ``result`` as JSON or as the human-readable text ``human(result)``, after
    checking that every number in it is finite (:class:`NumericalError` otherwise: never a
    NaN, an infinity or a JSON null in place of a number); then each of ``warnings`` (the
    result's own, e.g. a fit's) with :func:`warn`. JSON keeps them in the result too."""
    check_finite_result(result)
    if as_json:
        typer.echo(dumps(result))
    else:
        typer.echo(human(result))
    for w in dict.fromkeys(warnings):
        warn(w)


def number_option(text: str, what: str) -> float:
    """A finite number given on the command line (``what`` names the option)."""
    try:
        v = float(text)
    except ValueError:
        raise InvalidInputError(f"{what}: '{text}' is not a number") from None
    if not math.isfinite(v):
        raise InvalidInputError(f"{what}: '{text}' is not a finite number")
    return v


def parse_assignments(text: Optional[str], what: str) -> dict:
    """'B=0,W=-500' -> {'B': 0.0, 'W': -500.0}."""
    out: dict = {}
    if not text:
        return out
    for part in text.split(","):
        part = part.strip()
        if not part:
            continue
        if "=" not in part:
            raise InvalidInputError(f"{what}: expected NAME=VALUE items separated by commas, got '{part}'")
        k, v = (s.strip() for s in part.split("=", 1))
        if k in out:
            raise InvalidInputError(f"{what}: '{k}' is given twice")
        out[k] = v
    return out
