"""The per-machine SQLite history of tracking runs (Sec. 4.3.4): one transaction per run."""

from __future__ import annotations

import json
import sqlite3
from datetime import datetime, timezone
from pathlib import Path
from typing import Union

from ...errors import ConfigError, FileFormatError
from ..model import Machine
from .cycles import Cycles
from .track import TrackResult

__all__ = ["History", "read_history"]



class History:
    """An embedded SQLite store of one machine's tracking history (writes are transactional)."""

    SCHEMA = """
    CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
    CREATE TABLE IF NOT EXISTS runs (id INTEGER PRIMARY KEY, created TEXT, source TEXT, n_points INTEGER);
    CREATE TABLE IF NOT EXISTS cycles (run INTEGER, cycle INTEGER, time REAL, stats TEXT, PRIMARY KEY (run, cycle));
    CREATE TABLE IF NOT EXISTS observations (run INTEGER, cycle INTEGER, idx INTEGER, commands TEXT, x REAL, y REAL, z REAL);
    CREATE TABLE IF NOT EXISTS groups (run INTEGER, cycle INTEGER, name TEXT, value REAL);
    CREATE TABLE IF NOT EXISTS residuals (run INTEGER, cycle INTEGER, idx INTEGER, full REAL, static REAL, drift_only REAL);
    CREATE TABLE IF NOT EXISTS temperatures (run INTEGER, cycle INTEGER, sensor TEXT, value REAL);
    """

    def __init__(self, path: Union[str, Path], machine: Machine, create: bool = True):
        self.path = Path(path)
        if not create and not self.path.exists():
            raise FileFormatError(f"{self.path}: history file not found")
        if not self.path.parent.is_dir():
            raise FileFormatError(f"{self.path}: the folder {self.path.parent} does not exist")
        try:
            self.conn = sqlite3.connect(self.path)
            with self.conn:
                self.conn.executescript(self.SCHEMA)
                rows = dict(self.conn.execute("SELECT key, value FROM meta").fetchall())
        except sqlite3.DatabaseError as exc:
            raise FileFormatError(f"{self.path}: not a gagekit history file ({exc})") from None
        sig = "|".join(g.name for g in machine.structure().groups)
        if rows:
            if rows.get("machine") != machine.name or rows.get("groups") != sig:
                raise ConfigError(
                    f"{self.path}: this history belongs to machine '{rows.get('machine')}', not '{machine.name}' "
                    "(or the machine file changed its error model): use another --history file"
                )
        elif create:
            with self.conn:
                self.conn.executemany("INSERT INTO meta VALUES (?, ?)", [("machine", machine.name), ("groups", sig),
                                      ("created", datetime.now(timezone.utc).isoformat())])

    def close(self) -> None:
        self.conn.close()

    def append(self, cycles: Cycles, result: TrackResult) -> int:
        """Store one tracking run in a single transaction; returns its run id."""
        with self.conn:
            cur = self.conn.execute("INSERT INTO runs (created, source, n_points) VALUES (?, ?, ?)",
                                    (datetime.now(timezone.utc).isoformat(), cycles.source, len(cycles.commands)))
            run = int(cur.lastrowid)
            for j, row in enumerate(result.cycles):
                cid = row["cycle"]
                self.conn.execute("INSERT INTO cycles VALUES (?, ?, ?, ?)", (run, cid, row.get("time"), json.dumps(row)))
                self.conn.executemany(
                    "INSERT INTO observations VALUES (?, ?, ?, ?, ?, ?, ?)",
                    [(run, cid, i, json.dumps(cycles.commands[i].tolist()), *map(float, cycles.measured[j, i]))
                     for i in range(len(cycles.commands))],
                )
                self.conn.executemany("INSERT INTO groups VALUES (?, ?, ?, ?)",
                                      [(run, cid, name, v[j]) for name, v in result.groups.items()])
                r = result.residuals
                self.conn.executemany(
                    "INSERT INTO residuals VALUES (?, ?, ?, ?, ?, ?)",
                    [(run, cid, i, float(r["full"][j, i]), float(r["static"][j, i]), float(r["drift_only"][j, i]))
                     for i in range(r["full"].shape[1])],
                )
                self.conn.executemany("INSERT INTO temperatures VALUES (?, ?, ?, ?)",
                                      [(run, cid, s, float(v[j])) for s, v in cycles.temperatures.items()])
        return run

    def summary(self) -> dict:
        meta = dict(self.conn.execute("SELECT key, value FROM meta").fetchall())
        runs = []
        for run, created, source, npts in self.conn.execute("SELECT id, created, source, n_points FROM runs ORDER BY id"):
            cyc = [json.loads(s) for (s,) in self.conn.execute("SELECT stats FROM cycles WHERE run = ? ORDER BY cycle", (run,))]
            runs.append({"run": run, "created": created, "source": source, "points": npts,
                         "cycles": [{"cycle": c["cycle"], "observed_mean": c["observed"]["mean"],
                                     "full_mean": c["full"]["mean"], "static_mean": c["static"]["mean"],
                                     "drift_only_mean": c["drift_only"]["mean"]} for c in cyc]})
        return {"machine": meta.get("machine"), "created": meta.get("created"), "runs": runs}


def read_history(path: Union[str, Path]) -> dict:
    """The summary of a history file, opened read-only (no machine file needed)."""
    p = Path(path)
    if not p.exists():
        raise FileFormatError(f"{p}: history file not found")
    h = History.__new__(History)
    h.path = p
    try:
        h.conn = sqlite3.connect(f"file:{p}?mode=ro", uri=True)
        return h.summary()
    except sqlite3.DatabaseError as exc:
        raise FileFormatError(f"{p}: not a gagekit history file ({exc})") from None
    finally:
        if hasattr(h, "conn"):
            h.conn.close()


