"""`gagekit gage check` end to end on the bundled castings (issue 4)."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

import gagekit

DATA = Path(gagekit.__file__).parent / "data"


def run(*args):
    return subprocess.run([sys.executable, "-m", "gagekit", "gage", "check", *map(str, args)],
                          capture_output=True, text=True, timeout=300)


def test_json_report_and_corrected_cloud(tmp_path):
    out_cloud = tmp_path / "corrected.ply"
    proc = run(DATA / "casting_short.ply", DATA / "casting_short.toml", "--json", "--report", tmp_path / "rep",
               "--out-cloud", out_cloud)
    assert proc.returncode == 0, proc.stderr
    d = json.loads(proc.stdout)
    assert d["status"] == "nonconforming"
    assert d["infeasible_groups"] == [["outer wall 1", "inner wall 1"]]
    assert d["limited_by_motion_bounds"] is False
    assert len(d["transform"]["matrix"]) == 4
    assert [g["name"] for g in d["gages"] if g["slack"] > 0] == ["outer wall 1", "inner wall 1"]
    rep = tmp_path / "rep"
    for name in ("report.html", "report.txt", "result.json", "region-outer-wall-1.png", "region-flange-top.png"):
        assert (rep / name).stat().st_size > 0, name
    assert (rep / "region-outer-wall-1.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "outer wall 1" in (rep / "report.txt").read_text()
    # the corrected cloud is the scan in the part frame with T* applied: its
    # flange-top points satisfy the band gages exactly as reported
    pts = gagekit.read_points(out_cloud)
    assert len(pts) == len(gagekit.read_points(DATA / "casting_short.ply"))
    top = pts[(np.abs(pts[:, 0] - 50) < 40) & (np.abs(pts[:, 1] - 80) < 12) & (np.abs(pts[:, 2] - 110.4) < 6)]
    g = {x["name"]: x for x in d["gages"]}
    low = top[:, 2].min() - 109.30
    assert g["top of flange min"]["allowance_after"] - 1e-9 <= low < g["top of flange min"]["allowance_after"] + 0.05


def test_human_output_and_errors(tmp_path):
    proc = run(DATA / "casting_ok.ply", DATA / "casting_ok.toml")
    assert proc.returncode == 0, proc.stderr
    assert "status: conforming" in proc.stdout and "allowance after" in proc.stdout
    bad = tmp_path / "bad.toml"
    bad.write_text((DATA / "casting_ok.toml").read_text().replace('region = "tower_top"', 'region = "tower"'))
    proc = run(DATA / "casting_ok.ply", bad)
    assert proc.returncode == 2 and proc.stdout == ""
    assert "gage 'top of tower': unknown region 'tower'" in proc.stderr
    proc = run(tmp_path / "missing.ply", DATA / "casting_ok.toml")
    assert proc.returncode == 2 and "no such file" in proc.stderr
