"""SPC: capability indices against hand-computed values (ISO 22514-2 / AIAG formulas),
Western Electric rules, invariances (hypothesis), and `gagekit stats` on a real batch."""

import json
import subprocess
import sys
from datetime import datetime, timedelta, timezone

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gagekit.stats import capability, imr_chart, trend_per_day, western_electric


def test_capability_by_hand():
    # x = 10 12 11 13 12: mean 11.6, s = sqrt(1.3), MR = 2 1 2 1, MRbar = 1.5, sigma = 1.5 / 1.128
    c = capability([10, 12, 11, 13, 12], lower=8, upper=16)
    sigma = 1.5 / 1.128
    assert c.n == 5 and c.mean == pytest.approx(11.6) and c.sd == pytest.approx(np.sqrt(1.3))
    assert c.sigma_within == pytest.approx(sigma)
    assert c.cp == pytest.approx(8 / (6 * sigma)) and c.cp == pytest.approx(1.00266, abs=1e-5)
    assert c.cpk == pytest.approx(3.6 / (3 * sigma)) and c.cpk == pytest.approx(0.90239, abs=1e-5)
    assert c.pp == pytest.approx(1.16941, abs=1e-5) and c.ppk == pytest.approx(1.05247, abs=1e-5)
    assert c.min_margin == pytest.approx(2.0)  # 10 - 8
    one = capability([10, 12, 11, 13, 12], lower=8)  # one-sided: Cpl only
    assert one.cp is None and one.cpk == pytest.approx(3.6 / (3 * sigma)) and "cp" not in one.to_dict()
    assert capability([5.0]).to_dict() == {"n": 1, "mean": 5.0, "min": 5.0, "max": 5.0, "resolution": 0.0, "notes": [
        "no specification limits: no capability indices", "one value: no spread, no capability indices"]}
    flat = capability([0.0, 0.0, 0.0], lower=0.0)
    assert flat.cpk is None and flat.min_margin == 0.0 and any("no variation above the resolution" in n for n in flat.notes)


def test_imr_limits():
    x = [10, 12, 11, 13, 12]
    ch = imr_chart(x)
    assert ch.center == pytest.approx(11.6) and ch.mr_center == pytest.approx(1.5)
    assert ch.ucl == pytest.approx(11.6 + 2.6596 * 1.5, abs=1e-3) and ch.mr_ucl == pytest.approx(3.267 * 1.5)
    assert imr_chart([1.0]) is None


@pytest.mark.parametrize("sign", [1, -1])
def test_western_electric_rules(sign):
    def sig(z):
        return [(s.index, s.rule) for s in western_electric(sign * np.array(z, dtype=float), 0.0, 1.0)]

    assert sig([0, 0.2, 3.5, 0]) == [(2, 1)]
    assert sig([0, 2.5, 0.1, 2.5, 0]) == [(3, 2)]
    assert sig([1.5, 1.5, -0.2, 1.5, 1.5, 0]) == [(4, 3)]
    assert sig([0.5] * 8) == [(7, 4)]
    assert sig([0.5, -0.5] * 6) == []


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-100, 100), min_size=3, max_size=40), st.floats(0.1, 50), st.floats(-1e3, 1e3))
def test_indices_do_not_depend_on_units_or_origin(xs, a, b):
    x = np.array(xs)
    if np.ptp(x) < 1e-6 or np.abs(np.diff(x)).mean() < 1e-6:
        return
    lo, up = x.min() - 1.0, x.max() + 2.0
    c1 = capability(x, lo, up)
    c2 = capability(a * x + b, a * lo + b, a * up + b)
    for k in ("cp", "cpk", "pp", "ppk"):
        assert getattr(c2, k) == pytest.approx(getattr(c1, k), rel=1e-6, abs=1e-9)
    assert c1.cpk <= c1.cp + 1e-12 and c1.ppk <= c1.pp + 1e-12
    assert c1.min_margin == pytest.approx(min(x.min() - lo, up - x.max()))


def test_trend_per_day():
    t = [0.0, 1.0, 2.0, 3.0]
    assert trend_per_day(t, [1.0, 1.5, 2.0, 2.5]) == pytest.approx(0.5)
    assert trend_per_day([1.0, 1.0], [0.0, 1.0]) is None


def gk(*args):
    return subprocess.run([sys.executable, "-m", "gagekit", *map(str, args)], capture_output=True, text=True, timeout=600)


