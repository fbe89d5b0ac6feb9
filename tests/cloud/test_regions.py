"""Sampling regions (oriented boxes): Rust classification against a numpy reference."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gagekit
from gagekit.errors import ConfigError, InvalidInputError


def reference(points, box):
    from scipy.spatial.transform import Rotation

    r = Rotation.from_rotvec(box.rotation).as_matrix()
    local = (points - np.array(box.center)) @ r
    return np.flatnonzero(np.all(np.abs(local) <= np.array(box.size) / 2, axis=1))


coord = st.floats(-50, 50, allow_nan=False)
size = st.floats(0.5, 60, allow_nan=False)
angle = st.floats(-3, 3, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(center=st.tuples(coord, coord, coord), sz=st.tuples(size, size, size), rot=st.tuples(angle, angle, angle), seed=st.integers(0, 2**31))
def test_select_matches_numpy(center, sz, rot, seed):
    pts = np.random.default_rng(seed).uniform(-60, 60, size=(3000, 3))
    box = gagekit.Box(center, sz, rot)
    got = gagekit.select(pts, box)
    ref = reference(pts, box)
    # points within rounding of a face may differ; none do for random data at this scale
    np.testing.assert_array_equal(got, ref)


def test_classify_many_boxes_and_overlap():
    pts = np.random.default_rng(1).uniform(-10, 10, size=(100_000, 3))
    boxes = [gagekit.Box((0, 0, 0), (4, 4, 4)), gagekit.Box((1, 0, 0), (4, 4, 4), (0, 0, 0.3)), gagekit.Box((30, 0, 0), (1, 1, 1))]
    out = gagekit.classify(pts, boxes)
    assert len(out) == 3 and len(out[2]) == 0
    for box, idx in zip(boxes, out):
        np.testing.assert_array_equal(idx, reference(pts, box))
    assert len(np.intersect1d(out[0], out[1])) > 0


def test_bad_regions_and_points():
    with pytest.raises(ConfigError, match="z axis"):
        gagekit.Box((0, 0, 0), (1, 1, 0), name="flange")
    with pytest.raises(ConfigError, match="three numbers"):
        gagekit.Box((0, 0), (1, 1, 1))
    with pytest.raises(InvalidInputError, match="point 1"):
        gagekit.select([[0, 0, 0], [np.nan, 0, 0]], gagekit.Box((0, 0, 0), (1, 1, 1)))
    with pytest.raises(InvalidInputError, match="shape"):
        gagekit.select(np.zeros((4, 2)), gagekit.Box((0, 0, 0), (1, 1, 1)))
    assert len(gagekit.select(np.zeros((0, 3)), gagekit.Box((0, 0, 0), (1, 1, 1)))) == 0


def test_regions_from_toml(tmp_path):
    f = tmp_path / "g.toml"
    f.write_text('[[region]]\nname = "top"\ncenter = [0, 0, 1]\nsize = [2, 2, 0.5]\n[[region]]\nname = "side"\ncenter = [1, 0, 0]\nsize = [0.5, 2, 2]\nrotation = [0, 0, 0.1]\n')
    boxes = gagekit.load_regions(f)
    assert [b.name for b in boxes] == ["top", "side"] and boxes[1].rotation == (0, 0, 0.1)
    f.write_text('[[region]]\nname = "top"\ncenter = [0, 0, 1]\n')
    with pytest.raises(ConfigError, match="'top' has no 'size'"):
        gagekit.load_regions(f)
    f.write_text("[[region]\n")
    with pytest.raises(ConfigError, match="not valid TOML"):
        gagekit.load_regions(f)


def test_a_regions_file_in_degrees_is_read_as_the_gage_reader_reads_it(tmp_path):
    # load_regions (``cloud regions`` without an [alignment]) used to take degrees as radians
    from gagekit.gage.spec import parse_region_spec
    from gagekit._util import load_toml

    body = '[[region]]\nname = "tilted"\ncenter = [0, 0, 0]\nsize = [4, 1, 1]\nrotation = [0, 0, 90]\n'
    deg = tmp_path / "deg.toml"
    deg.write_text('angle_unit = "deg"\n' + body)
    rad = tmp_path / "rad.toml"
    rad.write_text(body.replace("[0, 0, 90]", f"[0, 0, {np.pi / 2!r}]"))
    got = gagekit.load_regions(deg)[0]
    assert got.rotation == pytest.approx((0.0, 0.0, np.pi / 2), abs=1e-15)
    assert got.rotation == pytest.approx(parse_region_spec(load_toml(deg, "regions"), str(deg)).regions[0].box.rotation, abs=1e-15)
    pts = np.array([[0.0, 1.5, 0.0], [1.5, 0.0, 0.0]])  # inside only when turned by 90 degrees
    assert [list(i) for i in gagekit.classify(pts, gagekit.load_regions(deg))] == [[0]]
    assert [list(i) for i in gagekit.classify(pts, gagekit.load_regions(rad))] == [[0]]
