"""A self-contained HTML report: sections of text, tables and PNG figures.

The page needs no network access: figures are embedded as base64 PNG, the
style sheet is inline. Every figure is also written as a PNG file beside the
page, so that shop-floor documents can reuse it. The markup comes from the Jinja2
templates in ``report/templates/`` (``page.html.j2``: the page; ``parts.html.j2``: a
paragraph, a table, a figure), rendered with autoescaping: text, titles and table cells
are escaped; only :meth:`Report.raw` markup made by the report modules and the embedded
script libraries pass as they are.
"""

from __future__ import annotations

import base64
import io
import re
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any, Sequence

_CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,Arial,sans-serif;margin:2em auto;max-width:1100px;color:#222;line-height:1.45}
h1{border-bottom:3px solid #2a5d9f;padding-bottom:.2em}h2{color:#2a5d9f;margin-top:2em;border-bottom:1px solid #ccc}
table{border-collapse:collapse;margin:1em 0;font-size:.92em}th,td{border:1px solid #bbb;padding:.25em .6em}
th{background:#eef3fa;text-align:left}td.num{text-align:right;font-variant-numeric:tabular-nums}
figure{margin:1em 0}figure img{max-width:100%;border:1px solid #ddd}figcaption{font-size:.9em;color:#555}
.ok{color:#17723a;font-weight:600}.bad{color:#b3261e;font-weight:600}nav li{margin:.15em 0}
"""


@lru_cache(maxsize=1)
def _templates():
    """The report templates (one Jinja2 environment per process, autoescaping on)."""
    import jinja2

    env = jinja2.Environment(loader=jinja2.PackageLoader("gagekit.report", "templates"),
                             autoescape=True, undefined=jinja2.StrictUndefined, keep_trailing_newline=False)
    env.filters["num"] = _num
    return env


def _parts():
    return _templates().get_template("parts.html.j2").module


def _num(v: Any) -> str:
    return f"{v:.6g}" if isinstance(v, float) else str(v)


@dataclass
class _Section:
    title: str
    anchor: str
    parts: list[str] = field(default_factory=list)


def _slug(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-") or "section"


class Report:
    """Collects sections, then :meth:`write` produces ``report.html`` (and PNGs)."""

    def __init__(self, title: str, subtitle: str = "") -> None:
        self.title = title
        self.subtitle = subtitle
        self.sections: list[_Section] = []
        self._figures: list[tuple[str, bytes]] = []
        self._scripts: dict[str, str] = {}

    def section(self, title: str) -> "Report":
        anchor = _slug(title)
        taken = {s.anchor for s in self.sections}
        k = 2
        while anchor in taken:
            anchor = f"{_slug(title)}-{k}"
            k += 1
        self.sections.append(_Section(title, anchor))
        return self

    def _current(self) -> _Section:
        if not self.sections:
            self.section(self.title)
        return self.sections[-1]

    def text(self, text: str, css_class: str | None = None) -> "Report":
        self._current().parts.append(str(_parts().text(text, css_class)))
        return self

    def table(self, headers: Sequence[str], rows: Sequence[Sequence[Any]], caption: str = "") -> "Report":
        self._current().parts.append(str(_parts().table([str(h) for h in headers], [list(r) for r in rows], caption)))
        return self

    def figure(self, fig: Any, name: str, caption: str = "") -> "Report":
        """Embed a matplotlib figure (closed afterwards) as a PNG."""
        import matplotlib.pyplot as plt

        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
        plt.close(fig)
        png = buf.getvalue()
        fname = f"{_slug(name)}.png"
        self._figures.append((fname, png))
        b64 = base64.b64encode(png).decode("ascii")
        self._current().parts.append(str(_parts().figure(caption or name, b64, caption)))
        return self

    def raw(self, markup: str) -> "Report":
        """Append trusted HTML made by a report module (tables with classes, plot divs)."""
        self._current().parts.append(markup)
        return self

    def script(self, name: str, source: str) -> "Report":
        """Embed a JavaScript library once per page (in the head), e.g. plotly.js: the
        page stays self-contained and works offline."""
        self._scripts.setdefault(name, source)
        return self

    def html(self) -> str:
        return _templates().get_template("page.html.j2").render(
            title=self.title, subtitle=self.subtitle, css=_CSS, scripts=self._scripts, sections=self.sections)

    def write(self, directory: str | Path, name: str = "report.html") -> Path:
        """Write the page and its figures into ``directory``; return the page's path."""
        from .._files import write_bytes, write_text

        out = Path(directory)
        for fname, png in self._figures:
            write_bytes(out / fname, png)
        page = out / name
        write_text(page, self.html())
        return page
