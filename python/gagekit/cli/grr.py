"""`gagekit stats grr`: is the measuring system good enough? Crossed ANOVA gage R&R and the
Type-1 gage study (AIAG MSA 4th ed.; VDA 5), from a study CSV or the results database."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from ._common import JSON_OPTION, emit, table


def _human(s: dict) -> str:
    out = [f"gage study of {s['source']}"]
    for st in s["studies"]:
        if "type1" in st:
            t = st["type1"]
            out.append(f"\n{st['characteristic']}: Type-1 study of part {st['part']}, n = {t['n']}, reference "
                       f"{t['reference']:g}, tolerance {t['tolerance']:g}")
            out.append(table(["mean", "sd", "bias", "bias p", "Cg", "Cgk", "capable"],
                             [[t["mean"], t["sd"], t["bias"], t["bias_p"], t["cg"], t["cgk"],
                               "yes" if t["capable"] else "no"]]))
            out += [f"  warning: {w}" for w in t.get("warnings", [])]
            continue
        g = st["grr"]
        d = g["design"]
        out.append(f"\n{st['characteristic']}: {d['parts']} parts x {d['appraisers']} appraisers x {d['trials']} trials"
                   + (f", interaction pooled (p = {g['interaction_p']:.3g} > {g['pool_alpha']:g})" if g["pooled"] else ""))
        out.append(table(["source", "df", "SS", "MS", "F", "p"],
                         [[r["source"], r["df"], r["ss"], r.get("ms", "-"), r.get("f", "-"), r.get("p", "-")]
                          for r in g["anova"]]))
        tol = g.get("percent_tolerance", {})
        out.append(table(["", "sd", "% TV", "% tolerance"],
                         [[k, g["sd"][k], g["percent_tv"][k] if k in g["percent_tv"] else "-", tol.get(k, "-")]
                          for k in ("EV", "AV", "interaction", "GRR", "PV", "TV")]))
        acc = g["acceptance"]
        out.append(f"  ndc {g['ndc']}; %GRR of TV: {acc['by_tv']}"
                   + (f"; of tolerance: {acc['by_tolerance']}" if "by_tolerance" in acc else "")
                   + " (AIAG: < 10 % acceptable, 10-30 % conditional, > 30 % unacceptable)")
        out += [f"  warning: {w}" for w in g.get("warnings", [])]
    return "\n".join(out)


def grr(
    csv: Optional[Path] = typer.Option(None, "--csv", help="Study CSV with a header part,appraiser,trial,value"
                                                          "[,characteristic]."),
    db: Optional[str] = typer.Option(None, "--db", help="Results database holding repeated scans of the same parts."),
    spec: Optional[Path] = typer.Option(None, "--spec", help="With --db: only the results of this drawing or gage "
                                                             "file (PART.toml)."),
    pattern: str = typer.Option("{part}_{appraiser}_{trial}", "--pattern",
                                help="With --db: how a scan's file name (without suffix) names the part, the "
                                     "appraiser and the trial, e.g. '{part}_{appraiser}_{trial}' for P03_anna_2.e57."),
    tolerance: Optional[float] = typer.Option(None, "--tolerance", help="USL - LSL of the characteristic "
                                                                        "(default: from the stored limits)."),
    reference: Optional[float] = typer.Option(None, "--type1", metavar="REFERENCE",
                                              help="Type-1 study instead: the reference part's true value "
                                                   "(Cg = 0.2 T / 6 s, Cgk = (0.1 T - |bias|) / 3 s)."),
    part: Optional[str] = typer.Option(None, "--part", help="With --type1: the reference part's id."),
    characteristic: Optional[str] = typer.Option(None, "--characteristic", help="Only this characteristic."),
    pool_alpha: float = typer.Option(0.25, "--pool-alpha", min=0.0, max=1.0,
                                     help="Pool the part x appraiser interaction when its p-value exceeds this (AIAG: 0.25)."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Crossed ANOVA gage R&R (AIAG MSA 4th ed.): ANOVA table, EV, AV, interaction, GRR, PV,
    TV, %GRR of the total variation and of the tolerance, ndc, AIAG acceptance; or with
    --type1 the Type-1 gage study (Cg, Cgk) of repeated measurements of one part."""
    from .._util import load_toml
    from ..errors import ConfigError
    from ..stats.grr import read_study_csv, studies, study_rows_from_db

    if (csv is None) == (db is None):
        raise ConfigError("stats grr: give either --csv STUDY.csv or --db URL")
    if spec is not None and db is None:
        raise ConfigError("stats grr: --spec selects results of --db")
    if csv is not None:
        rows = read_study_csv(csv)
        source = str(csv)
    else:
        documents = None
        if spec is not None:
            doc = load_toml(spec)
            documents = [{"spec": doc}, {"part": doc}]
        rows = study_rows_from_db(db, documents, pattern)
        from ..store.schema import safe_url

        source = safe_url(db) if isinstance(db, str) and "://" in db else str(db)
    if characteristic is not None:
        rows = [r for r in rows if r["characteristic"] == characteristic]
    if not rows:
        raise ConfigError(f"stats grr: no measurements{' of ' + characteristic if characteristic else ''} in {source}")
    s = {"source": source, "studies": studies(rows, tolerance=tolerance, reference=reference, part=part,
                                              pool_alpha=pool_alpha)}
    emit(s, as_json, _human)
