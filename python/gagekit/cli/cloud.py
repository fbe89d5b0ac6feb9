"""`gagekit cloud`: read point clouds, report their extent, filter them by convex hull."""

from __future__ import annotations

import typer

app = typer.Typer(help="Point clouds: information, convex-hull filter.", no_args_is_help=True)
