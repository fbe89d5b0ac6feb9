"""The tracking history of a machine (Sec. 4.3.4), kept in the results database.

``machine track --history FILE`` appends each tracking run to a SQLite file holding the
schema of :mod:`gagekit.store` (a run is a calibration of the machine with its cycles,
group values, observations, residuals and temperatures; :mod:`gagekit.store.machines`), one
transaction per run, so the same file is read by ``gagekit stats --db sqlite:///FILE``.
A history file of the older gagekit (its own tables ``meta``, ``runs``, ...) is read as it
is and converted in place, in one transaction, the first time a run is appended to it
(``gagekit db upgrade`` converts it too).

Robust on the shop floor (issue 12): opened read-write even for reads, so the journal of a
crashed writer is rolled back; a busy timeout (``GAGEKIT_HISTORY_TIMEOUT`` s, default 30)
and the write lock taken up front (``BEGIN IMMEDIATE``); typed errors for locked, read-only
and damaged files; a foreign SQLite database refused and left unchanged; a history file
belongs to one machine and its error model, and says precisely what changed.
"""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path
from typing import Optional, Union

from ...errors import ConfigError, FileFormatError, InvalidInputError, SchemaVersionError, StoreError
from ..model import Machine
from .cycles import Cycles
from .track import TrackResult

__all__ = ["History", "read_history"]

_SQLITE_MAGIC = b"SQLite format 3\x00"
#: the tables of the history files of the older gagekit
LEGACY_TABLES = ("meta", "runs", "cycles", "observations", "groups", "residuals", "temperatures")


class History:
    """A machine's tracking runs in a SQLite results database (writes are transactional).

    The file is checked when opened (before any computation): a foreign or damaged
    database, a read-only file, another machine or another error model raise a typed error
    and the file is left unchanged. :meth:`append` stores one run in one transaction."""

    #: seconds a connection waits for another process's lock before giving up (the
    #: environment variable GAGEKIT_HISTORY_TIMEOUT overrides it)
    TIMEOUT = 30.0

    def __init__(self, path: Union[str, Path], machine: Machine, create: bool = True, timeout: Optional[float] = None):
        self.path = Path(path)
        self.timeout = _timeout(timeout)
        self.machine = machine
        self.signature = "|".join(g.name for g in machine.structure().groups)
        exists = _check_history_path(self.path, create, write=True)
        if not exists and not create:
            raise FileFormatError(f"{self.path}: not a gagekit history file (an empty SQLite database)")
        self.engine = _engine(self.path, self.timeout, create=create, write=True)
        if exists:
            self._run(lambda conn: self._owner_check(conn, _classify(conn, self.path)))

    def _run(self, fn):
        import sqlalchemy as sa

        from ..._files import sqlite_error

        try:
            with self.engine.begin() as conn:  # BEGIN IMMEDIATE: the write lock up front
                return fn(conn)
        except sa.exc.DBAPIError as exc:
            raise sqlite_error(exc.orig or exc, self.path, "history file") from None

    def _owner_check(self, conn, state: str) -> str:
        if state == "legacy":
            meta = dict(conn.exec_driver_sql("SELECT key, value FROM meta").fetchall())
            owners = [(meta.get("machine"), meta.get("groups"))]
        elif state == "current":
            import sqlalchemy as sa

            from ...store import models as m

            owners = conn.execute(sa.select(m.MachineRow.name, m.MachineRow.signature)).all()
        else:
            owners = []
        for name, sig in owners:
            _check_owner(self.path, {"machine": name, "groups": sig}, self.machine.name, self.signature)
        return state

    def close(self) -> None:
        self.engine.dispose()

    def append(self, cycles: Cycles, result: TrackResult) -> int:
        """Store one tracking run in a single transaction; returns its run (calibration) id."""
        from ...store.machines import append_tracking
        from ...store.schema import _alembic_upgrade

        def write(conn) -> int:
            state = self._owner_check(conn, _classify(conn, self.path))
            if state == "legacy":
                from ...store.legacy import migrate_history

                migrate_history(conn, _alembic_upgrade)
            elif state == "empty":
                _alembic_upgrade(conn)
            return append_tracking(
                conn, self.machine.name, self.signature, source=cycles.source, commands=cycles.commands,
                measured=cycles.measured, temperatures=cycles.temperatures, cycles=result.cycles, groups=result.groups,
                group_units=result.group_units, group_effect=result.group_effect, residuals=result.residuals,
                frame=result.frame)

        try:
            return self._run(write)
        except (FileFormatError, StoreError, ConfigError) as exc:
            if isinstance(exc, ConfigError) and str(exc).startswith(str(self.path)):
                raise
            raise type(exc)(f"{exc}; the run was not stored") from None

    def summary(self) -> dict:
        return read_history(self.path, self.timeout, machine=self.machine.name)


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
        _settle_journal(p)
        with open(p, "rb") as fh:
            head = fh.read(16)
        if head and head != _SQLITE_MAGIC:
            raise FileFormatError(f"{p}: not a gagekit history file (not an SQLite database)")
        if write:
            output_file(p)  # writable file and folder (the journal lives beside it)
        return bool(head)
    output_file(p)
    return False


