"""`gagekit db`: the results database (schema migrations, exports)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from ._common import JSON_OPTION, emit

app = typer.Typer(help="The results database: upgrade its schema, export its tables.", no_args_is_help=True)


@app.command("upgrade")
def upgrade(
    url: str = typer.Argument(..., help="sqlite:///FILE, a file path, or postgresql://user@host/db"),
    as_json: bool = JSON_OPTION,
) -> None:
    """Apply the schema migrations (creates an empty database; converts an old history file)."""
    from ..store import safe_url
    from ..store import upgrade as do_upgrade

    before, after = do_upgrade(url)
    res = {"database": safe_url(url), "from": before, "to": after}
    emit(res, as_json, lambda r: f"{r['database']}: schema {r['from'] or '(empty)'} -> {r['to']}"
         if r["from"] != r["to"] else f"{r['database']}: schema {r['to']} is current")


@app.command("export")
def export(
    url: str = typer.Argument(..., help="sqlite:///FILE, a file path, or postgresql://user@host/db"),
    fmt: str = typer.Option("parquet", "--format", "-f", help="parquet or csv"),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="Folder for one file per table (default: ./gagekit-export)."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Write every table to Parquet or CSV files (one per table)."""
    from ..store.dump import export_tables

    files = export_tables(url, out if out is not None else Path("gagekit-export"), fmt.lower())
    emit({"files": [str(f) for f in files]}, as_json, lambda r: "\n".join(r["files"]))
