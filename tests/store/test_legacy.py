"""Tracking history files of the older gagekit (one SQLite file per machine) are migrated
into the results database by `gagekit db upgrade`, every run and value kept."""

import json
import sqlite3
import subprocess
import sys

import numpy as np
import pytest
import sqlalchemy as sa

import gagekit
from gagekit.errors import SchemaVersionError
from gagekit.machine import Truth, load_machine
from gagekit.machine.tracking import simulate_cycles, track
from gagekit.store import ResultStore
from gagekit.store import models as m
from gagekit.store.schema import create_engine

# the old file format, as the older gagekit's History class wrote it
OLD_SCHEMA = """
CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE runs (id INTEGER PRIMARY KEY, created TEXT, source TEXT, n_points INTEGER);
CREATE TABLE cycles (run INTEGER, cycle INTEGER, time REAL, stats TEXT, PRIMARY KEY (run, cycle));
CREATE TABLE observations (run INTEGER, cycle INTEGER, idx INTEGER, commands TEXT, x REAL, y REAL, z REAL);
CREATE TABLE groups (run INTEGER, cycle INTEGER, name TEXT, value REAL);
CREATE TABLE residuals (run INTEGER, cycle INTEGER, idx INTEGER, full REAL, static REAL, drift_only REAL);
CREATE TABLE temperatures (run INTEGER, cycle INTEGER, sensor TEXT, value REAL);
"""


def write_old_history(path, machine, cycles, result, runs=2):
    con = sqlite3.connect(path)
    with con:
        con.executescript(OLD_SCHEMA)
        sig = "|".join(g.name for g in machine.structure().groups)
        con.executemany("INSERT INTO meta VALUES (?, ?)", [("machine", machine.name), ("groups", sig),
                                                           ("created", "2025-03-01T08:00:00+00:00")])
        for run in range(1, runs + 1):
            con.execute("INSERT INTO runs VALUES (?, ?, ?, ?)", (run, f"2025-03-0{run}T08:00:00+00:00", "cycles.csv",
                                                                 len(cycles.commands)))
            for j, row in enumerate(result.cycles):
                cid = row["cycle"]
                con.execute("INSERT INTO cycles VALUES (?, ?, ?, ?)", (run, cid, row.get("time"), json.dumps(row)))
                con.executemany("INSERT INTO observations VALUES (?, ?, ?, ?, ?, ?, ?)",
                                [(run, cid, i, json.dumps(cycles.commands[i].tolist()), *map(float, cycles.measured[j, i]))
                                 for i in range(len(cycles.commands))])
                con.executemany("INSERT INTO groups VALUES (?, ?, ?, ?)", [(run, cid, n, v[j]) for n, v in result.groups.items()])
                r = result.residuals
                con.executemany("INSERT INTO residuals VALUES (?, ?, ?, ?, ?, ?)",
                                [(run, cid, i, float(r["full"][j, i]), float(r["static"][j, i]), float(r["drift_only"][j, i]))
                                 for i in range(r["full"].shape[1])])
                con.executemany("INSERT INTO temperatures VALUES (?, ?, ?, ?)",
                                [(run, cid, s, float(v[j])) for s, v in cycles.temperatures.items()])
    con.close()


@pytest.fixture(scope="module")
def tracked():
    from gagekit.machine.tracking import Cycles

    machine = load_machine(gagekit.machine.example_machine_path())
    plan = machine.sample_commands(40, seed=2)
    blocks, info = simulate_cycles(machine, Truth.random(machine, seed=4), plan, cycles=4, seed=3)
    data = np.concatenate(blocks)
    h = info["header"]
    cyc = Cycles(cycle_ids=(1, 2, 3, 4), commands=np.ascontiguousarray(blocks[0][:, 1:1 + len(machine.joint_names)]),
                 measured=np.stack([b[:, h.index("x"):h.index("z") + 1] for b in blocks]),
                 joint_names=tuple(machine.joint_names), time=np.array([0.0, 60, 120, 180]),
                 temperatures={s: np.array([b[0, h.index(s)] for b in blocks]) for s in h if s.startswith("temp_")})
    assert data.shape[0] == 160
    return machine, cyc, track(machine, cyc)


