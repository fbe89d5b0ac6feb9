"""The CAD model beside the scan (issue 24): a real `gagekit studio` server serves the
drawing's `[part] cad` (or a model chosen in the folder) as a compact binary mesh, and after
Run the per-vertex colours of `gagekit compare --report` (the same functions); bad requests
are 4xx JSON errors, files confined to the studio folder; large models are decimated."""

import base64
import importlib.util
import os
import shutil
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from starlette.testclient import TestClient

from gagekit.cad import read_cad
from gagekit.cad.compare import vertex_deviations
from gagekit.report.compare import colour_limit, vertex_rgb
from gagekit.samples import data_path
from gagekit.studio.app import LOOPBACK_HOSTS, create_app
from gagekit.studio.cadview import MAX_CAD_TRIANGLES, decimate
from gagekit.studio.session import Session, load_scan
from servers import StudioServer, assert_4xx, body

pytest.importorskip("uvicorn", reason="the studio extra (uvicorn, starlette) is needed")

_spec = importlib.util.spec_from_file_location("cad_models", Path(__file__).parents[1] / "cad" / "cad_models.py")
cad_models = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(cad_models)


def mesh_of(studio: StudioServer):
    """(vertices in mm, triangles, headers) of GET /api/cad/mesh."""
    req = urllib.request.Request(studio.base + "api/cad/mesh", headers={"X-Studio-Token": studio.token})
    with urllib.request.urlopen(req, timeout=60) as r:
        data, headers = r.read(), r.headers
    nv, nt = int(headers["X-Vertex-Count"]), int(headers["X-Triangle-Count"])
    assert len(data) == 12 * nv + 12 * nt and headers["content-type"] == "application/octet-stream"
    origin = np.array([float(x) for x in headers["X-Origin"].split(",")])
    v = np.frombuffer(data, "<f4", 3 * nv).reshape(-1, 3).astype(np.float64) + origin
    t = np.frombuffer(data, "<u4", 3 * nt, offset=12 * nv).reshape(-1, 3)
    return v, t, headers


@pytest.fixture()
def bracket(tmp_path):
    """The bracket's scan, its OBJ model and the CAD drawing pointing at the OBJ (the STEP
    model's tessellation with the same named faces: read in a second, not 20)."""
    folder = tmp_path / "bracket"
    folder.mkdir()
    shutil.copy(data_path("bracket.ply"), folder / "bracket.ply")
    shutil.copy(data_path("bracket.obj"), folder / "bracket.obj")
    (folder / "part.toml").write_text(
        data_path("bracket_cad.toml").read_text().replace('cad = "bracket.step"', 'cad = "bracket.obj"'))
    return folder


def test_the_drawings_cad_is_served_and_coloured_after_run_as_compare_report_colours_it(bracket):
    import gagekit

    studio = StudioServer(str(bracket / "bracket.ply"), str(bracket / "part.toml"))
    try:
        status, state, _ = studio.request("GET", "/api/state")
        assert status == 200 and state["cad"] == {"open": None, "drawing": "bracket.obj", "drawing_error": None}
        assert_4xx(studio.request("GET", "/api/cad/mesh"), "no CAD model")
        assert studio.request("GET", "/api/files")[1]["cads"] == ["bracket.obj"]   # the PLY scan has no faces
        status, info, _ = studio.request("POST", "/api/cad", body({}), timeout=60)
        model = read_cad(bracket / "bracket.obj")
        assert status == 200 and info["name"] == "bracket.obj" and info["faces"] == 14
        assert info["triangles"] == info["shown_triangles"] == len(model.triangles) and not info["decimated"]
        v, t, headers = mesh_of(studio)
        assert int(headers["X-Cad-Key"]) == info["key"]
        np.testing.assert_array_equal(t, model.triangles)
        np.testing.assert_allclose(v, model.vertices, atol=1e-5)               # float32 about the model's centre
        status, res, _ = studio.request("POST", "/api/run", body({"doc": state["spec"]["doc"]}), timeout=240)
        assert status == 200 and res["kind"] == "part"
        cad = res["cad"]
        assert cad["key"] == info["key"] and cad["info"]["name"] == "bracket.obj"
        # the colours of `gagekit compare --report`: every scan point's signed distance to the
        # model, the mean over the points whose nearest triangle touches the vertex, RdBu_r
        pts = gagekit.read_points(bracket / "bracket.ply")
        d = model.distances(pts)
        mean, count = vertex_deviations(model, d.triangle, d.distance)
        lim = colour_limit(d.distance)
        assert cad["limit"] == pytest.approx(lim, rel=1e-12) and cad["n_points"] == len(pts)
        rgb = np.frombuffer(base64.b64decode(cad["colours"]), np.uint8).reshape(-1, 3)
        np.testing.assert_array_equal(rgb, vertex_rgb(mean, count, lim))
        assert cad["coloured_vertices"] == int((count > 0).sum()) > 1000
        assert (rgb[count == 0] == 200).all()                                 # grey: no point near
        assert len(cad["stops"]) == 11 and cad["stops"][0].startswith("#")
        assert cad["range"] == pytest.approx([float(d.distance.min()), float(d.distance.max())])
        # the inspection itself is the library's
        want = gagekit.inspect_scan(pts, str(bracket / "part.toml"))
        assert [t["measured"] for t in res["result"]["tolerances"]] == pytest.approx([t.measured for t in want.tolerances])
    finally:
        studio.stop()


