"""`gagekit inspect batch`: the same JSON as `gagekit inspect` per scan, callouts stored
with their feature, datum frame and zone, SPC over the drawing's tolerances, on local
workers and on a real Dask LocalCluster into a real PostgreSQL."""

import json
import os
import shutil

import numpy as np
import pytest
import sqlalchemy as sa

import gagekit
from gagekit.samples import data_path
from gagekit.store import models as m
from gagekit.store.schema import create_engine

from test_batch import gk, lines

N = 3


@pytest.fixture(scope="module")
def brackets(tmp_path_factory):
    """(PART.toml, [scans]): the bundled bracket, then machined again with its top face
    raised by 1, 2... micrometres (flatness stays 0, the profile of the top grows)."""
    root = tmp_path_factory.mktemp("brackets")
    part = root / "bracket.toml"
    shutil.copy(data_path("bracket.toml"), part)
    base = gagekit.read_points(data_path("bracket.ply"))
    top = (np.abs(base[:, 2] - 40.0) < 0.3) & (base[:, 0] > 0.5)  # the top face (z = 40 + its slope), x in [1, 99]
    scans = []
    for k in range(N):
        pts = base.copy()
        pts[top & (pts[:, 0] < 99.5), 2] += 0.001 * k
        p = root / "scans" / f"bracket_{k}.ply"
        p.parent.mkdir(exist_ok=True)
        gagekit.write_points(p, pts)
        t = 1_700_000_000 + 3600 * k
        os.utime(p, (t, t))
        scans.append(p)
    return part, scans


def without_seconds(result: dict) -> dict:
    return {k: v for k, v in result.items() if k != "seconds"}


def callouts(url: str) -> list:
    engine = create_engine(url)
    t = m.InspectionResult.__table__
    with engine.connect() as conn:
        rows = [dict(r._mapping) for r in conn.execute(sa.select(t.c.result_id, t.c.tolerance, t.c.characteristic, t.c.value,
                                                                 t.c.upper, t.c.feature, t.c.datums, t.c.zone, t.c.n_points))]
    engine.dispose()
    return rows


def test_inspect_batch_gives_the_inspect_json_stores_callouts_and_restarts(brackets, tmp_path):
    part, scans = brackets
    folder = tmp_path / "scans"
    shutil.copytree(scans[0].parent, folder)
    shutil.copy(folder / scans[0].name, folder / "copy_of_0.ply")  # one content, two paths
    (folder / "broken.ply").write_bytes(b"ply\nformat nonsense\n")
    url = f"sqlite:///{tmp_path / 'r.db'}"
    got, summary = lines(gk("inspect", "batch", part, folder, "--db", url, "--json", "-w", "2"))
    assert summary == {"scans": N + 2, "ok": N + 1, "failed": 1, "skipped": 0}
    by = {os.path.basename(d["scan"]): d for d in got}
    assert by["broken.ply"]["status"] == "error" and "broken.ply" in by["broken.ply"]["error"]
    single = json.loads(gk("inspect", folder / scans[2].name, part, "--json").stdout)
    assert without_seconds(by[scans[2].name]["result"]) == without_seconds(single)
    assert by["copy_of_0.ply"]["result"] == by[scans[0].name]["result"]  # evaluated once
    profile = [next(t["measured"] for t in by[s.name]["result"]["tolerances"] if t["characteristic"] == "profile")
               for s in scans]
    assert profile[1] > profile[0] and profile[2] > profile[1]

    rows = callouts(url)
    n_callouts = len(single["tolerances"])
    assert len(rows) == N * n_callouts
    pos = [r for r in rows if r["tolerance"] == "position of bore |A|B|C|"]
    assert len(pos) == N and {r["feature"] for r in pos} == {"bore"} and {r["zone"] for r in pos} == {"diameter"}
    want = next(t for t in single["tolerances"] if t["characteristic"] == "position" and t["feature"] == "bore")
    assert want["measured"] in {r["value"] for r in pos} and {r["upper"] for r in pos} == {want["tolerance"]}
    assert {r["datums"] for r in rows if r["characteristic"] == "flatness"} == {""}

    # run again: everything skipped, nothing stored twice
    _, again = lines(gk("inspect", "batch", part, folder, "--db", url, "--json"))
    assert again == {"scans": N + 2, "ok": 0, "failed": 0, "skipped": N + 2}
    assert len(callouts(url)) == N * n_callouts

    # SPC over the drawing's tolerances
    stats = json.loads(gk("stats", "--db", url, "--spec", part, "--json").stdout)
    (spec,) = stats["specs"]
    assert spec["kind"] == "inspect" and spec["part"] == "bracket" and spec["results"] == N + 1 and spec["failed"] == 1
    chars = {c["name"]: c for c in spec["characteristics"]}
    assert len(chars) == n_callouts
    prof = next(c for n, c in chars.items() if n.startswith("tolerance: profile of top"))
    assert prof["n"] == N and prof["mean"] == pytest.approx(np.mean(profile), abs=1e-12)
    assert prof["min_margin"] == pytest.approx(min(t - v for t, v in zip([want_tol(single, "profile")] * N, profile)))


