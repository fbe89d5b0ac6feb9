"""The report of a batch: summary counts and one row per scan (batch.json and report.html)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Sequence, Union

from .._files import write_text
from .html import Report

__all__ = ["write_batch_report", "scan_row"]


def scan_row(line: dict) -> list:
    """path, status, outcome, key figure of one ``--json`` line."""
    r = line.get("result") or {}
    if "gages" in r:  # a virtual-gage result
        worst = min(r["gages"], key=lambda g: g["allowance_after"])
        t = r["transform"]
        return [line["scan"], line["status"], r["status"], f"{worst['name']}: {worst['allowance_after']:.4f}",
                f"beta {t['beta']:.5f} rad, d ({t['dx']:.3f}, {t['dy']:.3f}, {t['dz']:.3f}) mm"]
    if "form_error" in r:
        return [line["scan"], line["status"], r.get("criterion", ""), f"{r['form_error']:.6g}", r.get("shape", "")]
    return [line["scan"], line["status"], line.get("error") or "", "", ""]


def write_batch_report(directory: Union[str, Path], title: str, lines: Sequence[dict], summary) -> Path:
    """Write ``batch.json`` (every line and the summary) and ``report.html`` into the folder
    ``directory``, atomically (:func:`gagekit._files.atomic_dir`)."""
    from .._files import atomic_dir

    out = Path(directory)
    doc = {"summary": summary.to_dict(), "seconds": summary.seconds, "executor": summary.executor,
           "database": summary.database, "scans": list(lines)}
    text = json.dumps(doc, indent=2, allow_nan=False)
    rep = Report(title, f"{summary.scans} scans on {summary.executor}; results in {summary.database}")
    rep.section("Summary").table(["scans", "ok", "failed", "skipped", "seconds"],
                                 [[summary.scans, summary.ok, summary.failed, summary.skipped, round(summary.seconds, 2)]])
    gage = any("gages" in (ln.get("result") or {}) for ln in lines)
    headers = (["scan", "status", "outcome", "smallest allowance after T* (mm)", "T*"] if gage
               else ["scan", "status", "criterion / error", "form error (mm)", "shape"])
    rep.section("Scans").table(headers, [scan_row(ln) for ln in lines])
    with atomic_dir(out) as tmp:  # the old folder or the new one, never half of each
        write_text(tmp / "batch.json", text)
        rep.write(tmp)
    return out / "report.html"
