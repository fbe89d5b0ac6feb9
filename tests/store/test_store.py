"""The results database on SQLite and on a real PostgreSQL server: schema, versions,
idempotent writes, 8 concurrent writer processes, exports."""

import json
import multiprocessing
import socket
from datetime import datetime, timedelta, timezone

import pytest
import sqlalchemy as sa

from gagekit.errors import SchemaVersionError, StoreError
from gagekit.store import ResultStore, head_revision, known_revisions, upgrade
from gagekit.store import models as m
from gagekit.store.schema import create_engine
from gagekit.batch.tasks import Outcome


@pytest.fixture(params=["sqlite", "postgresql"])
def db_url(request, tmp_path):
    if request.param == "sqlite":
        return f"sqlite:///{tmp_path / 'r.db'}"
    return request.getfixturevalue("postgres_url")


T0 = datetime(2026, 1, 5, 8, 0, tzinfo=timezone.utc)


def gage_result(k: int) -> dict:
    """A result shaped as `gage check --json` prints it (the detail rows come from it)."""
    return {"status": "conforming", "objective": 1.0 + k, "largest_release": 0.0,
            "transform": {"alpha": 0.0, "beta": 1e-3 * k, "gamma": 0.0, "dx": 0.1 * k, "dy": -0.2, "dz": 0.3, "matrix": []},
            "gages": [{"name": f"g{j}", "region": "r", "points": 10, "filtered_points": 5, "allowance_before": 0.5 * j,
                       "allowance_after": 0.25 * j + 0.01 * k, "q": 1.0, "slack": 0.0} for j in range(3)]}


def outcome(k: int) -> Outcome:
    return Outcome("ok", gage_result(k), None, T0 + timedelta(minutes=k), T0 + timedelta(minutes=k, seconds=2), 2.0, "w")


def test_migrations_create_exactly_the_models(tmp_path):
    from alembic.autogenerate import compare_metadata
    from alembic.runtime.migration import MigrationContext

    store = ResultStore(f"sqlite:///{tmp_path / 'a.db'}")
    with store.engine.connect() as conn:
        diff = compare_metadata(MigrationContext.configure(conn), m.Base.metadata)
    store.close()
    assert diff == []
    assert store.revision == head_revision() == known_revisions()[-1]


def test_migrations_match_models_on_postgresql(postgres_url):
    from alembic.autogenerate import compare_metadata
    from alembic.runtime.migration import MigrationContext

    store = ResultStore(postgres_url)
    with store.engine.connect() as conn:
        diff = compare_metadata(MigrationContext.configure(conn), m.Base.metadata)
    store.close()
    assert diff == []


def test_record_is_idempotent_and_keeps_every_path(db_url):
    store = ResultStore(db_url)
    sid = store.ensure_spec("gage", "a" * 64, {"spec": {}}, "x.toml", "casting")
    assert store.ensure_spec("gage", "a" * 64, {"spec": {}}, "x.toml", "casting") == sid
    assert store.record("gage", sid, "c" * 64, 100, T0, ["one.ply", "two.ply"], outcome(1)) is True
    assert store.record("gage", sid, "c" * 64, 100, T0, ["three.ply"], outcome(2)) is False
    found = store.find("c" * 64, sid)
    assert found.status == "ok" and found.result == gage_result(1) and found.path == "one.ply"
    with store.engine.connect() as conn:
        assert conn.execute(sa.select(sa.func.count()).select_from(m.Result)).scalar() == 1
        assert conn.execute(sa.select(sa.func.count()).select_from(m.GageAllowance)).scalar() == 3
        paths = set(conn.execute(sa.select(m.ScanPath.path)).scalars())
        check = conn.execute(sa.select(m.GageCheck.beta, m.GageCheck.dx)).one()
    assert paths == {"one.ply", "two.ply", "three.ply"}
    assert check == (1e-3, 0.1)
    store.close()


def _writer(url: str, spec_hash: str, ks: list, barrier) -> int:
    store = ResultStore(url)
    sid = store.ensure_spec("gage", spec_hash, {"spec": {"n": 1}}, None, None)
    barrier.wait(timeout=300)  # a writer that failed to open the store breaks the barrier: an error, not a hang
    mine = sum(store.record("gage", sid, f"{k:064d}", 10 + k, T0, [f"scan_{k}.ply", f"copy_{k % 8}/scan_{k}.ply"], outcome(k))
               for k in ks)
    store.close()
    return mine


