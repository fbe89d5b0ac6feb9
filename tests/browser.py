"""Open an HTML page in headless Chromium: console errors, image decoding, screenshot.

The page is copied with a small probe script that records ``window.onerror``,
``console.error`` and, after load, each image's ``naturalWidth``; Chromium's
``--dump-dom`` then returns the DOM with the probe's findings.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path
from typing import Optional

PROBE = """<script>
window.__errors = [];
window.addEventListener('error', e => window.__errors.push(String(e.message || e.type)), true);
const __ce = console.error; console.error = (...a) => { window.__errors.push(a.join(' ')); __ce(...a); };
window.addEventListener('load', () => {
  const imgs = Array.from(document.images).map(i => ({alt: i.alt, w: i.naturalWidth, h: i.naturalHeight, ok: i.complete}));
  const pre = document.createElement('pre'); pre.id = '__probe';
  pre.textContent = JSON.stringify({errors: window.__errors, images: imgs});
  document.body.appendChild(pre);
});
</script>"""


def chromium() -> Optional[str]:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


def _run(binary: str, *args: str) -> subprocess.CompletedProcess:
    cmd = [binary, "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
           "--no-first-run", "--disable-extensions", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120)


def inspect(page: Path, screenshot: Path) -> dict:
    """Load ``page``; return {'errors': [...], 'images': [...], 'console': [...]}."""
    binary = chromium()
    assert binary, "chromium not installed"
    probe_page = page.with_name("__probe_" + page.name)
    html = page.read_text(encoding="utf-8")
    probe_page.write_text(html.replace("<head>", "<head>" + PROBE, 1), encoding="utf-8")
    try:
        proc = _run(binary, "--enable-logging=stderr", "--v=0", "--virtual-time-budget=10000",
                    "--dump-dom", probe_page.as_uri())
        m = re.search(r'<pre id="__probe">(.*?)</pre>', proc.stdout, re.S)
        assert m, f"probe did not run; chromium said: {proc.stderr[-2000:]}"
        found = json.loads(m.group(1).replace("&quot;", '"').replace("&lt;", "<").replace("&gt;", ">").replace("&amp;", "&"))
        found["console"] = [ln for ln in proc.stderr.splitlines() if "CONSOLE" in ln and "error" in ln.lower()]
        _run(binary, f"--screenshot={screenshot}", "--window-size=1200,2400", "--hide-scrollbars", page.as_uri())
        return found
    finally:
        probe_page.unlink(missing_ok=True)
