"""Writing and reading scan results: one transaction per scan, idempotent.

A result is keyed by (scan content hash, spec hash). :meth:`ResultStore.record` inserts
the scan, its paths, the result and its detail rows (gage allowances and T*, form fits,
inspection tolerances) in one transaction with ``INSERT ... ON CONFLICT DO NOTHING`` on
the unique keys, so concurrent writers never store a result twice and never lose one, and
a batch run again finds what is done.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Iterable, Mapping, Optional, Sequence, Union

import sqlalchemy as sa
from sqlalchemy.engine import URL

from ..errors import StoreError
from . import models as m
from .schema import _reason, create_engine, ensure_schema, safe_url, use_wal

__all__ = ["ResultStore", "StoredResult", "spec_hash", "canonical_json", "now", "inspection_rows"]


def now() -> datetime:
    return datetime.now(timezone.utc)


def canonical_json(obj: Any) -> str:
    """JSON with sorted keys and no spaces: the same document always hashes the same."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=False)


def spec_hash(kind: str, document: Mapping[str, Any], options: Mapping[str, Any]) -> str:
    """SHA-256 of the canonical JSON of (kind, document, options)."""
    return hashlib.sha256(canonical_json({"kind": kind, "document": document, "options": options}).encode()).hexdigest()


@dataclass(frozen=True)
class StoredResult:
    status: str
    result: Optional[dict]
    error: Optional[str]
    path: str


_STATEMENTS: dict = {}


def _dialect_insert(conn: sa.Connection):
    """The ``insert`` of the connection's dialect (PostgreSQL or SQLite): the one with
    ``ON CONFLICT`` clauses."""
    if conn.dialect.name == "postgresql":
        from sqlalchemy.dialects.postgresql import insert
    else:
        from sqlalchemy.dialects.sqlite import insert
    return insert


def _insert_ignore(conn: sa.Connection, table: sa.Table, rows: Union[dict, list], keys: Sequence[str],
                   returning: Optional[sa.Column] = None):
    """INSERT ... ON CONFLICT (keys) DO NOTHING [RETURNING col] on SQLite and PostgreSQL
    (statements built once per dialect: building them costs more than running them)."""
    key = (conn.dialect.name, table.name, tuple(keys), None if returning is None else returning.name)
    stmt = _STATEMENTS.get(key)
    if stmt is None:
        stmt = _dialect_insert(conn)(table).on_conflict_do_nothing(index_elements=list(keys))
        if returning is not None:
            stmt = stmt.returning(returning)
        _STATEMENTS[key] = stmt
    return conn.execute(stmt, rows)


def _plain_insert(table: sa.Table):
    stmt = _STATEMENTS.get(table.name)
    if stmt is None:
        stmt = _STATEMENTS[table.name] = sa.insert(table)
    return stmt


def _upsert_scan(conn: sa.Connection, row: dict) -> int:
    """The id of the scan with this content hash, stored first if new: one statement
    (INSERT ... ON CONFLICT DO UPDATE ... RETURNING, the update a no-op) instead of an
    insert-or-ignore and a select - each statement is a trip through the driver, and in
    a batch's parent the result collection waits for it."""
    key = (conn.dialect.name, "scan-upsert")
    stmt = _STATEMENTS.get(key)
    if stmt is None:
        ins = _dialect_insert(conn)(m.Scan.__table__)
        stmt = _STATEMENTS[key] = ins.on_conflict_do_update(
            index_elements=["content_hash"], set_={"content_hash": ins.excluded.content_hash}).returning(m.Scan.__table__.c.id)
    return conn.execute(stmt, row).scalar_one()


def _details(kind: str, result_id: int, result: Mapping[str, Any]) -> list[tuple[sa.Table, list[dict]]]:
    """The detail rows of a result, from the JSON the single-scan command prints."""
    if kind == "gage":
        t = result["transform"]
        check = {"result_id": result_id, "status": result["status"], "objective": result["objective"],
                 "largest_release": result["largest_release"], **{k: t[k] for k in ("alpha", "beta", "gamma", "dx", "dy", "dz")}}
        rule = _rule_name(result)
        gages = [{"result_id": result_id, "gage": g["name"], "region": g["region"], "points": g["points"],
                  "filtered_points": g["filtered_points"], "allowance_before": g["allowance_before"],
                  "allowance_after": g["allowance_after"], "q": g["q"], "slack": g["slack"],
                  **_uncertainty_columns(g, rule)} for g in result["gages"]]
        return [(m.GageCheck.__table__, [check]), (m.GageAllowance.__table__, gages)]
    if kind == "form":
        row = {"result_id": result_id, "shape": result["shape"], "criterion": result["criterion"],
               "n_points": result["n_points"], "form_error": result["form_error"], "radius": result.get("radius")}
        return [(m.FormResult.__table__, [row])]
    if kind == "inspect":  # gagekit.inspect: each callout's measured value against its tolerance (upper limit)
        rows = [{"result_id": result_id, **row} for row in inspection_rows(result)]
        return [(m.InspectionResult.__table__, rows)] if rows else []
    return []


