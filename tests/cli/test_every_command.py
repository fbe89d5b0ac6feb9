"""Every command of the `gagekit` CLI once, with its human (non-JSON) output, on the bundled
data (issue 12, item 1: `cloud regions` crashed on every input without --json and no test ran
its human output). A command added without a recipe here fails `test_every_command_has_a_recipe`."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import typer

import gagekit
from gagekit.cli import app
from gagekit.samples import data_path

ROOT = Path(__file__).resolve().parents[2]
M = gagekit.machine.example_machine_path()
PLY, TOML = data_path("casting_ok.ply"), data_path("casting_ok.toml")
CIRCLE = ROOT / "tests" / "data" / "nist-l2" / "circle2d" / "cir2d1.ds"
PLANE = next((ROOT / "tests" / "data" / "nist-l2" / "plane").glob("*.ds"))
CYL = data_path("cylinders") / "set1.csv"

#: command path -> arguments (T: the per-module temporary folder); run in this order
RECIPES: dict[str, list] = {
    "cloud info": [PLY],
    "cloud hull": [PLY, "--out", "T/hull.ply"],
    "cloud regions": [PLY, TOML],
    "form circle": [CIRCLE],
    "form fit": ["plane", PLANE],
    "form cylinder": [CYL],
    "form roundness": [data_path("roundness_profile.csv"), "--filter", "gaussian", "--upr", 50, "--report", "T/roundness"],
    "form straightness": [data_path("straightness_profile.csv"), "--filter", "gaussian", "--cutoff", 2.5],
    "form flatness": [PLANE, "--reference", "MZPL"],
    "gage check": [PLY, TOML, "--no-groups"],
    "machine check": [M],
    "machine simulate": [M, "--points", 120, "--out", "T/obs.csv", "--truth", "T/truth.json"],
    "machine identify": [M, "T/obs.csv", "--out", "T/cal.json", "--residuals", "T/res.csv"],
    "machine predict": [M, "T/cal.json", "T/obs.csv", "--out", "T/pred.csv"],
    "machine compensate": [M, "T/cal.json", "T/obs.csv", "--out", "T/comp.csv"],
    "machine compensate-nc": [M, "T/cal.json", "T/prog.nc", "--out", "T/prog-comp.nc"],
    "machine export": [M, "T/cal.json", "--format", "grid-csv", "--out", "T/grid.csv"],
    "machine iso230-2": [data_path("ecmc_axis1_runs.csv")],
    "data list": [],
    "data path": ["round"],
    "machine ballbar": [ROOT / "tests" / "data" / "ballbar" / "simulated_xy.csv", "--plane", "XY", "--radius", 150, "--feed", 1000],
    "machine design": [M, "--points", 60, "--candidates", 2000, "--out", "T/plan.csv"],
    "machine evaluate-plan": [M, "T/plan.csv", "--seeds", 2, "--test-points", 200],
    "machine simulate-cycles": [M, "T/plan.csv", "--cycles", 3, "--out", "T/cyc.csv"],
    "machine track": [M, "T/cyc.csv", "--history", "T/h.sqlite", "--report", "T/track"],
    "machine history": ["T/h.sqlite"],
    "gage batch": [TOML, PLY, "--workers", 1, "--db", "sqlite:///T/batch.db"],
    "form batch": ["circle", CIRCLE, "-c", "least-squares", "--workers", 1, "--db", "sqlite:///T/batch.db"],
    "inspect batch": [data_path("bracket.toml"), data_path("bracket.ply"), "--workers", 1, "--db", "sqlite:///T/batch.db"],
    "db upgrade": ["sqlite:///T/batch.db"],
    "db export": ["sqlite:///T/batch.db", "--format", "csv", "--out", "T/export"],
    "stats": ["--db", "sqlite:///T/batch.db"],
    "stats grr": ["--csv", ROOT / "tests" / "data" / "grr" / "aiag_msa4.csv", "--tolerance", 6],
    "inspect scan": [data_path("bracket.ply"), data_path("bracket.toml")],  # `gagekit inspect SCAN PART` is the same
    "demo": ["--quick", "--out", "T/demo"],
    "compare": [data_path("bracket.ply"), data_path("bracket.step"), "--align", "none", "--deviations", "T/dev.npy"],
    "qif import": [data_path("nist_ctc_01_asme1_ap242.qif.gz"), "--out", "T/ctc01.toml"],
    "schema": ["part", "--out", "T/part.schema.json"],
    "studio": None,  # a web server that runs until stopped: tests/studio runs it
}

PROGRAM = "%\nO1000\nN10 G21 G90 G17\nN20 G0 B0 X-1000 Y400 Z1000 W-500\nN30 G1 X-900 F500\nN40 Y450\nN50 M30\n%\n"


def _leaves(cmd, prefix=()):
    sub = getattr(cmd, "commands", None)
    if not sub:
        yield " ".join(prefix)
        return
    for name, c in sub.items():
        yield from _leaves(c, (*prefix, name))


def test_every_command_has_a_recipe():
    missing = sorted(set(_leaves(typer.main.get_command(app))) - set(RECIPES))
    assert not missing, f"add a recipe to tests/cli/test_every_command.py for: {missing}"


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    d = tmp_path_factory.mktemp("every")
    (d / "prog.nc").write_text(PROGRAM)
    return d


@pytest.mark.parametrize("command", [c for c, r in RECIPES.items() if r is not None])
def test_human_output(command, folder):
    args = [str(a).replace("T/", f"{folder}/", 1) if str(a).startswith(("T/", "sqlite:///T/")) else str(a)
            for a in RECIPES[command]]
    proc = subprocess.run([sys.executable, "-m", "gagekit", *command.split(), *args], capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr and "gagekit: error" not in proc.stderr, proc.stderr
    assert proc.stdout.strip(), f"{command}: no output"
    assert "nan" not in proc.stdout.lower().split(), proc.stdout
