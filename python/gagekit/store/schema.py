"""Opening a results database: URLs, engines, schema versions, migrations (Alembic).

``sqlite:///file.db`` (or a bare file path) is the embedded default; ``postgresql://...``
uses psycopg 3. The schema is versioned by the Alembic revisions shipped in
``gagekit/store/migrations/versions``:

* an empty database is created at the newest revision;
* a database at an older revision is refused until ``gagekit db upgrade URL`` migrates it;
* a database at a revision this gagekit does not know (written by a newer gagekit) is
  refused, naming that revision;
* a database with tables but no gagekit revision is not ours and is refused.

Creation and upgrades hold a lock (SQLite: ``BEGIN IMMEDIATE``; PostgreSQL: a transaction
advisory lock), so many processes opening a new database at once create it once.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional, Union

import sqlalchemy as sa
from sqlalchemy.engine import URL, Engine

from ..errors import ConfigError, SchemaVersionError, StoreError

MIGRATIONS = Path(__file__).resolve().parent / "migrations"
#: the advisory-lock key of schema changes on PostgreSQL ("gagekit" in ASCII, truncated)
_PG_LOCK = 0x6761_6765_6B69_74
#: SQLite waits this long (s) for another writer's lock before failing
SQLITE_TIMEOUT = 60.0

__all__ = ["MIGRATIONS", "parse_url", "safe_url", "create_engine", "current_revision", "head_revision",
           "known_revisions", "ensure_schema", "upgrade", "LEGACY_HISTORY_TABLES"]

#: tables of the per-machine SQLite history files written before the results database
LEGACY_HISTORY_TABLES = frozenset({"meta", "runs", "cycles", "observations", "groups", "residuals", "temperatures"})


def parse_url(url: Union[str, Path, URL]) -> URL:
    """A SQLAlchemy URL from ``sqlite:///file``, ``postgresql://...`` or a plain file path."""
    if isinstance(url, URL):
        u = url
    else:
        text = str(url).strip()
        if not text:
            raise StoreError("empty database URL")
        if "\x00" in text:
            raise StoreError("a database URL cannot hold a NUL character")
        if "://" not in text:
            return URL.create("sqlite", database=str(Path(text)))
        try:
            u = sa.make_url(text)
        except (sa.exc.ArgumentError, ValueError) as exc:  # ValueError: a bad port or IPv6 host
            raise StoreError(f"{text}: not a database URL ({exc})") from None
    backend = u.get_backend_name()
    if backend == "postgresql" and u.drivername == "postgresql":
        u = u.set(drivername="postgresql+psycopg")
    if backend not in ("sqlite", "postgresql"):
        raise StoreError(f"{safe_url(u)}: unsupported database (use sqlite:///FILE or postgresql://...)")
    return u


def safe_url(url: Union[str, URL]) -> str:
    """The URL as text with its password hidden (for messages)."""
    if isinstance(url, URL):
        return url.render_as_string(hide_password=True)
    try:
        return sa.make_url(str(url)).render_as_string(hide_password=True)
    except sa.exc.ArgumentError:
        return str(url)


def _sqlite_events(engine: Engine) -> None:
    """pysqlite's own transaction handling defers BEGIN and never locks before the first
    write; two writers that both read first then deadlock into 'database is locked'.
    Every transaction starts with BEGIN IMMEDIATE instead (SQLAlchemy's documented recipe),
    so writers queue on the busy timeout; foreign keys are enforced. Connecting changes
    nothing in the file (a foreign or damaged file is left as it was)."""

    @sa.event.listens_for(engine, "connect")
    def _connect(dbapi_conn, _record):  # pragma: no cover - trivial
        dbapi_conn.isolation_level = None
        cur = dbapi_conn.cursor()
        cur.execute("PRAGMA foreign_keys = ON")
        cur.execute("PRAGMA synchronous = NORMAL")  # in WAL mode: no fsync per commit (see use_wal)
        cur.close()

    @sa.event.listens_for(engine, "begin")
    def _begin(conn):  # pragma: no cover - trivial
        conn.exec_driver_sql("BEGIN IMMEDIATE")


def create_engine(url: Union[str, Path, URL], *, must_exist: bool = False) -> Engine:
    """An engine for ``url`` that has connected once (errors name the URL)."""
    u = parse_url(url)
    if u.get_backend_name() == "sqlite":
        db = u.database or ""
        if db in ("", ":memory:"):
            raise StoreError("an in-memory SQLite database keeps nothing: give a file (sqlite:///FILE)")
        path = Path(db)
        if must_exist and not path.exists():
            raise StoreError(f"{safe_url(u)}: no such database file")
        if not path.parent.is_dir():
            raise StoreError(f"{safe_url(u)}: the folder {path.parent} does not exist")
        if path.exists() and not path.is_file():
            raise StoreError(f"{safe_url(u)}: not a file")
        engine = sa.create_engine(u, connect_args={"timeout": SQLITE_TIMEOUT})
        _sqlite_events(engine)
    else:
        try:
            engine = sa.create_engine(u, connect_args={"connect_timeout": 10}, pool_pre_ping=True)
        except ImportError as exc:  # the driver (psycopg) is an extra: one line, not a traceback
            raise ConfigError(f"{safe_url(u)}: PostgreSQL needs its driver ({exc.name or 'psycopg'} is missing): "
                              "pip install 'gagekit[postgresql]'") from None
    try:
        with engine.connect():
            pass
    except sa.exc.SQLAlchemyError as exc:
        engine.dispose()
        raise StoreError(f"cannot open the database {safe_url(u)}: {_reason(exc)}") from None
    return engine


