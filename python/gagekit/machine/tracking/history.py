"""The per-machine SQLite history of tracking runs (Sec. 4.3.4): one transaction per run.

Robust against the shop floor (issue 12): opened read-write even for reads (a crashed
writer's journal is rolled back), a busy timeout and the write lock taken up front, typed
errors for locked, read-only and damaged files, and a foreign SQLite database refused and
left unchanged."""

from __future__ import annotations

import json
import sqlite3
from datetime import datetime, timezone
from pathlib import Path
from typing import Optional, Union

from ...errors import ConfigError, FileFormatError, InvalidInputError
from ..model import Machine
from .cycles import Cycles
from .track import TrackResult

__all__ = ["History", "read_history"]


class History:
    """An embedded SQLite store of one machine's tracking history (writes are transactional).

    Robustness (issue 12): the file is opened read-write even for reads, so that the
    journal of a crashed writer is rolled back instead of failing; every connection has a
    busy timeout (``timeout`` seconds) and a write takes the write lock up front
    (``BEGIN IMMEDIATE``); a locked, read-only, damaged or foreign SQLite file (one without
    gagekit's ``meta`` table) raises a typed error and is never modified.
    """

    SCHEMA = """
    CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
    CREATE TABLE IF NOT EXISTS runs (id INTEGER PRIMARY KEY, created TEXT, source TEXT, n_points INTEGER);
    CREATE TABLE IF NOT EXISTS cycles (run INTEGER, cycle INTEGER, time REAL, stats TEXT, PRIMARY KEY (run, cycle));
    CREATE TABLE IF NOT EXISTS observations (run INTEGER, cycle INTEGER, idx INTEGER, commands TEXT, x REAL, y REAL, z REAL);
    CREATE TABLE IF NOT EXISTS groups (run INTEGER, cycle INTEGER, name TEXT, value REAL);
    CREATE TABLE IF NOT EXISTS residuals (run INTEGER, cycle INTEGER, idx INTEGER, full REAL, static REAL, drift_only REAL);
    CREATE TABLE IF NOT EXISTS temperatures (run INTEGER, cycle INTEGER, sensor TEXT, value REAL);
    """
    TABLES = ("meta", "runs", "cycles", "observations", "groups", "residuals", "temperatures")
    #: seconds a connection waits for another process's lock before giving up (the
    #: environment variable GAGEKIT_HISTORY_TIMEOUT overrides it)
    TIMEOUT = 30.0

    def __init__(self, path: Union[str, Path], machine: Machine, create: bool = True, timeout: Optional[float] = None):
        from ..._files import sqlite_error

        self.path = Path(path)
        self.timeout = _timeout(timeout)
        _check_history_path(self.path, create, write=True)
        self.conn = _connect(self.path, self.timeout, create=create)
        try:
            self._begin()
            rows = _meta(self.conn, self.path)  # refuses a foreign database before writing anything
            sig = "|".join(g.name for g in machine.structure().groups)
            if rows:
                _check_owner(self.path, rows, machine.name, sig)
            elif create:
                for stmt in self.SCHEMA.split(";"):
                    if stmt.strip():
                        self.conn.execute(stmt)
                self.conn.executemany("INSERT INTO meta VALUES (?, ?)", [("machine", machine.name), ("groups", sig),
                                      ("created", datetime.now(timezone.utc).isoformat())])
            else:
                raise FileFormatError(f"{self.path}: not a gagekit history file (an empty SQLite database)")
            self.conn.execute("COMMIT")
        except sqlite3.Error as exc:
            self._abort()
            raise sqlite_error(exc, self.path, "history file") from None
        except BaseException:
            self._abort()
            raise

    def _abort(self) -> None:
        try:
            if self.conn.in_transaction:
                self.conn.execute("ROLLBACK")
        except sqlite3.Error:
            pass
        finally:
            self.conn.close()

    def _begin(self) -> None:
        """Take the write lock now (waits up to the busy timeout for other writers)."""
        self.conn.execute("BEGIN IMMEDIATE")

    def close(self) -> None:
        self.conn.close()

    def append(self, cycles: Cycles, result: TrackResult) -> int:
        """Store one tracking run in a single transaction; returns its run id."""
        from ..._files import sqlite_error

        try:
            self._begin()
            try:
                run = self._insert(cycles, result)
                self.conn.execute("COMMIT")
            except BaseException:
                self.conn.execute("ROLLBACK")
                raise
        except sqlite3.Error as exc:
            err = sqlite_error(exc, self.path, "history file")
            raise type(err)(f"{err}; the run was not stored") from None
        return run

    def _insert(self, cycles: Cycles, result: TrackResult) -> int:
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


