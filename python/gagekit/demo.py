"""The end-to-end demonstration behind ``gagekit demo``.

Each step runs one capability on bundled or honestly simulated data, prints a
compact summary table, adds its section to one HTML report and writes its JSON
(``DIR/<step>.json``). ``quick`` shrinks the sizes for a smoke run.
"""

from __future__ import annotations

import json
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Optional

from . import _progress
from ._util import to_jsonable
from .report import Report


@dataclass
class DemoContext:
    out: Path
    quick: bool
    report: Report
    echo: Callable[[str], None]


@dataclass(frozen=True)
class StepOutcome:
    name: str
    title: str
    seconds: float
    summary: str
    data: dict = field(repr=False)

    def to_dict(self) -> dict:
        return {"name": self.name, "title": self.title, "seconds": self.seconds, "result": self.data}


@dataclass(frozen=True)
class DemoResult:
    out: Path
    report: Path
    steps: tuple[StepOutcome, ...]

    def to_dict(self) -> dict:
        return {"out": str(self.out), "report": str(self.report), "steps": [s.to_dict() for s in self.steps]}


# A step: (name, title, function(ctx) -> (json-ready dict, summary text)).
Step = tuple[str, str, Callable[[DemoContext], tuple[dict, str]]]


def _steps() -> list[Step]:
    from . import demo_steps

    return demo_steps.STEPS


def run_demo(out: Optional[Path] = None, quick: bool = False, echo: Callable[[str], None] = print,
             only: Optional[list[str]] = None) -> DemoResult:
    """Run every demo step (or those named in ``only``); write the report into ``out``.

    The folder is built under a temporary name beside ``out`` and renamed at the end
    (:func:`gagekit._files.atomic_dir`): an interrupted demo leaves no half-written report."""
    from ._files import atomic_dir, output_dir

    if out is None:
        out = Path(tempfile.mkdtemp(prefix="gagekit-demo-")) / "report"
    final = output_dir(out)
    with atomic_dir(final) as tmp:
        res = _run_demo(tmp, quick, echo, only)
    page = final / res.report.name
    echo(f"\nreport: {page}")
    return DemoResult(final, page, res.steps)


def _run_demo(out: Path, quick: bool, echo: Callable[[str], None], only: Optional[list[str]]) -> DemoResult:
    from ._files import write_text

    report = Report("gagekit demo", "Machining accuracy on bundled sample data: every number below was computed by this run.")
    ctx = DemoContext(out, quick, report, echo)
    outcomes = []
    steps = [s for s in _steps() if only is None or s[0] in only]
    for name, title, fn in _progress.track(steps, "demo steps"):
        echo(f"\n== {title}")
        t0 = time.perf_counter()
        report.section(title)
        data, summary = fn(ctx)
        dt = time.perf_counter() - t0
        echo(summary)
        echo(f"({dt:.2f} s)")
        write_text(out / f"{name}.json", json.dumps(to_jsonable(data), indent=2, allow_nan=False))
        outcomes.append(StepOutcome(name, title, dt, summary, data))
    page = report.write(out)
    return DemoResult(out, page, tuple(outcomes))
