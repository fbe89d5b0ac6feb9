"""Every endpoint of the studio server, and the bad requests it must refuse with a 4xx
message while it keeps serving."""

import base64
import shutil

import numpy as np
import pytest
from starlette.testclient import TestClient

import gagekit
from gagekit.cloud.regions import Box
from gagekit.studio import app as studio_app
from gagekit.studio.app import create_app
from gagekit.studio.session import Session, load_scan

from gagekit.samples import data_path

CASTING = data_path("casting_ok.ply")
CASTING_SPEC = data_path("casting_ok.toml")


@pytest.fixture()
def folder(tmp_path):
    shutil.copy(CASTING, tmp_path / "casting.ply")
    shutil.copy(CASTING_SPEC, tmp_path / "casting.toml")
    (tmp_path / "sub").mkdir()
    return tmp_path


@pytest.fixture()
def session(folder):
    return Session(load_scan(folder / "casting.ply", lod_max=50_000), folder / "casting.toml", lod_max=50_000)


@pytest.fixture()
def client(folder, session):
    return TestClient(create_app(session, folder, allowed_hosts=studio_app.LOOPBACK_HOSTS), base_url="http://127.0.0.1:8765")


def doc_of(client):
    return client.get("/api/state").json()["spec"]["doc"]


def test_page_and_client_files_are_served(client):
    r = client.get("/")
    assert r.status_code == 200 and "<script type=\"module\" src=\"/static/studio.js\">" in r.text
    for f in ("studio.js", "view.js", "api.js", "studio.css", "vendor/three/build/three.module.js",
              "vendor/three/examples/jsm/controls/TransformControls.js", "vendor/three/LICENSE"):
        assert client.get(f"/static/{f}").status_code == 200, f
    assert client.get("/static/../session.py").status_code == 404
    assert client.get("/static/%2e%2e/session.py").status_code == 404


def test_state_and_lod_points(client, session):
    st = client.get("/api/state").json()
    assert st["scan"]["count"] == len(gagekit.read_points(CASTING)) == 120929
    assert st["scan"]["lod_count"] == 50_000
    assert st["spec"]["validation"] == {"valid": True, "errors": [], "warnings": []}
    assert [r["name"] for r in st["spec"]["doc"]["region"]][:3] == ["Z1", "Z2", "Z3"]
    r = client.get("/api/scan/points")
    assert r.headers["content-type"] == "application/octet-stream" and r.headers["x-point-count"] == "50000"
    xyz = np.frombuffer(r.content, dtype="<f4").reshape(-1, 3) + np.array(st["scan"]["origin"])
    full = session.scan.points
    np.testing.assert_allclose(xyz, full[session.scan.lod], atol=1e-4)
    # the subsample is fixed: a second load shows the same points
    assert np.array_equal(load_scan(CASTING, lod_max=50_000).lod, session.scan.lod)


def test_regions_counts_and_alignment(client, session):
    doc = doc_of(client)
    res = client.post("/api/regions", json={"doc": doc}).json()
    spec = gagekit.GageSpec.from_dict(doc)
    al = gagekit.gage.datum_alignment(session.scan.points, spec)
    want = {r.name: len(gagekit.select(session.scan.points, gagekit.gage.region_in_scanner(r, al))) for r in spec.regions}
    assert {r["name"]: r["count"] for r in res["regions"]} == want
    np.testing.assert_allclose(res["alignment"]["H"], al.H)
    assert res["validation"]["valid"]
    doc["region"][0]["size"] = [0, 1, 1]
    res = client.post("/api/regions", json={"doc": doc}).json()
    assert res["regions"][0]["count"] is None and "size along its x axis" in res["regions"][0]["error"]
    assert res["validation"]["errors"][0]["table"] == "region" and res["validation"]["errors"][0]["name"] == "Z1"


