"""The studio on a drawing (PART.toml): feature regions counted, the inspection run on the
server through gagekit.inspect, deviations per shown point, the drawing saved in the format
`gagekit inspect` reads (byte-identical when unchanged), errors located by table."""

import base64
import copy
import shutil

import numpy as np
import pytest
from starlette.testclient import TestClient

import gagekit
from gagekit.cloud.regions import select
from gagekit.samples import data_path
from gagekit.inspect import inspect, load_part_spec
from gagekit.studio import app as studio_app
from gagekit.studio.app import create_app
from gagekit.studio.session import Session, load_scan

BRACKET = data_path("bracket.ply")
DRAWING = data_path("bracket.toml")


@pytest.fixture()
def folder(tmp_path):
    shutil.copy(BRACKET, tmp_path / "bracket.ply")
    shutil.copy(DRAWING, tmp_path / "bracket.toml")
    return tmp_path


@pytest.fixture()
def session(folder):
    return Session(load_scan(folder / "bracket.ply", lod_max=10_000), folder / "bracket.toml", lod_max=10_000)


@pytest.fixture()
def client(folder, session):
    return TestClient(create_app(session, folder, allowed_hosts=studio_app.LOOPBACK_HOSTS), base_url="http://127.0.0.1:8765")


def doc_of(client):
    return client.get("/api/state").json()["spec"]["doc"]


def test_state_says_drawing_and_lists_the_characteristics(client):
    st = client.get("/api/state").json()
    assert st["spec"]["kind"] == "part" and st["spec"]["validation"]["valid"]
    assert [f["name"] for f in st["spec"]["doc"]["feature"]][:3] == ["A", "B", "C"]
    from gagekit.inspect import SHAPES

    assert st["inspection"]["shapes"] == list(SHAPES)
    assert "position" in st["inspection"]["applies_to"] and "plane" in st["inspection"]["applies_to"]["flatness"]


def test_feature_regions_are_counted_over_all_points(client, session):
    body = client.post("/api/regions", json={"doc": doc_of(client)}).json()
    spec = load_part_spec(DRAWING)
    pts = gagekit.read_points(BRACKET)
    assert [r["name"] for r in body["regions"]] == list(spec.features)
    for r in body["regions"]:
        assert r["count"] == len(select(pts, spec.features[r["name"]].region)) > 0
    assert body["alignment"] is None and body["validation"]["valid"]
    one = client.post("/api/select", json={"region": {**doc_of(client)["feature"][5]["region"], "frame": "scanner"}}).json()
    assert one["count"] == body["regions"][5]["count"]


def test_inspection_runs_on_the_server_as_the_library_does(client, session):
    res = client.post("/api/run", json={"doc": doc_of(client)})
    assert res.status_code == 200
    body = res.json()
    pts = gagekit.read_points(BRACKET)
    want = inspect(pts, load_part_spec(DRAWING))
    got = body["result"]
    assert body["kind"] == "part" and got["status"] == want.status == "nonconforming"
    assert [(t["feature"], t["characteristic"], t["measured"]) for t in got["tolerances"]] == \
           [(t.feature, t.characteristic, t.measured) for t in want.tolerances]
    # each shown point of a feature carries its deviation from that feature's fit
    values = np.frombuffer(base64.b64decode(body["values"]), dtype="<f4")
    lod = session.scan.lod
    assert len(values) == len(lod)
    fd = want.feature_data["top"]
    shown = np.isin(fd.indices, lod)
    assert shown.sum() > 10
    pos = np.searchsorted(lod, fd.indices[shown])
    np.testing.assert_allclose(values[pos], fd.deviations()[shown], atol=1e-6)
    in_any = np.zeros(len(pts), bool)
    for f in want.feature_data.values():
        in_any[f.indices] = True
    assert np.isfinite(values).sum() == in_any[lod].sum()
    assert body["value_range"][0] <= values[np.isfinite(values)].min() + 1e-6


def test_drawing_round_trip_and_edits_read_back_in_gagekit_inspect(client, folder):
    original = (folder / "bracket.toml").read_bytes()
    res = client.post("/api/save", json={"doc": doc_of(client)}).json()
    assert res["unchanged"] and (folder / "bracket.toml").read_bytes() == original
    doc = doc_of(client)
    edited = copy.deepcopy(doc)
    edited["tolerance"][0]["tolerance"] = 0.02                             # flatness of A
    edited["feature"].append({"name": "pad", "shape": "plane", "outward": [0.0, 0.0, 1.0],
                              "region": {"center": [50.0, 40.0, 40.0], "size": [20.0, 20.0, 1.0]}})
    edited["datums"]["P"] = "pad"
    edited["tolerance"].append({"feature": "pad", "characteristic": "parallelism", "tolerance": 0.05, "datums": ["A"]})
    res = client.post("/api/save", json={"doc": edited, "path": "edited.toml"})
    assert res.status_code == 200 and res.json()["validation"]["valid"]
    text = (folder / "edited.toml").read_text()
    old = original.decode()
    assert text.startswith(old.split("[[feature]]")[0])                     # untouched text kept as it was
    assert "region = {center = [50.0, 40.0, 40.0]" in text.split('name = "pad"')[1]  # inline, as drawings have it
    spec = load_part_spec(folder / "edited.toml")
    assert spec.features["pad"].region.size == (20.0, 20.0, 1.0) and spec.tolerances[0].tolerance == 0.02
    result = inspect(gagekit.read_points(BRACKET), spec)
    pad = next(t for t in result.tolerances if t.feature == "pad")
    top = next(t for t in result.tolerances if t.characteristic == "parallelism" and t.feature == "top")
    # the top is sloped along x: over the pad's 20 mm it rises 20/98 of its 98 mm rise
    assert pad.characteristic == "parallelism" and pad.measured == pytest.approx(top.measured * 20 / 98, rel=0.02)


def test_drawing_errors_are_shown_next_to_their_table(client):
    doc = doc_of(client)
    doc["tolerance"][2]["characteristic"] = "roundness"                    # of a plane
    res = client.post("/api/run", json={"doc": doc})
    assert res.status_code == 422
    err = res.json()["errors"][0]
    assert err["table"] == "tolerance" and err["index"] == 3 and "does not apply" in err["message"]
    doc = doc_of(client)
    del doc["feature"][0]["outward"]
    err = client.post("/api/regions", json={"doc": doc}).json()["validation"]["errors"][0]
    assert err["table"] == "feature" and err["index"] == 1 and "outward" in err["message"]


def test_a_new_drawing_and_a_bad_kind(client, folder):
    spec = client.post("/api/spec", json={"path": "new_part.toml", "kind": "part"}).json()
    assert spec["kind"] == "part" and spec["exists"] is False and spec["doc"] == {"part": {"name": "new_part"}}
    assert spec["validation"]["errors"][0]["table"] == "feature"
    res = client.post("/api/spec", json={"path": "x.toml", "kind": "drawing"})
    assert res.status_code == 400 and "kind" in res.json()["error"]