def test_eight_processes_write_200_results_and_lose_nothing(db_url):
    """8 processes at once, each result offered by two of them: 200 rows, each once, intact."""
    ctx = multiprocessing.get_context("spawn")  # 8 real processes; spawn, not fork: a fork of this multi-threaded test process (Dask, SQLAlchemy pools) can deadlock in the child
    procs = 8
    owners = {w: [k for k in range(200) if k % procs == w or (k + 3) % procs == w] for w in range(procs)}
    with ctx.Manager() as mgr:
        barrier = mgr.Barrier(procs)
        with ctx.Pool(procs) as pool:
            inserted = pool.starmap(_writer, [(db_url, "b" * 64, owners[w], barrier) for w in range(procs)])
    assert sum(inserted) == 200  # every result stored by exactly one writer
    engine = create_engine(db_url)
    with engine.connect() as conn:
        rows = conn.execute(sa.select(m.Scan.content_hash, m.Result.result, m.Result.seconds)
                            .join(m.Result, m.Result.scan_id == m.Scan.id)).all()
        n_allow = conn.execute(sa.select(sa.func.count()).select_from(m.GageAllowance)).scalar()
        n_paths = conn.execute(sa.select(sa.func.count()).select_from(m.ScanPath)).scalar()
        n_scans = conn.execute(sa.select(sa.func.count()).select_from(m.Scan)).scalar()
    engine.dispose()
    assert len(rows) == 200 and n_scans == 200 and n_allow == 600 and n_paths == 400
    got = {int(h): r for h, r, _ in rows}
    assert got == {k: gage_result(k) for k in range(200)}


def test_newer_schema_is_refused_naming_the_version(db_url):
    ResultStore(db_url).close()
    engine = create_engine(db_url)
    with engine.begin() as conn:
        conn.execute(sa.text("UPDATE alembic_version SET version_num = '0999'"))
    engine.dispose()
    with pytest.raises(SchemaVersionError, match=r"schema version 0999, newer than this gagekit knows"):
        ResultStore(db_url)


def inspection_json(k: int) -> dict:
    """An inspection result as `gagekit inspect --json` prints it (the parts the store reads)."""
    tol = [("flatness", "A", [], 0.01, 0.002 * k), ("perpendicularity", "C", ["A"], 0.05, 0.039),
           ("perpendicularity", "C", ["A", "B"], 0.05, 0.0), ("position", "bore", ["A", "B", "C"], 0.1, 0.0585)]
    return {"part": "bracket", "n_points": 1000, "status": "conforming",
            "tolerances": [{"feature": f, "characteristic": c, "tolerance": t, "measured": v, "pass": v <= t,
                            "margin": t - v, "datums": d, "n_points": 100 + j, "zone": "diameter" if c == "position" else "width",
                            "toleranced_element": "surface"} for j, (c, f, d, t, v) in enumerate(tol)]}