def _rule_name(result: Mapping[str, Any]) -> Optional[str]:
    """The decision rule a result was decided by (its JSON ``decision_rule.name``), if any."""
    rule = result.get("decision_rule")
    return rule.get("name") if isinstance(rule, Mapping) else None


def _uncertainty_columns(row: Mapping[str, Any], rule: Optional[str]) -> dict:
    """``u``, ``expanded_u``, ``decision``, ``decision_rule`` of a callout's / a gage's JSON
    (None where it has no uncertainty: computed without --uncertainty)."""
    unc = row.get("uncertainty") if isinstance(row.get("uncertainty"), Mapping) else {}
    decided = row.get("decision") if unc else None
    return {"u": unc.get("u"), "expanded_u": unc.get("U"), "decision": decided, "decision_rule": rule if unc else None}


def inspection_rows(result: Mapping[str, Any]) -> list[dict]:
    """The ``inspection_results`` rows of an inspection's JSON (``gagekit inspect --json``):
    per callout its name (the callout's ``name``, else "characteristic of feature |datums|";
    a repeated name is numbered), value against the tolerance as upper limit, and what it is."""
    rows, seen = [], set()
    rule = _rule_name(result)
    for t in result.get("tolerances", []):
        datums = list(t.get("datums") or [])
        name = t.get("name") or (f"{t['characteristic']} of {t['feature']}" + (f" |{'|'.join(datums)}|" if datums else ""))
        base, k = name, 2
        while name in seen:  # the same callout twice: numbered
            name, k = f"{base} #{k}", k + 1
        seen.add(name)
        # sizes, distances, angles carry their limits; a material condition its zone with the bonus
        upper = t.get("upper_limit", t.get("tolerance_zone", t["tolerance"]))
        rows.append({"tolerance": name, "characteristic": t["characteristic"], "value": t["measured"],
                     "lower": t.get("lower_limit"), "upper": upper, "conforming": bool(t["pass"]), "feature": t.get("feature"),
                     "datums": "|".join(datums), "zone": t.get("zone"), "n_points": t.get("n_points"),
                     **_uncertainty_columns(t, rule)})
    return rows


