"""Bad PART.toml input: one clear ConfigError per mistake, naming the table and the key."""

import copy

import numpy as np
import pytest

from gagekit import inspect_scan
from gagekit.errors import ConfigError, DegenerateGeometryError, GagekitError
from gagekit.inspect import part_spec_from_dict

BASE = {
    "feature": [
        {"name": "A", "shape": "plane", "region": {"center": [0, 0, 0], "size": [10, 10, 1]}, "outward": [0, 0, -1]},
        {"name": "B", "shape": "plane", "region": {"center": [0, -5, 5], "size": [10, 1, 10]}, "outward": [0, -1, 0]},
        {"name": "top", "shape": "plane", "region": {"center": [0, 0, 10], "size": [10, 10, 1]}, "outward": [0, 0, 1]},
    ],
    "datums": {"A": "A", "B": "B"},
    "tolerance": [{"feature": "top", "characteristic": "parallelism", "tolerance": 0.1, "datums": ["A"]}],
}


def _bad(edit):
    doc = copy.deepcopy(BASE)
    edit(doc)
    with pytest.raises(ConfigError) as exc:
        part_spec_from_dict(doc, "PART.toml")
    return str(exc.value)


def test_the_base_spec_is_fine():
    part_spec_from_dict(copy.deepcopy(BASE), "PART.toml")


@pytest.mark.parametrize("edit, words", [
    (lambda d: d["tolerance"][0].update(characteristic="roundnes"), ["[[tolerance]] #1", "'characteristic'", "roundnes"]),
    (lambda d: d["feature"][2].update(shape="torus"), ["[[feature]] #3", "'shape'", "torus"]),
    (lambda d: d["tolerance"][0].update(characteristic="roundness", datums=[]), ["[[tolerance]] #1", "'characteristic'", "does not apply to a plane"]),
    (lambda d: d["tolerance"][0].pop("datums"), ["[[tolerance]] #1", "'datums' is missing"]),
    (lambda d: d["tolerance"][0].update(datums=["A", "A"]), ["[[tolerance]] #1", "'datums'", "twice"]),
    (lambda d: d["datums"].update(C="A"), ["[datums] C", "already datum A"]),
    (lambda d: d["feature"][2].update(outward=[0, 0, 0]), ["[[feature]] #3", "'outward'", "zero length"]),
    (lambda d: d["tolerance"][0].update(datums=["Q"]), ["[[tolerance]] #1", "'datums'", "'Q'"]),
    (lambda d: d["tolerance"][0].update(tolerance=-1), ["[[tolerance]] #1", "'tolerance'", "positive"]),
    (lambda d: d["tolerance"][0].update(characteristic="flatness"), ["[[tolerance]] #1", "'datums'", "takes no datums"]),
    (lambda d: d["tolerance"][0].update(characteristic="total-runout"), ["[[tolerance]] #1", "'datums'", "datum axis"]),
    (lambda d: d["tolerance"][0].update(characteristic="position"), ["[[tolerance]] #1", "'nominal'"]),
    (lambda d: d["feature"][0].update(colour="red"), ["[[feature]] #1", "'colour'"]),
    (lambda d: d["feature"][1].update(region={"center": [0, 0, 0], "size": [1, 0, 1]}), ["[[feature]] #2", "'region'", "positive"]),
    (lambda d: d["tolerance"][0].update(feature="nope"), ["[[tolerance]] #1", "'feature'", "nope"]),
])
def test_one_clear_error_each(edit, words):
    msg = _bad(edit)
    for w in words:
        assert w in msg, (w, msg)
    assert msg.startswith("PART.toml")


def _plate_points():
    u, v = np.meshgrid(np.linspace(-4, 4, 9), np.linspace(-4, 4, 9), indexing="ij")
    u, v = u.ravel(), v.ravel()
    return np.concatenate([np.column_stack([u, v, 0 * u]), np.column_stack([u, v, 0 * u + 10]),
                           np.column_stack([u, 0 * u - 5, 5 + v])])


def test_a_region_with_too_few_points():
    doc = copy.deepcopy(BASE)
    doc["feature"][2]["region"] = {"center": [50, 50, 50], "size": [1, 1, 1]}
    with pytest.raises(DegenerateGeometryError, match=r"\[\[feature\]\] 'top': 'region' holds 0 point"):
        inspect_scan(_plate_points(), part_spec_from_dict(doc, "PART.toml"))


def test_a_secondary_datum_parallel_to_the_primary():
    doc = copy.deepcopy(BASE)
    doc["datums"]["B"] = "top"
    doc["tolerance"][0] = {"feature": "B", "characteristic": "perpendicularity", "tolerance": 0.1, "datums": ["A", "B"]}
    doc["feature"][2]["outward"] = [0, 0, 1]
    with pytest.raises(ConfigError, match=r"datum B \(feature 'top'\).*parallel to the primary datum A"):
        inspect_scan(_plate_points(), part_spec_from_dict(doc, "PART.toml"))


def test_bad_points_are_typed_errors():
    spec = part_spec_from_dict(copy.deepcopy(BASE), "PART.toml")
    pts = _plate_points()
    pts[3, 1] = np.nan
    with pytest.raises(GagekitError, match="point 3"):
        inspect_scan(pts, spec)
    with pytest.raises(GagekitError):
        inspect_scan(np.zeros((5, 2)), spec)
