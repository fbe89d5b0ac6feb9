"""The command-line options of issue 26 Sec. 1-2 on inspect, form fit and compare: JSON keys,
the decision rule in every report, one-line errors with exit status 2."""

from __future__ import annotations

import json
import subprocess
import sys
from types import SimpleNamespace

import pytest

from gagekit.samples import data_path

BRACKET, PART = str(data_path("bracket.ply")), str(data_path("bracket.toml"))


def _run(*args):
    p = subprocess.run([sys.executable, "-m", "gagekit", *map(str, args)], capture_output=True, text=True, timeout=600)
    return SimpleNamespace(exit_code=p.returncode, output=p.stdout, stderr=p.stderr)


@pytest.mark.parametrize("args,needle", [
    (["--uncertainty", "5", "--noise", "0.001"], "at least 10"),
    (["--uncertainty", "lots", "--noise", "0.001"], "number of trials"),
    (["--uncertainty", "20", "--noise", "-0.001"], "sigma must be a finite number >= 0"),
    (["--uncertainty", "20", "--noise", "loud"], "--noise"),
    (["--uncertainty", "20"], "--noise SIGMA|auto or --measurement"),
    (["--noise", "0.001"], "--uncertainty"),
    (["--decision-rule", "strict"], "decision rule"),
    (["--decision-rule", "guard-band=-1"], "FRACTION"),
])
def test_bad_uncertainty_options_are_one_line_errors(args, needle):
    r = _run("inspect", BRACKET, PART, *args)
    assert r.exit_code == 2, r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("gagekit: error:") and needle in lines[0], r.stderr
    assert r.output == ""


def test_inspect_states_the_rule_without_an_uncertainty():
    r = _run("inspect", BRACKET, PART, "--json")
    d = json.loads(r.output)
    assert d["decision_rule"]["name"] == "simple" and d["decision"] == "nonconforming"
    assert {t["decision"] for t in d["tolerances"]} == {"conforming", "nonconforming"}
    assert "monte_carlo" not in d and all("uncertainty" not in t for t in d["tolerances"])
    text = _run("inspect", BRACKET, PART, "--decision-rule", "guard-band=0.5").output
    assert "decision rule: guard-band=0.5" in text


def test_form_fit_uncertainty_json(tmp_path):
    m = tmp_path / "scanner.toml"
    m.write_text("[measurement]\nsigma = 0.001\nprobing = 0.002\n")
    r = _run("form", "fit", "circle", data_path("round.csv"), "-c", "lsq", "--uncertainty", "50", "--measurement", m,
             "--seed", "4", "--json")
    assert r.exit_code == 0, r.stderr
    d = json.loads(r.output)
    u = d["uncertainty"]["radius"]
    assert set(u) == {"u", "U", "k", "coverage", "interval", "bias", "method", "trials"}
    assert u["interval"][0] < d["radius"] < u["interval"][1] and u["trials"] == 50
    assert d["monte_carlo"]["model"]["probing"] == 0.002 and "center.x" in d["uncertainty"]
    again = json.loads(_run("form", "fit", "circle", data_path("round.csv"), "-c", "lsq", "--uncertainty", "50",
                            "--measurement", m, "--seed", "4", "--threads", "1", "--json").output)
    assert again["uncertainty"] == d["uncertainty"]


def test_compare_uncertainty_json():
    r = _run("compare", BRACKET, data_path("bracket.obj"), "--align", "none", "--uncertainty", "10", "--noise", "0.002",
             "--json")
    assert r.exit_code == 0, r.stderr
    d = json.loads(r.output)
    u = d["uncertainty"]["deviations.max"]
    assert u["trials"] == 10 and u["U"] > 0 and d["monte_carlo"]["model"]["sigma"] == 0.002
    assert any(k.startswith("faces.") for k in d["uncertainty"])


def test_a_streamed_scan_gets_the_same_uncertainties_as_a_whole_read(tmp_path):
    import sys as _sys
    from pathlib import Path

    import numpy as np

    _sys.path.insert(0, str(Path(__file__).parent))
    from coverage_part import part_toml, scan

    np.save(tmp_path / "scan.npy", scan(np.random.default_rng(2)))
    (tmp_path / "part.toml").write_text(part_toml())
    args = ["inspect", tmp_path / "scan.npy", tmp_path / "part.toml", "--uncertainty", "12", "--noise", "0.005", "--json"]
    whole = json.loads(_run(*args).output)
    streamed = _run(*args, "--chunk-points", "97")
    assert streamed.exit_code == 0, streamed.stderr
    s = json.loads(streamed.output)
    assert [t["uncertainty"] for t in s["tolerances"]] == [t["uncertainty"] for t in whole["tolerances"]]
    assert [t["decision"] for t in s["tolerances"]] == [t["decision"] for t in whole["tolerances"]]