def want_tol(result: dict, characteristic: str) -> float:
    return next(t["tolerance"] for t in result["tolerances"] if t["characteristic"] == characteristic)


def test_inspect_batch_refuses_a_bad_drawing_before_it_starts(brackets, tmp_path):
    part, scans = brackets
    bad = tmp_path / "bad.toml"
    bad.write_text(part.read_text().replace('characteristic = "flatness"', 'characteristic = "flatnes"', 1))
    proc = gk("inspect", "batch", bad, *scans, "--db", f"sqlite:///{tmp_path / 'r.db'}")
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.startswith("gagekit: error: ") and "flatnes" in proc.stderr and len(proc.stderr.splitlines()) == 1
    assert not (tmp_path / "r.db").exists()


def test_inspect_batch_on_dask_and_postgresql(brackets, dask_cluster, postgres_url):
    part, scans = brackets
    got, summary = lines(gk("inspect", "batch", part, *scans[:2], "--scheduler", dask_cluster.scheduler_address,
                            "--db", postgres_url, "--json"))
    assert summary == {"scans": 2, "ok": 2, "failed": 0, "skipped": 0}
    single = json.loads(gk("inspect", scans[1], part, "--json").stdout)
    assert without_seconds(next(d for d in got if d["scan"] == str(scans[1]))["result"]) == without_seconds(single)
    rows = [r for r in callouts(postgres_url) if r["feature"] == "bore" and r["characteristic"] == "position"]
    assert len(rows) == 2 and {r["datums"] for r in rows} == {"A|B|C"}


def test_inspect_batch_with_uncertainty_stores_u_and_decisions_for_stats(brackets, tmp_path):
    """`inspect batch --uncertainty`: each scan's result is `inspect --uncertainty --json`'s
    (same seed, same numbers on any thread count), every callout row stores u, U, the
    decision and the rule, and `stats` takes the measurement's u from the stored results
    (sqrt(mean u^2)) when --measurement-uncertainty is not given."""
    part, scans = brackets
    url = f"sqlite:///{tmp_path / 'u.db'}"
    opts = ["--uncertainty", "10", "--noise", "0.001", "--seed", "3"]
    got, summary = lines(gk("inspect", "batch", part, *scans[:2], "--db", url, "--json", "-w", "2", *opts))
    assert summary == {"scans": 2, "ok": 2, "failed": 0, "skipped": 0}
    single = json.loads(gk("inspect", scans[1], part, "--json", *opts, "--threads", "2").stdout)
    by = {os.path.basename(d["scan"]): d["result"] for d in got}
    batch = by[scans[1].name]
    for a, b in zip(batch["tolerances"], single["tolerances"]):
        assert a["uncertainty"] == b["uncertainty"] and a["decision"] == b["decision"]
    assert batch["monte_carlo"]["trials"] == 10 and batch["decision_rule"]["name"] == "iso14253"
    engine = create_engine(url)
    t = m.InspectionResult.__table__
    with engine.connect() as conn:
        rows = [dict(r._mapping) for r in conn.execute(sa.select(t.c.tolerance, t.c.value, t.c.u, t.c.expanded_u,
                                                                 t.c.decision, t.c.decision_rule))]
    engine.dispose()
    assert len(rows) == 2 * len(single["tolerances"])
    assert all(r["u"] is not None and r["expanded_u"] >= 0 and r["decision_rule"] == "iso14253" for r in rows)
    assert {r["decision"] for r in rows} <= {"conforming", "not-proven", "nonconforming"}
    stats = json.loads(gk("stats", "--db", url, "--spec", part, "--json").stdout)
    (spec,) = stats["specs"]
    flat = next(c for c in spec["characteristics"] if c["name"] == "tolerance: flatness of A")
    us = [r["u"] for r in rows if r["tolerance"] == "flatness of A"]
    assert flat["measurement"]["u"] == pytest.approx(float(np.sqrt(np.mean(np.square(us)))), rel=1e-12)
    assert flat["measurement"]["source"].startswith("stored results")
    # a decision rule without --uncertainty is refused before the batch starts
    proc = gk("inspect", "batch", part, *scans[:1], "--db", f"sqlite:///{tmp_path / 'x.db'}", "--decision-rule", "simple")
    assert proc.returncode == 2 and "needs --uncertainty" in proc.stderr
