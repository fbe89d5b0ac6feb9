"""STEP models through OpenCASCADE (the cad extra): distances within 1 um of the exact
surface, faces with their STEP ids and names, the bundled bracket."""

from __future__ import annotations

import numpy as np
import pytest

from gagekit.cad import read_cad
from gagekit.samples import data_path

from cad_models import step_solid

pytest.importorskip("OCP")


@pytest.mark.parametrize("kind", ["box", "cylinder"])
def test_step_distances_within_one_micrometre(tmp_path, kind):
    path = tmp_path / f"{kind}.step"
    step_solid(path, kind)
    model = read_cad(path)
    assert model.signed and model.unit == "mm"
    assert all(f.id > 0 for f in model.faces)
    rng = np.random.default_rng(2)
    pts, expect = [], []
    if kind == "box":
        assert len(model.faces) == 6
        for h in (-3.0, -0.4, 0.001, 0.5, 4.0):
            x = rng.uniform(5, 35, 200)
            y = rng.uniform(5, 25, 200)
            pts.append(np.column_stack([x, y, 20 + h + 0 * x]))
            expect.append(np.full(200, h))
    else:
        assert {f.kind for f in model.faces} == {"cylinder", "plane"}
        for h in (-4.0, -0.5, -0.0004, 0.0003, 0.5, 6.0):
            th = rng.uniform(0, 2 * np.pi, 400)
            z = rng.uniform(5, 25, 400)
            pts.append(np.column_stack([(10 + h) * np.cos(th), (10 + h) * np.sin(th), z]))
            expect.append(np.full(400, h))
    d = model.distances(np.concatenate(pts))
    err = np.abs(d.distance - np.concatenate(expect))
    assert err.max() < 1e-3, err.max()
    if kind == "cylinder":
        assert err.max() < 1e-9  # refined in closed form on the exact cylinder
        assert d.refined > 0


def test_bracket_step_faces_keep_ids_and_names():
    model = read_cad(data_path("bracket.step"))
    names = {f.name for f in model.faces}
    assert {"A", "B", "C", "top", "chamfer", "bore", "boss", "boss-top", "ball", "pin"} <= names
    assert model.face_index("bore") == model.face_index(f"#{model.faces[model.face_index('bore')].id}")
    assert model.signed
    assert model.faces[model.face_index("ball")].kind == "sphere"


def test_step_without_the_extra_is_one_line(tmp_path, monkeypatch):
    from gagekit.cad import step
    from gagekit.errors import FileFormatError

    monkeypatch.setattr(step, "ocp_available", lambda: False)
    with pytest.raises(FileFormatError, match=r"install gagekit\[cad\]"):
        read_cad(data_path("bracket.step"))
