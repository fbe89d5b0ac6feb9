"""The tracking history file through the CLI (kept when the history moves to another store):
typed errors for locked, read-only, damaged and foreign files, a foreign database never
modified, reads after a crashed writer, a precise message for a changed machine file."""

from __future__ import annotations

import json
import signal
import sqlite3
import subprocess
import sys
import time

import pytest

from .conftest import EXAMPLE_MACHINE, assert_clean_error, assert_ok, gk


@pytest.fixture(scope="module")
def cycles(tmp_path_factory):
    d = tmp_path_factory.mktemp("hist")
    assert_ok(gk("machine", "design", EXAMPLE_MACHINE, "--points", 60, "--candidates", 2000, "--out", d / "plan.csv"))
    assert_ok(gk("machine", "simulate-cycles", EXAMPLE_MACHINE, d / "plan.csv", "--cycles", 3, "--out", d / "cyc.csv"))
    return d / "cyc.csv"


def _runs(h):
    proc = gk("machine", "history", h, "--json")
    assert_ok(proc)
    return len(json.loads(proc.stdout)["runs"])


def test_append_and_read(tmp_path, cycles):
    h = tmp_path / "h.sqlite"
    for k in (1, 2):
        proc = gk("machine", "track", EXAMPLE_MACHINE, cycles, "--history", h, "--json")
        assert_ok(proc)
        assert json.loads(proc.stdout)["history_run"] == k
    assert _runs(h) == 2
    proc = gk("machine", "history", h)  # human output too
    assert_ok(proc)
    assert "2 run(s)" in proc.stdout


def test_foreign_database_is_refused_and_left_unchanged(tmp_path, cycles):
    f = tmp_path / "parts.sqlite"
    con = sqlite3.connect(f)
    con.execute("CREATE TABLE parts (id INTEGER, name TEXT)")
    con.execute("INSERT INTO parts VALUES (1, 'flange')")
    con.commit()
    con.close()
    before = f.read_bytes()
    assert_clean_error(gk("machine", "track", EXAMPLE_MACHINE, cycles, "--history", f), "not a gagekit history")
    assert_clean_error(gk("machine", "history", f), "not a gagekit history")
    assert f.read_bytes() == before


@pytest.mark.parametrize("content", [b"hello, not a database" * 50, b"SQLite format 3\x00" + b"\xff" * 3000])
def test_damaged_files(tmp_path, cycles, content):
    f = tmp_path / "bad.sqlite"
    f.write_bytes(content)
    assert_clean_error(gk("machine", "history", f))
    assert_clean_error(gk("machine", "track", EXAMPLE_MACHINE, cycles, "--history", f))
    assert f.read_bytes() == content


def test_read_only_history(tmp_path, cycles):
    h = tmp_path / "h.sqlite"
    assert_ok(gk("machine", "track", EXAMPLE_MACHINE, cycles, "--history", h))
    h.chmod(0o444)
    assert _runs(h) == 1  # reading a read-only history works
    assert_clean_error(gk("machine", "track", EXAMPLE_MACHINE, cycles, "--history", h), "read-only")
    assert_clean_error(gk("machine", "history", tmp_path / "none.sqlite"), "not found")


def test_a_changed_machine_file_gets_a_precise_message(tmp_path, cycles):
    h = tmp_path / "h.sqlite"
    assert_ok(gk("machine", "track", EXAMPLE_MACHINE, cycles, "--history", h))
    text = EXAMPLE_MACHINE.read_text().replace("fourier_terms = 1 ", "fourier_terms = 2 ")
    assert text != EXAMPLE_MACHINE.read_text()
    m2 = tmp_path / "m2.toml"
    m2.write_text(text)
    line = assert_clean_error(gk("machine", "track", m2, cycles, "--history", h))
    assert "another error model" in line and "not 'dissertation" not in line


