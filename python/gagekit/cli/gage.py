"""`gagekit gage`: Virtual gages: can a scanned casting be machined to print? (Ch. 5)"""

from __future__ import annotations

import typer

app = typer.Typer(help="Virtual gages: can a scanned casting be machined to print? (Ch. 5)", no_args_is_help=True)
