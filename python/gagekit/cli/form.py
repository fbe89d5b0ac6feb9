"""`gagekit form`: Form of lines, planes, circles, spheres and cylinders (Ch. 6)."""

from __future__ import annotations

import typer

app = typer.Typer(help="Form of lines, planes, circles, spheres and cylinders (Ch. 6).", no_args_is_help=True)
