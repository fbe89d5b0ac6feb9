"""gage_distances: every point of a gage's region at T*, Eq. 5.4; the smallest of them is
the gage's allowance after T* (a linear function is smallest at a hull vertex)."""

import numpy as np
import pytest

import gagekit
from gagekit.samples import data_path
from gagekit.gage import check_gages, gage_distances, region_in_scanner, datum_alignment


@pytest.mark.parametrize("name", ["casting_ok", "casting_short"])
def test_smallest_distance_is_the_allowance_after(name):
    pts = gagekit.read_points(data_path(f"{name}.ply"))
    spec = gagekit.GageSpec.load(data_path(f"{name}.toml"))
    res = check_gages(pts, spec)
    out = gage_distances(pts, spec, res)
    assert len(out) == len(spec.gages)
    for (idx, e), g in zip(out, res.gages):
        assert len(idx) == g.points == len(e)
        assert e.min() == pytest.approx(g.allowance_after, abs=1e-9)
        assert e.max() <= g.q + 1e-9 or g.slack > 0


def test_regions_follow_the_datum_frame():
    pts = gagekit.read_points(data_path("casting_ok.ply"))
    spec = gagekit.GageSpec.load(data_path("casting_ok.toml"))
    al = datum_alignment(pts, spec)
    assert al is not None
    np.testing.assert_allclose(al.H @ al.frame, np.eye(4), atol=1e-12)
    part = spec.region("flange_top")
    moved = region_in_scanner(part, al)
    assert moved.size == part.box.size and moved.center != part.box.center
    scanner = spec.region("Z1")
    assert region_in_scanner(scanner, al) is scanner.box
    assert region_in_scanner(part, None) is part.box