def test_a_database_of_the_first_schema_is_upgraded_with_its_results(db_url):
    """A database written by revision 0001 (built from the shipped Alembic history, filled
    as 0001's gagekit filled it): refused until `db upgrade`, which adds the callout columns,
    fills them from the stored JSON and renames the callouts as new results name them."""
    from alembic import command
    from alembic.config import Config

    from gagekit.store.results import inspection_rows
    from gagekit.store.schema import MIGRATIONS

    revs = known_revisions()
    assert revs[:2] == ["0001", "0002"]
    engine = create_engine(db_url)
    cfg = Config()
    cfg.set_main_option("script_location", str(MIGRATIONS))
    with engine.begin() as conn:
        cfg.attributes["connection"] = conn
        command.upgrade(cfg, "0001")
    with engine.begin() as conn:  # what 0001's ResultStore.record wrote for two inspections
        conn.execute(sa.text("INSERT INTO specs (id, hash, kind, document, created) VALUES (1, 'h', 'inspect', '{}', :t)"),
                     {"t": T0})
        for k in (1, 2):
            conn.execute(sa.text("INSERT INTO scans (id, content_hash, size_bytes, scanned, created) VALUES (:k, :h, 10, :t, :t)"),
                         {"k": k, "h": f"c{k}", "t": T0})
            conn.execute(sa.text("INSERT INTO results (id, scan_id, spec_id, path, status, result, started, finished, seconds) "
                                 "VALUES (:k, :k, 1, :p, 'ok', :r, :t, :t, 1.0)"),
                         {"k": k, "p": f"s{k}.ply", "r": json.dumps(inspection_json(k)), "t": T0})
            for name, t in (("flatness of A", 0), ("perpendicularity of C", 1), ("perpendicularity of C #2", 2),
                            ("position of bore", 3)):
                tol = inspection_json(k)["tolerances"][t]
                conn.execute(sa.text("INSERT INTO inspection_results (result_id, tolerance, characteristic, value, upper, "
                                     "conforming) VALUES (:k, :n, :c, :v, :u, :ok)"),
                             {"k": k, "n": name, "c": tol["characteristic"], "v": tol["measured"], "u": tol["tolerance"],
                              "ok": tol["pass"]})
        if conn.dialect.name == "postgresql":  # the ids were given: move the serial sequences past them
            for table in ("specs", "scans", "results"):
                conn.execute(sa.text(f"SELECT setval(pg_get_serial_sequence('{table}', 'id'), (SELECT max(id) FROM {table}))"))
    engine.dispose()

    with pytest.raises(SchemaVersionError, match=r"schema version 0001, older .*`gagekit db upgrade"):
        ResultStore(db_url)
    assert upgrade(db_url) == ("0001", head_revision())
    store = ResultStore(db_url)
    t = m.InspectionResult.__table__
    with store.engine.connect() as conn:
        got = [dict(r._mapping) for r in conn.execute(
            sa.select(t.c.result_id, t.c.tolerance, t.c.characteristic, t.c.value, t.c.lower, t.c.upper, t.c.conforming,
                      t.c.feature, t.c.datums, t.c.zone, t.c.n_points, t.c.u, t.c.expanded_u, t.c.decision,
                      t.c.decision_rule).order_by(t.c.result_id, t.c.id))]
    # the upgraded rows are exactly the rows this gagekit writes for the same results
    assert got == [{"result_id": k, **row} for k in (1, 2) for row in inspection_rows(inspection_json(k))]
    assert [r["tolerance"] for r in got[:4]] == ["flatness of A", "perpendicularity of C |A|",
                                                 "perpendicularity of C |A|B|", "position of bore |A|B|C|"]
    # and new results land beside them
    spec = store.ensure_spec("inspect", "h2", {"part": {}})
    assert store.record("inspect", spec, "c3", 10, T0, ["s3.ply"], Outcome("ok", inspection_json(3), None, T0, T0, 1.0))
    store.close()
    assert upgrade(db_url) == (head_revision(), head_revision())


def test_a_foreign_database_is_refused(tmp_path):
    import sqlite3

    f = tmp_path / "other.db"
    with sqlite3.connect(f) as c:
        c.execute("CREATE TABLE invoices (id INTEGER)")
    with pytest.raises(StoreError, match="not a gagekit results database"):
        ResultStore(f"sqlite:///{f}")


def test_unreachable_databases_name_their_url(tmp_path):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with pytest.raises(StoreError, match=rf"127.0.0.1:{port}/nowhere") as e:
        ResultStore(f"postgresql://who:secret@127.0.0.1:{port}/nowhere")
    assert "secret" not in str(e.value)
    with pytest.raises(StoreError, match="does not exist"):
        ResultStore(f"sqlite:///{tmp_path / 'no' / 'such' / 'r.db'}")
    with pytest.raises(StoreError, match="unsupported database"):
        ResultStore("mysql://x@localhost/db")


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_export_writes_every_table(db_url, tmp_path, fmt):
    import pyarrow.csv as pacsv
    import pyarrow.parquet as pq

    from gagekit.store.dump import export_tables

    store = ResultStore(db_url)
    sid = store.ensure_spec("gage", "d" * 64, {"spec": {"x": 1}}, "g.toml", "p")
    for k in range(5):
        store.record("gage", sid, f"{k:064d}", 5, T0, [f"s{k}.ply"], outcome(k))
    store.close()
    files = export_tables(db_url, tmp_path / "out", fmt)
    assert {f.name for f in files} == {f"{t}.{fmt}" for t in m.TABLES}
    read = pq.read_table if fmt == "parquet" else pacsv.read_csv
    allow = read(tmp_path / "out" / f"gage_allowances.{fmt}")
    results = read(tmp_path / "out" / f"results.{fmt}")
    assert allow.num_rows == 15 and results.num_rows == 5
    assert json.loads(results.column("result")[2].as_py()) == gage_result(2)
    assert sorted(allow.column("allowance_after").to_pylist())[-1] == pytest.approx(0.54)


