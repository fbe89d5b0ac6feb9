"""Machines and their calibrations in the results database (Sec. 4.3 tracking runs).

A tracking run (``machine track``) is one calibration of a machine: its tracker frame
(Eq. 4.11), and per measurement cycle the statistics of Tables 4.4-4.6, the identified
group values (Eqs. 4.12-4.13), the observations, the residual norms (Eqs. 4.14-4.18) and the
cycle-mean temperatures - one transaction per run. A machine is its name with the signature
of its error model (the group names); the same name with another model is refused.
"""

from __future__ import annotations

from typing import Any, Mapping, Optional, Sequence

import sqlalchemy as sa

from ..errors import ConfigError, StoreError
from . import models as m
from .results import now

__all__ = ["machine_id", "append_tracking", "machine_summary", "machine_names"]


def machine_id(conn: sa.Connection, name: str, signature: str, *, create: bool = True) -> Optional[int]:
    """The machine's id; a machine of that name with another error model is a ConfigError."""
    rows = conn.execute(sa.select(m.MachineRow.id, m.MachineRow.signature).where(m.MachineRow.name == name)).all()
    for mid, sig in rows:
        if sig == signature:
            return mid
    if rows:
        raise ConfigError(f"the database holds machine '{name}' with another error model (the machine file changed "
                          "its groups): use another database or another machine name")
    if not create:
        return None
    return conn.execute(sa.insert(m.MachineRow).values(name=name, signature=signature, created=now())
                        .returning(m.MachineRow.id)).scalar_one()


def append_tracking(conn: sa.Connection, machine: str, signature: str, *, source: Optional[str],
                    commands: Any, measured: Any, temperatures: Mapping[str, Sequence[float]],
                    cycles: Sequence[Mapping[str, Any]], groups: Mapping[str, Sequence[float]],
                    group_units: Mapping[str, str], group_effect: Mapping[str, float],
                    residuals: Mapping[str, Any], frame: Optional[Mapping[str, Any]]) -> int:
    """Store one tracking run as a calibration (in the caller's transaction); returns its id."""
    mid = machine_id(conn, machine, signature)
    cal = conn.execute(sa.insert(m.Calibration).values(machine_id=mid, kind="track", created=now(), source=source,
                                                       n_points=len(commands), frame=dict(frame) if frame else None)
                       .returning(m.Calibration.id)).scalar_one()
    n = len(commands)
    for j, row in enumerate(cycles):
        cid = int(row["cycle"])
        conn.execute(sa.insert(m.TrackingCycle).values(calibration_id=cal, cycle=cid, time=row.get("time"), stats=dict(row)))
        conn.execute(sa.insert(m.GroupValue), [
            {"calibration_id": cal, "cycle": cid, "name": name, "value": float(v[j]), "unit": group_units.get(name),
             "effect_mm": group_effect.get(name)} for name, v in groups.items()])
        conn.execute(sa.insert(m.CycleObservation), [
            {"calibration_id": cal, "cycle": cid, "idx": i, "commands": [float(c) for c in commands[i]],
             "x": float(measured[j][i][0]), "y": float(measured[j][i][1]), "z": float(measured[j][i][2])} for i in range(n)])
        conn.execute(sa.insert(m.CycleResidual), [
            {"calibration_id": cal, "cycle": cid, "idx": i, "full": float(residuals["full"][j][i]),
             "static": float(residuals["static"][j][i]), "drift_only": float(residuals["drift_only"][j][i])}
            for i in range(len(residuals["full"][j]))])
        if temperatures:
            conn.execute(sa.insert(m.CycleTemperature), [
                {"calibration_id": cal, "cycle": cid, "sensor": s, "value": float(v[j])} for s, v in temperatures.items()])
    return cal


def machine_names(conn: sa.Connection) -> list[str]:
    return list(conn.execute(sa.select(m.MachineRow.name).order_by(m.MachineRow.id)).scalars())


def machine_summary(conn: sa.Connection, name: Optional[str] = None) -> dict:
    """The runs of a machine (the only one when ``name`` is None): id, creation time, source,
    points and the statistics of each cycle (``stats``, Tables 4.4-4.6)."""
    q = sa.select(m.MachineRow.id, m.MachineRow.name, m.MachineRow.created).order_by(m.MachineRow.id)
    if name is not None:
        q = q.where(m.MachineRow.name == name)
    rows = conn.execute(q).all()
    if not rows:
        raise StoreError("no machine in the database" if name is None else f"no machine '{name}' in the database")
    if len(rows) > 1:
        raise ConfigError(f"the database holds {len(rows)} machines ({', '.join(r[1] for r in rows)}): name one")
    mid, mname, created = rows[0]
    runs = []
    for cal, ccreated, source, npts in conn.execute(
            sa.select(m.Calibration.id, m.Calibration.created, m.Calibration.source, m.Calibration.n_points)
            .where(m.Calibration.machine_id == mid).order_by(m.Calibration.id)):
        cyc = conn.execute(sa.select(m.TrackingCycle.stats).where(m.TrackingCycle.calibration_id == cal)
                           .order_by(m.TrackingCycle.cycle)).scalars().all()
        runs.append({"run": cal, "created": ccreated.isoformat(), "source": source, "points": npts, "stats": list(cyc)})
    return {"machine": mname, "created": created.isoformat(), "runs": runs}