def _settle_journal(p: Path) -> None:
    """Let SQLite read the file first when a rollback journal lies beside it: a writer killed
    inside the first transaction of a new history leaves a first page never written (no
    SQLite header) and a hot journal, which SQLite rolls back on the first read (back to an
    empty database). Reading the header before would refuse the file as foreign. Nothing is
    done for a file SQLite cannot open: the header check then says what it is."""
    journal = p.with_name(p.name + "-journal")
    try:
        if journal.stat().st_size == 0:
            return
    except OSError:
        return
    try:
        conn = sqlite3.connect(f"file:{p.resolve()}?mode=rw", uri=True, timeout=_timeout(None), isolation_level=None)
        try:
            conn.execute("SELECT count(*) FROM sqlite_master").fetchone()
        finally:
            conn.close()
    except sqlite3.Error:
        pass


def _engine(p: Path, timeout: float, create: bool, write: bool):
    """SQLAlchemy over one sqlite3 connection per use, opened read-write (``rwc`` to create),
    with the busy timeout; writers begin with BEGIN IMMEDIATE, readers with BEGIN."""
    import sqlalchemy as sa

    mode = "rwc" if create else "rw"  # read-write even for reads: a crashed writer's journal is rolled back

    def connect() -> sqlite3.Connection:
        conn = sqlite3.connect(f"file:{p.resolve()}?mode={mode}", uri=True, timeout=timeout, isolation_level=None,
                               check_same_thread=False)
        conn.execute(f"PRAGMA busy_timeout = {int(timeout * 1000)}")
        return conn

    engine = sa.create_engine("sqlite://", creator=connect, poolclass=sa.pool.NullPool)

    @sa.event.listens_for(engine, "begin")
    def _begin(conn):  # pragma: no cover - trivial
        conn.exec_driver_sql("BEGIN IMMEDIATE" if write else "BEGIN")

    return engine


def _foreign(p: Path, tables: list) -> FileFormatError:
    shown = ", ".join(tables[:5]) + (", ..." if len(tables) > 5 else "")
    return FileFormatError(f"{p}: not a gagekit history file (an SQLite database with tables {shown}); "
                           "it was left unchanged: choose another --history file")


def _classify(conn, p: Path) -> str:
    """'empty', 'current' or 'legacy'; a typed error for any other database (unchanged)."""
    tables = sorted(r[0] for r in conn.exec_driver_sql("SELECT name FROM sqlite_master WHERE type = 'table'"))
    if not tables:
        return "empty"
    if "alembic_version" not in tables:
        if "meta" in tables and set(tables) <= set(LEGACY_TABLES):
            rows = dict(conn.exec_driver_sql("SELECT key, value FROM meta").fetchall())
            if "machine" in rows:
                return "legacy"
        raise _foreign(p, tables)
    from ...store.schema import _state

    try:
        state, rev = _state(conn, str(p))
    except SchemaVersionError:
        raise
    except StoreError:
        raise _foreign(p, tables) from None
    if state == "old":
        raise SchemaVersionError(f"{p}: the history file has an older schema ({rev}): run `gagekit db upgrade {p}`")
    return state


def _legacy_summary(conn) -> dict:
    """The runs of a history file of the older gagekit, read as they are."""
    q = conn.exec_driver_sql
    meta = dict(q("SELECT key, value FROM meta").fetchall())
    runs = []
    for run, created, source, npts in q("SELECT id, created, source, n_points FROM runs ORDER BY id").fetchall():
        cyc = [json.loads(s) for (s,) in q("SELECT stats FROM cycles WHERE run = ? ORDER BY cycle", (run,)).fetchall()]
        runs.append({"run": run, "created": created, "source": source, "points": npts, "cycles": _cycle_rows(cyc)})
    return {"machine": meta.get("machine"), "created": meta.get("created"), "runs": runs}


def _cycle_rows(cycles: list) -> list:
    return [{"cycle": c["cycle"], "observed_mean": c["observed"]["mean"], "full_mean": c["full"]["mean"],
             "static_mean": c["static"]["mean"], "drift_only_mean": c["drift_only"]["mean"]} for c in cycles]


def read_history(path: Union[str, Path], timeout: Optional[float] = None, machine: Optional[str] = None) -> dict:
    """The summary of a history file (no machine file needed; a results database of several
    machines needs ``machine``). Opened read-write so that an interrupted writer's journal
    is rolled back; a read-only file is read as it is."""
    import sqlalchemy as sa

    from ..._files import sqlite_error

    p = Path(path)
    _check_history_path(p, create=False, write=False)
    engine = _engine(p, _timeout(timeout), create=False, write=False)
    try:
        with engine.begin() as conn:  # a read transaction: a consistent snapshot of every table
            state = _classify(conn, p)
            if state == "empty":
                raise FileFormatError(f"{p}: not a gagekit history file (an empty SQLite database)")
            if state == "legacy":
                return _legacy_summary(conn)
            from ...store.machines import machine_summary

            try:
                s = machine_summary(conn, machine)
            except StoreError as exc:
                raise FileFormatError(f"{p}: {exc}") from None
            for run in s["runs"]:
                run["cycles"] = _cycle_rows(run.pop("stats"))
            return s
    except sa.exc.DBAPIError as exc:
        raise sqlite_error(exc.orig or exc, p, "history file") from None
    finally:
        engine.dispose()