def test_csv_export_needs_no_pyarrow(tmp_path):
    """`db export --format csv` runs on a bare install (issue 22 item 1): pyarrow cannot be
    imported, the CSV files are written by the standard library and read back by it; only
    Parquet asks for the extra, in one line."""
    import csv
    import subprocess
    import sys

    url = f"sqlite:///{tmp_path / 'r.db'}"
    store = ResultStore(url)
    sid = store.ensure_spec("gage", "d" * 64, {"spec": {"x": 1}}, "g.toml", "p")
    for k in range(3):
        store.record("gage", sid, f"{k:064d}", 5, T0, [f"s{k}.ply"], outcome(k))
    store.close()
    code = ("import sys; sys.modules['pyarrow'] = None\nfrom gagekit.cli import main\n"
            "main(['db', 'export', sys.argv[1], '--format', sys.argv[2], '--out', sys.argv[3]])")
    run = lambda fmt, out: subprocess.run([sys.executable, "-c", code, url, fmt, str(tmp_path / out)],  # noqa: E731
                                          capture_output=True, text=True, timeout=120)
    p = run("csv", "csv")
    assert p.returncode == 0, p.stderr
    with open(tmp_path / "csv" / "results.csv", newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 3 and json.loads(rows[2]["result"]) == gage_result(2)
    assert rows[0]["finished"].endswith("Z") and datetime.fromisoformat(rows[0]["finished"][:-1]) > datetime(2000, 1, 1)
    p = run("parquet", "pq")
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "gagekit[parquet]" in p.stderr, p.stderr


def test_a_database_of_revision_0002_gains_the_acquisition_time(db_url):
    """Revision 0003 adds scans.acquired: a database written at 0002 is refused until `db
    upgrade`, keeps its scans (acquired NULL: their results are timed by when they were
    stored) and then takes scans with an acquisition time; SPC orders by it."""
    from alembic import command
    from alembic.config import Config

    from gagekit.stats import collect
    from gagekit.store.schema import MIGRATIONS

    assert known_revisions()[:3] == ["0001", "0002", "0003"]
    engine = create_engine(db_url)
    cfg = Config()
    cfg.set_main_option("script_location", str(MIGRATIONS))
    with engine.begin() as conn:
        cfg.attributes["connection"] = conn
        command.upgrade(cfg, "0002")
    engine.dispose()
    with pytest.raises(SchemaVersionError, match="older"):
        ResultStore(db_url)
    # a scan as 0002's gagekit stored it
    engine = create_engine(db_url)
    with engine.begin() as conn:
        conn.execute(sa.text("INSERT INTO scans (content_hash, size_bytes, scanned, created) VALUES ('old', 10, :t, :t)"),
                     {"t": T0})
    engine.dispose()
    assert upgrade(db_url) == ("0002", head_revision())
    store = ResultStore(db_url)
    with store.engine.connect() as conn:
        assert conn.execute(sa.select(m.Scan.acquired).where(m.Scan.content_hash == "old")).scalar_one() is None
    sid = store.ensure_spec("gage", "e" * 64, {"spec": {"x": 1}}, "g.toml", "p")
    later = T0 + timedelta(days=3)
    # acquired on January 3, 7 and 8, stored in another order of time (all at T0)
    for k in range(3):
        assert store.record("gage", sid, f"{k:064d}", 5, T0, [f"s{k}.ply"], outcome(k),
                            acquired=later - timedelta(days=2 - k) if k else later - timedelta(days=5))
    store.close()
    s = collect(db_url)
    (c,) = [c for c in s["specs"][0]["characteristics"] if c["name"] == "allowance after T*: g1"]
    assert c["series"]["scan"] == ["s0.ply", "s1.ply", "s2.ply"]
    assert c["series"]["time_source"] == ["acquired"] * 3
    assert c["series"]["time"][0].startswith("2026-01-03") and c["series"]["time"][2].startswith("2026-01-08")
