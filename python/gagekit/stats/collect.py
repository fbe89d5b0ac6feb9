"""SPC of a results database: every characteristic of every spec, every machine's drift.

Characteristics and their limits:

* virtual gages (Ch. 5): per gage the allowance after T* (mm), lower limit 0 (short of
  material below it, Eq. 5.11's slack; a gage whose allowance stays 0 is the one that
  places the part), the allowance before T* (the casting as fixtured, lower limit 0) and
  the stock q_i after T* (the deepest cut, Eq. 5.4, no limit); and T* itself, each free motion against the
  bounds of Omega (Eq. 5.2: +-max_shift mm, +-max_angle rad), where a fixture drifting
  towards a bound is seen before a casting cannot be corrected any more;
* form fits (Ch. 6): the form error (mm), upper limit the ``--tolerance`` when given;
* inspections: each tolerance's value against its lower/upper limits as stored.

Values are in time order of the scans (the files' modification times). Machines: the
identified parameter groups of every calibration (each cycle of each tracking run is an
identification, Eqs. 4.12-4.13, timed by the run's start plus the cycle's time in minutes), their change since the first one and its trend per day - Fig. 4.8
across days instead of across the cycles of one day.
"""

from __future__ import annotations

from collections import defaultdict
from datetime import datetime, timedelta, timezone
from typing import Any, Optional

import sqlalchemy as sa

from ..store import models as m
from ..store.schema import _reason, create_engine, ensure_schema, safe_url
from ..errors import StoreError
from .spc import capability, imr_chart, trend_per_day

__all__ = ["collect", "characteristic"]


def _days(times: list) -> list[float]:
    t0 = None
    out = []
    for t in times:
        if t.tzinfo is None:
            t = t.replace(tzinfo=timezone.utc)
        if t0 is None:
            t0 = t
        out.append((t - t0).total_seconds() / 86400.0)
    return out


def characteristic(name: str, unit: str, values: list, times: list, scans: list,
                   lower: Optional[float] = None, upper: Optional[float] = None) -> dict:
    """Capability, I-MR chart with Western Electric signals, trend per day of one series."""
    cap = capability(values, lower, upper)
    d: dict[str, Any] = {"name": name, "unit": unit, **cap.to_dict()}
    trend = trend_per_day(_days(times), values)
    if trend is not None:
        d["trend_per_day"] = trend
    chart = imr_chart(values)
    if chart is not None:
        c = chart.to_dict()
        for s in c["signals"]:
            s["scan"] = scans[s["index"]]
        d["chart"] = c
    d["series"] = {"time": [t.isoformat() for t in times], "value": list(map(float, values)), "scan": scans}
    return d


def _results(conn, spec_id: int, extra_cols, join_table, *where):
    q = (sa.select(m.Result.id, m.Result.path, m.Scan.scanned, *extra_cols)
         .join(m.Scan, m.Scan.id == m.Result.scan_id)
         .join(join_table, join_table.result_id == m.Result.id)
         .where(m.Result.spec_id == spec_id, m.Result.status == "ok", *where)
         .order_by(m.Scan.scanned, m.Result.path))
    return conn.execute(q).all()


def _gage_spec(conn, spec) -> list[dict]:
    doc = (spec.document or {}).get("spec", {})
    motion = doc.get("motion", {}) if isinstance(doc, dict) else {}
    free = motion.get("free", ["alpha", "beta", "gamma", "dx", "dy", "dz"])
    max_angle = float(motion.get("max_angle", 0.05))
    max_shift = float(motion.get("max_shift", 20.0))
    if doc.get("angle_unit") == "deg":
        import math

        max_angle = math.radians(max_angle)
    out = []
    rows = _results(conn, spec.id, [m.GageAllowance.gage, m.GageAllowance.allowance_after,
                                     m.GageAllowance.allowance_before, m.GageAllowance.q], m.GageAllowance)
    by = defaultdict(list)
    order: list[str] = []
    for rid, path, scanned, gage, after, before, q in rows:
        if gage not in by:
            order.append(gage)
        by[gage].append((scanned, path, after, before, q))
    for col, what, lower in ((2, "allowance after T*", 0.0), (3, "allowance before T*", 0.0), (4, "stock q after T*", None)):
        for g in order:
            s = by[g]
            out.append(characteristic(f"{what}: {g}", "mm", [r[col] for r in s], [r[0] for r in s], [r[1] for r in s],
                                      lower=lower))
    cols = [getattr(m.GageCheck, k) for k in ("alpha", "beta", "gamma", "dx", "dy", "dz")]
    rows = _results(conn, spec.id, cols, m.GageCheck)
    if rows:
        for k, motion_name in enumerate(("alpha", "beta", "gamma", "dx", "dy", "dz")):
            if motion_name not in free:
                continue
            bound = max_angle if motion_name in ("alpha", "beta", "gamma") else max_shift
            out.append(characteristic(f"T* {motion_name}", "rad" if bound is max_angle else "mm",
                                      [r[3 + k] for r in rows], [r[2] for r in rows], [r[1] for r in rows],
                                      lower=-bound, upper=bound))
    return out


def _form_spec(conn, spec, tolerance: Optional[float]) -> list[dict]:
    rows = _results(conn, spec.id, [m.FormResult.form_error], m.FormResult)
    if not rows:
        return []
    d = spec.document or {}
    return [characteristic(f"form error: {d.get('shape', '?')} ({d.get('criterion', '?')})", "mm",
                           [r[3] for r in rows], [r[2] for r in rows], [r[1] for r in rows], upper=tolerance)]