def use_wal(engine: Engine) -> None:
    """Put a SQLite database of ours into write-ahead-log mode (kept in the file).

    With ``synchronous = NORMAL`` (SQLite's recommendation for WAL) a commit is not flushed
    to the disk on its own, so a transaction costs microseconds instead of an fsync: a
    crash of the process loses nothing committed, a power cut may lose the last commits but
    never corrupts the file, and a batch run again redoes exactly those scans."""
    if engine.dialect.name != "sqlite":
        return
    import sqlite3
    import time

    raw = engine.raw_connection()  # outside a transaction (no BEGIN): the mode cannot change inside one
    try:
        cur = raw.cursor()
        deadline = time.monotonic() + SQLITE_TIMEOUT
        while True:
            try:
                if cur.execute("PRAGMA journal_mode").fetchone()[0].lower() != "wal":
                    cur.execute("PRAGMA journal_mode = WAL")
                break
            except sqlite3.OperationalError as exc:
                # changing the mode while another process writes (creating the schema, say)
                # fails at once with "locked", SQLite's busy timeout does not wait for it
                if "locked" not in str(exc) or time.monotonic() > deadline:
                    raise
                time.sleep(0.05)
        cur.close()
    finally:
        raw.close()


def _reason(exc: BaseException) -> str:
    orig = getattr(exc, "orig", None) or exc
    text = str(orig).strip().splitlines()
    return text[0] if text else type(orig).__name__


def _script():
    from alembic.script import ScriptDirectory

    return ScriptDirectory(str(MIGRATIONS))


def head_revision() -> str:
    """The newest schema revision this gagekit ships."""
    return _script().get_current_head()


def known_revisions() -> list[str]:
    """Every revision this gagekit ships, oldest first."""
    return [s.revision for s in reversed(list(_script().walk_revisions()))]


def current_revision(conn: sa.Connection) -> Optional[str]:
    """The database's revision (None when it has no version table)."""
    from alembic.runtime.migration import MigrationContext

    return MigrationContext.configure(conn).get_current_revision()


def _lock(conn: sa.Connection) -> None:
    if conn.dialect.name == "postgresql":
        conn.exec_driver_sql(f"SELECT pg_advisory_xact_lock({_PG_LOCK})")


def _alembic_upgrade(conn: sa.Connection, target: str = "head") -> None:
    from alembic import command
    from alembic.config import Config

    cfg = Config()
    cfg.set_main_option("script_location", str(MIGRATIONS))
    cfg.attributes["connection"] = conn
    command.upgrade(cfg, target)


def _state(conn: sa.Connection, url: str) -> tuple[str, Optional[str]]:
    """('empty' | 'current' | 'old' | 'legacy', revision); raises for newer or foreign."""
    tables = set(sa.inspect(conn).get_table_names())
    rev = current_revision(conn) if "alembic_version" in tables else None
    if rev is None:
        other = tables - {"alembic_version"}
        if not other:
            return "empty", None
        if LEGACY_HISTORY_TABLES <= other:
            return "legacy", None
        raise StoreError(f"{url}: not a gagekit results database (it has tables {', '.join(sorted(other)[:6])}"
                         f"{', ...' if len(other) > 6 else ''} and no gagekit schema version)")
    known = known_revisions()
    if rev not in known:
        raise SchemaVersionError(
            f"{url}: the database has schema version {rev}, newer than this gagekit knows "
            f"(newest {known[-1]}): upgrade gagekit to use it")
    return ("current" if rev == known[-1] else "old"), rev


def ensure_schema(engine: Engine, *, create: bool = True) -> str:
    """Check (and for an empty database with ``create``, create) the schema; returns the
    revision. Older schemas raise :class:`SchemaVersionError` naming ``gagekit db upgrade``."""
    url = safe_url(engine.url)
    try:
        with engine.connect() as conn:
            state, rev = _state(conn, url)
        if state == "current":
            return rev
        if state == "old":
            raise SchemaVersionError(
                f"{url}: the database has schema version {rev}, older than this gagekit's {head_revision()}: "
                f"run `gagekit db upgrade {url}` first")
        if state == "legacy":
            raise SchemaVersionError(
                f"{url}: a tracking history file of an older gagekit: run `gagekit db upgrade {url}` to migrate it")
        if not create:
            raise StoreError(f"{url}: the database is empty (no gagekit results)")
        with engine.begin() as conn:
            _lock(conn)
            state, rev = _state(conn, url)  # another process may have created it meanwhile
            if state == "empty":
                _alembic_upgrade(conn)
        return head_revision()
    except sa.exc.SQLAlchemyError as exc:
        raise StoreError(f"cannot use the database {url}: {_reason(exc)}") from None


def upgrade(url: Union[str, Path, URL]) -> tuple[Optional[str], str]:
    """Migrate the database to the newest schema (creating it when empty, converting a
    legacy history file); returns (revision before, revision after)."""
    engine = create_engine(url)
    u = safe_url(engine.url)
    try:
        with engine.begin() as conn:
            _lock(conn)
            state, rev = _state(conn, u)
            if state == "legacy":
                from .legacy import migrate_history

                migrate_history(conn, _alembic_upgrade)
                rev = "legacy-history"
            elif state != "current":
                _alembic_upgrade(conn)
        return rev, head_revision()
    except sa.exc.SQLAlchemyError as exc:
        raise StoreError(f"cannot upgrade the database {u}: {_reason(exc)}") from None
    finally:
        engine.dispose()
