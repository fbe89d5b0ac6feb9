"""End-to-end tests of the `gagekit` console script."""

import subprocess
import sys

import gagekit


def run(*args, check=True):
    proc = subprocess.run(
        [sys.executable, "-m", "gagekit", *args], capture_output=True, text=True, timeout=600
    )
    if check:
        assert proc.returncode == 0, proc.stderr
    return proc


def test_version():
    assert run("--version").stdout.strip() == f"gagekit {gagekit.__version__}"


def test_help_lists_the_groups():
    out = run("--help").stdout
    for group in ("cloud", "form", "gage", "machine", "demo"):
        assert group in out


def test_cloud_info_json(tmp_path):
    import json

    import numpy as np

    f = tmp_path / "c.csv"
    gagekit.write_points(f, np.array([[0.0, 0, 0], [1, 2, 3], [-1, 5, 2]]))
    out = json.loads(run("cloud", "info", str(f), "--json").stdout)
    assert out["count"] == 3 and out["min"] == [-1, 0, 0] and out["max"] == [1, 5, 3]
    human = run("cloud", "info", str(f)).stdout
    assert "3 points" in human


def test_errors_are_one_line_on_stderr(tmp_path):
    f = tmp_path / "bad.xyz"
    f.write_text("1 2 3\n4 5\n")
    proc = run("cloud", "info", str(f), "--json", check=False)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.startswith("gagekit: error:") and "line 2" in proc.stderr


def test_cloud_hull_and_regions(tmp_path):
    import json

    import numpy as np

    rng = np.random.default_rng(3)
    pts = np.vstack([rng.uniform(-1, 1, size=(2000, 3)), [[5, 0, 0]]])
    f = tmp_path / "c.npy"
    np.save(f, pts)
    out = tmp_path / "hull.csv"
    res = json.loads(run("cloud", "hull", str(f), "--out", str(out), "--json").stdout)
    assert res["count"] == 2001 and 2000 in res["indices"]
    np.testing.assert_array_equal(gagekit.read_points(out), pts[res["indices"]])
    regions = tmp_path / "r.toml"
    regions.write_text('[[region]]\nname = "left"\ncenter = [-0.5, 0, 0]\nsize = [1, 2, 2]\n[[region]]\nname = "far"\ncenter = [5, 0, 0]\nsize = [0.1, 0.1, 0.1]\n')
    res = json.loads(run("cloud", "regions", str(f), str(regions), "--json").stdout)
    names = {r["name"]: r for r in res["regions"]}
    assert names["far"]["points"] == 1 and names["far"]["hull_vertices"] == 1
    assert 0 < names["left"]["hull_vertices"] < names["left"]["points"]
