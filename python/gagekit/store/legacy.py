"""Converting a tracking history file of an older gagekit into the results database.

Those SQLite files (``machine track --history``) held one machine in the tables ``meta``
(machine name, group signature, creation time), ``runs``, ``cycles`` (statistics as JSON),
``observations``, ``groups``, ``residuals`` and ``temperatures``. :func:`migrate_history`
creates the current schema in the same file, copies every run as a calibration of that
machine with its cycles, group values, observations, residuals and temperatures, and drops
the old tables, all in the caller's transaction (nothing changes if anything fails).
"""

from __future__ import annotations

import json
from datetime import datetime, timezone
from typing import Callable, Optional

import sqlalchemy as sa

from . import models as m

__all__ = ["migrate_history"]

_OLD_TABLES = ("observations", "residuals", "temperatures", "groups", "cycles", "runs", "meta")


def _time(text: Optional[str]) -> datetime:
    if not text:
        return datetime.now(timezone.utc)
    t = datetime.fromisoformat(text)
    return t if t.tzinfo else t.replace(tzinfo=timezone.utc)


def migrate_history(conn: sa.Connection, create_schema: Callable[[sa.Connection], None]) -> int:
    """Convert the legacy history tables on ``conn`` (in its transaction): read them, create
    the current schema with ``create_schema(conn)`` (the caller's migration, so this module
    does not import the schema module back), copy the runs; returns the number copied."""
    q = conn.exec_driver_sql
    meta = dict(q("SELECT key, value FROM meta").fetchall())
    runs = q("SELECT id, created, source, n_points FROM runs ORDER BY id").fetchall()
    create_schema(conn)
    machine = meta.get("machine") or "unknown machine"
    sig = meta.get("groups") or ""
    mid = conn.execute(sa.insert(m.MachineRow).values(name=machine, signature=sig, created=_time(meta.get("created")))
                       .returning(m.MachineRow.id)).scalar_one()
    for run, created, source, npts in runs:
        cal = conn.execute(sa.insert(m.Calibration).values(machine_id=mid, kind="track", created=_time(created),
                                                           source=source, n_points=int(npts or 0), frame=None)
                           .returning(m.Calibration.id)).scalar_one()
        rows = [{"calibration_id": cal, "cycle": c, "time": t, "stats": json.loads(s)}
                for c, t, s in q("SELECT cycle, time, stats FROM cycles WHERE run = ? ORDER BY cycle", (run,))]
        if rows:
            conn.execute(sa.insert(m.TrackingCycle), rows)
        rows = [{"calibration_id": cal, "cycle": c, "name": n, "value": v, "unit": None, "effect_mm": None}
                for c, n, v in q("SELECT cycle, name, value FROM groups WHERE run = ?", (run,))]
        if rows:
            conn.execute(sa.insert(m.GroupValue), rows)
        rows = [{"calibration_id": cal, "cycle": c, "idx": i, "commands": json.loads(cmd), "x": x, "y": y, "z": z}
                for c, i, cmd, x, y, z in q("SELECT cycle, idx, commands, x, y, z FROM observations WHERE run = ?", (run,))]
        if rows:
            conn.execute(sa.insert(m.CycleObservation), rows)
        rows = [{"calibration_id": cal, "cycle": c, "idx": i, "full": f, "static": s, "drift_only": d}
                for c, i, f, s, d in q("SELECT cycle, idx, full, static, drift_only FROM residuals WHERE run = ?", (run,))]
        if rows:
            conn.execute(sa.insert(m.CycleResidual), rows)
        rows = [{"calibration_id": cal, "cycle": c, "sensor": s, "value": v}
                for c, s, v in q("SELECT cycle, sensor, value FROM temperatures WHERE run = ?", (run,))]
        if rows:
            conn.execute(sa.insert(m.CycleTemperature), rows)
    for t in _OLD_TABLES:
        q(f'DROP TABLE "{t}"')
    return len(runs)
