"""`gagekit demo`: every step runs on the bundled data and the report shows them all."""

import json
import subprocess
import sys

import pytest

import browser

SECTIONS = ["Point cloud", "Machine calibration", "Optimal error observer", "Thermal error tracking",
            "Virtual gages on two castings", "casting_ok: virtual gage result", "casting_short: virtual gage result",
            "Form of cylinders", "inspection of a bracket (ISO 1101, ISO 5459)", "Inspection of the bracket",
            "Deviation from the CAD model"]


@pytest.fixture(scope="module")
def demo_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    proc = subprocess.run([sys.executable, "-m", "gagekit", "demo", "--quick", "--out", str(out), "--json"],
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    summary = json.loads(proc.stdout)  # --json: nothing else on stdout
    assert [s["name"] for s in summary["steps"]] == ["cloud", "machine", "observer", "tracking", "castings", "cylinders", "inspection", "cad"]
    return out


def test_report_has_every_section_and_step_json(demo_dir):
    html = (demo_dir / "report.html").read_text()
    for title in SECTIONS:
        assert title in html, title
    castings = json.loads((demo_dir / "castings.json").read_text())
    assert castings["casting_ok"]["status"] == "conforming"
    assert castings["casting_short"]["status"] == "nonconforming"
    cyl = json.loads((demo_dir / "cylinders.json").read_text())
    assert {f["criterion"] for f in cyl["set3"]} == {"least-squares", "min-circumscribed", "max-inscribed", "minimum-zone"}
    insp = json.loads((demo_dir / "inspection.json").read_text())
    assert insp["status"] == "nonconforming" and insp["max_abs_difference_from_expected"] < 1e-9
    cad = json.loads((demo_dir / "cad.json").read_text())
    assert cad["n_beyond"] == 0 and {f["name"] for f in cad["faces"] if f["n"]} >= {"A", "top", "bore", "ball"}
    machine = json.loads((demo_dir / "machine.json").read_text())
    assert set(machine["calibrations"]) == {"joint", "two-step"}


@pytest.mark.skipif(browser.chromium() is None, reason="Chromium is not installed (Debian package 'chromium'); .ci/run installs it")
def test_demo_report_renders_in_chromium(demo_dir):
    found = browser.inspect(demo_dir / "report.html", demo_dir / "screenshot.png")
    assert found["errors"] == [] and found["console"] == []
    assert len(found["images"]) >= 8 and all(i["w"] > 0 for i in found["images"]), found["images"]
    assert (demo_dir / "screenshot.png").stat().st_size > 10_000


def test_readme_first_command_in_a_fresh_venv(tmp_path):
    """`pip install . && gagekit demo` in a new virtual environment (no system packages):
    the declared dependencies alone are enough to produce the full report."""
    import os
    import shutil
    import venv
    from pathlib import Path

    ROOT = Path(__file__).resolve().parents[2]  # the checkout (not `from conftest`: tests/qif has a conftest too)

    env_dir = tmp_path / "venv"
    venv.EnvBuilder(with_pip=True).create(env_dir)
    bindir = env_dir / ("Scripts" if os.name == "nt" else "bin")
    # copy the checkout (without its build artefacts) so the test never writes into it
    src = tmp_path / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns("target", ".git", "__pycache__", "*.so", ".pytest_cache", ".hypothesis"))
    env = {**os.environ, "CARGO_TARGET_DIR": str(ROOT / "target"), "PATH": f"{bindir}{os.pathsep}{os.environ['PATH']}"}
    env.pop("PYTHONPATH", None)
    out = tmp_path / "demo"
    cmd = f"pip install -q . && gagekit demo --quick --quiet --out {out}"
    proc = subprocess.run(["bash", "-c", cmd], cwd=src, env=env, capture_output=True, text=True, timeout=1500)
    assert proc.returncode == 0, proc.stderr[-3000:]
    html = Path(out / "report.html").read_text()
    for title in SECTIONS:
        assert title in html, title
