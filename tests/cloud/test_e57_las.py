"""E57 and LAS/LAZ on real public sample files (tests/data/README.md gives their sources
and licences). Expected counts and extents come from a second reader (pye57's raw fields,
laspy, or the LAS header's bytes parsed here), never from gagekit."""

import struct
from pathlib import Path

import numpy as np
import pytest

import gagekit
from gagekit.cli import main
from gagekit.errors import FileFormatError

DATA = Path(__file__).resolve().parents[1] / "data"
E57 = DATA / "e57"
LAS = DATA / "las"


def _pye57_raw(path):
    pye57 = pytest.importorskip("pye57")
    e = pye57.E57(str(path))
    return [e.read_scan_raw(i) for i in range(e.scan_count)]


# E57 ------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["bunnyDouble", "bunnyInt19"])
def test_bunny_is_metres_and_complete(name):
    cloud = gagekit.read_cloud(E57 / f"{name}.e57")
    assert len(cloud.points) == 30571  # libE57 reference data: the Stanford bunny, 30,571 points
    assert (cloud.source_unit, cloud.scale_to_mm, cloud.invalid_dropped) == ("m", 1000.0, 0)
    (raw,) = _pye57_raw(E57 / f"{name}.e57")
    xyz = np.column_stack([raw["cartesianX"], raw["cartesianY"], raw["cartesianZ"]]) * 1000.0
    np.testing.assert_allclose(cloud.points, xyz, rtol=0, atol=1e-9)
    # the bunny is about 156 x 147 x 121 mm, not 0.16 mm
    assert 150 < np.ptp(cloud.points[:, 0]) < 160


def test_scaled_integer_bunny_agrees_with_double_bunny():
    d = gagekit.read_points(E57 / "bunnyDouble.e57")
    i = gagekit.read_points(E57 / "bunnyInt19.e57")
    # 19-bit scaled integers over the bunny's range: resolution well below 1 um
    assert np.abs(d - i).max() < 1e-3


def test_spherical_coordinates_are_converted_and_invalid_dropped():
    (raw,) = _pye57_raw(E57 / "tiny_spherical.e57")
    ok = raw["sphericalInvalidState"] == 0
    r, az, el = (raw[k][ok] for k in ("sphericalRange", "sphericalAzimuth", "sphericalElevation"))
    # ASTM E2807 spherical convention: x = r cos(el) cos(az), y = r cos(el) sin(az), z = r sin(el)
    want = np.column_stack([r * np.cos(el) * np.cos(az), r * np.cos(el) * np.sin(az), r * np.sin(el)]) * 1000.0
    cloud = gagekit.read_cloud(E57 / "tiny_spherical.e57")
    assert cloud.invalid_dropped == int((~ok).sum()) > 0
    np.testing.assert_allclose(cloud.points, want, atol=1e-9)


def test_cartesian_invalid_points_are_dropped_and_counted(capsys):
    (raw,) = _pye57_raw(E57 / "cartesian_invalid_state_single.e57")
    ok = raw["cartesianInvalidState"] == 0
    cloud = gagekit.read_cloud(E57 / "cartesian_invalid_state_single.e57")
    assert cloud.invalid_dropped == int((~ok).sum()) == 2
    want = np.column_stack([raw["cartesianX"][ok], raw["cartesianY"][ok], raw["cartesianZ"][ok]]) * 1000.0
    np.testing.assert_array_equal(cloud.points, want)
    with pytest.raises(SystemExit):
        main(["cloud", "info", str(E57 / "cartesian_invalid_state_single.e57")])
    assert "invalid points dropped: 2" in capsys.readouterr().out


@pytest.mark.parametrize("name", ["bad-crc", "corrupt_crc", "empty_pc"])
def test_corrupt_e57_is_one_line(capfd, name):
    with pytest.raises(FileFormatError, match="not a readable E57 file|no points"):
        gagekit.read_points(E57 / f"{name}.e57")
    capfd.readouterr()
    with pytest.raises(SystemExit) as ex:
        main(["cloud", "info", str(E57 / f"{name}.e57")])
    out, err = capfd.readouterr()  # file-descriptor level: C++ output would show here
    assert ex.value.code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"gagekit: error: {E57 / name}.e57: "), err


