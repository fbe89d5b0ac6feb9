"""`gagekit schema KIND`: the JSON Schema of a TOML file type, for editors (taplo / Even Better TOML)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer


def schema(
    kind: str = typer.Argument(..., help="The file type: gages, part, machine, regions, zones or exclusions."),
    out: Optional[Path] = typer.Option(None, "--out", help="Write the schema to this file (atomically) instead of stdout."),
) -> None:
    """Print the JSON Schema (draft 2020-12, unknown keys refused) of a gagekit TOML file type,
    generated from the schema its reader validates with.

    A first line `#:schema FILE.json` in a TOML file lets Even Better TOML (VS Code) and taplo
    complete and check it as it is typed. Exit status 0; 2 for an unknown KIND or an unwritable --out.
    """
    from .._files import output_file, write_text
    from ..schema import json_schema

    text = json.dumps(json_schema(kind), indent=2) + "\n"
    if out is None:
        typer.echo(text, nl=False)
        return
    output_file(out)
    write_text(out, text)
    typer.echo(f"{kind} schema: {out}")
