"""Export every table of a results database to Parquet (pyarrow) or CSV files (the standard
library: a bare install exports CSV).

One file per table (``results.parquet``, ``gage_allowances.csv``, ...), written into a
folder atomically (a temporary folder beside it, then renamed), JSON columns as JSON text,
times as UTC timestamps (CSV: ISO 8601, ``2026-01-31T12:00:00.000000Z``), booleans
``true`` / ``false``, NULL as an empty field.
"""

from __future__ import annotations

import csv
import json
import os
import shutil
import tempfile
from datetime import timezone as _tz
from pathlib import Path
from typing import Any, Union

import sqlalchemy as sa

from ..errors import ConfigError, StoreError
from .models import Base
from .schema import _reason, create_engine, ensure_schema, safe_url

FORMATS = ("parquet", "csv")

__all__ = ["FORMATS", "export_tables"]

_UTC = _tz.utc


def _kind(column: sa.Column) -> str:
    t = column.type
    if isinstance(t, sa.JSON):
        return "json"
    if isinstance(t, sa.DateTime):
        return "time"
    if isinstance(t, sa.Boolean):
        return "bool"
    if isinstance(t, (sa.Integer, sa.BigInteger)):
        return "int"
    if isinstance(t, sa.Float):
        return "float"
    return "str"


def _columns(conn: sa.Connection, table: sa.Table) -> list[tuple[str, str, list[Any]]]:
    """Every column of ``table`` as (name, kind, values), rows in primary-key order; JSON as
    text, times made UTC-aware, booleans as bool."""
    rows = conn.execute(sa.select(table).order_by(*table.primary_key.columns)).mappings().all()
    out = []
    for c in table.columns:
        kind = _kind(c)
        vals = [r[c.name] for r in rows]
        if kind == "json":
            vals = [None if v is None else json.dumps(v, allow_nan=False) for v in vals]
        elif kind == "time":
            vals = [None if v is None else (v if v.tzinfo else v.replace(tzinfo=_UTC)) for v in vals]
        elif kind == "bool":
            vals = [None if v is None else bool(v) for v in vals]
        out.append((c.name, kind, vals))
    return out


def _write_parquet(columns: list[tuple[str, str, list[Any]]], path: Path) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    types = {"json": pa.string(), "time": pa.timestamp("us", tz="UTC"), "bool": pa.bool_(),
             "int": pa.int64(), "float": pa.float64(), "str": pa.string()}
    pq.write_table(pa.table({name: pa.array(vals, types[kind]) for name, kind, vals in columns}), path)


def _csv_field(kind: str, v: Any) -> Any:
    if v is None:
        return ""
    if kind == "time":
        return v.astimezone(_UTC).strftime("%Y-%m-%dT%H:%M:%S.%fZ")
    if kind == "bool":
        return "true" if v else "false"
    if kind == "float":
        return repr(float(v))
    return v


def _write_csv(columns: list[tuple[str, str, list[Any]]], path: Path) -> None:
    n = len(columns[0][2]) if columns else 0
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow([name for name, _, _ in columns])
        for i in range(n):
            w.writerow([_csv_field(kind, vals[i]) for _, kind, vals in columns])


def export_tables(url: str, out: Union[str, Path], fmt: str = "parquet") -> list[Path]:
    """Write every table of the database at ``url`` into the folder ``out``; returns the files."""
    if fmt not in FORMATS:
        raise ConfigError(f"--format must be one of {', '.join(FORMATS)}, got {fmt!r}")
    if fmt == "parquet":
        try:
            import pyarrow.parquet  # noqa: F401
        except ImportError:
            raise ConfigError("db export --format parquet needs pyarrow: pip install 'gagekit[parquet]'") from None
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"{out}: exists and is not a folder")
    if not out.parent.is_dir():
        raise ConfigError(f"{out}: the folder {out.parent} does not exist")
    engine = create_engine(url, must_exist=True)
    try:
        ensure_schema(engine, create=False)
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
        try:
            names = []
            with engine.connect() as conn:
                for table in Base.metadata.sorted_tables:
                    name = f"{table.name}.{fmt}"
                    (_write_parquet if fmt == "parquet" else _write_csv)(_columns(conn, table), tmp / name)
                    names.append(name)
            out.mkdir(exist_ok=True)
            for name in names:
                os.replace(tmp / name, out / name)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        return [out / n for n in names]
    except sa.exc.SQLAlchemyError as exc:
        raise StoreError(f"cannot export {safe_url(engine.url)}: {_reason(exc)}") from None
    finally:
        engine.dispose()