def _inspect_spec(conn, spec) -> list[dict]:
    rows = _results(conn, spec.id, [m.InspectionResult.tolerance, m.InspectionResult.value, m.InspectionResult.lower,
                                    m.InspectionResult.upper], m.InspectionResult)
    by = defaultdict(list)
    for rid, path, scanned, tol, value, lo, up in rows:
        by[tol].append((scanned, path, value, lo, up))
    return [characteristic(f"tolerance: {t}", "mm", [v for _, _, v, _, _ in s], [x[0] for x in s], [x[1] for x in s],
                           lower=s[-1][3], upper=s[-1][4]) for t, s in by.items()]


def _machines(conn) -> list[dict]:
    out = []
    for mid, name in conn.execute(sa.select(m.MachineRow.id, m.MachineRow.name).order_by(m.MachineRow.id)):
        cals = conn.execute(sa.select(m.Calibration.id, m.Calibration.created)
                            .where(m.Calibration.machine_id == mid).order_by(m.Calibration.created, m.Calibration.id)).all()
        if not cals:
            continue
        series: dict[str, list] = defaultdict(list)
        units: dict[str, Optional[str]] = {}
        effects: dict[str, Optional[float]] = {}
        n_points = 0
        for cid, created in cals:
            if created.tzinfo is None:
                created = created.replace(tzinfo=timezone.utc)
            times = dict(conn.execute(sa.select(m.TrackingCycle.cycle, m.TrackingCycle.time)
                                      .where(m.TrackingCycle.calibration_id == cid)).all())
            cycles = set()
            for cyc, gname, value, unit, effect in conn.execute(
                    sa.select(m.GroupValue.cycle, m.GroupValue.name, m.GroupValue.value, m.GroupValue.unit,
                              m.GroupValue.effect_mm)
                    .where(m.GroupValue.calibration_id == cid).order_by(m.GroupValue.cycle, m.GroupValue.id)):
                # a cycle's time column is in minutes from the run's start; without it, cycles an hour apart
                minutes = times.get(cyc)
                t = created + timedelta(minutes=float(minutes) if minutes is not None else 60.0 * (cyc - 1))
                series[gname].append((t, value))
                units[gname] = unit
                effects[gname] = effect
                cycles.add(cyc)
            n_points += len(cycles)
        groups = []
        for gname, s in series.items():
            s.sort(key=lambda tv: tv[0])
            times = [t for t, _ in s]
            vals = [v for _, v in s]
            change = [v - vals[0] for v in vals]
            g = {"name": gname, "identifications": len(vals), "first": vals[0], "last": vals[-1],
                 "max_change": max(change, key=abs), "values": vals, "times": [t.isoformat() for t in times]}
            if units.get(gname):
                g["unit"] = units[gname]
            if effects.get(gname) is not None:
                g["effect_mm_per_unit"] = effects[gname]
                g["max_change_effect_um"] = abs(g["max_change"]) * effects[gname] * 1000.0
            tr = trend_per_day(_days(times), vals)
            if tr is not None:
                g["trend_per_day"] = tr
            groups.append(g)
        groups.sort(key=lambda g: -g.get("max_change_effect_um", abs(g["max_change"])))
        out.append({"machine": name, "calibrations": len(cals), "identifications": n_points,
                    "from": cals[0][1].isoformat(), "to": cals[-1][1].isoformat(), "groups": groups})
    return out


def collect(url: str, *, documents: Optional[list] = None, tolerance: Optional[float] = None) -> dict:
    """The SPC of the database at ``url``: every spec, or those whose stored document is one
    of ``documents`` (a gage file is stored as ``{"spec": parsed TOML}``), and the machines."""
    engine = create_engine(url, must_exist=True)
    try:
        ensure_schema(engine, create=False)
        with engine.connect() as conn:
            q = sa.select(m.Spec.id, m.Spec.hash, m.Spec.kind, m.Spec.source, m.Spec.document, m.Part.name) \
                .outerjoin(m.Part, m.Part.id == m.Spec.part_id).order_by(m.Spec.id)
            specs = []
            for spec in conn.execute(q):
                if documents is not None and spec.document not in documents:
                    continue
                n = conn.execute(sa.select(sa.func.count()).select_from(m.Result).where(m.Result.spec_id == spec.id)).scalar()
                failed = conn.execute(sa.select(sa.func.count()).select_from(m.Result)
                                      .where(m.Result.spec_id == spec.id, m.Result.status == "error")).scalar()
                if spec.kind == "gage":
                    chars = _gage_spec(conn, spec)
                elif spec.kind == "form":
                    chars = _form_spec(conn, spec, tolerance)
                else:
                    chars = _inspect_spec(conn, spec)
                entry = {"spec": spec.hash[:12], "kind": spec.kind, "results": n, "failed": failed,
                         "characteristics": chars}
                if spec.source:
                    entry["source"] = spec.source
                if spec.name:
                    entry["part"] = spec.name
                specs.append(entry)
            machines = _machines(conn) if documents is None else []
        return {"database": safe_url(engine.url), "generated": datetime.now(timezone.utc).isoformat(),
                "specs": specs, "machines": machines}
    except sa.exc.SQLAlchemyError as exc:
        raise StoreError(f"cannot read {safe_url(engine.url)}: {_reason(exc)}") from None
    finally:
        engine.dispose()