def test_a_model_chosen_in_the_folder_and_the_run_loads_the_drawings_on_its_own(bracket):
    v, t = cad_models.box((60.0, 40.0, 20.0))
    cad_models.write_stl(bracket / "block.stl", v + [60.0, 40.0, 20.0], t, binary=True)
    studio = StudioServer(str(bracket / "bracket.ply"), str(bracket / "part.toml"))
    try:
        doc = studio.request("GET", "/api/state")[1]["spec"]["doc"]
        status, info, _ = studio.request("POST", "/api/cad", body({"path": "block.stl", "units": "mm", "max_distance": 5}))
        assert status == 200 and info["triangles"] == 12 and info["max_distance"] == 5
        mv, mt, _ = mesh_of(studio)
        assert len(mt) == 12 and np.allclose(mv.min(axis=0), 0) and np.allclose(mv.max(axis=0), [120, 80, 40])
        status, res, _ = studio.request("POST", "/api/run", body({"doc": doc}), timeout=240)
        assert status == 200 and res["cad"]["info"]["name"] == "block.stl" and res["cad"]["n_beyond"] > 0
        assert studio.request("POST", "/api/cad", body({"close": True}))[1]["open"] is None
        assert_4xx(studio.request("GET", "/api/cad/mesh"), "no CAD model")
        # with none open, the Run of a drawing with [part] cad opens the drawing's (read once)
        status, res, _ = studio.request("POST", "/api/run", body({"doc": doc}), timeout=240)
        assert status == 200 and res["cad"]["info"]["name"] == "bracket.obj"
        assert studio.request("GET", "/api/state")[1]["cad"]["open"]["name"] == "bracket.obj"
    finally:
        studio.stop()


def test_bad_cad_requests_are_4xx_json_errors_confined_to_the_folder(bracket, tmp_path):
    (tmp_path / "secret.stl").write_bytes(b"solid x\nendsolid x\n")
    (bracket / "link.stl").symlink_to(tmp_path / "secret.stl")
    (bracket / "broken.stl").write_text("solid broken\n  vertex 0 0 0\n  vertex 1 0 0\n")
    (bracket / "cloud.ply").write_bytes((bracket / "bracket.ply").read_bytes())
    (bracket / "notes.txt").write_text("x")
    os.mkfifo(bracket / "pipe.stl")
    (bracket / "outside.toml").write_text('[part]\nname = "x"\ncad = "../secret.stl"\n')
    studio = StudioServer(str(bracket / "bracket.ply"), str(bracket / "part.toml"))
    try:
        post = lambda data: studio.request("POST", "/api/cad", body(data), timeout=30)  # noqa: E731
        assert_4xx(post({"path": "../secret.stl"}), "outside", status=403)
        assert_4xx(post({"path": str(tmp_path / "secret.stl")}), "outside", status=403)
        assert_4xx(post({"path": "link.stl"}), "outside", status=403)
        assert_4xx(post({"path": "notes.txt"}), "must end in")
        assert_4xx(post({"path": "missing.stl"}), "missing.stl")
        assert_4xx(post({"path": "pipe.stl"}), "FIFO")
        assert_4xx(post({"path": "broken.stl"}), "multiple of 3")
        assert_4xx(post({"path": "cloud.ply"}), "no faces")
        assert_4xx(post({"path": "bracket.obj", "units": "furlong"}), "furlong")
        assert_4xx(post({"path": "bracket.obj", "units": 3}), "units")
        for bad in (-1, 0, True, "5", [5]):
            assert_4xx(post({"path": "bracket.obj", "max_distance": bad}), "max_distance")
        assert_4xx(post({"path": 5}))
        assert_4xx(studio.request("POST", "/api/cad", b"[1, 2]"), "JSON object")
        assert_4xx(studio.request("POST", "/api/cad", b'{"path": "\\ud800.stl"}'), "Unicode")
        assert_4xx(studio.request("GET", "/api/cad/mesh", token=False), "token")
        assert_4xx(studio.request("POST", "/api/cad", body({}), token=False), "token")
        # a drawing whose [part] cad leads outside the folder: said in the state, refused (403)
        assert studio.request("POST", "/api/spec", body({"path": "outside.toml", "kind": "part"}))[0] == 200
        cad = studio.request("GET", "/api/state")[1]["cad"]
        assert cad["drawing"] is None and "outside the studio folder" in cad["drawing_error"]
        assert_4xx(post({}), "outside", status=403)
        doc = {"part": {"name": "x", "cad": "../secret.stl"},
               "feature": [{"name": "s", "shape": "surface", "faces": ["x"]}],
               "tolerance": [{"feature": "s", "characteristic": "profile", "tolerance": 0.1}]}
        assert_4xx(studio.request("POST", "/api/run", body({"doc": doc}), timeout=60), "outside", status=403)
        assert studio.request("GET", "/api/state")[0] == 200                 # still serving
    finally:
        studio.stop()


