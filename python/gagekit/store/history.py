"""A machine's tracking history in the results database (``machine track --history``).

``--history`` takes a SQLite file (or any database URL): each tracking run is stored as a
calibration of the machine with its cycles (:mod:`gagekit.store.machines`), one transaction
per run. A history file of the older gagekit (its own tables ``meta``, ``runs``, ...) is
read as it is, and converted into the results database in place (one transaction) the
first time a run is appended to it.

Errors name the file: a missing file to read, a damaged file or a database that is not
gagekit's (left unchanged), a read-only file, a file locked by another writer for longer
than ``GAGEKIT_HISTORY_TIMEOUT`` seconds (default 60), a machine whose error model changed.
"""

from __future__ import annotations

import json
import os
import sqlite3
from pathlib import Path
from typing import Any, Optional, Union

import sqlalchemy as sa

from ..errors import ConfigError, FileFormatError, SchemaVersionError, StoreError
from .machines import append_tracking, machine_summary
from .schema import LEGACY_HISTORY_TABLES, _alembic_upgrade, _lock, _reason, _state

__all__ = ["History", "read_history", "history_timeout"]

_NOT_OURS = "not a gagekit history file"


def history_timeout() -> float:
    """Seconds a history write waits for another writer's lock (``GAGEKIT_HISTORY_TIMEOUT``)."""
    try:
        return max(0.0, float(os.environ.get("GAGEKIT_HISTORY_TIMEOUT", "60")))
    except ValueError:
        return 60.0


def _engine(path: Path, read_only: bool) -> sa.Engine:
    """A SQLite engine on ``path`` that changes nothing by connecting (read-only: mode=ro)."""
    from .schema import _sqlite_events

    uri = f"file:{path}?mode=ro" if read_only else f"file:{path}?mode=rw"
    engine = sa.create_engine("sqlite://", creator=lambda: sqlite3.connect(uri, uri=True, timeout=history_timeout()),
                              poolclass=sa.pool.NullPool)
    _sqlite_events(engine)
    return engine


def _error(path: Path, exc: BaseException) -> Exception:
    """One typed error for what SQLite said about ``path``."""
    text = _reason(exc)
    low = text.lower()
    if "readonly" in low or "read-only" in low:
        return StoreError(f"{path}: the history file is read-only ({text})")
    if "locked" in low or "busy" in low:
        return StoreError(f"{path}: the history file is locked by another writer ({text}); "
                          f"waited {history_timeout():g} s (GAGEKIT_HISTORY_TIMEOUT)")
    if "not a database" in low or "malformed" in low or "corrupt" in low:
        return FileFormatError(f"{path}: {_NOT_OURS} ({text})")
    return StoreError(f"{path}: {text}")


def _check_path(path: Path, must_exist: bool) -> None:
    if path.exists() and not path.is_file():
        raise FileFormatError(f"{path}: not a file")
    if must_exist and not path.exists():
        raise FileFormatError(f"{path}: history file not found")
    if not path.parent.is_dir():
        raise FileFormatError(f"{path}: the folder {path.parent} does not exist")


def _classify(conn: sa.Connection, path: Path) -> str:
    """'empty' | 'current' | 'legacy'; a foreign or newer database raises (left unchanged)."""
    try:
        state, _ = _state(conn, str(path))
    except SchemaVersionError:
        raise
    except StoreError as exc:
        raise FileFormatError(f"{path}: {_NOT_OURS} ({exc})") from None
    if state == "old":
        raise SchemaVersionError(f"{path}: the history file has an older schema: run `gagekit db upgrade {path}` first")
    return state


class History:
    """One machine's tracking runs in a SQLite results database (``path``)."""

    def __init__(self, path: Union[str, Path], machine: Any, create: bool = True):
        self.path = Path(path)
        self.machine = machine
        self.signature = "|".join(g.name for g in machine.structure().groups)
        _check_path(self.path, must_exist=not create)
        if create and not self.path.exists():
            try:
                self.path.touch()
            except OSError as exc:
                raise StoreError(f"{self.path}: cannot create the history file ({exc.strerror or exc})") from None
        self.engine = _engine(self.path, read_only=False)

    def close(self) -> None:
        self.engine.dispose()

    def append(self, cycles: Any, result: Any) -> int:
        """Store one tracking run (one transaction); returns its run (calibration) id."""
        try:
            with self.engine.begin() as conn:
                _lock(conn)
                state = _classify(conn, self.path)
                if state == "legacy":
                    from .legacy import migrate_history

                    migrate_history(conn)
                elif state == "empty":
                    _alembic_upgrade(conn)
                return append_tracking(
                    conn, self.machine.name, self.signature, source=cycles.source, commands=cycles.commands,
                    measured=cycles.measured, temperatures=cycles.temperatures, cycles=result.cycles,
                    groups=result.groups, group_units=result.group_units, group_effect=result.group_effect,
                    residuals=result.residuals, frame=result.frame)
        except ConfigError as exc:
            raise ConfigError(f"{self.path}: {exc}") from None
        except sa.exc.SQLAlchemyError as exc:
            raise _error(self.path, exc) from None

    def summary(self) -> dict:
        return read_history(self.path, machine=self.machine.name)


def _legacy_summary(conn: sa.Connection) -> dict:
    """The runs of an older gagekit's history file, read as they are."""
    q = conn.exec_driver_sql
    meta = dict(q("SELECT key, value FROM meta").fetchall())
    runs = []
    for run, created, source, npts in q("SELECT id, created, source, n_points FROM runs ORDER BY id").fetchall():
        cyc = [json.loads(s) for (s,) in q("SELECT stats FROM cycles WHERE run = ? ORDER BY cycle", (run,)).fetchall()]
        runs.append({"run": run, "created": created, "source": source, "points": npts,
                     "cycles": [{"cycle": c["cycle"], "observed_mean": c["observed"]["mean"], "full_mean": c["full"]["mean"],
                                 "static_mean": c["static"]["mean"], "drift_only_mean": c["drift_only"]["mean"]}
                                for c in cyc]})
    return {"machine": meta.get("machine"), "created": meta.get("created"), "runs": runs}


def read_history(path: Union[str, Path], machine: Optional[str] = None) -> dict:
    """The runs stored in a history file, opened read-only (no machine file needed; a file
    holding several machines needs ``machine``)."""
    p = Path(path)
    _check_path(p, must_exist=True)
    engine = _engine(p, read_only=True)
    try:
        with engine.connect() as conn:
            names = set(sa.inspect(conn).get_table_names())
            if "alembic_version" not in names and LEGACY_HISTORY_TABLES <= names:
                return _legacy_summary(conn)
            state = _classify(conn, p)
            if state == "empty":
                raise FileFormatError(f"{p}: {_NOT_OURS} (it is empty)")
            try:
                return machine_summary(conn, machine)
            except StoreError as exc:
                raise StoreError(f"{p}: {exc}") from None
    except sa.exc.SQLAlchemyError as exc:
        raise _error(p, exc) from None
    finally:
        engine.dispose()

