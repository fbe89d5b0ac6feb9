"""`gagekit data list` / `gagekit data path NAME`: the bundled samples the tour runs on
(issue 22 item 1), inside the installed package, never outside it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import gagekit
from gagekit.samples import SAMPLES, sample_path

PACKAGE = Path(gagekit.__file__).resolve().parent


def _run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "gagekit", "data", *args], capture_output=True, text=True, timeout=120)


def test_every_sample_is_a_file_inside_the_package():
    for name in ("round", "bore", "ball", "cone", "program", "machine", "iso230-2", "ballbar", "sphere", "rtest", "sphere-cycles"):
        assert name in SAMPLES
    for name in SAMPLES:
        p = sample_path(name).resolve()
        assert p.is_file() and p.stat().st_size > 0, name
        assert PACKAGE in p.parents, f"{name}: {p} is outside the package"


def test_data_list_and_path():
    p = _run("list", "--json")
    assert p.returncode == 0, p.stderr
    rows = json.loads(p.stdout)["samples"]
    assert [r["name"] for r in rows] == list(SAMPLES)
    assert all(Path(r["path"]).is_file() for r in rows)
    p = _run("path", "round")
    assert p.returncode == 0 and Path(p.stdout.strip()) == sample_path("round") and p.stdout.count("\n") == 1


def test_unknown_sample_is_one_error_line():
    p = _run("path", "no-such-sample")
    assert p.returncode == 2 and p.stdout == ""
    assert p.stderr.startswith("gagekit: error: no bundled sample named 'no-such-sample'") and p.stderr.count("\n") == 1
    assert "round" in p.stderr  # it names the samples there are


def test_samples_match_their_generator(tmp_path, monkeypatch):
    """The bundled form samples are what make_form_samples.py writes (deterministic)."""
    from gagekit.data import make_form_samples as gen

    monkeypatch.setattr(gen, "HERE", tmp_path)
    gen.main()
    for f in ("round.csv", "bore.csv", "ball.csv", "cone.csv", "program.nc"):
        assert (tmp_path / f).read_bytes() == (PACKAGE / "data" / f).read_bytes(), f


def test_instrument_samples_match_their_generator(tmp_path, monkeypatch):
    """The bundled ballbar, sphere, R-test and probing-cycle samples are what
    make_instrument_samples.py writes (deterministic)."""
    from gagekit.data import make_instrument_samples as gen

    monkeypatch.setattr(gen, "HERE", tmp_path)
    gen.main()
    for name in ("ballbar", "sphere", "rtest", "sphere-cycles"):
        f = sample_path(name).name
        assert (tmp_path / f).read_bytes() == sample_path(name).read_bytes(), f


def test_grr_sample_matches_its_generator(tmp_path):
    """The bundled gage R&R study is what make_grr_sample.py writes (deterministic)."""
    from gagekit.data import make_grr_sample as gen

    gen.main(tmp_path)
    assert (tmp_path / "grr_study.csv").read_bytes() == sample_path("grr-study").read_bytes()


def test_roundness_samples_match_their_generator(tmp_path):
    """The bundled roundness and straightness traces are what make_roundness_samples.py writes."""
    from gagekit.data import make_roundness_samples as gen

    gen.main(tmp_path)
    assert (tmp_path / "roundness_profile.csv").read_bytes() == sample_path("roundness").read_bytes()
    assert (tmp_path / "straightness_profile.csv").read_bytes() == sample_path("straightness").read_bytes()
