"""The HTML report: self-contained, and it renders in a real browser."""

import base64
import re

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import browser  # noqa: E402
from gagekit.report import Report  # noqa: E402


def _report():
    r = Report("Test report", "made by a test")
    r.section("Numbers").table(["name", "value (mm)"], [["a", 1.5], ["b & c", 2]], caption="two rows")
    fig, ax = plt.subplots()
    x = np.linspace(0, 1, 50)
    ax.plot(x, x**2)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    r.section("Numbers").figure(fig, "parabola", "A parabola")
    return r


def test_report_is_self_contained(tmp_path):
    page = _report().write(tmp_path)
    html = page.read_text()
    assert "http://" not in html and "https://" not in html
    assert "b &amp; c" in html
    assert (tmp_path / "parabola.png").read_bytes().startswith(b"\x89PNG")
    imgs = re.findall(r'src="data:image/png;base64,([^"]+)"', html)
    assert len(imgs) == 1 and base64.b64decode(imgs[0]).startswith(b"\x89PNG")
    assert html.count("<section") == 2  # a repeated title gets its own anchor


@pytest.mark.skipif(browser.chromium() is None, reason="Chromium is not installed (Debian package 'chromium'); .ci/run installs it")
def test_report_renders_in_chromium(tmp_path):
    page = _report().write(tmp_path)
    shot = tmp_path / "shot.png"
    found = browser.inspect(page, shot)
    assert found["errors"] == [] and found["console"] == []
    assert len(found["images"]) == 1 and all(i["w"] > 0 for i in found["images"])
    assert shot.read_bytes().startswith(b"\x89PNG")