def test_select_counts_all_points_and_masks_the_shown_ones(client, session):
    client.post("/api/regions", json={"doc": doc_of(client)})          # finds the alignment
    table = {"center": [50.0, 80.0, 110.4], "size": [80.0, 24.0, 12.0], "rotation": [0, 0, 0], "frame": "part"}
    res = client.post("/api/select", json={"region": table}).json()
    box = gagekit.gage.region_in_scanner(gagekit.gage.Region(Box(table["center"], table["size"]), "part"), session.alignment)
    inside = gagekit.select(session.scan.points, box)
    assert res["count"] == len(inside) == 3084
    # 3084 of 120929 points inside, about 1300 of the 50000 shown: sent as their positions
    assert "mask" not in res
    shown = np.frombuffer(base64.b64decode(res["indices"]), dtype="<u4")
    assert res["lod_count"] == len(shown)
    assert np.array_equal(session.scan.lod[shown], np.intersect1d(session.scan.lod, inside))
    scanner = {"center": [414.327902, -205.123776, 65.868523], "size": [14, 14, 3], "rotation": [0.03, -0.02, 0.55],
               "frame": "scanner"}
    assert client.post("/api/select", json={"region": scanner}).json()["count"] == 852
    # a box holding most of the scan: a bit mask is smaller than the positions
    big = client.post("/api/select", json={"region": {"center": [400, -150, 130], "size": [1e3, 1e3, 1e3],
                                                      "frame": "scanner"}}).json()
    mask = np.unpackbits(np.frombuffer(base64.b64decode(big["mask"]), dtype=np.uint8), bitorder="little")
    assert "indices" not in big and big["count"] == 120929 and mask[: len(session.scan.lod)].all()


def test_run_matches_the_library_and_colours_every_gage_point(client, session):
    doc = doc_of(client)
    res = client.post("/api/run", json={"doc": doc})
    assert res.status_code == 200
    body = res.json()
    want = gagekit.check_gages(gagekit.read_points(CASTING), CASTING_SPEC)
    assert body["result"]["status"] == want.status
    for got, g in zip(body["result"]["gages"], want.gages):
        assert got["name"] == g.name and got["allowance_after"] == pytest.approx(g.allowance_after, abs=1e-9)
    values = np.frombuffer(base64.b64decode(body["values"]), dtype="<f4")
    assert len(values) == len(session.scan.lod) and np.isfinite(values).sum() > 1000
    # every coloured value is a distance at T*: none is below the smallest allowance after T*
    assert values[np.isfinite(values)].min() >= min(g.allowance_after for g in want.gages) - 1e-4
    view = np.array(body["view_matrix"])
    np.testing.assert_allclose(view, want.transform.as_array() @ want.alignment.H, atol=1e-9)


def test_run_reports_spec_errors_next_to_their_table(client):
    doc = doc_of(client)
    doc["gage"][0]["region"] = "nowhere"
    res = client.post("/api/run", json={"doc": doc})
    assert res.status_code == 422
    err = res.json()["errors"][0]
    assert err["table"] == "gage" and err["name"] == "top of flange min" and "unknown region" in err["message"]
    doc = doc_of(client)
    doc["region"][7]["center"] = [1e4, 0, 0]                      # flange_top far away: catches no points
    res = client.post("/api/run", json={"doc": doc})
    assert res.status_code == 422 and res.json()["errors"][0]["table"] == "region"
    assert "catches no points" in res.json()["error"]


def test_save_round_trip_is_byte_identical_and_edits_are_atomic(client, folder):
    original = (folder / "casting.toml").read_bytes()
    res = client.post("/api/save", json={"doc": doc_of(client)}).json()
    assert res["unchanged"] and (folder / "casting.toml").read_bytes() == original
    doc = doc_of(client)
    doc["motion"]["max_shift"] = 12.5
    res = client.post("/api/save", json={"doc": doc, "path": "sub/edited.toml"})
    assert res.status_code == 200 and res.json()["validation"]["valid"]
    text = (folder / "sub" / "edited.toml").read_text()
    assert "max_shift = 12.5" in text and gagekit.GageSpec.load(folder / "sub" / "edited.toml").motion.max_shift == 12.5
    assert not [p for p in folder.rglob("*tmp*")]
    assert (folder / "casting.toml").read_bytes() == original
    # the saved file reads as gage check reads it
    assert gagekit.check_gages(gagekit.read_points(CASTING), folder / "sub" / "edited.toml").status == "conforming"


