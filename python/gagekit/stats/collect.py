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

With a measurement standard uncertainty (``measurement_u``, ``--measurement-uncertainty``)
every measured length characteristic (allowances, stock, form errors, inspection values; not
the motions of T*, which are computed from many points) also gets the ISO 22514-7 split of its
observed variance into process and measurement (:func:`gagekit.stats.spc.measurement_split`):
``measurement`` {u, observed {cp, cpk, ...}, process {cp, cpk, ...}, q_mp_pct, ...}.

Values are in time order of the scans: the acquisition time the scan file records (E57
``acquisitionStart``, LAS creation date: ``scans.acquired``), else the time the result was
stored (a file's modification time says when it was copied, not when it was scanned); the
series gives each value's time and its ``time_source``. Results carry a resolution
(:data:`gagekit.stats.spc.RESOLUTION`, ``--resolution``): values within it of a limit are on
the limit, and a characteristic that does not vary above it has no index (see
:mod:`gagekit.stats.spc`). Machines: the
identified parameter groups of every calibration (each cycle of each tracking run is an
identification, Eqs. 4.12-4.13, timed by the run's start plus the cycle's time in minutes), their change since the first one and its trend per day - Fig. 4.8
across days instead of across the cycles of one day.
"""

from __future__ import annotations

import math
from collections import defaultdict
from datetime import datetime, timedelta, timezone
from typing import Any, Optional

import sqlalchemy as sa

from ..store import models as m
from ..store.schema import _reason, create_engine, ensure_schema, safe_url
from ..errors import StoreError
from .spc import MIN_CAPABILITY_VALUES, MIN_TREND_DAYS, RESOLUTION, capability, imr_chart, on_limits, trend_per_day

__all__ = ["collect", "characteristic", "messages"]


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


def _utc(t: datetime) -> datetime:
    return t.replace(tzinfo=timezone.utc) if t.tzinfo is None else t


def characteristic(name: str, unit: str, values: list, times: list, scans: list,
                   lower: Optional[float] = None, upper: Optional[float] = None, *,
                   resolution: Optional[float] = None, time_source: Optional[list] = None,
                   measurement_u: Optional[float] = None) -> dict:
    """Capability, I-MR chart with Western Electric signals, trend per day of one series
    (``resolution``: of the unit, default :data:`RESOLUTION`; ``measurement_u``: the
    measurement's standard uncertainty, ISO 22514-7)."""
    res = RESOLUTION.get(unit, 0.0) if resolution is None else resolution
    cap = capability(values, lower, upper, resolution=res, unit=unit, measurement_u=measurement_u)
    x = on_limits(values, lower, upper, res)
    d: dict[str, Any] = {"name": name, "unit": unit, **cap.to_dict()}
    notes = d.setdefault("notes", [])
    if lower is not None or upper is not None:
        d["zero_margin"] = bool(cap.on_limit)
    days = _days(times)
    trend = trend_per_day(days, x) if cap.varies else None
    if trend is not None:
        d["trend_per_day"] = trend
    elif len(days) >= 2 and cap.varies:
        span = (max(days) - min(days)) * 24.0
        notes.append(f"{span:.3g} h of data, less than {MIN_TREND_DAYS:g} day: no trend per day")
    if not notes:
        del d["notes"]
    chart = imr_chart(x, res)
    if chart is not None:
        c = chart.to_dict()
        for s in c["signals"]:
            s["scan"] = scans[s["index"]]
        d["chart"] = c
    d["series"] = {"time": [_utc(t).isoformat() for t in times], "value": list(map(float, x)), "scan": scans}
    if time_source is not None:
        d["series"]["time_source"] = time_source
    return d


def messages(c: dict) -> list[tuple[str, str]]:
    """(kind, line) of a characteristic's warnings and notes for people: ``zero margin``
    (values on a limit), ``warning`` (too few values), ``note`` (why an index or a trend is
    missing; the obvious "no specification limits" left out)."""
    out = [("zero margin" if "nothing is left" in w else "warning", f"{c['name']}: {w}") for w in c.get("warnings", [])]
    out += [("note", f"{c['name']}: {n}") for n in c.get("notes", []) if not n.startswith("no specification limits")]
    m = c.get("measurement")
    if m is not None:
        ob, pr = m["observed"], m["process"]
        parts = [f"{k} observed {ob[k]:.3g}" + (f", process {pr[k]:.3g}" if k in pr else "") for k in ("cpk", "ppk") if k in ob]
        if parts:
            q = f"; Q_MP {m['q_mp_pct']:.0f} %" if "q_mp_pct" in m else ""
            out.append(("measurement", f"{c['name']}: u = {m['u']:.3g} (ISO 22514-7, observed = process + measurement): "
                        + "; ".join(parts) + q))
        out += [("note", f"{c['name']}: {n}") for n in m.get("notes", [])]
    return out


def _time(acquired: Optional[datetime], stored: datetime) -> tuple[datetime, str]:
    return (_utc(acquired), "acquired") if acquired is not None else (_utc(stored), "stored")


def _results(conn, spec_id: int, extra_cols, join_table, *where):
    """(result id, path, time, time source, *extra) of a spec's ok results, in time order:
    the scan's acquisition time, else the time its result was stored; equal times by path."""
    q = (sa.select(m.Result.id, m.Result.path, m.Scan.acquired, m.Result.finished, *extra_cols)
         .join(m.Scan, m.Scan.id == m.Result.scan_id)
         .join(join_table, join_table.result_id == m.Result.id)
         .where(m.Result.spec_id == spec_id, m.Result.status == "ok", *where))
    rows = [(r[0], r[1], *_time(r[2], r[3]), *r[4:]) for r in conn.execute(q).all()]
    rows.sort(key=lambda r: (r[2], r[1]))
    return rows


def _series(name: str, unit: str, rows: list, col: int, res: dict, u_col: Optional[int] = None, **limits) -> dict:
    """One characteristic from ``_results`` rows (value in column ``col``); ``res`` may carry
    the measurement's standard uncertainty under ``"u"`` (lengths only). Without it, the
    uncertainties stored with the results (column ``u_col``: each result's Monte Carlo u,
    ``--uncertainty``) give u = sqrt(mean u_i^2), the measurement variance averaged over
    the results that have one (``measurement.source`` says so)."""
    u = res.get("u") if unit == "mm" and not name.startswith("T* ") else None
    stored = [float(r[u_col]) for r in rows if r[u_col] is not None] if u_col is not None and u is None else []
    if stored:
        u = math.sqrt(sum(x * x for x in stored) / len(stored))
    d = characteristic(name, unit, [r[col] for r in rows], [r[2] for r in rows], [r[1] for r in rows],
                       resolution=res.get(unit, 0.0), time_source=[r[3] for r in rows], measurement_u=u, **limits)
    if stored and isinstance(d.get("measurement"), dict):
        d["measurement"]["source"] = (f"stored results: sqrt(mean u^2) of the Monte Carlo u of {len(stored)} of "
                                        f"{len(rows)} results (JCGM 101)")
    return d


def _gage_spec(conn, spec, res: dict) -> list[dict]:
    """Per gage: the allowance after T* (lower limit 0: the part can be machined to print),
    the allowance before T* and the stock q (no specification limits: the casting as
    fixtured and the deepest cut are not toleranced, so no capability); per free motion
    of T*, its value against the bounds of Omega."""
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
                                     m.GageAllowance.allowance_before, m.GageAllowance.q, m.GageAllowance.u], m.GageAllowance)
    by: dict[str, list] = defaultdict(list)
    for r in rows:
        by[r[4]].append(r)
    for col, what, lower in ((5, "allowance after T*", 0.0), (6, "allowance before T*", None), (7, "stock q after T*", None)):
        for g, s in by.items():  # the stored u is the allowance after T*'s
            out.append(_series(f"{what}: {g}", "mm", s, col, res, u_col=8 if col == 5 else None, lower=lower))
    cols = [getattr(m.GageCheck, k) for k in ("alpha", "beta", "gamma", "dx", "dy", "dz")]
    rows = _results(conn, spec.id, cols, m.GageCheck)
    if rows:
        for k, motion_name in enumerate(("alpha", "beta", "gamma", "dx", "dy", "dz")):
            if motion_name not in free:
                continue
            angle = motion_name in ("alpha", "beta", "gamma")
            bound = max_angle if angle else max_shift
            out.append(_series(f"T* {motion_name}", "rad" if angle else "mm", rows, 4 + k, res, lower=-bound, upper=bound))
    return out