def test_step_models_and_the_one_line_message_without_the_cad_extra(tmp_path, monkeypatch):
    pytest.importorskip("OCP", reason="the cad extra (cadquery-ocp) is needed for STEP models")
    from gagekit.cad import step

    cad_models.step_solid(tmp_path / "box.step", "box")
    rng = np.random.default_rng(1)
    pts = np.column_stack([rng.uniform(1, 39, 500), rng.uniform(1, 29, 500), np.full(500, 20.003)])  # 3 um above the top
    np.savetxt(tmp_path / "scan.xyz", pts)
    session = Session(load_scan(tmp_path / "scan.xyz"), tmp_path / "part.toml", kind="part")
    client = TestClient(create_app(session, tmp_path, allowed_hosts=LOOPBACK_HOSTS), base_url="http://127.0.0.1:8765")
    res = client.post("/api/cad", json={"path": "box.step"})
    assert res.status_code == 200 and res.json()["format"] == "step" and res.json()["faces"] == 6
    colours = session.cad.colours(*_distances(session))
    assert colours["range"] == pytest.approx([0.003, 0.003], abs=1e-6)      # exact faces: 3 um, the sign outward
    monkeypatch.setattr(step, "ocp_available", lambda: False)
    res = client.post("/api/cad", json={"path": "box.step"})
    assert res.status_code == 400 and res.json()["error"].count("\n") == 0
    assert "install gagekit[cad]" in res.json()["error"]


def _distances(session):
    d = session.cad.model.distances(session.scan.points)
    return d.triangle, d.distance


