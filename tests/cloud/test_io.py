"""Point-cloud reading and writing: every format, round trips, and bad files."""

from pathlib import Path

import numpy as np
import pytest

import gagekit
from gagekit.errors import FileFormatError, GagekitError, InvalidInputError

from conftest import NIST as _NIST

NIST = _NIST

RNG = np.random.default_rng(7)
PTS = RNG.normal(scale=100.0, size=(500, 3))


@pytest.mark.parametrize("suffix", [".ply", ".csv", ".xyz", ".txt", ".npy"])
def test_round_trip_is_exact(tmp_path, suffix):
    f = tmp_path / f"cloud{suffix}"
    gagekit.write_points(f, PTS)
    back = gagekit.read_points(f)
    assert back.dtype == np.float64 and back.flags.c_contiguous
    np.testing.assert_array_equal(back, PTS)


def test_ascii_ply_and_float32(tmp_path):
    from plyfile import PlyData, PlyElement

    v = np.empty(3, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("red", "u1")])
    v["x"], v["y"], v["z"], v["red"] = [1.5, 2, 3], [4, 5, 6], [7, 8, 9.25], [1, 2, 3]
    for text in (True, False):
        f = tmp_path / f"v{int(text)}.ply"
        PlyData([PlyElement.describe(v, "vertex")], text=text).write(str(f))
        np.testing.assert_array_equal(gagekit.read_points(f), [[1.5, 4, 7], [2, 5, 8], [3, 6, 9.25]])


def test_ascii_variants(tmp_path):
    f = tmp_path / "scan.txt"
    f.write_text("# scanner export\nX\tY\tZ\tI\n1\t2\t3\t0.1\n\n4\t5\t6\t0.2\n")
    np.testing.assert_array_equal(gagekit.read_points(f), [[1, 2, 3], [4, 5, 6]])
    g = tmp_path / "named.csv"
    g.write_text("id;z;x;y\n7;3;1;2\n")
    np.testing.assert_array_equal(gagekit.read_points(g), [[1, 2, 3]])
    h = tmp_path / "circle.xy"
    h.write_text("1 2\n3 4\n")
    np.testing.assert_array_equal(gagekit.read_points(h, dim=2), [[1, 2], [3, 4]])


def test_nist_ds_matches_count():
    files = sorted(NIST.glob("*/*.ds"))
    assert len(files) > 50
    for f in files:
        pts = gagekit.read_points(f)
        assert len(pts) == int(f.read_text().split()[0])


def test_unknown_extension_is_sniffed(tmp_path):
    f = tmp_path / "cloud.dat"
    gagekit.write_points(tmp_path / "c.ply", PTS)
    f.write_bytes((tmp_path / "c.ply").read_bytes())
    np.testing.assert_array_equal(gagekit.read_points(f), PTS)


@pytest.mark.parametrize(
    "content, message",
    [
        ("", "no points"),
        ("x y z\n", "no points"),
        ("1 2 3\n4 5\n", "line 2"),
        ("1 2 3\n4 oops 6\n", "line 2"),
    ],
)
def test_bad_ascii_names_file_and_line(tmp_path, content, message):
    f = tmp_path / "bad.xyz"
    f.write_text(content)
    with pytest.raises(FileFormatError) as err:
        gagekit.read_points(f)
    assert message in str(err.value) and "bad.xyz" in str(err.value)


def test_nan_is_rejected_with_its_line(tmp_path):
    f = tmp_path / "nan.csv"
    f.write_text("x,y,z\n1,2,3\n4,NaN,6\n")
    with pytest.raises(InvalidInputError, match="line 3"):
        gagekit.read_points(f)
    g = tmp_path / "nan.npy"
    a = PTS.copy()
    a[17, 1] = np.inf
    np.save(g, a)
    with pytest.raises(InvalidInputError, match="point 17"):
        gagekit.read_points(g)


def test_bad_files(tmp_path):
    with pytest.raises(FileFormatError, match="no such file"):
        gagekit.read_points(tmp_path / "missing.ply")
    (tmp_path / "broken.ply").write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 10\n")
    with pytest.raises(FileFormatError, match="broken.ply"):
        gagekit.read_points(tmp_path / "broken.ply")
    (tmp_path / "blob.bin").write_bytes(b"\x00\x01\x02\x03" * 10)
    with pytest.raises(FileFormatError, match="unknown binary format"):
        gagekit.read_points(tmp_path / "blob.bin")
    np.save(tmp_path / "flat.npy", np.zeros(5))
    with pytest.raises(FileFormatError, match=r"\(n, 3\)"):
        gagekit.read_points(tmp_path / "flat.npy")
    ds = tmp_path / "short.ds"
    ds.write_text("5\n1 2 3\n")
    with pytest.raises(FileFormatError, match="announces 5 points"):
        gagekit.read_points(ds)
    with pytest.raises(GagekitError, match="cannot write"):
        gagekit.write_points(tmp_path / "a.stl", PTS)


def test_las_round_trip(tmp_path):
    laspy = pytest.importorskip("laspy")
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales = np.array([1e-4, 1e-4, 1e-4])
    header.offsets = np.array([0.0, 0.0, 0.0])
    las = laspy.LasData(header)
    pts = np.round(PTS, 4)
    las.x, las.y, las.z = pts[:, 0], pts[:, 1], pts[:, 2]
    f = tmp_path / "scan.las"
    las.write(str(f))
    # no CRS in the header: metres (issue 13), so x1000; units= overrides
    np.testing.assert_allclose(gagekit.read_points(f), pts * 1000.0, atol=1e-6)
    np.testing.assert_allclose(gagekit.read_points(f, units="mm"), pts, atol=1e-9)


def test_e57_round_trip(tmp_path):
    pye57 = pytest.importorskip("pye57")
    f = tmp_path / "scan.e57"
    e57 = pye57.E57(str(f), mode="w")
    e57.write_scan_raw({"cartesianX": PTS[:, 0], "cartesianY": PTS[:, 1], "cartesianZ": PTS[:, 2]})
    e57.close()
    # E57 stores metres (ASTM E2807)
    np.testing.assert_allclose(gagekit.read_points(f), PTS * 1000.0, atol=1e-6)


def test_written_binary_ply_is_aligned_and_read_without_a_copy(tmp_path):
    """gagekit's PLY body starts at a multiple of 8 bytes (the header's comment line is
    padded), so reading it back maps the file as the array (issue 13, reading speed)."""
    from gagekit import _core

    for n in (1, 7, 1000, 123457):
        f = tmp_path / f"c{n}.ply"
        pts = np.arange(3.0 * n).reshape(n, 3) + 0.25
        gagekit.write_points(f, pts)
        layout = _core.cloud.ply_layout(str(f))
        assert layout.vertices == n and layout.direct_offset is not None and layout.direct_offset % 8 == 0
        got = gagekit.read_points(f)
        assert np.array_equal(got, pts)
        assert isinstance(got.base, np.memmap) or isinstance(getattr(got.base, "base", None), np.memmap)
        assert f.read_bytes().startswith(b"ply\nformat binary_little_endian 1.0\ncomment gagekit")
