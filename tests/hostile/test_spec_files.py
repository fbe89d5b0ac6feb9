"""Broken TOML for every spec type: machine, gage, regions, zones, exclusions.

Every single-key mutation of a valid file (deleted, or replaced by one of
``mutants.HOSTILE_VALUES``), whole-file damage and non-regular paths. Each case ends in a
clean error line (exit 2) or a finite JSON result. The suite runs every 7th key mutation
(all damage cases); ``benches/hostile_census.py`` runs them all."""

from __future__ import annotations

from pathlib import Path

import pytest

from gagekit.cloud import read_points, write_points

from .conftest import CASTING_PLY, CASTING_TOML, EXAMPLE_MACHINE, check_outcome, gk, gk_inproc
from .mutants import damaged, mutants, spec_commands, special_paths

STRIDE = 7


@pytest.fixture(scope="module")
def small_cloud(tmp_path_factory) -> Path:
    """Every 10th point of the bundled casting (the gage checks stay fast)."""
    p = tmp_path_factory.mktemp("cloud") / "casting.npy"
    write_points(p, read_points(CASTING_PLY)[::10])
    return p


def specs(tmp: Path, cloud: Path) -> dict:
    return spec_commands(tmp, EXAMPLE_MACHINE, CASTING_TOML, cloud)


def cases(kind: str, valid: Path, stride: int):
    yield from damaged(valid)
    for k, case in enumerate(mutants(valid)):
        if k % stride == 0:
            yield case


@pytest.mark.parametrize("kind", ["machine", "gage", "regions", "zones", "exclusions"])
def test_broken_spec_files(kind, tmp_path, small_cloud):
    valid, argv = specs(tmp_path, small_cloud)[kind]
    f = tmp_path / f"case{Path(valid).suffix}"
    tally = {"clean": 0, "ok": 0}
    for label, data in cases(kind, Path(valid), STRIDE):
        f.write_bytes(data)
        code, out, err = gk_inproc(*[f if a == "SPEC" else a for a in argv])
        tally[check_outcome(code, out, err, f"{kind}: {label}")] += 1
    assert tally["clean"] > 10, tally
    # the valid file itself gives a result
    code, out, err = gk_inproc(*[valid if a == "SPEC" else a for a in argv])
    assert check_outcome(code, out, err, f"{kind}: valid") == "ok"


@pytest.mark.parametrize("kind", ["machine", "gage", "regions", "zones", "exclusions"])
def test_special_paths_never_hang(kind, tmp_path, small_cloud):
    """A missing file, a folder and a FIFO (which would block a reader forever)."""
    _, argv = specs(tmp_path, small_cloud)[kind]
    for label, p in special_paths(tmp_path):
        proc = gk(*[p if a == "SPEC" else a for a in argv], timeout=60)
        check_outcome(proc.returncode, proc.stdout, proc.stderr, f"{kind}: {label}")
        assert proc.returncode == 2
