"""Files that would read as points all at one place are refused (issue 22 section 4): a LAS
header with a scale factor 0 (every coordinate its offset) and an E57 whose every range is 0
(a failed acquisition: 2,651 points at the origin), one line on the command line."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import gagekit
from gagekit.errors import FileFormatError

LAS = Path(__file__).resolve().parents[1] / "data" / "las"


@pytest.mark.parametrize("axis", [0, 2])
def test_las_scale_factor_zero_is_refused(tmp_path, axis):
    pytest.importorskip("laspy")
    b = bytearray((LAS / "simple.las").read_bytes())
    at = 131 + 8 * axis  # x, y, z scale factors: doubles at bytes 131, 139, 147 of the LAS 1.x header
    assert np.frombuffer(bytes(b[at:at + 8]), "<f8")[0] > 0
    b[at:at + 8] = np.float64(0.0).tobytes()
    f = tmp_path / "scale0.las"
    f.write_bytes(bytes(b))
    with pytest.raises(FileFormatError, match=f"{'xyz'[axis]} scale factor is 0"):
        gagekit.read_points(f)
    p = subprocess.run([sys.executable, "-m", "gagekit", "cloud", "info", str(f)], capture_output=True, text=True)
    assert p.returncode == 2 and p.stdout == "" and len(p.stderr.splitlines()) == 1 and "scale factor is 0" in p.stderr


def _zero_range_e57(path, n=2651):
    pye57 = pytest.importorskip("pye57")
    rng = np.random.default_rng(0)
    zero = np.zeros(n)
    w = pye57.E57(str(path), mode="w")
    w.write_scan_raw({"cartesianX": zero, "cartesianY": zero, "cartesianZ": zero, "sphericalRange": zero,
                      "sphericalAzimuth": rng.uniform(-3, 3, n), "sphericalElevation": rng.uniform(-1, 1, n)})
    w.close()


def test_e57_with_every_range_zero_is_refused(tmp_path):
    f = tmp_path / "read_error.e57"
    _zero_range_e57(f)
    with pytest.raises(FileFormatError, match="all 2651 points are at one place"):
        gagekit.read_points(f)
    p = subprocess.run([sys.executable, "-m", "gagekit", "cloud", "info", str(f)], capture_output=True, text=True)
    assert p.returncode == 2 and p.stdout == "" and len(p.stderr.splitlines()) == 1
    assert p.stderr.startswith(f"gagekit: error: {f}: all 2651 points are at one place (0, 0, 0 m; every range 0?)")


def test_a_single_point_e57_is_still_read(tmp_path):
    pye57 = pytest.importorskip("pye57")
    f = tmp_path / "one.e57"
    w = pye57.E57(str(f), mode="w")
    w.write_scan_raw({"cartesianX": np.array([1.0]), "cartesianY": np.array([2.0]), "cartesianZ": np.array([3.0])})
    w.close()
    np.testing.assert_allclose(gagekit.read_points(f), [[1000.0, 2000.0, 3000.0]])
