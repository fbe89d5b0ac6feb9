"""`gagekit inspect SCAN PART.toml [--units U] [--json] [--report DIR]`."""

import json
import subprocess
import sys

import numpy as np
import pytest

import browser
import gagekit
from gagekit.samples import data_path

PLY, TOML = str(data_path("bracket.ply")), str(data_path("bracket.toml"))


def run(*args):
    return subprocess.run([sys.executable, "-m", "gagekit", *args], capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def report_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("inspect")
    proc = run("inspect", PLY, TOML, "--json", "--report", str(out))
    assert proc.returncode == 0, proc.stderr  # a nonconforming part is a result, not an error
    return out, json.loads(proc.stdout)


def test_json_and_exit_status(report_dir):
    out, d = report_dir
    assert d["status"] == "nonconforming"
    assert [t["pass"] for t in d["tolerances"]].count(False) == 2
    assert json.loads((out / "result.json").read_text()) == d


def test_human_output():
    proc = run("inspect", PLY, TOML)
    assert proc.returncode == 0
    assert "FAIL" in proc.stdout and "bracket: nonconforming (18/20 callouts pass)" in proc.stdout


def test_units_convert_the_scan(tmp_path):
    pts = gagekit.read_points(PLY)
    f = tmp_path / "bracket_m.csv"
    gagekit.write_points(f, pts / 1000.0)
    a = json.loads(run("inspect", PLY, TOML, "--json").stdout)
    b = json.loads(run("inspect", str(f), TOML, "--units", "m", "--json").stdout)
    for x, y in zip(a["tolerances"], b["tolerances"]):
        assert y["measured"] == pytest.approx(x["measured"], abs=1e-9)


@pytest.mark.parametrize("edit, words", [
    (lambda s: s.replace('characteristic = "cylindricity"', 'characteristic = "roundnes"', 1), "'characteristic'"),
    (lambda s: s.replace('outward = [0, 0, -1]', 'outward = [0, 0, 0]', 1), "'outward' has zero length"),
    (lambda s: s + "\n[[tolerance]]\nfeature = \"A\"\ncharacteristic = \"roundness\"\ntolerance = 0.1\n", "does not apply to a plane"),
])
def test_errors_are_one_line_exit_2(tmp_path, edit, words):
    bad = tmp_path / "bad.toml"
    bad.write_text(edit(open(TOML).read()))
    proc = run("inspect", PLY, str(bad))
    assert proc.returncode == 2 and proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gagekit: error: ") and words in lines[0], proc.stderr


def test_missing_scan_is_exit_2(tmp_path):
    proc = run("inspect", str(tmp_path / "none.ply"), TOML)
    assert proc.returncode == 2 and proc.stderr.startswith("gagekit: error: ")


def test_report_page_is_self_contained(report_dir):
    out, _ = report_dir
    html = (out / "report.html").read_text()
    assert "<script src=" not in html and "<link" not in html  # plotly.js is embedded
    assert 'data-library="plotly"' in html and "Plotly.newPlot" in html
    assert html.count('data-result="FAIL"') == 2 and html.count('data-result="PASS"') == 18


@pytest.mark.skipif(browser.chromium() is None, reason="Chromium is not installed (Debian package 'chromium')")
def test_report_renders_in_chromium(report_dir):
    out, _ = report_dir
    page = out / "report.html"
    # the probe reports errors; it also counts the plotly canvases / SVG the 3-D view made
    found = browser.inspect(page, out / "shot.png")
    assert found["errors"] == [] and found["console"] == []
    assert (out / "shot.png").stat().st_size > 20_000
    # plotly drew the 3-D view into its div (scene, colour bar, legend with the frame axes)
    dom = browser._run(browser.chromium(), "--virtual-time-budget=10000", "--dump-dom", page.as_uri()).stdout
    assert 'class="plot-container plotly"' in dom and "gl-container" in dom
    assert "datum frame x" in dom and "deviation (um)" in dom


def test_inspect_scan_is_the_default_subcommand_with_options_anywhere(tmp_path):
    """`gagekit inspect SCAN PART`, `gagekit inspect --json SCAN PART` and
    `gagekit inspect scan SCAN PART` are one command (`inspect batch` sits beside it)."""
    import json
    import subprocess
    import sys

    from gagekit.samples import data_path

    scan, part = str(data_path("bracket.ply")), str(data_path("bracket.toml"))
    outs = []
    for args in ([scan, part, "--json"], ["--json", scan, part], ["scan", scan, part, "--json"]):
        p = subprocess.run([sys.executable, "-m", "gagekit", "inspect", *args], capture_output=True, text=True, timeout=300)
        assert p.returncode == 0, p.stderr
        d = json.loads(p.stdout)
        d.pop("seconds")
        outs.append(d)
    assert outs[0] == outs[1] == outs[2] and outs[0]["part"] == "bracket"


def test_scan_and_drawing_swapped_say_so():
    """`inspect PART.toml SCAN.ply`: the binary scan where the drawing's TOML was expected is
    named as such, with the hint to check the order (it said only 'not UTF-8 text')."""
    proc = run("inspect", TOML, PLY)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.strip() == (f"gagekit: error: {PLY}: a binary .ply file where a text TOML file was expected "
                                   "(check the order of the arguments)")
