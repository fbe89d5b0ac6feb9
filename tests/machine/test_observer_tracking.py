"""Thermal tracking (Sec. 4.3.2-4.3.4): cycles, static and drift-only comparisons, temperature
model, history store, CLI."""

import json
import sqlite3
import subprocess
import sys

import numpy as np
import pytest

import gagekit
from gagekit.errors import ConfigError, DegenerateGeometryError, FileFormatError, InvalidInputError
from gagekit.machine import Truth, load_machine, parse_machine, read_commands
from gagekit.machine.observations import write_csv
from gagekit.machine.tracking import History, read_cycles, read_history, simulate_cycles, track
from gagekit.machine.tracking.simulate import SENSORS

EXAMPLE = gagekit.machine.example_machine_path()


@pytest.fixture(scope="module")
def machine():
    return load_machine(EXAMPLE)


@pytest.fixture(scope="module")
def cycles_csv(machine, tmp_path_factory):
    d = tmp_path_factory.mktemp("track")
    plan = machine.sample_commands(60, seed=5)
    blocks, info = simulate_cycles(machine, Truth.random(machine, seed=3), plan, cycles=6, seed=1)
    write_csv(d / "cycles.csv", info["header"], np.concatenate(blocks))
    write_csv(d / "plan.csv", machine.joint_names, plan)
    return d


def test_tracking_recovers_the_thermal_story(machine, cycles_csv):
    c = read_cycles(cycles_csv / "cycles.csv", machine)
    assert c.cycle_ids == (1, 2, 3, 4, 5, 6) and c.measured.shape == (6, 60, 3)
    assert set(c.temperatures) == set(SENSORS) and len(SENSORS) == 10
    r = track(machine, c)
    rows = r.cycles
    noise_floor = 0.0089 * 2 * np.sqrt(2 / np.pi)  # mean norm of 3-D tracker noise
    for row in rows:
        # re-identification each cycle keeps the residual at the noise (Table 4.4)
        assert row["full"]["mean"] < 1.3 * noise_floor
        assert row["full"]["mean"] <= row["drift_only"]["mean"] + 1e-12 <= row["static"]["mean"] + 2e-12
    # cycle 1: all three coincide; the static calibration degrades while heating (Table 4.5)
    assert rows[0]["static"]["mean"] == pytest.approx(rows[0]["full"]["mean"])
    static = [row["static"]["mean"] for row in rows]
    assert static[4] > 3 * static[0] and static[5] < static[4]  # cooling in cycle 6
    tm = r.temperature_model
    assert tm["fitted"] and len(tm["leave_one_cycle_out"]) == 6
    # the temperature model predicts the hot cycles better than the static calibration
    assert tm["leave_one_cycle_out"][4]["mean"] < static[4]
    assert len(r.groups) == 32 and all(len(v) == 6 for v in r.groups.values())


def test_history_store(machine, cycles_csv, tmp_path):
    c = read_cycles(cycles_csv / "cycles.csv", machine)
    r = track(machine, c)
    h = History(tmp_path / "h.sqlite", machine)
    assert h.append(c, r) == 1 and h.append(c, r) == 2
    h.close()
    s = read_history(tmp_path / "h.sqlite")
    assert s["machine"] == machine.name and [run["run"] for run in s["runs"]] == [1, 2]
    con = sqlite3.connect(tmp_path / "h.sqlite")
    assert con.execute("SELECT COUNT(*) FROM observations").fetchone()[0] == 2 * 6 * 60
    assert con.execute("SELECT COUNT(*) FROM groups").fetchone()[0] == 2 * 6 * 32
    con.close()
    other = parse_machine(EXAMPLE.read_text().replace('name = "dissertation-5axis-BXZYW"', 'name = "other"'))
    with pytest.raises(ConfigError, match="belongs to machine"):
        History(tmp_path / "h.sqlite", other)
    (tmp_path / "junk.sqlite").write_text("not a database at all" * 20)
    with pytest.raises(FileFormatError, match="not a gagekit history"):
        History(tmp_path / "junk.sqlite", machine)


def test_bad_cycles(machine, cycles_csv, tmp_path):
    text = (cycles_csv / "cycles.csv").read_text().splitlines()
    # a cycle with a different command set
    bad = [text[0]] + text[1:61] + [text[61].replace(text[61].split(",")[1], "0.5", 1)] + text[62:]
    (tmp_path / "diff.csv").write_text("\n".join(bad))
    with pytest.raises(InvalidInputError, match="cycle 2 measures different commands"):
        read_cycles(tmp_path / "diff.csv", machine)
    (tmp_path / "nocycle.csv").write_text(text[0].replace("cycle", "lap") + "\n" + "\n".join(text[1:5]))
    with pytest.raises(FileFormatError, match="missing column"):
        read_cycles(tmp_path / "nocycle.csv", machine)
    small = [text[0]] + [ln for ln in text[1:] if True][:10]
    (tmp_path / "small.csv").write_text("\n".join(small))
    with pytest.raises(DegenerateGeometryError, match="at least 32"):
        track(machine, read_cycles(tmp_path / "small.csv", machine))


def gk(*args, ok=True):
    proc = subprocess.run([sys.executable, "-m", "gagekit", "machine", *map(str, args)], capture_output=True, text=True, timeout=300)
    if ok:
        assert proc.returncode == 0, proc.stderr
    return proc


def test_simulate_thermal_mode_equals_simulate_cycles(cycles_csv, tmp_path):
    """`machine simulate --plan --cycles` is the thermal mode; `simulate-cycles` is its short form."""
    plan = cycles_csv / "plan.csv"
    d = json.loads(gk("simulate", EXAMPLE, "--plan", plan, "--cycles", 2, "--seed", 4, "--out", tmp_path / "a.csv", "--json").stdout)
    assert d["cycles"] == 2 and d["points"] == len(read_commands(plan, load_machine(EXAMPLE)))
    gk("simulate-cycles", EXAMPLE, plan, "--cycles", 2, "--seed", 4, "--out", tmp_path / "b.csv")
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    cyc = read_cycles(tmp_path / "a.csv", load_machine(EXAMPLE))
    assert cyc.cycle_ids == (1, 2) and set(cyc.temperatures) == set(SENSORS)
    bad = gk("simulate", EXAMPLE, "--points", 5, "--plan", plan, "--out", tmp_path / "c.csv", ok=False)
    assert bad.returncode == 2 and "either --points" in bad.stderr


def test_cli_track_history(cycles_csv, tmp_path):
    gk("simulate-cycles", EXAMPLE, cycles_csv / "plan.csv", "--cycles", 3, "--out", tmp_path / "c.csv")
    d = json.loads(gk("track", EXAMPLE, tmp_path / "c.csv", "--history", tmp_path / "h.sqlite", "--report", tmp_path / "rep", "--json").stdout)
    assert [c["cycle"] for c in d["cycles"]] == [1, 2, 3]
    for key in ("observed", "full", "static", "drift_only"):
        assert set(d["cycles"][1][key]) >= {"mean", "max"}
    assert "temperature_model" in d and len(d["groups"]) == 32
    assert (tmp_path / "rep" / "drift.png").stat().st_size > 1000
    h = json.loads(gk("history", tmp_path / "h.sqlite", "--json").stdout)
    assert len(h["runs"]) == 1 and len(h["runs"][0]["cycles"]) == 3
    bad = gk("history", tmp_path / "missing.sqlite", ok=False)
    assert bad.returncode == 2 and "not found" in bad.stderr
