"""`inspect`: a roundness callout with `filter = { upr = 50 }` and `reference` gives the filtered
ISO 12181 parameters in its row (issue 25 Sec. 4): keys `parameters`, `filter`, `reference`."""

from __future__ import annotations

import math

import numpy as np
import pytest

import gagekit
from gagekit.errors import ConfigError
from gagekit.form.parameters import gaussian_transmission
from gagekit.inspect import inspect, part_spec_from_dict

A3, A45 = 0.004, 0.002


def shaft(sections=6, n=3600, rotation=None, shift=(0.0, 0.0, 0.0)):
    """A shaft of radius 10 along z, 3 lobes of A3 and chatter of A45 at 45 UPR in every section."""
    t = 2 * np.pi * np.arange(n) / n
    r = 10 + A3 * np.cos(3 * t) + A45 * np.cos(45 * t)
    pts = np.concatenate([np.column_stack([r * np.cos(t), r * np.sin(t), np.full(n, z)])
                          for z in np.linspace(2, 18, sections)])
    if rotation is not None:
        pts = pts @ np.asarray(rotation).T
    return pts + shift


def spec(filter=None, reference=None, shape="cylinder", rotation=(0.0, 0.0, 0.0), shift=(0.0, 0.0, 0.0)):
    tol = {"feature": "shaft", "characteristic": "roundness", "tolerance": 0.01, "sections": 6}
    if filter is not None:
        tol["filter"] = filter
    if reference is not None:
        tol["reference"] = reference
    size = [24, 24, 20] if shape == "cylinder" else [24, 24, 0.5]
    center = [0, 0, 10] if shape == "cylinder" else [0, 0, 2]
    return part_spec_from_dict({
        "feature": [{"name": "shaft", "shape": shape, "kind": "shaft", "direction": [0, 0, 1],
                     "region": {"center": center, "size": size}}],
        "tolerance": [tol],
    }, "shaft.toml").moved(_rot(rotation), shift)


def _rot(v):
    from gagekit._rotation import rotation_from_vector

    return rotation_from_vector(v)


@pytest.mark.parametrize("shape", ["cylinder", "circle"])
def test_filtered_row_carries_the_parameters(shape):
    pts = shaft() if shape == "cylinder" else shaft(sections=1)
    row = inspect(pts, spec({"upr": 50}, shape=shape)).to_dict()["tolerances"][0]
    want = 2 * (A3 * gaussian_transmission(3, 50)) + 0.0  # 3 lobes alone would be this
    assert set(row["parameters"]) == {"RONt", "RONp", "RONv", "RONq"}
    assert row["filter"] == {"type": "gaussian", "upr": 50.0}
    assert row["reference"] == "MZCI"
    assert row["measured"] == row["parameters"]["RONt"]
    # filtered chatter keeps 57 % (exp(-pi (alpha 45/50)^2)): RONt lies between the lobes alone and the unfiltered sum
    assert want < row["measured"] < 2 * (A3 + A45)
    unf = inspect(pts, spec(shape=shape)).to_dict()["tolerances"][0]
    assert "parameters" not in unf and unf["measured"] == pytest.approx(2 * (A3 + A45), abs=1e-6)
    none = inspect(pts, spec({"type": "none"}, "LSCI", shape=shape)).to_dict()["tolerances"][0]
    assert none["reference"] == "LSCI" and none["filter"] == {"type": "none"}
    assert none["parameters"]["RONt"] == pytest.approx(unf["measured"], abs=1e-9)


def test_filtered_three_lobes_alone_are_exact():
    n = 3600
    t = 2 * np.pi * np.arange(n) / n
    r = 10 + A3 * np.cos(3 * t)
    pts = np.column_stack([r * np.cos(t), r * np.sin(t), np.full(n, 2.0)])
    for upr in (15, 50):
        row = inspect(pts, spec({"upr": upr}, shape="circle")).to_dict()["tolerances"][0]
        assert row["measured"] == pytest.approx(2 * A3 * gaussian_transmission(3, upr), abs=1e-9)


def test_rigid_motion_changes_no_filtered_parameter():
    rot, shift = (0.3, -0.2, 0.9), (120.0, -40.0, 15.0)
    a = inspect(shaft(), spec({"upr": 50}, "LSCI")).to_dict()["tolerances"][0]
    b = inspect(shaft(rotation=_rot(rot), shift=shift), spec({"upr": 50}, "LSCI", rotation=rot, shift=shift)).to_dict()["tolerances"][0]
    for k in a["parameters"]:
        assert a["parameters"][k] == pytest.approx(b["parameters"][k], abs=1e-7), k


@pytest.mark.parametrize("tol, words", [
    ({"filter": {"upr": 0}}, "positive"),
    ({"filter": {"upr": -50}}, "positive"),
    ({"filter": {"type": "spline", "upr": 50}}, "filter.type"),
    ({"filter": {}}, "upr"),
    ({"filter": 50}, "table"),
    ({"reference": "XX"}, "reference"),
])
def test_bad_filter_is_a_config_error(tol, words):
    doc = {"feature": [{"name": "shaft", "shape": "circle", "region": {"center": [0, 0, 2], "size": [24, 24, 0.5]}}],
           "tolerance": [{"feature": "shaft", "characteristic": "roundness", "tolerance": 0.01, **tol}]}
    with pytest.raises(ConfigError) as exc:
        part_spec_from_dict(doc, "bad.toml")
    assert words in str(exc.value)


def test_filter_only_on_roundness():
    doc = {"feature": [{"name": "f", "shape": "plane", "region": {"center": [0, 0, 0], "size": [1, 1, 1]}, "outward": [0, 0, 1]}],
           "tolerance": [{"feature": "f", "characteristic": "flatness", "tolerance": 0.01, "filter": {"upr": 50}}]}
    with pytest.raises(ConfigError, match="roundness"):
        part_spec_from_dict(doc, "bad.toml")
