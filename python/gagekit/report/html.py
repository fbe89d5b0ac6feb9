"""A self-contained HTML report: sections of text, tables and PNG figures.

The page needs no network access: figures are embedded as base64 PNG, the
style sheet is inline. Every figure is also written as a PNG file beside the
page, so that shop-floor documents can reuse it.
"""

from __future__ import annotations

import base64
import html
import io
import re
from dataclasses import dataclass, field
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


@dataclass
class _Section:
    title: str
    anchor: str
    parts: list[str] = field(default_factory=list)


def _slug(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-") or "section"


def _cell(v: Any) -> str:
    if isinstance(v, float):
        return f'<td class="num">{v:.6g}</td>'
    if isinstance(v, int) and not isinstance(v, bool):
        return f'<td class="num">{v}</td>'
    return f"<td>{html.escape(str(v))}</td>"


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
        cls = f' class="{css_class}"' if css_class else ""
        self._current().parts.append(f"<p{cls}>{html.escape(text)}</p>")
        return self

    def table(self, headers: Sequence[str], rows: Sequence[Sequence[Any]], caption: str = "") -> "Report":
        head = "".join(f"<th>{html.escape(str(h))}</th>" for h in headers)
        body = "".join("<tr>" + "".join(_cell(c) for c in r) + "</tr>" for r in rows)
        cap = f"<caption>{html.escape(caption)}</caption>" if caption else ""
        self._current().parts.append(f"<table>{cap}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")
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
        cap = f"<figcaption>{html.escape(caption)}</figcaption>" if caption else ""
        self._current().parts.append(
            f'<figure><img alt="{html.escape(caption or name)}" src="data:image/png;base64,{b64}">{cap}</figure>'
        )
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
        nav = "".join(f'<li><a href="#{s.anchor}">{html.escape(s.title)}</a></li>' for s in self.sections)
        body = "".join(
            f'<section id="{s.anchor}"><h2>{html.escape(s.title)}</h2>{"".join(s.parts)}</section>' for s in self.sections
        )
        sub = f"<p>{html.escape(self.subtitle)}</p>" if self.subtitle else ""
        scripts = "".join(f'<script data-library="{html.escape(k)}">{v}</script>' for k, v in self._scripts.items())
        return (
            "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(self.title)}</title><style>{_CSS}</style>{scripts}</head><body>"
            f"<h1>{html.escape(self.title)}</h1>{sub}<nav><ol>{nav}</ol></nav>{body}</body></html>"
        )

    def write(self, directory: str | Path, name: str = "report.html") -> Path:
        """Write the page and its figures into ``directory``; return the page's path."""
        from .._files import write_bytes, write_text

        out = Path(directory)
        for fname, png in self._figures:
            write_bytes(out / fname, png)
        page = out / name
        write_text(page, self.html())
        return page