_SQLITE_MAGIC = b"SQLite format 3\x00"


def _timeout(timeout: Optional[float]) -> float:
    import os

    if timeout is None:
        try:
            timeout = float(os.environ.get("GAGEKIT_HISTORY_TIMEOUT", History.TIMEOUT))
        except ValueError:
            raise ConfigError("GAGEKIT_HISTORY_TIMEOUT must be a number of seconds") from None
    if not (0 <= timeout <= 86400):
        raise InvalidInputError(f"history busy timeout must be 0 to 86400 s, got {timeout}")
    return float(timeout)


def _check_owner(p: Path, rows: dict, name: str, sig: str) -> None:
    """The history must belong to this machine and its error model (same groups)."""
    if rows.get("machine") != name:
        raise ConfigError(f"{p}: this history belongs to machine '{rows.get('machine')}', not '{name}': "
                          "use another --history file")
    if rows.get("groups") != sig:
        old, new = (rows.get("groups") or "").split("|"), sig.split("|")
        diff = next((f"group '{a}' is now '{b}'" for a, b in zip(old, new) if a != b),
                    f"{len(old)} groups are now {len(new)}")
        raise ConfigError(f"{p}: this history of machine '{name}' was written with another error model "
                          f"({diff}): the machine file changed since; use another --history file")


def _check_history_path(p: Path, create: bool, write: bool) -> bool:
    """Typed errors before SQLite touches the file: a regular file with SQLite's header
    (or a new file in a writable folder). Returns whether the file exists (non-empty)."""
    from ..._files import input_file, output_file

    if p.exists() or not create:
        input_file(p, "history file")
        with open(p, "rb") as fh:
            head = fh.read(16)
        if head and head != _SQLITE_MAGIC:
            raise FileFormatError(f"{p}: not a gagekit history file (not an SQLite database)")
        if write:
            output_file(p)  # writable file and folder (the journal lives beside it)
        return bool(head)
    output_file(p)
    return False


def _connect(p: Path, timeout: float, create: bool) -> sqlite3.Connection:
    from ..._files import sqlite_error

    mode = "rwc" if create else "rw"  # read-write even for reads: a crashed writer's journal is rolled back
    try:
        conn = sqlite3.connect(f"file:{p.resolve()}?mode={mode}", uri=True, timeout=timeout, isolation_level=None)
        conn.execute(f"PRAGMA busy_timeout = {int(timeout * 1000)}")
    except sqlite3.Error as exc:
        raise sqlite_error(exc, p, "history file") from None
    return conn


def _tables(conn: sqlite3.Connection) -> list[str]:
    return [r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table' ORDER BY name")]


def _foreign(p: Path, tables: list[str]) -> FileFormatError:
    shown = ", ".join(tables[:5]) + (", ..." if len(tables) > 5 else "")
    return FileFormatError(f"{p}: not a gagekit history file (an SQLite database with tables {shown}); "
                           "it was left unchanged: choose another --history file")


def _meta(conn: sqlite3.Connection, p: Path) -> dict:
    """The meta rows of a gagekit history; a typed error for any other database."""
    tables = _tables(conn)
    if not tables:
        return {}
    if "meta" not in tables or not set(tables) <= set(History.TABLES):
        raise _foreign(p, tables)
    rows = dict(conn.execute("SELECT key, value FROM meta").fetchall())
    if "machine" not in rows:
        raise _foreign(p, tables)
    return rows


def read_history(path: Union[str, Path], timeout: Optional[float] = None) -> dict:
    """The summary of a history file (no machine file needed). Opened read-write so that
    an interrupted writer's journal is rolled back; a read-only file is read as it is."""
    from ..._files import sqlite_error

    p = Path(path)
    _check_history_path(p, create=False, write=False)
    t = _timeout(timeout)
    h = History.__new__(History)
    h.path, h.timeout = p, t
    h.conn = _connect(p, t, create=False)
    try:
        h.conn.execute("BEGIN")  # a read transaction: a consistent snapshot of every table
        if not _meta(h.conn, p):
            raise FileFormatError(f"{p}: not a gagekit history file (an empty SQLite database)")
        return h.summary()
    except sqlite3.Error as exc:
        raise sqlite_error(exc, p, "history file") from None
    finally:
        h.conn.close()
