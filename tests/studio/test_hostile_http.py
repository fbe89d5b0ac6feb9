"""The studio as a real server (uvicorn on 127.0.0.1, `gagekit studio` in a child process)
against hostile requests (issue 22, sections 3 and 6): a FIFO, JSON nested 100,000 deep, a
lone surrogate, integers of 2^70, a rotation of ["x", null, {}] - each a 4xx JSON error,
never a 500 and never a blocked server; Ctrl-C stops it afterwards. Every address needs
the access token (as Jupyter does) and the browser opens the tokenised address;
/api/files lists no symlink that leads outside the folder."""

import json
import os
import shutil
import sys
import time
from pathlib import Path

import pytest

from gagekit.samples import data_path
from servers import StudioServer, assert_4xx, body

pytest.importorskip("uvicorn", reason="the studio extra (uvicorn, starlette) is needed")


@pytest.fixture()
def casting(tmp_path):
    folder = tmp_path / "studio"
    folder.mkdir()
    shutil.copy(data_path("casting_ok.ply"), folder / "casting.ply")
    shutil.copy(data_path("casting_ok.toml"), folder / "casting.toml")
    return folder


@pytest.fixture()
def bracket(tmp_path):
    folder = tmp_path / "bracket"
    folder.mkdir()
    shutil.copy(data_path("bracket.ply"), folder / "bracket.ply")
    shutil.copy(data_path("bracket.toml"), folder / "bracket.toml")
    return folder


def test_a_fifo_neither_blocks_the_server_nor_ctrl_c(casting):
    os.mkfifo(casting / "pipe.toml")
    os.mkfifo(casting / "pipe.ply")
    studio = StudioServer(str(casting / "casting.ply"), str(casting / "casting.toml"))
    try:
        assert_4xx(studio.request("POST", "/api/spec", body({"path": "pipe.toml"}), timeout=20), "FIFO")
        assert_4xx(studio.request("POST", "/api/spec", body({"path": "pipe.toml", "kind": "part"}), timeout=20), "FIFO")
        assert_4xx(studio.request("POST", "/api/scan", body({"path": "pipe.ply"}), timeout=20), "FIFO")
        status, state, _ = studio.request("GET", "/api/state", timeout=20)
        assert status == 200 and state["spec"]["name"] == "casting.toml"   # still serving, the spec unchanged
        assert studio.interrupt(timeout=15) is not None, "Ctrl-C did not stop the studio"
    finally:
        studio.stop()


def test_hostile_json_is_a_4xx_json_error_never_a_500(bracket):
    studio = StudioServer(str(bracket / "bracket.ply"), str(bracket / "bracket.toml"))
    try:
        status, state, _ = studio.request("GET", "/api/state")
        assert status == 200
        doc = state["spec"]["doc"]
        deep = b'{"doc": ' + b"[" * 100_000 + b"]" * 100_000 + b"}"
        for path in ("/api/run", "/api/regions", "/api/save", "/api/select", "/api/spec", "/api/scan"):
            assert_4xx(studio.request("POST", path, deep), "deep")
            assert_4xx(studio.request("POST", path, b'{"path": "\\ud800.toml", "doc": {"a": "\\udfff"}}'))
        assert_4xx(studio.request("POST", "/api/scan", b'{"path": "\\ud800.ply"}'), "Unicode")
        assert_4xx(studio.request("POST", "/api/spec", b'{"path": "x\\udc80.toml"}'), "Unicode")
        assert_4xx(studio.request("POST", "/api/save", b'{"doc": {"part": {"name": "\\ud800"}}, "path": "x.toml"}'),
                   "Unicode")
        for where in ("part", "feature", "tolerance"):
            for n in (2 ** 70, 10 ** 9, 2 ** 63 - 1):
                d = json.loads(json.dumps(doc))
                if where == "part":
                    d["part"]["sections"] = n
                else:
                    d[where][0]["sections"] = n
                assert_4xx(studio.request("POST", "/api/run", body({"doc": d}), timeout=60), "sections")
        region = {"center": [0, 0, 0], "size": [1, 1, 1], "rotation": ["x", None, {}]}
        assert_4xx(studio.request("POST", "/api/select", body({"region": region})), "rotation")
        d = json.loads(json.dumps(doc))
        d["feature"][0]["region"]["rotation"] = ["x", None, {}]
        assert_4xx(studio.request("POST", "/api/run", body({"doc": d})), "rotation")
        status, res, _ = studio.request("POST", "/api/regions", body({"doc": d}))
        assert status == 200 and "rotation" in res["regions"][0]["error"]
        for bad in ({"center": ["x", None, {}], "size": [1, 1, 1]}, {"center": [0, 0, 0], "size": [2 ** 70, 1, 1]},
                    {"center": [0, 0, 0], "size": [1, 1, 1e999]}, [], "x", None):
            assert_4xx(studio.request("POST", "/api/select", body({"region": bad})))
        # a finite rotation vector of any length is a rotation (its angle taken modulo 2 pi): answered
        huge = {"center": [0, 0, 0], "size": [1, 1, 1], "rotation": [1e308, 1e308, 1e308]}
        assert studio.request("POST", "/api/select", body({"region": huge}))[0] == 200
        status, state, _ = studio.request("GET", "/api/state")
        assert status == 200
    finally:
        studio.stop()


