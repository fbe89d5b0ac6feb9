"""A scan holds more than the part (issue 22 section 4): the material side of each datum of
the 3-2-1 alignment comes from the datums' own points, never from the whole cloud, so the
bundled castings with far clutter added (a fixture, the machine table, a second part) give
bit-identical `gage check --json` results, and `cloud regions` cuts the part-frame regions
after the same alignment (the same counts as `gage check`)."""

import json
import subprocess
import sys

import numpy as np
import pytest

import gagekit
from gagekit.samples import data_path


def gk(*args):
    p = subprocess.run([sys.executable, "-m", "gagekit", *map(str, args)], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


@pytest.fixture(scope="module")
def clean():
    return {name: gk("gage", "check", data_path(f"{name}.ply"), data_path(f"{name}.toml"), "--json")
            for name in ("casting_ok", "casting_short")}


def _cluttered(tmp_path, name, n, distance, direction, seed=0):
    """The casting scan with ``n`` points in a 1 m cube ``distance`` mm from its bounding-box
    centre along ``direction`` (scanner frame)."""
    pts = gagekit.read_points(data_path(f"{name}.ply"))
    centre = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
    rng = np.random.default_rng(seed)
    junk = centre + distance * np.asarray(direction, float) + rng.uniform(-500, 500, (n, 3))
    out = tmp_path / f"{name}_clutter.ply"
    gagekit.write_points(out, np.vstack([pts, junk]))
    return out


@pytest.mark.parametrize("name", ["casting_ok", "casting_short"])
@pytest.mark.parametrize("n, distance, direction", [
    (1_000, 50_000.0, (-1, 0, 0)),
    (1_000, 50_000.0, (0, -1, 0)),
    (1_000, 50_000.0, (0, 0, -1)),
    (1_000, 50_000.0, (1, 1, 1)),
    (100_000, 5_000.0, (-1, 0, 0)),
])
def test_far_clutter_changes_nothing(clean, tmp_path, name, n, distance, direction):
    scan = _cluttered(tmp_path, name, n, distance, direction)
    got = gk("gage", "check", scan, data_path(f"{name}.toml"), "--json")
    assert got == clean[name]  # bit-identical: every float, every count


@pytest.mark.parametrize("clutter", [False, True])
def test_cloud_regions_applies_the_alignment_of_gage_check(clean, tmp_path, clutter):
    name = "casting_ok"
    scan = _cluttered(tmp_path, name, 100_000, 5_000.0, (-1, 0, 0)) if clutter else data_path(f"{name}.ply")
    regions = {r["name"]: r for r in gk("cloud", "regions", scan, data_path(f"{name}.toml"), "--json")["regions"]}
    check = clean[name]
    for g in check["gages"]:  # part-frame regions: the gage's counts
        assert (regions[g["region"]]["points"], regions[g["region"]]["hull_vertices"]) == (g["points"], g["filtered_points"])
    for datum in ("primary", "secondary", "tertiary"):  # scanner-frame datum regions
        d = check["alignment"][datum]
        assert sum(regions[r]["points"] for r in d["regions"]) == d["points"]