def test_open_scan_spec_and_list_files(client, folder):
    files = client.get("/api/files").json()
    assert files == {"scans": ["casting.ply"], "specs": ["casting.toml"], "cads": []}
    pts = gagekit.read_points(CASTING)[:5000]
    gagekit.write_points(folder / "sub" / "small.ply", pts)
    info = client.post("/api/scan", json={"path": "sub/small.ply"}).json()
    assert info["count"] == 5000 and client.get("/api/state").json()["scan"]["count"] == 5000
    spec = client.post("/api/spec", json={"path": "sub/new.toml"}).json()
    assert spec["exists"] is False and spec["validation"]["errors"][0]["table"] == "gage"


@pytest.mark.parametrize("path", ["../outside.toml", "/etc/passwd.toml", "sub/../../x.toml", "..", "", 5, None,
                                  "a\x00b.toml"])
def test_paths_outside_the_folder_are_refused(client, path):
    for url, body in (("/api/save", {"doc": {"gage": []}, "path": path}), ("/api/spec", {"path": path}),
                      ("/api/scan", {"path": path})):
        if url == "/api/save" and path in ("", None):
            continue
        r = client.post(url, json=body)
        assert r.status_code in (400, 403), (url, path, r.status_code)
        assert r.json()["error"]
    assert client.get("/api/state").status_code == 200


def test_symlink_out_of_the_folder_is_refused(client, folder, tmp_path_factory):
    outside = tmp_path_factory.mktemp("outside")
    (folder / "link").symlink_to(outside, target_is_directory=True)
    r = client.post("/api/save", json={"doc": {"gage": []}, "path": "link/evil.toml"})
    assert r.status_code == 403 and not (outside / "evil.toml").exists()


def test_malformed_oversized_and_wrong_requests(client):
    bad = [
        (dict(content=b"{not json", headers={"content-type": "application/json"}), 400, "malformed JSON"),
        (dict(content=b"[1, 2]", headers={"content-type": "application/json"}), 400, "JSON object"),
        (dict(content=b'{"doc": NaN}', headers={"content-type": "application/json"}), 400, "malformed JSON"),
        (dict(content=b"\xff\xfe", headers={"content-type": "application/json"}), 400, "malformed JSON"),
        (dict(content=b"{}", headers={"content-type": "text/plain"}), 415, "application/json"),
        (dict(content=b"{" + b" " * (studio_app.MAX_BODY + 10) + b"}", headers={"content-type": "application/json"}),
         413, "larger"),
        (dict(json={"doc": "not a table"}), 400, "doc"),
        (dict(json={"doc": {}, "groups": "yes"}), 400, "groups"),
    ]
    for kwargs, status, words in bad:
        r = client.post("/api/run", **kwargs)
        assert r.status_code == status, (kwargs.get("content", b"")[:20], r.status_code, r.text[:200])
        assert words in r.json()["error"]
    for region in (None, {"center": [0, 0, 0]}, {"center": [0, 0, 0], "size": [1, -1, 1]},
                   {"center": ["a", 0, 0], "size": [1, 1, 1]}, {"center": [0, 0, 0], "size": [1, 1, 1], "frame": "x"}):
        r = client.post("/api/select", json={"region": region})
        assert 400 <= r.status_code < 500 and r.json()["error"], region
    assert client.get("/api/nothing").status_code == 404
    assert client.get("/api/run").status_code == 405
    assert client.get("/api/state").status_code == 200                 # still serving


def test_loopback_server_refuses_foreign_host_headers(client):
    assert client.get("/api/state", headers={"host": "evil.example:8765"}).status_code == 400
    assert client.get("/api/state", headers={"host": "localhost:8765"}).status_code == 200


def test_token_is_required_when_listening_elsewhere(folder, session):
    app = create_app(session, folder, token="s3cret-token")
    c = TestClient(app, base_url="http://192.0.2.10:8765")
    assert c.get("/api/state").status_code == 401
    assert c.get("/static/studio.js").status_code == 401
    assert c.get("/api/state", headers={"x-studio-token": "wrong"}).status_code == 401
    assert c.get("/api/state", headers={"x-studio-token": "s3cret-token"}).status_code == 200
    r = c.get("/?token=s3cret-token")
    assert r.status_code == 200 and "HttpOnly" in r.headers["set-cookie"]
    assert c.get("/api/state").status_code == 200                        # the cookie carries it now
