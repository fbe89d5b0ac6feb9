"""Export every table of a results database to Parquet or CSV files (pyarrow).

One file per table (``results.parquet``, ``gage_allowances.csv``, ...), written into a
folder atomically (a temporary folder beside it, then renamed), JSON columns as JSON text,
times as UTC timestamps.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path
from typing import Union

import sqlalchemy as sa

from ..errors import ConfigError, StoreError
from .models import Base
from .schema import _reason, create_engine, ensure_schema, safe_url

FORMATS = ("parquet", "csv")

__all__ = ["FORMATS", "export_tables"]


def _arrow_table(conn: sa.Connection, table: sa.Table):
    import pyarrow as pa

    rows = conn.execute(sa.select(table).order_by(*table.primary_key.columns)).mappings().all()
    cols = {}
    for c in table.columns:
        vals = [r[c.name] for r in rows]
        if isinstance(c.type, sa.JSON):
            cols[c.name] = pa.array([None if v is None else json.dumps(v, allow_nan=False) for v in vals], pa.string())
        elif isinstance(c.type, sa.DateTime):
            cols[c.name] = pa.array([None if v is None else (v if v.tzinfo else v.replace(tzinfo=_UTC)) for v in vals],
                                    pa.timestamp("us", tz="UTC"))
        elif isinstance(c.type, sa.Boolean):
            cols[c.name] = pa.array([None if v is None else bool(v) for v in vals], pa.bool_())
        elif isinstance(c.type, (sa.Integer, sa.BigInteger)):
            cols[c.name] = pa.array(vals, pa.int64())
        elif isinstance(c.type, sa.Float):
            cols[c.name] = pa.array(vals, pa.float64())
        else:
            cols[c.name] = pa.array(vals, pa.string())
    return pa.table(cols)


from datetime import timezone as _tz  # noqa: E402

_UTC = _tz.utc


def export_tables(url: str, out: Union[str, Path], fmt: str = "parquet") -> list[Path]:
    """Write every table of the database at ``url`` into the folder ``out``; returns the files."""
    if fmt not in FORMATS:
        raise ConfigError(f"--format must be one of {', '.join(FORMATS)}, got {fmt!r}")
    try:
        import pyarrow.csv as pacsv
        import pyarrow.parquet as pq
    except ImportError:
        raise ConfigError("db export needs pyarrow: pip install 'gagekit[parquet]'") from None
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
                    t = _arrow_table(conn, table)
                    name = f"{table.name}.{fmt}"
                    if fmt == "parquet":
                        pq.write_table(t, tmp / name)
                    else:
                        pacsv.write_csv(t, tmp / name)
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
