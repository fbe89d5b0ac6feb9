"""`gagekit machine ...` end to end: check, simulate, identify, predict, compensate."""

import json
import subprocess
import sys

import pytest


from conftest import EXAMPLE_MACHINE

EXAMPLE = EXAMPLE_MACHINE


def gk(*args, ok=True):
    proc = subprocess.run([sys.executable, "-m", "gagekit", "machine", *map(str, args)], capture_output=True, text=True, timeout=300)
    if ok:
        assert proc.returncode == 0, proc.stderr
    return proc


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("machine")
    gk("simulate", EXAMPLE, "--points", 290, "--seed", 1, "--out", d / "obs.csv", "--truth", d / "truth.json")
    gk("simulate", EXAMPLE, "--points", 50, "--seed", 2, "--params", d / "truth.json", "--out", d / "test.csv")
    return d


def test_check_json(tmp_path):
    d = json.loads(gk("check", EXAMPLE, "--json").stdout)
    assert d["n_parameters"] == 52 and d["rank"] == 32
    assert sorted(d["no_effect"]) == ["T4.alpha", "T5.alpha", "W.dalpha"]
    assert len(d["groups"]) == 32 and d["chain"][0] == "B"


def test_identify_json_has_the_issue_keys(files):
    out = gk("identify", EXAMPLE, files / "obs.csv", "--test", files / "test.csv", "--json", "--out", files / "cal.json").stdout
    d = json.loads(out)
    for key in ("rank", "condition_number", "groups", "unidentifiable", "frame", "residuals", "test"):
        assert key in d
    g = d["groups"][0]
    assert set(g) >= {"name", "terms", "value", "std"}
    assert set(d["frame"]) == {"rotation", "translation"}
    r = d["residuals"]
    assert set(r) >= {"nominal", "model", "decrease_mean_pct", "decrease_max_pct"}
    assert set(r["nominal"]) == {"mean", "max"} and set(r["model"]) == {"mean", "max"}
    assert set(d["test"]["residuals"]["model"]) == {"mean", "max"}
    assert d["rank"] == 32 and d["method"] == "joint"
    assert json.loads((files / "cal.json").read_text())["groups"] == d["groups"]
    two = json.loads(gk("identify", EXAMPLE, files / "obs.csv", "--method", "two-step", "--json").stdout)
    assert two["residuals"]["model"]["mean"] > d["residuals"]["model"]["mean"]


def test_identify_human_table(files):
    out = gk("identify", EXAMPLE, files / "obs.csv", "--test", files / "test.csv", "--residuals", files / "res.csv").stdout
    res = (files / "res.csv").read_text().splitlines()
    assert res[0] == "test,B,X,Z,Y,W,nx,ny,nz,nominal,mx,my,mz,model" and len(res) == 1 + 290 + 50
    assert "T1.dx + T2.dx + T3.dx + 450*T4.beta + T4.dx - 312.035*T5.beta + T5.dx" in out
    assert "% decrease" in out and "test set (50 points)" in out


def test_predict_and_compensate(files):
    gk("identify", EXAMPLE, files / "obs.csv", "--out", files / "cal2.json")
    gk("predict", EXAMPLE, files / "cal2.json", files / "test.csv", "--out", files / "err.csv")
    lines = (files / "err.csv").read_text().splitlines()
    assert lines[0] == "B,X,Z,Y,W,ex,ey,ez,ux,uy,uz" and len(lines) == 51
    d = json.loads(gk("compensate", EXAMPLE, files / "cal2.json", files / "test.csv", "--out", files / "comp.csv", "--json").stdout)
    assert d["points"] == 50 and d["remaining_max"] < 1e-9


def test_errors_are_one_line_exit_2(files, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(EXAMPLE.read_text().replace('"B", "T1"', '"B", "Q", "T1"'))
    p = gk("check", bad, ok=False)
    assert p.returncode == 2 and p.stdout == ""
    assert p.stderr.strip().endswith("chain: unknown element 'Q' (define it as [joints.Q] or [shapes.Q])")
    assert len(p.stderr.strip().splitlines()) == 1
    text = (files / "obs.csv").read_text().splitlines()
    (tmp_path / "few.csv").write_text("\n".join(text[:11]) + "\n")
    p = gk("identify", EXAMPLE, tmp_path / "few.csv", ok=False)
    assert p.returncode == 2 and "10 observations are fewer than the 32 identifiable groups" in p.stderr
    (tmp_path / "cols.csv").write_text(text[0].replace(",W,", ",V,") + "\n" + "\n".join(text[1:]) + "\n")
    p = gk("identify", EXAMPLE, tmp_path / "cols.csv", ok=False)
    assert p.returncode == 2 and "missing column(s) W" in p.stderr


def test_out_of_range_warns_on_stderr(files, tmp_path):
    text = (files / "obs.csv").read_text().splitlines()
    row = text[1].split(",")
    row[1] = "1300.0"  # X beyond +1250
    (tmp_path / "r.csv").write_text("\n".join([text[0], ",".join(row)] + text[2:]) + "\n")
    p = gk("identify", EXAMPLE, tmp_path / "r.csv", "--json")
    assert "warning: " in p.stderr and "(X: 1)" in p.stderr
    json.loads(p.stdout)


def test_simulate_cycles_accepts_plan_as_its_help_says(tmp_path):
    """`simulate-cycles` is short for `simulate --plan PLAN.csv --cycles N` and takes --plan too
    (issue 22 section 6); the plan given twice, or not at all, is one error line."""
    plan = tmp_path / "plan.csv"
    plan.write_text("B,X,Z,Y,W\n0,-1000,1000,400,-500\n90,0,1500,1000,-500\n180,500,2000,2000,-300\n"
                    "270,1200,950,2400,-700\n45,-500,1200,800,-400\n")
    a = gk("simulate-cycles", EXAMPLE, "--plan", plan, "--cycles", 2, "--out", tmp_path / "a.csv")
    b = gk("simulate-cycles", EXAMPLE, plan, "--cycles", 2, "--out", tmp_path / "b.csv")
    c = gk("simulate", EXAMPLE, "--plan", plan, "--cycles", 2, "--out", tmp_path / "c.csv")
    assert a.returncode == b.returncode == c.returncode == 0, a.stderr + b.stderr + c.stderr
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes() == (tmp_path / "c.csv").read_bytes()
    for args in ((plan, "--plan", plan), ()):
        p = gk("simulate-cycles", EXAMPLE, *args, "--out", tmp_path / "d.csv", ok=False)
        assert p.returncode == 2 and p.stderr.count("\n") == 1 and "give the plan once" in p.stderr, p.stderr
