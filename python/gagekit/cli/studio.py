"""`gagekit studio`: set up gages and inspections on the scan itself, in the browser (Sec. 7.2, item 5)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer


def studio(
    scan: Path = typer.Argument(..., help="Scanned cloud: XYZ/CSV/TXT, NIST .ds, PLY, .npy, LAS/LAZ, E57."),
    spec: Optional[Path] = typer.Argument(None, help="Gage file or drawing (PART.toml with [[feature]] and [[tolerance]]) to edit; created on the first save if missing."),
    units: Optional[str] = typer.Option(None, "--units", help="Length unit of the scan file (default: mm)."),
    port: int = typer.Option(8765, "--port", help="TCP port (0: any free port)."),
    no_browser: bool = typer.Option(False, "--no-browser", help="Do not open a browser window."),
    host: Optional[str] = typer.Option(
        None, "--host",
        help="Listen on this address instead of 127.0.0.1; every request then needs the access token printed here."),
    root: Optional[Path] = typer.Option(
        None, "--root", help="Folder whose files the page may open and save (default: the scan's folder)."),
    kind: str = typer.Option("gage", "--kind", help="What a SPEC.toml that does not exist yet becomes: gage (a gage file) "
                                                    "or part (a drawing for `gagekit inspect`)."),
) -> None:
    """Open the scan in a local web application: regions as gages and datums, or as inspection
    features with tolerances; run the check or the inspection; save.

    Listens on 127.0.0.1 unless --host is given; stops with Ctrl+C.
    """
    try:
        from ..studio import serve
    except ImportError as exc:
        from ..errors import ConfigError

        raise ConfigError(f"the studio needs its extra packages ({exc.name} is missing): pip install 'gagekit[studio]'") from None

    if kind not in ("gage", "part"):
        from ..errors import ConfigError

        raise ConfigError(f"--kind {kind}: choose gage or part")
    serve(scan, spec, units=units, kind=kind, port=port, host=host, open_browser=not no_browser, root=root,
          echo=lambda s: typer.echo(s, err=True))