def icosphere(r: float, levels: int):
    """A sphere of radius r as a closed triangle mesh (an icosahedron subdivided ``levels`` times)."""
    p = (1 + 5 ** 0.5) / 2
    v = [(-1, p, 0), (1, p, 0), (-1, -p, 0), (1, -p, 0), (0, -1, p), (0, 1, p), (0, -1, -p), (0, 1, -p),
         (p, 0, -1), (p, 0, 1), (-p, 0, -1), (-p, 0, 1)]
    t = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7),
         (9, 8, 1)]
    v = [np.array(x, float) / np.linalg.norm(x) for x in v]
    for _ in range(levels):
        mid, nt = {}, []

        def m(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                c = v[a] + v[b]
                v.append(c / np.linalg.norm(c))
                mid[key] = len(v) - 1
            return mid[key]

        for a, b, c in t:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            nt += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        t = nt
    return r * np.array(v), np.array(t, dtype=np.int64)


def test_a_large_model_is_decimated_and_its_colours_are_the_means_of_the_points(tmp_path):
    """20,480 triangles shown as at most 2,000: the shown vertices stay near the sphere, and
    points 0.02 mm outside it everywhere colour every shown vertex +0.02 (the mean of the
    points of the vertices it merges), the limit of the colour scale 0.02."""
    v, t = icosphere(25.0, 5)
    assert len(t) == 20_480
    cad_models.write_stl(tmp_path / "sphere.stl", v, t)
    rng = np.random.default_rng(0)
    u = rng.normal(size=(20_000, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    np.savetxt(tmp_path / "scan.xyz", 25.02 * u)
    session = Session(load_scan(tmp_path / "scan.xyz"), None, kind="part")
    session.cad_max_triangles = 2000
    client = TestClient(create_app(session, tmp_path, allowed_hosts=LOOPBACK_HOSTS), base_url="http://127.0.0.1:8765")
    info = client.post("/api/cad", json={"path": "sphere.stl"}).json()
    assert info["decimated"] and 500 < info["shown_triangles"] <= 2000 and info["max_triangles"] == 2000
    res = client.get("/api/cad/mesh")
    nv = int(res.headers["X-Vertex-Count"])
    origin = np.array([float(x) for x in res.headers["X-Origin"].split(",")])
    shown = np.frombuffer(res.content, "<f4", 3 * nv).reshape(-1, 3) + origin
    r = np.linalg.norm(shown, axis=1)
    assert np.all(np.abs(r - 25.0) < 1.0)                     # a cell's mean lies near the surface
    tri, dev = _distances(session)
    # chordal distances: the facets lie up to 25 (1 - cos(edge/2)) inside the sphere
    assert np.all(dev > 0.0) and np.all(dev < 0.02 + 0.02)
    colours = session.cad.colours(tri, dev)
    mean, count = vertex_deviations(session.cad.model, tri, dev)
    want = np.bincount(session.cad.cluster, weights=mean * count, minlength=nv) / np.bincount(session.cad.cluster, weights=count, minlength=nv)
    rgb = np.frombuffer(base64.b64decode(colours["colours"]), np.uint8).reshape(-1, 3)
    np.testing.assert_array_equal(rgb, vertex_rgb(want, np.ones(nv), colour_limit(dev)))
    assert colours["coloured_vertices"] == nv


def test_decimate_leaves_a_small_mesh_alone_and_keeps_its_triangles_outward():
    v, t = icosphere(10.0, 3)
    same = decimate(v, t, MAX_CAD_TRIANGLES)
    assert same[2] is None and same[1] is t or np.array_equal(same[1], t)
    dv, dt, cluster = decimate(v, t, 300)
    assert len(dt) <= 300 and cluster.shape == (len(v),) and cluster.max() < len(dv)
    c = dv[dt]
    n = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
    assert (np.einsum("ij,ij->i", n, c.mean(axis=1)) > 0).mean() > 0.95   # winding kept: normals point out


def test_vertex_deviations_are_the_means_of_the_points_nearest_to_each_vertexs_triangles():
    """A box; 3 points above its top face (z = 1) at +0.1, +0.2, +0.3 mm: the top's 4
    vertices take the mean of the points whose nearest triangle touches them; the rest none."""
    from gagekit.cad.model import CadFace, CadModel

    v, t = cad_models.box((2.0, 1.5, 1.0))
    model = CadModel("box", "stl", "mm", v, t, np.zeros(len(t), np.int64), (CadFace(0, 0, "box"),))
    pts = np.array([[-1.5, -1.0, 1.1], [1.5, 1.0, 1.2], [1.4, 0.9, 1.3]])
    d = model.distances(pts)
    np.testing.assert_allclose(d.distance, [0.1, 0.2, 0.3], atol=1e-12)
    mean, count = vertex_deviations(model, d.triangle, d.distance)
    top = np.flatnonzero(v[:, 2] > 0)
    assert count[v[:, 2] < 0].sum() == 0 and count[top].sum() == 9
    for k in top:
        near = [j for j in range(3) if k in t[d.triangle[j]]]
        assert count[k] == len(near)
        if near:
            assert mean[k] == pytest.approx(np.mean(d.distance[near]), abs=1e-12)
    nan = vertex_deviations(model, np.array([d.triangle[0], -1]), np.array([np.nan, 0.5]))
    assert nan[1].sum() == 0                                               # NaN deviations and no triangle: unused


def test_a_3mf_model_in_the_folder_is_listed_and_served(tmp_path):
    import zipfile

    v, t = cad_models.box((1.0, 1.0, 1.0))
    vs = "".join(f'<vertex x="{a}" y="{b}" z="{c}"/>' for a, b, c in v.tolist())
    ts = "".join(f'<triangle v1="{a}" v2="{b}" v3="{c}"/>' for a, b, c in t.tolist())
    with zipfile.ZipFile(tmp_path / "cube.3mf", "w") as z:
        z.writestr("3D/3dmodel.model", '<model unit="centimeter" xmlns="http://schemas.microsoft.com/3dmanufacturing/'
                   f'core/2015/02"><resources><object id="1" name="cube"><mesh><vertices>{vs}</vertices><triangles>{ts}'
                   '</triangles></mesh></object></resources><build><item objectid="1"/></build></model>')
    np.savetxt(tmp_path / "scan.xyz", np.array([[0.0, 0.0, 10.5], [0.0, 0.0, 11.0], [0.0, 0.0, 9.0]]))
    session = Session(load_scan(tmp_path / "scan.xyz"), None, kind="part")
    client = TestClient(create_app(session, tmp_path, allowed_hosts=LOOPBACK_HOSTS), base_url="http://127.0.0.1:8765")
    assert client.get("/api/files").json()["cads"] == ["cube.3mf"]
    info = client.post("/api/cad", json={"path": "cube.3mf"}).json()
    assert info["format"] == "3mf" and info["unit"] == "cm" and info["triangles"] == 12
    tri, dev = _distances(session)
    np.testing.assert_allclose(dev, [0.5, 1.0, -1.0], atol=1e-12)          # the cube is +-10 mm