def test_a_gage_document_with_a_bad_rotation_is_a_4xx(casting):
    studio = StudioServer(str(casting / "casting.ply"), str(casting / "casting.toml"))
    try:
        doc = studio.request("GET", "/api/state")[1]["spec"]["doc"]
        doc["region"][0]["rotation"] = ["x", None, {}]
        assert_4xx(studio.request("POST", "/api/run", body({"doc": doc})), "rotation")
        status, res, _ = studio.request("POST", "/api/regions", body({"doc": doc}))
        assert status == 200 and "rotation" in res["regions"][0]["error"]
        doc["motion"]["max_shift"] = 2 ** 70
        assert_4xx(studio.request("POST", "/api/run", body({"doc": doc})))
        # found by the census: datum names and region names that are not names (were HTTP 500)
        doc = studio.request("GET", "/api/state")[1]["spec"]["doc"]
        for change in ({"alignment": dict(doc["alignment"], secondary=["x", None, {}])},
                       {"region": [dict(doc["region"][0], name=[0, 0])] + doc["region"][1:]}):
            status, res, _ = studio.request("POST", "/api/regions", body({"doc": dict(doc, **change)}))
            assert status < 500, (change, status, res)
    finally:
        studio.stop()


def test_every_address_needs_the_token_and_the_browser_opens_the_tokenised_url(casting, tmp_path):
    seen = tmp_path / "opened.txt"
    recorder = tmp_path / "browser.py"
    # written beside and renamed: the file appears whole (open(..., 'w') creates it empty
    # before the URL is written, and the wait below could read it in between)
    recorder.write_text("import os, sys\nopen(sys.argv[1] + '.part', 'w').write(sys.argv[2])\n"
                        "os.replace(sys.argv[1] + '.part', sys.argv[1])\n")
    env = dict(os.environ, BROWSER=f"{sys.executable} {recorder} {seen} %s")
    studio = StudioServer(str(casting / "casting.ply"), env=env, browser=True)
    try:
        assert studio.token and studio.url == f"{studio.base}?token={studio.token}"
        assert studio.base.startswith("http://127.0.0.1:")
        for path in ("/", "/api/state", "/api/files", "/api/scan/points", "/static/studio.js"):
            status, data, _ = studio.request("GET", path, token=False)
            assert status == 401 and "token" in data["error"], path
        assert_4xx(studio.request("POST", "/api/run", body({"doc": {}}), token=False), "token")
        assert studio.request("GET", "/api/state")[0] == 200
        # the page loaded with ?token= sets a cookie that the page's own requests then carry
        import http.cookiejar
        import urllib.request

        jar = http.cookiejar.CookieJar()
        opener = urllib.request.build_opener(urllib.request.HTTPCookieProcessor(jar))
        assert opener.open(studio.url, timeout=20).status == 200
        assert [c.name for c in jar] and all(c.value == studio.token for c in jar)
        assert opener.open(studio.base + "api/state", timeout=20).status == 200
        deadline = time.monotonic() + 30
        while not seen.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        assert seen.read_text() == studio.url
    finally:
        studio.stop()


def test_files_lists_no_symlink_leading_outside_the_folder(casting, tmp_path):
    outside = tmp_path / "outside"
    outside.mkdir()
    shutil.copy(data_path("casting_ok.ply"), outside / "secret.ply")
    (outside / "secret.toml").write_text("[motion]\n")
    (casting / "link.ply").symlink_to(outside / "secret.ply")
    (casting / "link.toml").symlink_to(outside / "secret.toml")
    (casting / "linkdir").symlink_to(outside, target_is_directory=True)
    (casting / "inside.ply").symlink_to(casting / "casting.ply")  # stays inside: listed
    (casting / "sub").mkdir()
    (casting / "sub" / "up.toml").symlink_to(casting / "casting.toml")
    studio = StudioServer(str(casting / "casting.ply"))
    try:
        status, files, _ = studio.request("GET", "/api/files")
        assert status == 200
        assert files == {"scans": ["casting.ply", "inside.ply"], "specs": ["casting.toml", "sub/up.toml"], "cads": []}
        assert_4xx(studio.request("POST", "/api/scan", body({"path": "link.ply"})), "outside")
        assert_4xx(studio.request("POST", "/api/spec", body({"path": "linkdir/secret.toml"})), "outside")
    finally:
        studio.stop()
