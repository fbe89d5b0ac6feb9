"""The bundled bracket: every callout equals its analytic value; the same part moved by a
rigid motion measures the same."""

import numpy as np
import pytest

from bracket_fixture import bracket, key  # noqa: F401  (the fixture)
from gagekit import inspect_scan


def test_every_callout_matches_its_construction(bracket):
    pts, spec, gen = bracket
    res = inspect_scan(pts, spec)
    assert len(res.tolerances) == len(gen.EXPECTED) == 20
    for t in res.tolerances:
        want = gen.EXPECTED[key(t)]
        assert t.measured == pytest.approx(want, abs=1e-9), key(t)
        assert t.measured >= 0.0
        assert t.margin == pytest.approx(t.tolerance - t.measured)
    failing = {key(t) for t in res.tolerances if not t.passed}
    assert failing == {"parallelism of top", "total-runout of boss-top"}
    assert res.status == "nonconforming"
    # the datum frame A|B|C is the block's corner, axes into the material
    f = res.frame
    assert f.datums == ("A", "B", "C") and f.right_handed
    assert np.allclose(f.origin, 0.0, atol=1e-12) and np.allclose(f.axes, np.eye(3), atol=1e-12)
    assert len(f.free_translations) == 0 and not f.free_rotation


def test_regenerated_scan_is_the_bundled_one(bracket):
    pts, _, gen = bracket
    assert np.array_equal(gen.make_bracket(), pts)


def _rotation(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


@pytest.mark.parametrize("seed", [1, 2])
def test_rigid_motion_invariance(bracket, seed):
    pts, spec, _ = bracket
    rng = np.random.default_rng(seed)
    R, t = _rotation(rng), rng.uniform(-500, 500, 3)
    base = inspect_scan(pts, spec)
    moved = inspect_scan(pts @ R.T + t, spec.moved(R, t))
    for a, b in zip(base.tolerances, moved.tolerances):
        assert b.measured == pytest.approx(a.measured, abs=1e-9), key(a)
    # the frame moves with the part
    assert np.allclose(moved.frame.origin, R @ base.frame.origin + t, atol=1e-9)
    assert np.allclose(moved.frame.axes, base.frame.axes @ R.T, atol=1e-9)


def test_json_keys(bracket):
    pts, spec, _ = bracket
    d = inspect_scan(pts, spec).to_dict()
    assert {"datums", "frame", "tolerances", "features", "status"} <= set(d)
    for t in d["tolerances"]:
        assert {"feature", "characteristic", "tolerance", "measured", "pass", "margin", "datums", "n_points"} <= set(t)
    for dt in d["datums"]:
        assert {"feature", "method", "point"} <= set(dt) and ("normal" in dt or "direction" in dt)
    assert set(d["frame"]) >= {"origin", "axes"}
    assert d["status"] in ("conforming", "nonconforming")