def test_truncated_e57(tmp_path):
    f = tmp_path / "cut.e57"
    f.write_bytes((E57 / "bunnyDouble.e57").read_bytes()[:300_000])
    with pytest.raises(FileFormatError, match="not a readable E57 file"):
        gagekit.read_points(f)


# LAS / LAZ --------------------------------------------------------------------------------


def _las_header(path):
    """Point count, scales, offsets, max and min from the LAS 1.x public header block."""
    b = Path(path).read_bytes()[:227]
    assert b[:4] == b"LASF"
    count = struct.unpack_from("<I", b, 107)[0]
    scale = np.array(struct.unpack_from("<3d", b, 131))
    offset = np.array(struct.unpack_from("<3d", b, 155))
    mx_x, mn_x, mx_y, mn_y, mx_z, mn_z = struct.unpack_from("<6d", b, 179)
    return count, scale, offset, np.array([mn_x, mn_y, mn_z]), np.array([mx_x, mx_y, mx_z])


@pytest.mark.parametrize("name", ["simple.las", "simple.laz"])
def test_simple_las_and_laz_without_crs_are_metres(name):
    pytest.importorskip("laspy")
    count, scale, _, lo, hi = _las_header(LAS / "simple.las")
    cloud = gagekit.read_cloud(LAS / name)
    assert len(cloud.points) == count == 1065
    assert cloud.source_unit == "m" and "no CRS" in cloud.unit_basis
    np.testing.assert_allclose(cloud.points.min(axis=0), lo * 1000.0, atol=scale.max() * 1000)
    np.testing.assert_allclose(cloud.points.max(axis=0), hi * 1000.0, atol=scale.max() * 1000)


def test_laz_equals_las():
    pytest.importorskip("laspy")
    np.testing.assert_array_equal(gagekit.read_points(LAS / "simple.laz"), gagekit.read_points(LAS / "simple.las"))


def test_geotiff_foot_and_wkt_us_survey_foot():
    pytest.importorskip("laspy")
    count, scale, _, lo, _ = _las_header(LAS / "autzen_geo_proj.las")
    c = gagekit.read_cloud(LAS / "autzen_geo_proj.las")  # ProjLinearUnitsGeoKey 9002: foot
    assert (c.source_unit, c.scale_to_mm, len(c.points)) == ("ft", 304.8, count)
    np.testing.assert_allclose(c.points.min(axis=0), lo * 304.8, atol=scale.max() * 304.8)
    t = gagekit.read_cloud(LAS / "test1_4.las")  # WKT UNIT["US survey foot",0.3048006096012192]
    assert t.source_unit == "us-ft" and abs(t.scale_to_mm - 1200 / 3937 * 1000) < 1e-12 and "WKT" in t.unit_basis
    m = gagekit.read_cloud(LAS / "test1_4.las", units="m")
    np.testing.assert_allclose(t.points, m.points * (1200 / 3937), rtol=1e-15)


def _las_with_wkt(tmp_path, wkt):
    laspy = pytest.importorskip("laspy")
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.scales = np.array([1e-3] * 3)
    header.offsets = np.zeros(3)
    header.add_crs  # noqa: B018  (laspy >= 2.2)
    header.vlrs.append(laspy.vlrs.known.WktCoordinateSystemVlr(wkt))
    las = laspy.LasData(header)
    las.x, las.y, las.z = [1.0, 2.0], [3.0, 4.0], [5.0, 6.0]
    f = tmp_path / "crs.las"
    las.write(str(f))
    return f