class ResultStore:
    """A results database opened for batches (creates the schema in an empty database)."""

    def __init__(self, url: Union[str, Path, URL], *, create: bool = True):
        self.engine = create_engine(url)
        self.url = safe_url(self.engine.url)
        try:
            self.revision = ensure_schema(self.engine, create=create)
            use_wal(self.engine)
        except Exception:
            self.engine.dispose()
            raise
        #: wall time spent in this store's write transactions (s), for the benchmark
        self.write_seconds = 0.0

    def close(self) -> None:
        self.engine.dispose()

    def __enter__(self) -> "ResultStore":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _fail(self, what: str, exc: BaseException) -> StoreError:
        return StoreError(f"{self.url}: {what}: {_reason(exc)}")

    # ------------------------------------------------------------------------ specs

    def ensure_spec(self, kind: str, hash_: str, document: Mapping[str, Any], source: Optional[str] = None,
                    part: Optional[str] = None) -> int:
        """The id of the spec with this hash, stored first if new."""
        try:
            with self.engine.begin() as conn:
                part_id = None
                if part:
                    _insert_ignore(conn, m.Part.__table__, {"name": part, "created": now()}, ["name"])
                    part_id = conn.execute(sa.select(m.Part.id).where(m.Part.name == part)).scalar_one()
                _insert_ignore(conn, m.Spec.__table__, {"hash": hash_, "kind": kind, "part_id": part_id, "source": source,
                                                        "document": dict(document), "created": now()}, ["hash"])
                return conn.execute(sa.select(m.Spec.id).where(m.Spec.hash == hash_)).scalar_one()
        except sa.exc.SQLAlchemyError as exc:
            raise self._fail("cannot store the specification", exc) from None

    # ------------------------------------------------------------------------ lookups

    def find(self, content_hash: str, spec_id: int) -> Optional[StoredResult]:
        """The stored result of this content against this spec, if any."""
        q = (sa.select(m.Result.status, m.Result.result, m.Result.error, m.Result.path)
             .join(m.Scan, m.Scan.id == m.Result.scan_id)
             .where(m.Scan.content_hash == content_hash, m.Result.spec_id == spec_id))
        try:
            with self.engine.connect() as conn:
                row = conn.execute(q).first()
        except sa.exc.SQLAlchemyError as exc:
            raise self._fail("cannot read", exc) from None
        return None if row is None else StoredResult(*row)

    def done(self, spec_id: int) -> dict[str, StoredResult]:
        """Every stored result of a spec, by content hash (one query for a whole batch)."""
        q = (sa.select(m.Scan.content_hash, m.Result.status, m.Result.result, m.Result.error, m.Result.path)
             .join(m.Scan, m.Scan.id == m.Result.scan_id).where(m.Result.spec_id == spec_id))
        try:
            with self.engine.connect() as conn:
                return {h: StoredResult(s, r, e, p) for h, s, r, e, p in conn.execute(q)}
        except sa.exc.SQLAlchemyError as exc:
            raise self._fail("cannot read", exc) from None

    # ------------------------------------------------------------------------ writes

    def _scan_id(self, conn: sa.Connection, content_hash: str, size: int, scanned: datetime,
                 acquired: Optional[datetime] = None) -> int:
        return _upsert_scan(conn, {"content_hash": content_hash, "size_bytes": size, "scanned": scanned, "created": now(),
                                   "acquired": acquired})

    def add_paths(self, content_hash: str, size: int, scanned: datetime, paths: Iterable[str], *,
                  acquired: Optional[datetime] = None) -> None:
        """Record more paths of a scan's content (one transaction)."""
        import time

        t0 = time.perf_counter()
        try:
            with self.engine.begin() as conn:
                sid = self._scan_id(conn, content_hash, size, scanned, acquired)
                rows = [{"scan_id": sid, "path": p, "seen": now()} for p in paths]
                if rows:
                    _insert_ignore(conn, m.ScanPath.__table__, rows, ["scan_id", "path"])
        except sa.exc.SQLAlchemyError as exc:
            raise self._fail("cannot record the scan paths", exc) from None
        finally:
            self.write_seconds += time.perf_counter() - t0

    def record(self, kind: str, spec_id: int, content_hash: str, size: int, scanned: datetime, paths: Sequence[str],
               outcome: Any, *, acquired: Optional[datetime] = None) -> bool:
        """Store one scan's outcome (a :class:`gagekit.batch.Outcome`) with its paths and
        detail rows, in one transaction; ``acquired`` is the scan's acquisition time from
        its header, where it has one.

        Returns False (and changes nothing but the paths) when the result was already there."""
        import time

        t0 = time.perf_counter()
        try:
            with self.engine.begin() as conn:
                sid = self._scan_id(conn, content_hash, size, scanned, acquired)
                _insert_ignore(conn, m.ScanPath.__table__, [{"scan_id": sid, "path": p, "seen": now()} for p in paths],
                               ["scan_id", "path"])
                row = {"scan_id": sid, "spec_id": spec_id, "path": paths[0], "status": outcome.status,
                       "error": outcome.error, "result": outcome.result, "started": outcome.started,
                       "finished": outcome.finished, "seconds": outcome.seconds, "worker": outcome.worker}
                rid = _insert_ignore(conn, m.Result.__table__, row, ["scan_id", "spec_id"],
                                     returning=m.Result.__table__.c.id).scalar()
                if rid is None:
                    return False  # already stored (by an earlier run or another writer)
                if outcome.status == "ok" and outcome.result is not None:
                    for table, rows in _details(kind, rid, outcome.result):
                        if rows:
                            conn.execute(_plain_insert(table), rows)
                return True
        except sa.exc.SQLAlchemyError as exc:
            raise self._fail("cannot store the result", exc) from None
        finally:
            self.write_seconds += time.perf_counter() - t0

    def forget_errors(self, spec_id: int) -> int:
        """Delete the stored errors of a spec (``--retry-failed``); returns how many."""
        try:
            with self.engine.begin() as conn:
                return conn.execute(sa.delete(m.Result.__table__).where(
                    m.Result.spec_id == spec_id, m.Result.status == "error")).rowcount
        except sa.exc.SQLAlchemyError as exc:
            raise self._fail("cannot delete", exc) from None

