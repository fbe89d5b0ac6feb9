"""The gage document: byte-identical round trip, minimal edits, errors located by table."""

import copy

import pytest

from gagekit.errors import ConfigError
from gagekit.gage import GageSpec
from gagekit.studio import specdoc
from gagekit.samples import data_path

COMMENTED = '''# a hand-written gage file: comments and layout must survive edits
length_unit = "mm"   # always mm

[motion]
free = ["dx", "dy", "dz"]  # no rotations
max_angle = 0.05
max_shift = 5

[[region]]
name = "top"
center = [50, 30, 10]   # integers on purpose
size = [80.0, 40.0, 2.0]

[[gage]]
name = "top min"
region = "top"
plane = [0.0, 0.0, 1.0, -9.5]
'''


@pytest.mark.parametrize("text", [data_path("casting_ok.toml").read_text(), data_path("casting_short.toml").read_text(),
                                  COMMENTED])
def test_unchanged_document_is_written_back_byte_for_byte(text):
    doc = specdoc.parse_text(text, "x.toml")
    assert specdoc.render(text, copy.deepcopy(doc), "x.toml") == text


def test_integers_given_back_as_floats_count_as_unchanged():
    doc = specdoc.parse_text(COMMENTED, "x.toml")
    doc["region"][0]["size"] = [80, 40, 2]          # what JSON.stringify makes of 80.0
    assert specdoc.render(COMMENTED, doc, "x.toml") == COMMENTED


def test_an_edit_changes_only_its_line_and_keeps_comments():
    doc = specdoc.parse_text(COMMENTED, "x.toml")
    doc["region"][0]["center"] = [51.25, 30, 10]
    out = specdoc.render(COMMENTED, doc, "x.toml")
    old, new = COMMENTED.splitlines(), out.splitlines()
    assert len(old) == len(new)
    diff = [(a, b) for a, b in zip(old, new) if a != b]
    assert diff == [("center = [50, 30, 10]   # integers on purpose", "center = [51.25, 30.0, 10.0]   # integers on purpose")]
    assert GageSpec.from_dict(specdoc.parse_text(out, "x.toml")).region("top").box.center == (51.25, 30.0, 10.0)


def test_adding_and_removing_tables_reads_back_as_edited():
    text = data_path("casting_ok.toml").read_text()
    doc = specdoc.parse_text(text, "x.toml")
    doc["region"] = [r for r in doc["region"] if r["name"] != "tower_top"]
    doc["gage"] = [g for g in doc["gage"] if g["region"] != "tower_top"]
    doc["region"].insert(3, {"name": "new", "frame": "part", "center": [1, 2, 3], "size": [4, 5, 6]})
    doc["gage"].append({"name": "new gage", "region": "new", "plane": [0, 0, 1, -2]})
    doc["alignment"]["primary"] = ["Z1", "Z2"]
    out = specdoc.render(text, doc, "x.toml")
    back = specdoc.parse_text(out, "x.toml")
    assert back == specdoc.parse_text(specdoc.render(text, doc, "x.toml"), "x.toml")
    assert [r["name"] for r in back["region"]] == [r["name"] for r in doc["region"]]
    assert back["region"][3]["center"] == [1.0, 2.0, 3.0]
    assert "\n\n\n" not in out and "tower_top" not in out
    assert out.startswith("# casting_ok: virtual gages")           # the comment header stays
    assert GageSpec.from_dict(back, "x.toml").gages[-1].name == "new gage"


def test_new_file_from_an_empty_text():
    doc = {"length_unit": "mm", "motion": {"free": [], "max_angle": 0.05, "max_shift": 20},
           "region": [{"name": "a", "frame": "part", "center": [1, 2, 3], "size": [1, 1, 1]}],
           "gage": [{"name": "g", "region": "a", "plane": [0, 0, 1, -1], "weight": 1, "slack_weight": 10}]}
    out = specdoc.render("", doc, "new.toml")
    assert out.startswith('length_unit = "mm"\n')
    assert "free = []" in out and "max_shift = 20.0" in out and "plane = [0.0, 0.0, 1.0, -1.0]" in out
    spec = GageSpec.from_dict(specdoc.parse_text(out, "new.toml"))
    assert spec.motion.free == () and spec.gages[0].plane == (0.0, 0.0, 1.0, -1.0)


def test_errors_are_located_by_table():
    v = specdoc.validate({"gage": [{"name": "g", "region": "zz", "plane": [0, 0, 1, 0]}]}, "s.toml")
    assert v.spec is None and v.errors[0]["table"] == "gage" and v.errors[0]["name"] == "g"
    assert not v.errors[0]["message"].startswith("s.toml")
    v = specdoc.validate({"motion": {"max_angle": "x"}, "gage": []}, "s.toml")
    assert v.errors[0]["table"] == "motion"
    v = specdoc.validate({"region": [{"name": "r", "center": [0, 0, 0], "size": [0, 1, 1]}],
                          "gage": [{"name": "g", "region": "r", "plane": [0, 0, 1, 0]}]}, "s.toml")
    assert (v.errors[0]["table"], v.errors[0]["name"]) == ("region", "r")
    v = specdoc.validate({"alignment": {"primary": ["r"]}, "region": [{"name": "r", "center": [0, 0, 0], "size": [1, 1, 1]}],
                          "gage": [{"name": "g", "region": "r", "plane": [0, 0, 1, 0]}]}, "s.toml")
    assert v.errors[0]["table"] == "alignment"
    v = specdoc.validate({"region": [{"name": "r", "center": [0, 0, 0], "size": [1, 1, 1]}],
                          "gage": [{"name": "g", "region": "r", "plane": [0, 0, 2, 0]}]}, "s.toml")
    assert v.spec is not None and v.warnings[0]["table"] == "gage"
    assert specdoc.validate({"gage": []}, "s.toml").errors[0]["table"] == "gage"
    assert specdoc.locate("s.toml: length_unit must be \"mm\"", "s.toml")["table"] == "top"


def test_bad_text_and_bad_documents():
    with pytest.raises(ConfigError, match="not valid TOML"):
        specdoc.parse_text("a = [", "s.toml")
    with pytest.raises(ConfigError):
        specdoc.render("", ["not", "a", "table"], "s.toml")
