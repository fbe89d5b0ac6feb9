"""Gage files: parsing, defaults and the exact error messages (issue 4)."""

import math

import pytest

from gagekit import ConfigError, GageFileWarning, GageSpec

BASE = """
length_unit = "mm"
[motion]
free = ["beta", "dx", "dy", "dz"]
max_angle = 0.05
max_shift = 20.0

[[region]]
name = "top"
center = [0.0, 0.0, 10.0]
size = [20.0, 20.0, 4.0]

[[gage]]
name = "top min"
region = "top"
plane = [0.0, 0.0, 1.0, -9.0]
"""


def parse(text, tmp_path):
    p = tmp_path / "g.toml"
    p.write_text(text)
    return GageSpec.load(p)


def test_defaults_and_fields(tmp_path):
    spec = parse(BASE, tmp_path)
    assert spec.motion.free == ("beta", "dx", "dy", "dz")
    assert spec.motion.flags() == [False, True, False, True, True, True]
    g = spec.gages[0]
    assert (g.weight, g.slack_weight) == (1.0, 10.0)
    assert spec.regions[0].frame == "part"
    assert spec.alignment is None


def test_degrees_and_normalisation_warning(tmp_path):
    text = BASE.replace("max_angle = 0.05", "max_angle = 2.0").replace("[0.0, 0.0, 1.0, -9.0]", "[0.0, 0.0, 2.0, -18.0]")
    with pytest.warns(GageFileWarning, match="normal had length 2"):
        spec = parse('angle_unit = "deg"\n' + text, tmp_path)
    assert spec.gages[0].plane == (0.0, 0.0, 1.0, -9.0)
    assert spec.motion.max_angle == pytest.approx(math.radians(2.0))


@pytest.mark.parametrize(
    "old,new,message",
    [
        ('region = "top"', 'region = "tpo"', "gage 'top min': unknown region 'tpo'; defined regions: top"),
        ('region = "top"\n', "", "gage 'top min' has no region"),
        ('"beta", "dx"', '"theta", "dx"', "[motion] free: unknown motion(s) 'theta'"),
        ("[0.0, 0.0, 1.0, -9.0]", "[0.0, 0.0, nan, -9.0]", "gage 'top min': plane must be finite"),
        ("[0.0, 0.0, 1.0, -9.0]", "[0.0, 0.0, 0.0, -9.0]", "gage 'top min': plane normal (a, b, c) is zero"),
        ("[0.0, 0.0, 1.0, -9.0]", "[0.0, 1.0, -9.0]", "plane must be four numbers"),
        ('length_unit = "mm"', 'length_unit = "in"', 'length_unit must be "mm"'),
        ("max_shift = 20.0", "max_shift = -1.0", "[motion] max_shift must be at least 0.0"),
        ('plane = [', 'slack_weigth = 3.0\nplane = [', "gage 'top min': unknown key(s) 'slack_weigth'"),
        ('center = [0.0, 0.0, 10.0]', 'frame = "world"\ncenter = [0.0, 0.0, 10.0]', 'frame must be "part" or "scanner"'),
    ],
)
def test_bad_files_name_the_problem(tmp_path, old, new, message):
    text = BASE.replace(old, new, 1)
    assert text != BASE
    with pytest.raises(ConfigError) as exc:
        parse(text, tmp_path)
    assert message in str(exc.value)
    assert str(exc.value).startswith(str(tmp_path / "g.toml"))


def test_no_gages_and_alignment_checks(tmp_path):
    with pytest.raises(ConfigError, match="no gages"):
        parse(BASE.split("[[gage]]")[0], tmp_path)
    with pytest.raises(ConfigError, match="needs 'tertiary'"):
        parse(BASE + '[alignment]\nprimary = ["top"]\nsecondary = ["top"]\n', tmp_path)
    with pytest.raises(ConfigError, match="must have frame = \"scanner\""):
        parse(BASE + '[alignment]\nprimary = ["top"]\nsecondary = ["top"]\ntertiary = ["top"]\n', tmp_path)
    with pytest.raises(ConfigError, match="not valid TOML"):
        parse(BASE + "[[gage]\n", tmp_path)


def test_duplicate_names(tmp_path):
    with pytest.raises(ConfigError, match="gage 'top min' is defined twice"):
        parse(BASE + BASE[BASE.index("[[gage]]"):], tmp_path)


def test_no_free_motion_means_check_as_placed(tmp_path):
    spec = parse(BASE.replace('free = ["beta", "dx", "dy", "dz"]', "free = []"), tmp_path)
    assert spec.motion.free == () and spec.motion.flags() == [False] * 6