def test_old_history_file_is_migrated_by_db_upgrade(tracked, tmp_path):
    machine, cyc, res = tracked
    f = tmp_path / "h.sqlite"
    write_old_history(f, machine, cyc, res, runs=2)
    url = f"sqlite:///{f}"
    with pytest.raises(SchemaVersionError, match="db upgrade"):
        ResultStore(url)
    proc = subprocess.run([sys.executable, "-m", "gagekit", "db", "upgrade", url, "--json"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["from"] == "legacy-history"
    engine = create_engine(url)
    with engine.connect() as conn:
        names = set(sa.inspect(conn).get_table_names())
        mach = conn.execute(sa.select(m.MachineRow.name, m.MachineRow.signature)).all()
        cals = conn.execute(sa.select(sa.func.count()).select_from(m.Calibration)).scalar()
        gv = conn.execute(sa.select(m.GroupValue.name, m.GroupValue.cycle, m.GroupValue.value)
                          .where(m.GroupValue.calibration_id == 2)).all()
        n_obs = conn.execute(sa.select(sa.func.count()).select_from(m.CycleObservation)).scalar()
        n_res = conn.execute(sa.select(sa.func.count()).select_from(m.CycleResidual)).scalar()
        stats = conn.execute(sa.select(m.TrackingCycle.stats).where(m.TrackingCycle.cycle == 3)).scalars().all()
    engine.dispose()
    assert "runs" not in names and "calibrations" in names
    assert mach == [(machine.name, "|".join(g.name for g in machine.structure().groups))]
    assert cals == 2 and n_obs == n_res == 2 * 4 * 40
    assert {(n, c): v for n, c, v in gv} == {(n, c): v[c - 1] for n, v in res.groups.items() for c in (1, 2, 3, 4)}
    assert stats[0] == json.loads(json.dumps(res.cycles[2]))
    ResultStore(url).close()  # now a current results database


def test_machine_history_reads_an_old_file_and_track_converts_it(tracked, tmp_path):
    from gagekit.machine.observations import write_csv

    machine, cyc, res = tracked
    f = tmp_path / "old.sqlite"
    write_old_history(f, machine, cyc, res, runs=2)
    before = f.read_bytes()
    gk = lambda *a: subprocess.run([sys.executable, "-m", "gagekit", *map(str, a)], capture_output=True, text=True)  # noqa: E731
    h = gk("machine", "history", f, "--json")
    assert h.returncode == 0, h.stderr
    assert [r["run"] for r in json.loads(h.stdout)["runs"]] == [1, 2] and f.read_bytes() == before  # read as it is
    header = ["cycle", *machine.joint_names, "x", "y", "z", "time", *cyc.temperatures]
    rows = np.concatenate([np.column_stack([np.full(len(cyc.commands), c), cyc.commands, cyc.measured[j],
                                            np.full(len(cyc.commands), cyc.time[j]),
                                            *[np.full(len(cyc.commands), v[j]) for v in cyc.temperatures.values()]])
                           for j, c in enumerate(cyc.cycle_ids)])
    write_csv(tmp_path / "cycles.csv", header, rows)
    t = gk("machine", "track", gagekit.machine.example_machine_path(), tmp_path / "cycles.csv", "--history", f, "--json")
    assert t.returncode == 0, t.stderr
    assert json.loads(t.stdout)["history_run"] == 3  # the two old runs kept, converted, then this one
    h = json.loads(gk("machine", "history", f, "--json").stdout)
    assert [r["run"] for r in h["runs"]] == [1, 2, 3] and h["machine"] == machine.name
    assert h["runs"][0]["cycles"][2]["full_mean"] == pytest.approx(res.cycles[2]["full"]["mean"])
    s = gk("stats", "--db", f"sqlite:///{f}", "--json")  # the same file is a results database now
    assert s.returncode == 0, s.stderr
    assert json.loads(s.stdout)["machines"][0]["calibrations"] == 3
