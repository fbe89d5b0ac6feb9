"""`gagekit machine`: Machine-tool volumetric error models, identification and observers (Ch. 3-4)."""

from __future__ import annotations

import typer

app = typer.Typer(help="Machine-tool volumetric error models, identification and observers (Ch. 3-4).", no_args_is_help=True)
