"""The studio in headless Chromium (Debian's, driven by Playwright): open a scan, add a
region by mouse, make it a gage, run, read the allowance, save, compare the file."""

import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import gagekit
from gagekit.cloud.regions import Box
from gagekit.samples import data_path

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
playwright = pytest.importorskip("playwright.sync_api", reason="playwright (pip) is needed for the browser tests")
if not Path(CHROMIUM).exists():
    pytest.skip("Debian's chromium is needed for the browser tests (apt-get install chromium)", allow_module_level=True)

EXPECTED = Path(__file__).with_name("data") / "plate_expected.toml"
ARGS = ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"]


class Studio:
    """`gagekit studio` in a child process on a free port."""

    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen([sys.executable, "-m", "gagekit", "studio", *args, "--no-browser", "--port", "0"],
                                     stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
        self.url = None
        lines = []
        for line in self.proc.stderr:
            lines.append(line)
            m = re.search(r"open (http://\S+)", line)
            if m:
                self.url = m.group(1)
                break
        assert self.url, "".join(lines)

    def stop(self) -> None:
        self.proc.terminate()
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()


@pytest.fixture(scope="module")
def browser():
    with playwright.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


def open_page(browser, url):
    page = browser.new_page(viewport={"width": 1400, "height": 850})
    problems = []
    page.on("console", lambda m: problems.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: problems.append(str(e)))
    page.goto(url)
    page.wait_for_function("window.__studio && window.__studio.ready", timeout=60000)
    return page, problems


def not_blank(path: Path) -> None:
    from PIL import Image

    img = np.asarray(Image.open(path).convert("RGB")).astype(float)
    view = img[:, : img.shape[1] - 490]                      # the 3-D view, left of the panel
    assert view.std() > 10, "the 3-D view is blank"
    background = np.array([0x20, 0x26, 0x2E], dtype=float)
    drawn = (np.abs(view - background).sum(axis=2) > 30).mean()
    assert drawn > 0.02, f"only {drawn:.1%} of the view differs from the background"


def test_add_region_by_mouse_gage_run_save(browser, tmp_path):
    plate = tmp_path / "plate.ply"
    rng = np.random.default_rng(0)
    top = np.column_stack([rng.uniform(0, 100, 6000), rng.uniform(0, 60, 6000), 10 + rng.normal(0, 0.02, 6000)])
    bottom = np.column_stack([rng.uniform(0, 100, 3000), rng.uniform(0, 60, 3000), np.zeros(3000)])
    sides = np.column_stack([rng.choice([0.0, 100.0], 2000), rng.uniform(0, 60, 2000), rng.uniform(0, 10, 2000)])
    pts = np.vstack([top, bottom, sides])
    gagekit.write_points(plate, pts)
    studio = Studio(str(plate), str(tmp_path / "plate.toml"))
    try:
        page, problems = open_page(browser, studio.url)
        # add a box by mouse: the button, then a click on the scan in the middle of the view
        page.click("#add-box")
        canvas = page.locator("#view canvas").bounding_box()
        page.mouse.click(canvas["x"] + canvas["width"] / 2, canvas["y"] + canvas["height"] / 2)
        page.wait_for_selector("#regions tbody tr[data-name='box1']", timeout=10000)
        picked = page.evaluate("window.__studio.state.doc.region[0].center")
        assert 0 <= picked[0] <= 100 and 0 <= picked[1] <= 60 and -0.5 <= picked[2] <= 10.5
        # place it on the top face by typing numbers
        for field, value in zip(("cx", "cy", "cz", "sx", "sy", "sz"), (50, 30, 10, 80, 40, 2)):
            page.fill(f"#re-{field}", str(value))
        box = Box((50, 30, 10), (80, 40, 2))
        inside = gagekit.select(pts, box)
        page.wait_for_function(f"document.querySelector('#re-count').textContent === '{len(inside):,}'", timeout=10000)
        # make it a gage: material above z = 9.5, checked as placed (no motion free)
        page.click("#gage-add")
        page.select_option(".gage .g-preset", "+z")
        page.fill(".gage .g-pos", "9.5")
        for cb in page.locator("#free input").all():
            cb.uncheck()
        page.click("#run")
        page.wait_for_selector("#results tbody tr", timeout=30000)
        allowance = float(page.inner_text("#results tbody tr td.allow-after"))
        assert allowance == pytest.approx(pts[inside, 2].min() - 9.5, abs=5e-5)
        assert page.inner_text("#results tbody tr td.points") == str(len(inside))
        page.fill("#save-path", "plate.toml")
        page.click("#save")
        page.wait_for_function("document.querySelector('#save-status').textContent.startsWith('saved')", timeout=10000)
        assert (tmp_path / "plate.toml").read_text() == EXPECTED.read_text()
        # the file reads as gage check reads it, with the same allowance
        res = gagekit.check_gages(pts, tmp_path / "plate.toml")
        assert res.gages[0].allowance_after == pytest.approx(allowance, abs=5e-5)
        shot = tmp_path / "plate.png"
        page.screenshot(path=str(shot))
        not_blank(shot)
        assert problems == [] and page.evaluate("window.__studio.errors") == []
    finally:
        studio.stop()


def test_casting_opens_runs_and_saves_byte_identical(browser, tmp_path):
    spec = tmp_path / "casting_ok.toml"
    shutil.copy(data_path("casting_ok.toml"), spec)
    original = spec.read_bytes()
    studio = Studio(str(data_path("casting_ok.ply")), str(spec))
    try:
        page, problems = open_page(browser, studio.url)
        assert page.locator("#regions tbody tr").count() == 13
        page.click("#regions tbody tr[data-name='flange_top']")
        page.wait_for_function("document.querySelector('#re-count').textContent === '3,084'", timeout=10000)
        page.click("#run")
        page.wait_for_selector("#results tbody tr", timeout=30000)
        assert page.locator("#results tbody tr").count() == 8
        assert page.inner_text("#run-status").startswith("conforming")
        page.check("#apply-t")
        page.click("#save")
        page.wait_for_function("document.querySelector('#save-status').textContent.startsWith('saved')", timeout=10000)
        assert "unchanged" in page.inner_text("#save-status")
        assert spec.read_bytes() == original
        shot = tmp_path / "casting.png"
        page.screenshot(path=str(shot))
        not_blank(shot)
        # a spec error shows next to its table
        page.fill("#re-sx", "-3")
        page.wait_for_function("document.querySelector('.errors[data-table=region]').textContent.includes('size')",
                               timeout=10000)
        assert problems == [] and page.evaluate("window.__studio.errors") == []
    finally:
        studio.stop()


def test_drawing_features_tolerances_inspection_and_save(browser, tmp_path):
    """A drawing (PART.toml): the bracket's features as regions, the inspection run on the
    server (its table equals gagekit.inspect), a new feature added by mouse with a flatness
    tolerance typed in, run again, saved: the file is the original with only additions,
    and `gagekit inspect` reads it."""
    import difflib

    from gagekit.inspect import inspect, load_part_spec

    scan, part = tmp_path / "bracket.ply", tmp_path / "bracket.toml"
    shutil.copy(data_path("bracket.ply"), scan)
    shutil.copy(data_path("bracket.toml"), part)
    original = part.read_text()
    pts = gagekit.read_points(scan)
    studio = Studio(str(scan), str(part))
    try:
        page, problems = open_page(browser, studio.url)
        assert page.locator("#regions tbody tr").count() == 11
        assert page.inner_text("#run-title") == "Inspection"
        page.click("#run")
        page.wait_for_selector("#callouts tbody tr", timeout=60000)
        want = inspect(pts, load_part_spec(part))
        rows = page.locator("#callouts tbody tr")
        assert rows.count() == len(want.tolerances) == 20
        bore = page.locator("#callouts tbody tr[data-feature='bore'][data-characteristic='position'] td.measured")
        pos = next(t for t in want.tolerances if t.feature == "bore" and t.characteristic == "position")
        assert float(bore.inner_text()) == pytest.approx(pos.measured, abs=5e-5)
        assert page.inner_text("#run-status").startswith("nonconforming: 18/20 callouts pass")
        assert not page.locator("#legend").is_hidden()
        # unchanged: saved byte for byte
        page.click("#save")
        page.wait_for_function("document.querySelector('#save-status').textContent.includes('unchanged')", timeout=10000)
        assert part.read_text() == original

        # a new feature, added by mouse, placed on the top face by typing numbers
        page.click("#add-box")
        canvas = page.locator("#view canvas").bounding_box()
        page.mouse.click(canvas["x"] + canvas["width"] / 2, canvas["y"] + canvas["height"] / 2)
        page.wait_for_selector("#regions tbody tr[data-name='F1']", timeout=10000)
        for field, value in zip(("cx", "cy", "cz", "sx", "sy", "sz"), (50, 40, 40, 20, 20, 1)):
            page.fill(f"#re-{field}", str(value))
        inside = gagekit.select(pts, Box((50, 40, 40), (20, 20, 1)))
        page.wait_for_function(f"document.querySelector('#re-count').textContent === '{len(inside):,}'", timeout=10000)
        assert page.input_value("#fe-shape") == "plane" and page.input_value("#fe-oz") == "1"
        page.click("#tol-add")
        page.select_option("#tolerances .tol .t-char", "flatness")
        page.fill("#tolerances .tol .t-tol", "0.05")
        page.click("#run")
        page.wait_for_function("document.querySelectorAll('#callouts tbody tr').length === 21", timeout=60000)
        flat = page.locator("#callouts tbody tr[data-feature='F1'] td.measured")
        page.fill("#save-path", "edited.toml")
        page.click("#save")
        page.wait_for_function("document.querySelector('#save-status').textContent.startsWith('saved edited.toml')",
                               timeout=10000)
        text = (tmp_path / "edited.toml").read_text()
        ops = difflib.SequenceMatcher(None, original.splitlines(), text.splitlines()).get_opcodes()
        assert {op for op, *_ in ops} == {"equal", "insert"}            # the original's lines all kept as they were
        spec = load_part_spec(tmp_path / "edited.toml")
        assert spec.features["F1"].region.center == (50.0, 40.0, 40.0) and spec.features["F1"].shape == "plane"
        result = inspect(pts, spec)
        f1 = next(t for t in result.tolerances if t.feature == "F1")
        assert f1.characteristic == "flatness" and f1.tolerance == 0.05
        assert float(flat.inner_text()) == pytest.approx(f1.measured, abs=5e-5)
        shot = tmp_path / "bracket.png"
        page.screenshot(path=str(shot))
        not_blank(shot)
        assert problems == [] and page.evaluate("window.__studio.errors") == []
    finally:
        studio.stop()


def test_part_mode_fits_the_callout_table_and_hides_apply_t(browser, tmp_path):
    """In part mode the callout table (7 columns, feature and characteristic names) fits the
    480-px panel without a horizontal scroll; "apply T*" belongs to gages only."""
    scan, part = tmp_path / "bracket.ply", tmp_path / "bracket.toml"
    shutil.copy(data_path("bracket.ply"), scan)
    shutil.copy(data_path("bracket.toml"), part)
    studio = Studio(str(scan), str(part))
    try:
        page, problems = open_page(browser, studio.url)
        assert not page.is_visible("#apply-t") and not page.is_visible("label:has(#apply-t)")
        page.click("#run")
        page.wait_for_selector("#callouts tbody tr", timeout=60000)
        fit = page.evaluate("""() => {
            const panel = document.querySelector('#panel'), table = document.querySelector('#callouts');
            const p = panel.getBoundingClientRect(), t = table.getBoundingClientRect();
            const pad = parseFloat(getComputedStyle(panel).paddingRight);
            return {panelScroll: panel.scrollWidth, panelClient: panel.clientWidth,
                    tableRight: t.right, panelInner: p.right - pad, tableScroll: table.scrollWidth, tableClient: table.clientWidth};
        }""")
        assert fit["panelScroll"] <= fit["panelClient"], fit
        assert fit["tableRight"] <= fit["panelInner"] + 0.5 and fit["tableScroll"] <= fit["tableClient"], fit
        assert not page.is_visible("label:has(#apply-t)")
        assert problems == [] and page.evaluate("window.__studio.errors") == []
    finally:
        studio.stop()
    studio = Studio(str(data_path("casting_ok.ply")))
    try:
        page, problems = open_page(browser, studio.url)
        assert page.is_visible("label:has(#apply-t)")   # a gage file: shown
    finally:
        studio.stop()


def test_cad_model_beside_the_scan_coloured_after_run(browser, tmp_path):
    """Part mode with `[part] cad`: the CAD model is drawn beside the scan as a three.js mesh
    (the server's triangles), grey until Run; after Run each vertex carries the colour the
    server computed (the colouring of `gagekit compare --report`), with its legend."""
    import base64

    from gagekit.cad import read_cad

    scan, part, obj = tmp_path / "bracket.ply", tmp_path / "part.toml", tmp_path / "bracket.obj"
    shutil.copy(data_path("bracket.ply"), scan)
    shutil.copy(data_path("bracket.obj"), obj)
    part.write_text(data_path("bracket_cad.toml").read_text().replace('cad = "bracket.step"', 'cad = "bracket.obj"'))
    model = read_cad(obj)
    studio = Studio(str(scan), str(part))
    try:
        page, problems = open_page(browser, studio.url)
        page.wait_for_function("window.__studio.cadSettled", timeout=60000)
        drawn = page.evaluate("""() => { const m = window.__studio.view.cad;
            return {v: m.geometry.getAttribute('position').count, t: m.geometry.index.count / 3, visible: m.visible,
                    grey: Array.from(m.geometry.getAttribute('color').array.slice(0, 6))}; }""")
        assert drawn == {"v": len(model.vertices), "t": len(model.triangles), "visible": True, "grey": [185] * 6}
        assert page.input_value("#cad-file") == "bracket.obj"
        assert page.is_hidden("#cad-legend")
        # the mesh is drawn: the view with the model differs from the view without it
        shown, hidden = tmp_path / "cad.png", tmp_path / "nocad.png"
        page.screenshot(path=str(shown))
        not_blank(shown)
        page.uncheck("#cad-show")
        page.evaluate("window.__studio.view.render()")
        page.screenshot(path=str(hidden))
        from PIL import Image

        a = np.asarray(Image.open(shown).convert("RGB")).astype(float)[:, :-490]
        b = np.asarray(Image.open(hidden).convert("RGB")).astype(float)[:, :-490]
        assert (np.abs(a - b).sum(axis=2) > 30).mean() > 0.05, "showing the CAD model changes little of the view"
        page.check("#cad-show")
        page.click("#run")
        page.wait_for_function("window.__studio.cad && window.__studio.cad.coloured", timeout=120000)
        assert not page.is_hidden("#cad-legend")
        lim = page.evaluate("window.__studio.cad.limit")
        assert page.inner_text("#cad-legend-max") == f"{lim:.3f}"
        colours = page.evaluate("Array.from(window.__studio.view.cad.geometry.getAttribute('color').array)")
        want = base64.b64decode(page.evaluate("window.__studio.state.run.cad.colours"))
        assert bytes(colours) == want and len(want) == 3 * len(model.vertices)
        rgb = np.frombuffer(want, np.uint8).reshape(-1, 3)
        assert (rgb != 200).any(axis=1).sum() > 1000          # coloured where the scan is, grey elsewhere
        coloured = tmp_path / "coloured.png"
        page.screenshot(path=str(coloured))
        not_blank(coloured)
        assert problems == [] and page.evaluate("window.__studio.errors") == []
    finally:
        studio.stop()