def test_unknown_crs_unit_warns_and_assumes_metres(tmp_path):
    f = _las_with_wkt(tmp_path, 'PROJCS["x",GEOGCS["g",UNIT["degree",0.0174532925199433]],UNIT["furlong",201.168]]')
    with pytest.warns(UserWarning, match="metres assumed"):
        pts = gagekit.read_points(f)
    np.testing.assert_allclose(pts[:, 0], [1000.0, 2000.0])
    assert gagekit.read_cloud(f, units="ft").warnings == ()


def test_geographic_las_needs_units(tmp_path):
    f = _las_with_wkt(tmp_path, 'GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],'
                                'PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]]')
    with pytest.raises(FileFormatError, match="degrees"):
        gagekit.read_points(f)
    assert gagekit.read_cloud(f, units="m").source_unit == "m"


def _crc32c(data: bytes) -> int:
    """CRC-32C (Castagnoli), the checksum of E57 pages (ASTM E2807, stored big-endian)."""
    table = []
    for i in range(256):
        c = i
        for _ in range(8):
            c = (c >> 1) ^ 0x82F63B78 if c & 1 else c >> 1
        table.append(c)
    crc = 0xFFFFFFFF
    for byte in data:
        crc = table[(crc ^ byte) & 0xFF] ^ (crc >> 8)
    return crc ^ 0xFFFFFFFF


def test_spherical_without_range_is_an_error(tmp_path):
    """tiny_spherical.e57 with its sphericalRange field renamed to intensity (same size,
    page checksum recomputed): azimuth and elevation without range are directions only."""
    b = bytearray((E57 / "tiny_spherical.e57").read_bytes())
    old, new = b'<sphericalRange type="Float"/>', b'<intensity type="Float"/>'
    i = b.index(old)
    b[i : i + len(old)] = new.ljust(len(old))
    page = i // 1024 * 1024
    assert _crc32c(bytes((E57 / "tiny_spherical.e57").read_bytes()[page : page + 1020])).to_bytes(4, "big") == b[page + 1020 : page + 1024]
    b[page + 1020 : page + 1024] = _crc32c(bytes(b[page : page + 1020])).to_bytes(4, "big")
    f = tmp_path / "no_range.e57"
    f.write_bytes(bytes(b))
    with pytest.raises(FileFormatError, match="without sphericalRange"):
        gagekit.read_points(f)


def test_poses_of_every_scan_are_applied(tmp_path):
    # a pose in a real file: pye57's translationWithoutRotation.e57, translation (4, 5, 6) m
    (raw,) = _pye57_raw(E57 / "translationWithoutRotation.e57")
    xyz = np.column_stack([raw["cartesianX"], raw["cartesianY"], raw["cartesianZ"]])
    np.testing.assert_allclose(gagekit.read_points(E57 / "translationWithoutRotation.e57"), (xyz + [4, 5, 6]) * 1000)
    # two scans written by pye57 (libE57), the first turned 90 degrees about z and moved
    pye57 = pytest.importorskip("pye57")
    f = tmp_path / "two.e57"
    w = pye57.E57(str(f), mode="w")
    local = {"cartesianX": np.array([1.0, 0.0, 0.5]), "cartesianY": np.array([0.0, 1.0, 0.25]), "cartesianZ": np.array([0.0, 0.0, 2.0])}
    half = np.pi / 4  # quaternion (w, x, y, z) of a 90-degree turn about z
    w.write_scan_raw(local, rotation=np.array([np.cos(half), 0, 0, np.sin(half)]), translation=np.array([1.0, 2.0, 3.0]))
    w.write_scan_raw(local)
    w.close()
    cloud = gagekit.read_cloud(f)
    p = np.column_stack([local["cartesianX"], local["cartesianY"], local["cartesianZ"]])
    turned = np.column_stack([-p[:, 1], p[:, 0], p[:, 2]]) + [1.0, 2.0, 3.0]
    assert cloud.scans == 2
    np.testing.assert_allclose(cloud.points, np.vstack([turned, p]) * 1000, atol=1e-9)