def _locker(path, seconds):
    p = subprocess.Popen([sys.executable, "-c",
                          "import sqlite3, sys, time; c = sqlite3.connect(sys.argv[1], isolation_level=None);"
                          "c.execute('BEGIN EXCLUSIVE'); print('locked', flush=True); time.sleep(float(sys.argv[2]))",
                          str(path), str(seconds)], stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "locked"
    return p


def test_a_short_lock_is_waited_for(tmp_path, cycles):
    h = tmp_path / "h.sqlite"
    assert_ok(gk("machine", "track", EXAMPLE_MACHINE, cycles, "--history", h))
    locker = _locker(h, 3)
    try:
        assert_ok(gk("machine", "track", EXAMPLE_MACHINE, cycles, "--history", h, timeout=120))
    finally:
        locker.wait(timeout=30)
    assert _runs(h) == 2


def test_a_long_lock_is_a_clean_error(tmp_path, cycles):
    h = tmp_path / "h.sqlite"
    assert_ok(gk("machine", "track", EXAMPLE_MACHINE, cycles, "--history", h))
    locker = _locker(h, 60)
    try:
        t0 = time.monotonic()
        proc = gk("machine", "track", EXAMPLE_MACHINE, cycles, "--history", h, timeout=120,
                  env={"GAGEKIT_HISTORY_TIMEOUT": "1"})
        assert time.monotonic() - t0 < 30
        assert_clean_error(proc, "locked")
    finally:
        locker.kill()
        locker.wait()
    assert _runs(h) == 1


def _killed_writer(h, statements: str) -> None:
    """A process that runs ``statements`` on connection ``c`` to ``h`` (inside a transaction
    it leaves open), then is killed with SIGKILL: a hot journal is left."""
    w = subprocess.Popen([sys.executable, "-c",
                          "import sqlite3, sys, time; c = sqlite3.connect(sys.argv[1], isolation_level=None);"
                          + statements + "print('writing', flush=True); time.sleep(60)", str(h)], stdout=subprocess.PIPE, text=True)
    assert w.stdout.readline().strip() == "writing"
    w.send_signal(signal.SIGKILL)
    w.wait()


def test_reads_after_a_killed_writer(tmp_path, cycles):
    """A writer killed inside its transaction leaves a hot journal; reads roll it back."""
    h = tmp_path / "h.sqlite"
    assert_ok(gk("machine", "track", EXAMPLE_MACHINE, cycles, "--history", h))
    _killed_writer(h, "c.execute('PRAGMA journal_mode=DELETE'); c.execute('BEGIN IMMEDIATE');"
                      "c.execute('PRAGMA cache_size=1');"
                      "[c.execute('INSERT INTO calibrations (machine_id, kind, created, source, n_points) VALUES (1, ?, ?, ?, ?)', ('track', 'x' * 500, 'y' * 500, i))"
                      " for i in range(20000)];")
    for _ in range(3):
        assert _runs(h) == 1


def test_a_history_killed_during_its_first_track_is_rolled_back(tmp_path, cycles):
    """A writer killed inside the first transaction of a new history leaves a file whose
    first page was never written (zeros, no SQLite header) beside a hot journal: SQLite rolls
    the journal back (to an empty database) before the header is read, so the next track
    writes its run and the history reads it (issue 22 section 2)."""
    h = tmp_path / "h.sqlite"
    _killed_writer(h, "c.execute('PRAGMA cache_size=2'); c.execute('BEGIN IMMEDIATE');"
                      "c.execute('CREATE TABLE alembic_version (version_num VARCHAR(32) NOT NULL)');"
                      "c.execute('CREATE TABLE calibrations (id INTEGER PRIMARY KEY, source TEXT)');"
                      "[c.execute('INSERT INTO calibrations (source) VALUES (?)', ('x' * 500,)) for i in range(4000)];")
    journal = h.with_name(h.name + "-journal")
    assert journal.stat().st_size > 0 and h.stat().st_size > 0
    assert h.read_bytes()[:16] != b"SQLite format 3\x00"  # the state the header check refused
    proc = gk("machine", "history", h)
    assert_clean_error(proc, "an empty SQLite database")  # rolled back: nothing was ever stored
    assert not journal.exists()
    assert_ok(gk("machine", "track", EXAMPLE_MACHINE, cycles, "--history", h))
    assert _runs(h) == 1
