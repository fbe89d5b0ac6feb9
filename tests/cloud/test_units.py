"""Units: every reader converts to millimetres; ``units=`` / ``--units`` override."""

import json

import numpy as np
import pytest

import gagekit
from gagekit.cli import main
from gagekit.cloud.units import MM_PER_UNIT, UNIT_NAMES, check_units
from gagekit.errors import InvalidInputError

def cli(capsys, argv):
    """Run the CLI in-process: (exit code, stdout, stderr)."""
    with pytest.raises(SystemExit) as ex:
        main([str(a) for a in argv])
    out = capsys.readouterr()
    return ex.value.code or 0, out.out, out.err


PTS = np.array([[1.0, 2.0, 3.0], [4.0, 5.5, -6.0], [0.25, 0.0, 1e3]])


def test_unit_table_is_exact():
    assert MM_PER_UNIT["in"] == 25.4 and MM_PER_UNIT["ft"] == 304.8 and MM_PER_UNIT["m"] == 1000.0
    # US survey foot: 1200/3937 m (NIST Handbook 44, appendix C)
    assert abs(MM_PER_UNIT["us-ft"] - 304.8006096012192) < 1e-12
    assert set(UNIT_NAMES) <= set(MM_PER_UNIT)


@pytest.mark.parametrize("unit", UNIT_NAMES)
@pytest.mark.parametrize("suffix", [".csv", ".ply", ".npy", ".xyz"])
def test_override_scales_every_format(tmp_path, unit, suffix):
    f = tmp_path / f"c{suffix}"
    gagekit.write_points(f, PTS)
    cloud = gagekit.read_cloud(f, units=unit)
    np.testing.assert_allclose(cloud.points, PTS * MM_PER_UNIT[unit], rtol=1e-15)
    assert cloud.source_unit == unit and cloud.scale_to_mm == MM_PER_UNIT[unit]
    np.testing.assert_allclose(gagekit.read_points(f, units=unit), cloud.points)


def test_unitless_formats_are_mm(tmp_path):
    f = tmp_path / "c.ply"
    gagekit.write_points(f, PTS)
    cloud = gagekit.read_cloud(f)
    assert (cloud.source_unit, cloud.scale_to_mm) == ("mm", 1.0)
    np.testing.assert_array_equal(cloud.points, PTS)


@pytest.mark.parametrize("bad", ["km", "", "mmm", 3])
def test_unknown_unit_is_an_error(tmp_path, bad):
    f = tmp_path / "c.csv"
    gagekit.write_points(f, PTS)
    with pytest.raises(InvalidInputError, match="unit"):
        gagekit.read_points(f, units=bad)


def test_aliases():
    assert check_units("M") == "m" and check_units("µm") == "um" and check_units(None) is None


def test_cli_info_reports_unit_and_scale(tmp_path, capsys):
    f = tmp_path / "c.csv"
    gagekit.write_points(f, PTS)
    code, out, _ = cli(capsys, ["cloud", "info", f, "--units", "in", "--json"])
    r = json.loads(out)
    assert r["source_unit"] == "in" and r["scale_to_mm"] == 25.4
    np.testing.assert_allclose(r["max"], PTS.max(axis=0) * 25.4)
    code, out, _ = cli(capsys, ["cloud", "info", f])
    assert "unit: mm" in out and "x 1" in out


@pytest.mark.parametrize(
    "argv",
    [
        ["cloud", "info", "{f}"],
        ["cloud", "hull", "{f}"],
        ["form", "fit", "plane", "{f}"],
        ["form", "cylinder", "{f}"],
        ["form", "circle", "{f}"],
    ],
)
def test_every_cloud_command_rejects_unknown_units(tmp_path, capsys, argv):
    f = tmp_path / "c.csv"
    gagekit.write_points(f, PTS)
    code, _, err = cli(capsys, [a.format(f=f) for a in argv] + ["--units", "furlong"])
    assert code == 2
    err = err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("gagekit: error:") and "furlong" in err[0]