def _form_spec(conn, spec, tolerance: Optional[float], res: dict) -> list[dict]:
    rows = _results(conn, spec.id, [m.FormResult.form_error], m.FormResult)
    if not rows:
        return []
    d = spec.document or {}
    return [_series(f"form error: {d.get('shape', '?')} ({d.get('criterion', '?')})", "mm", rows, 4, res,
                    upper=tolerance)]


def _inspect_spec(conn, spec, res: dict) -> list[dict]:
    rows = _results(conn, spec.id, [m.InspectionResult.tolerance, m.InspectionResult.value, m.InspectionResult.lower,
                                    m.InspectionResult.upper, m.InspectionResult.u], m.InspectionResult)
    by: dict[str, list] = defaultdict(list)
    for r in rows:
        by[r[4]].append(r)
    return [_series(f"tolerance: {t}", "mm", s, 5, res, u_col=8, lower=s[-1][6], upper=s[-1][7]) for t, s in by.items()]


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


def collect(url: str, *, documents: Optional[list] = None, tolerance: Optional[float] = None,
            resolution: float = RESOLUTION["mm"], measurement_u: Optional[float] = None) -> dict:
    """The SPC of the database at ``url``: every spec, or those whose stored document is one
    of ``documents`` (a gage file is stored as ``{"spec": parsed TOML}``), and the machines.

    ``tolerance`` (mm, > 0): the upper limit of form errors; ``resolution`` (mm, > 0): of
    lengths, and of angles over a 1 m lever (``resolution / 1000`` rad); ``measurement_u``
    (mm, >= 0): the standard uncertainty (k = 1) of a measured length (ISO 22514-7 split)."""
    import math

    from ..errors import ConfigError

    if tolerance is not None and not (math.isfinite(tolerance) and tolerance > 0):
        raise ConfigError(f"--tolerance {tolerance:g}: a form tolerance is a positive number of mm")
    if not (math.isfinite(resolution) and 0 < resolution < 1):
        raise ConfigError(f"--resolution {resolution:g}: the resolution of results is a positive number of mm below 1")
    if measurement_u is not None and not (math.isfinite(measurement_u) and measurement_u >= 0):
        raise ConfigError(f"--measurement-uncertainty {measurement_u:g}: a standard uncertainty is a number of mm >= 0")
    res = {"mm": resolution, "rad": resolution * 1e-3}
    keyed = dict(res, u=measurement_u) if measurement_u is not None else res
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
                    chars = _gage_spec(conn, spec, keyed)
                elif spec.kind == "form":
                    chars = _form_spec(conn, spec, tolerance, keyed)
                else:
                    chars = _inspect_spec(conn, spec, keyed)
                entry = {"spec": spec.hash[:12], "kind": spec.kind, "results": n, "failed": failed,
                         "characteristics": chars}
                if spec.source:
                    entry["source"] = spec.source
                if spec.name:
                    entry["part"] = spec.name
                specs.append(entry)
            machines = _machines(conn) if documents is None else []
        out = {"database": safe_url(engine.url), "generated": datetime.now(timezone.utc).isoformat(),
               "resolution": res, "min_values_for_capability": MIN_CAPABILITY_VALUES, "min_trend_days": MIN_TREND_DAYS,
               "specs": specs, "machines": machines}
        if measurement_u is not None:
            out["measurement"] = {"u": measurement_u, "k": 1, "unit": "mm", "applies_to": "measured lengths (not T*)",
                                  "model": "observed variance = process variance + measurement variance (ISO 22514-7)"}
        return out
    except sa.exc.SQLAlchemyError as exc:
        raise StoreError(f"cannot read {safe_url(engine.url)}: {_reason(exc)}") from None
    finally:
        engine.dispose()
