"""Distances to meshes against analytic values: convex polytopes to 1e-9 mm (points
offset along face normals, inside and outside; arbitrary points against the box's exact
signed distance), STEP box and cylinder to 1 um of the exact surface."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from gagekit.cad import read_cad
from gagekit.errors import DegenerateGeometryError, FileFormatError, InvalidInputError

from cad_models import box, octahedron, step_solid, write_stl


def _box_sdf(p, h):
    q = np.abs(p) - np.asarray(h)
    return np.linalg.norm(np.maximum(q, 0), axis=1) + np.minimum(q.max(axis=1), 0)


@pytest.mark.parametrize("binary", [True, False])
def test_box_stl_matches_the_exact_signed_distance(tmp_path, binary):
    h = (2.0, 1.5, 1.0)
    v, t = box(h)
    path = tmp_path / "box.stl"
    write_stl(path, v, t, binary)
    model = read_cad(path)
    assert model.signed and len(model.triangles) == 12 and len(model.vertices) == 8
    rng = np.random.default_rng(0)
    pts = rng.uniform(-4, 4, (20000, 3))
    d = model.distances(pts).distance
    assert np.abs(d - _box_sdf(pts, h)).max() < 1e-9


def test_octahedron_points_offset_along_face_normals(tmp_path):
    v, t = octahedron(3.0)
    path = tmp_path / "octa.obj"
    path.write_text("".join(f"v {a} {b} {c}\n" for a, b, c in v) + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in t))
    model = read_cad(path)
    assert model.signed
    rng = np.random.default_rng(1)
    for tri in t:
        a, b, c = v[tri]
        n = np.cross(b - a, c - a)
        n /= np.linalg.norm(n)
        w = rng.dirichlet([4, 4, 4], 200)
        w = w[w.min(axis=1) > 0.2][:50]  # well inside the face: the face is also the nearest from inside
        base = w @ np.array([a, b, c])
        for h in (-0.3, -0.05, 0.0, 0.02, 0.7, 5.0):
            d = model.distances(base + h * n).distance
            assert np.abs(d - h).max() < 1e-9


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_distances_are_invariant_under_rigid_motion(tmp_path_factory, seed):
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed)
    h = rng.uniform(0.5, 20, 3)
    v, t = box(h)
    R = Rotation.random(random_state=seed).as_matrix()
    s = rng.uniform(-100, 100, 3)
    path = tmp_path_factory.mktemp("m") / "box.ply"
    from plyfile import PlyData, PlyElement

    vm = v @ R.T + s
    vert = np.array([tuple(p) for p in vm], dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8")])
    face = np.array([(list(f),) for f in t], dtype=[("vertex_indices", "i4", (3,))])
    PlyData([PlyElement.describe(vert, "vertex"), PlyElement.describe(face, "face")]).write(str(path))
    model = read_cad(path)
    local = rng.uniform(-2, 2, (500, 3)) * h
    d = model.distances(local @ R.T + s).distance
    assert np.abs(d - _box_sdf(local, h)).max() < 1e-9


def test_open_mesh_is_unsigned_with_one_warning(tmp_path):
    v, t = box()
    path = tmp_path / "open.stl"
    write_stl(path, v, t[:-2])
    model = read_cad(path)
    assert not model.signed
    assert sum("open" in w for w in model.warnings) == 1
    assert (model.distances(np.zeros((1, 3))).distance >= 0).all()


def test_bad_meshes_are_typed_errors(tmp_path):
    p = tmp_path / "deg.obj"
    p.write_text("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n")
    with pytest.raises(DegenerateGeometryError, match="degenerate"):
        read_cad(p)
    p = tmp_path / "nan.obj"
    p.write_text("v 0 0 0\nv 1 nan 0\nv 2 1 0\nf 1 2 3\n")
    with pytest.raises(InvalidInputError, match="vertex 1"):
        read_cad(p)
    p = tmp_path / "none.obj"
    p.write_text("v 0 0 0\n")
    with pytest.raises(FileFormatError, match="no faces"):
        read_cad(p)
    p = tmp_path / "junk.stl"
    p.write_bytes(b"\x00\xff" * 100)
    with pytest.raises(FileFormatError, match="neither a binary STL"):
        read_cad(p)
    # a binary STL cut short (its header's count of triangles, more than the bytes hold),
    # whether its header is text-like or not: the numbers, not a guess at ASCII
    for head in (b"\0" * 80, b"solid exported by a CAD system".ljust(80, b" "), b"\x80" * 80):
        p = tmp_path / "cut.stl"
        p.write_bytes(head + (10).to_bytes(4, "little") + b"\x01" * 100)
        with pytest.raises(FileFormatError, match=r"declares 10 triangles \(584 bytes\), the file has 184 bytes \(cut short\)"):
            read_cad(p)
    p.write_bytes(b"\0" * 20)
    with pytest.raises(FileFormatError, match="84-byte header, the file has 20 bytes"):
        read_cad(p)
    p = tmp_path / "m.dxf"
    p.write_text("0\n")
    with pytest.raises(FileFormatError, match="unknown CAD format"):
        read_cad(p)


def test_mesh_units(tmp_path):
    v, t = box((1.0, 1.0, 1.0))
    path = tmp_path / "box.stl"
    write_stl(path, v, t)
    model = read_cad(path, units="in")
    assert model.unit == "in"
    assert np.allclose(np.abs(model.vertices), 25.4)
