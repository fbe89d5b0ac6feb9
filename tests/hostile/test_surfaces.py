"""The surfaces of issue 22 under hostile input (a sample of ``tests/hostile/surfaces.py``;
``benches/hostile_census.py`` runs them all): inspect, export, compensate-nc, batches,
stats, db - one clean error line or a finite result; the studio's HTTP API - a 4xx JSON
error or a finite JSON answer, never a 500 or a hang, and Ctrl-C stops it afterwards."""

from __future__ import annotations

import json
import os
import shutil

import pytest

from gagekit.samples import data_path

from .conftest import EXAMPLE_MACHINE, check_outcome, gk, gk_inproc
from .surfaces import command_cases, json_mutants, nc_mutants, studio_cases


def test_generators_cover_every_surface(tmp_path, sim):
    groups = {g for g, *_ in command_cases(tmp_path, EXAMPLE_MACHINE, sim / "cal.json", "sqlite:///x.db", quick=True)}
    assert groups == {"inspect: drawing", "inspect: scan", "export", "compensate-nc", "batch", "stats", "db"}
    assert sum(1 for _ in nc_mutants()) > 500
    labels = [label for label, _ in json_mutants({"region": [{"rotation": [0, 0, 0]}]})]
    assert "region.0.rotation=['x', None, {}]" in labels and "region.0.rotation=1180591620717411303424" in labels


def test_new_surfaces_sample(tmp_path, sim):
    """Every 7th command case (about 150): clean error or finite result, in time."""
    db = tmp_path / "stats.db"
    url = f"sqlite:///{db}"
    p = gk("form", "batch", "plane", data_path("casting_ok.ply"), "--db", url, "-w", "1", timeout=300)
    assert p.returncode == 0, p.stderr
    seen = set()
    for k, (group, label, argv, mode) in enumerate(command_cases(tmp_path, EXAMPLE_MACHINE, sim / "cal.json", url,
                                                                 quick=True)):
        if k % 7 and group in seen:
            continue
        seen.add(group)
        what = f"{group}: {label}"
        if mode == "inproc":
            code, out, err = gk_inproc(*argv)
        else:
            proc = gk(*argv, timeout=180)
            code, out, err = proc.returncode, proc.stdout, proc.stderr
        if code == 0 and out.strip() and not out.lstrip().startswith(("{", "[")):
            out = "{}"  # a text answer (an --json-less command): only the exit status and stderr are checked
        if code == 0 and "\n{" in out.strip():  # batches: one JSON line per scan
            assert all(json.loads(ln) for ln in out.splitlines() if ln.strip()), what
            continue
        check_outcome(code, out if out.strip() or code != 0 else "{}", err, what)


def test_studio_http_sample(tmp_path):
    pytest.importorskip("uvicorn")
    from servers import StudioServer

    folder, outside = tmp_path / "studio", tmp_path / "outside"
    folder.mkdir()
    outside.mkdir()
    shutil.copy(data_path("casting_ok.ply"), folder / "casting.ply")
    shutil.copy(data_path("casting_ok.toml"), folder / "casting.toml")
    (outside / "secret.toml").write_text("[motion]\n")
    os.mkfifo(folder / "pipe.toml")
    os.mkfifo(folder / "pipe.ply")
    (folder / "out.ply").symlink_to(data_path("casting_ok.ply"))
    (folder / "outdir").symlink_to(outside, target_is_directory=True)
    server = StudioServer(str(folder / "casting.ply"), str(folder / "casting.toml"))
    try:
        from gagekit.studio.specdoc import parse_text

        gage_doc = server.request("GET", "/api/state")[1]["spec"]["doc"]
        part_doc = parse_text(data_path("bracket.toml").read_text(), "bracket.toml")
        for k, (group, label, method, path, body) in enumerate(studio_cases(gage_doc, part_doc, quick=True)):
            if k % 5 and "bodies" not in group and "paths" not in group:
                continue
            status, data, seconds = server.request(method, path, body, timeout=60)
            assert status < 500, (group, label, status, data)
            if status >= 400:
                assert isinstance(data, dict) and data.get("error"), (group, label, status, data)
        assert server.interrupt(timeout=15) is not None, "Ctrl-C did not stop the studio"
    finally:
        server.stop()


def test_census_findings_are_clean_errors(tmp_path, sim):
    """What the census found: a URL with a bad port or host and one with a NUL (ValueError),
    a calibration whose group leader is not a name (TypeError)."""
    for url in ("postgresql://[::1", "postgresql://u@h:abc/db", "sqlite:///x\x00y.db"):
        for argv in (["stats", "--db", url], ["db", "upgrade", url], ["db", "export", url, "--format", "csv"]):
            code, out, err = gk_inproc(*argv)
            check_outcome(code, out, err, " ".join(argv))
    cal = json.loads((sim / "cal.json").read_text())
    cal["groups"][0]["leader"] = []
    (tmp_path / "cal.json").write_text(json.dumps(cal))
    code, out, err = gk_inproc("machine", "export", EXAMPLE_MACHINE, tmp_path / "cal.json", "--format", "grid-csv",
                               "--out", tmp_path / "t.csv", "--step", "200")
    assert "leader" not in err or "parameter name" in err
    check_outcome(code, out, err, "export with a list as group leader")
