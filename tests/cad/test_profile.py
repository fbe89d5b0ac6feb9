"""Profile of a surface on the bracket's CAD model (PART.toml with [part] cad and
features by faces): with datums the zone is fixed, without it floats (minimax)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gagekit import inspect_scan, load_part_spec, read_points
from gagekit.samples import data_path
from gagekit.errors import ConfigError

pytest.importorskip("OCP")

S_B, T, OFF, DELTA, BX, BZ = 1e-3, 6e-4, 0.01, 1e-3, 0.015, 0.01
L_CHAMFER = 20.0 * math.sqrt(2.0)


@pytest.fixture(scope="module")
def result():
    return inspect_scan(read_points(data_path("bracket.ply")), load_part_spec(data_path("bracket_cad.toml")))


def _value(result, feature, datums):
    for t in result.tolerances:
        if t.feature == feature and t.characteristic == "profile" and tuple(t.datums) == tuple(datums):
            return t
    raise KeyError(feature)


def test_profile_with_datums_is_fixed_in_the_datum_frame(result):
    top = _value(result, "top", ["A"])
    assert abs(top.measured - 2 * (OFF + 49 * T)) < 1e-6  # as the analytic plane callout of bracket.toml
    ball = _value(result, "ball", ["A", "B", "C"])
    # the sampled hemisphere just misses the direction of the offset: within 1e-5 below 2 |offset|
    assert 2 * math.hypot(BX, BZ) - 1e-5 < ball.measured <= 2 * math.hypot(BX, BZ) + 1e-9
    chamfer = _value(result, "chamfer", ["A", "B", "C"])
    assert abs(chamfer.measured - 2 * (L_CHAMFER - 1) * math.sin(DELTA)) < 2e-5
    assert top.zone == "width"


def test_profile_without_datums_floats(result):
    # a tilted but flat top and a shifted but perfect ball fit their CAD faces exactly
    assert _value(result, "top", []).measured < 1e-6
    # the floating fit runs on the tessellation (0.5 um): the exact sphere's zone is within 1 um
    assert _value(result, "ball", []).measured < 1e-3
    assert "certificate" in _value(result, "ball", []).details


def test_faces_feature_points_and_flatness(result):
    flat = [t for t in result.tolerances if t.characteristic == "flatness"][0]
    assert flat.measured < 1e-9 and flat.n_points > 100


def test_spec_errors(tmp_path):
    from gagekit.inspect import part_spec_from_dict

    base = {"feature": [{"name": "s", "shape": "surface", "faces": ["top"]}],
            "tolerance": [{"feature": "s", "characteristic": "profile", "tolerance": 0.1}]}
    with pytest.raises(ConfigError, match="cad"):
        part_spec_from_dict(base)
    with pytest.raises(ConfigError, match="needs 'faces'"):
        part_spec_from_dict({"part": {"cad": "x.step"}, "feature": [{"name": "s", "shape": "surface", "region": {"center": [0, 0, 0], "size": [1, 1, 1]}}],
                             "tolerance": base["tolerance"]})
    spec = part_spec_from_dict({"part": {"cad": "m.step"}, **base})
    assert spec.features["s"].faces == ("top",)
    with pytest.raises(ConfigError, match="offset"):
        part_spec_from_dict({"part": {"cad": "m.step"}, "feature": base["feature"] + [{"name": "p", "shape": "plane", "faces": [1], "outward": [0, 0, 1]}],
                             "tolerance": [{"feature": "p", "characteristic": "flatness", "tolerance": 0.1, "offset": 0.1}]})
    bad = {"part": {"cad": "m.step"}, "feature": [{"name": "s", "shape": "surface", "faces": []}], "tolerance": base["tolerance"]}
    with pytest.raises(ConfigError, match="faces"):
        part_spec_from_dict(bad)


def test_unknown_face_is_a_config_error(tmp_path):
    import shutil

    shutil.copy(data_path("bracket.step"), tmp_path / "bracket.step")
    text = data_path("bracket_cad.toml").read_text().replace('faces = ["top"]', 'faces = ["roof"]')
    (tmp_path / "p.toml").write_text(text)
    with pytest.raises(ConfigError, match="roof"):
        inspect_scan(read_points(data_path("bracket.ply")), load_part_spec(tmp_path / "p.toml"))


def test_result_json_of_surface_features(result):
    from gagekit._util import check_finite_result, dumps

    check_finite_result(result)
    d = result.to_dict()
    assert d["features"]["ball"] == {"shape": "surface", "n_points": d["features"]["ball"]["n_points"], "faces": ["ball"]}
    assert "profile" in dumps(result)
    assert len(result.deviations["top"][1]) == d["features"]["top"]["n_points"]