def test_stats_of_a_batch(casting_set, tmp_path):
    gages, scans = casting_set
    url = f"sqlite:///{tmp_path / 'r.db'}"
    b = gk("gage", "batch", gages, *scans, "--db", url, "--json", "-w", "2")
    assert b.returncode == 0, b.stderr
    results = {json.loads(ln)["scan"]: json.loads(ln)["result"] for ln in b.stdout.splitlines()[:-1]}
    proc = gk("stats", "--db", url, "--spec", gages, "--json", "--report", tmp_path / "spc")
    assert proc.returncode == 0, proc.stderr
    s = json.loads(proc.stdout)
    (spec,) = s["specs"]
    assert spec["kind"] == "gage" and spec["results"] == len(scans) and spec["failed"] == 0
    chars = {c["name"]: c for c in spec["characteristics"]}
    assert len(chars) == 3 * 8 + 4  # allowance after / before, stock, per gage; T* beta, dx, dy, dz
    c = chars["allowance before T*: outer wall 1"]
    # time order: PLY files record no acquisition time, so the time each result was stored
    assert c["series"]["time_source"] == ["stored"] * len(scans) and c["series"]["time"] == sorted(c["series"]["time"])
    assert sorted(c["series"]["scan"]) == [str(p) for p in scans]
    vals = [next(g["allowance_before"] for g in results[p]["gages"] if g["name"] == "outer wall 1")
            for p in c["series"]["scan"]]
    assert c["series"]["value"] == vals and c["mean"] == pytest.approx(np.mean(vals)) and c["n"] == len(scans)
    assert c["sd"] == pytest.approx(np.std(vals, ddof=1))
    # the casting as fixtured has no specification limit: no capability index
    assert "lower" not in c and "cpk" not in c and "ppk" not in c and "zero_margin" not in c
    after = [chars[n] for n in chars if n.startswith("allowance after T*")]
    assert all(a["lower"] == 0.0 and a["resolution"] == 1e-9 for a in after)
    # the gages that place each part sit on the limit after T*: flagged, not counted below it
    limiting = [a for a in after if a["zero_margin"]]
    assert limiting and all(a["min_margin"] == 0.0 and a["on_limit"] >= 1 for a in limiting)
    assert all(a["min_margin"] >= 0.0 for a in after)
    assert sum(a["on_limit"] for a in after) == sum(
        1 for r in results.values() for g in r["gages"] if abs(g["allowance_after"]) <= 1e-9)
    assert all(any("only 8 values" in w for w in a.get("warnings", [])) for a in after if "cpk" in a)
    dx = chars["T* dx"]
    assert dx["lower"] == -20.0 and dx["upper"] == 20.0 and "cpk" in dx and "chart" in dx
    assert dx["min_margin"] == pytest.approx(20.0 - max(abs(results[str(p)]["transform"]["dx"]) for p in scans))
    html = (tmp_path / "spc" / "report.html").read_text()
    assert "Western Electric" in html and "Cpk" in html
    charts = [c for c in chars.values() if "chart" in c and not c["name"].startswith(("allowance before", "stock"))]
    assert len(charts) >= 4 + 4  # T* and the gages that do not sit on their limit in every part
    assert len(list((tmp_path / "spc").glob("*.png"))) == len(charts) + 1 + 2  # and the trends: allowances, T* mm, rad


def test_machine_drift_across_calibrations(tmp_path):
    import sqlalchemy as sa

    import gagekit
    from gagekit.machine import Truth, load_machine
    from gagekit.machine.tracking import Cycles, simulate_cycles, track
    from gagekit.stats import collect
    from gagekit.store import ResultStore
    from gagekit.store import models as m
    from gagekit.store.machines import append_tracking

    machine = load_machine(gagekit.machine.example_machine_path())
    plan = machine.sample_commands(40, seed=2)
    store = ResultStore(f"sqlite:///{tmp_path / 'r.db'}")
    truth = Truth.random(machine, seed=4)
    sig = "|".join(g.name for g in machine.structure().groups)
    nj = len(machine.joint_names)
    for day in range(3):  # three mornings; the machine runs warmer each day (drift_scale)
        blocks, info = simulate_cycles(machine, truth, plan, cycles=2, seed=10 + day, drift_scale=1.0 + 2.0 * day)
        h = info["header"]
        cyc = Cycles((1, 2), np.ascontiguousarray(blocks[0][:, 1:1 + nj]),
                     np.stack([b[:, h.index("x"):h.index("z") + 1] for b in blocks]), tuple(machine.joint_names))
        r = track(machine, cyc)
        with store.engine.begin() as conn:
            cal = append_tracking(conn, machine.name, sig, source=f"day{day}.csv", commands=cyc.commands,
                                  measured=cyc.measured, temperatures={}, cycles=r.cycles, groups=r.groups,
                                  group_units=r.group_units, group_effect=r.group_effect, residuals=r.residuals,
                                  frame=r.frame)
            conn.execute(sa.update(m.Calibration).where(m.Calibration.id == cal)
                         .values(created=datetime(2026, 3, 2 + day, 7, tzinfo=timezone.utc)))
    store.close()
    s = collect(f"sqlite:///{tmp_path / 'r.db'}")
    (mach,) = s["machines"]
    assert mach["calibrations"] == 3 and mach["from"].startswith("2026-03-02") and mach["to"].startswith("2026-03-04")
    groups = {g["name"]: g for g in mach["groups"]}
    assert len(groups) == len(machine.structure().groups)
    top = mach["groups"][0]
    assert top["max_change_effect_um"] == max(g["max_change_effect_um"] for g in mach["groups"])
    assert top["values"][0] == top["first"] and top["identifications"] == 6 and "trend_per_day" in top
    times = [datetime.fromisoformat(t) for t in top["times"]]
    assert times == sorted(times) and times[1] - times[0] == timedelta(minutes=60)  # cycle 2, an hour into day 1
    # the simulator's thermal terms drift (Fig. 4.8: the Y and W axes): Y.delta is among the 8 largest drifts
    assert "Y.delta" in [g["name"] for g in mach["groups"][:8]]
