"""`gagekit qif`: QIF 3.0 model-based definitions in (``qif import``); ``--qif-results`` on
``inspect`` and ``inspect batch`` writes the results out (docs/qif.md)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Optional

import typer

from ._common import JSON_OPTION, emit, float_option

app = typer.Typer(help="QIF 3.0 (ISO 23952): import a model-based definition as PART.toml; results go out with "
                       "`inspect --qif-results`.", no_args_is_help=True)

QIF_RESULTS_OPTION = typer.Option(None, "--qif-results", help="Also write the results as a QIF 3.0 MeasurementsResults "
                                  "document (needs gagekit[qif]).")
INSTRUMENT_OPTION = typer.Option("", "--instrument", help="The instrument named in the QIF results (MeasurementResources).")


def _human(s: dict) -> str:
    from ._common import table

    rows = [[e["qif_id"], e["type"], e["name"], e["characteristic"], ", ".join(e["features"])] for e in s["evaluated"]]
    out = [f"{s['model']}: QIF {s['version']}, units {s['units']['file']}; {s['characteristics']} characteristics, "
           f"{len(s['evaluated'])} evaluated, {len(s['unsupported'])} not evaluated by this gagekit"]
    if rows:
        out.append(table(["qif id", "QIF type", "name", "gagekit", "features"], rows))
    if s["unsupported"]:
        out.append("not evaluated:")
        out.append(table(["qif id", "QIF type", "name", "in PART.toml", "why"],
                         [[e["qif_id"], e["type"], e["name"], e["toml"], e["reason"]] for e in s["unsupported"]]))
    for w in s["warnings"]:
        out.append(f"note: {w}")
    out.append(f"wrote {s['out']}")
    return "\n".join(out)


@app.command("import")
def qif_import(
    model: Path = typer.Argument(..., help="QIF 3.0 model-based definition (.qif, or .qif.gz)."),
    out: Path = typer.Option(..., "--out", "-o", help="The PART.toml to write."),
    as_json: bool = JSON_OPTION,
    band: float = float_option(0.5, "--band", "Half thickness (mm) of a surface's region box."),
    inset: float = float_option(1.0, "--inset", "How far (mm) a region stays inside its face's boundary."),
) -> None:
    """Turn a QIF model's features, datums and characteristics into a PART.toml for `gagekit inspect`.

    Every characteristic is accounted for: evaluated, written as a comment (sizes,
    distances, angles, material modifiers this gagekit does not evaluate yet) or listed
    as not evaluated, with the reason (JSON `unsupported`).
    """
    from .._files import output_file, write_text
    from ..qif import part_from_model, read_model

    output_file(out)
    m = read_model(model)
    draft = part_from_model(m, band=band, inset=inset, model_ref=_rel(model, out))
    write_text(out, draft.toml)
    draft.summary["out"] = str(out)
    emit(draft.summary, as_json, _human)


def _rel(model: Path, out: Path) -> str:
    """The model's path as PART.toml records it: relative to the PART.toml's folder when
    it can be, else absolute."""
    import os

    try:
        rel = os.path.relpath(Path(model).resolve(), Path(out).resolve().parent)
    except ValueError:
        rel = str(Path(model).resolve())
    return rel.replace(os.sep, "/")


def check_output(path: Optional[Path]) -> None:
    """--qif-results, checked before the work: the extra is installed, the file writable."""
    if path is None:
        return
    from .._files import output_file
    from ..qif._xml import etree

    etree()
    output_file(path)


def write_results(path: Optional[Path], runs: list, spec: Any, spec_path: Any, instrument: str) -> None:
    """--qif-results of the inspection commands (nothing when the option is not given)."""
    if path is None:
        return
    from ..qif import write_inspection_results

    write_inspection_results(path, runs, spec, spec_path, instrument)
