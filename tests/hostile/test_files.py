"""gagekit._files: typed errors at every file boundary, atomic outputs (library level)."""

from __future__ import annotations

import os
import stat

import pytest

from gagekit import _files
from gagekit.errors import FileAccessError, FileFormatError, GagekitError


def test_input_file_refuses_missing_folder_fifo(tmp_path):
    with pytest.raises(FileAccessError, match="not found"):
        _files.input_file(tmp_path / "nope.toml")
    with pytest.raises(FileAccessError, match="is a folder"):
        _files.input_file(tmp_path)
    fifo = tmp_path / "f.toml"
    os.mkfifo(fifo)
    with pytest.raises(FileAccessError, match="FIFO"):  # returns at once: stat never blocks
        _files.read_text(fifo)


def test_read_text_maps_decoding_and_drops_a_bom(tmp_path):
    p = tmp_path / "latin1.toml"
    p.write_bytes("name = 'caf\xe9'".encode("latin-1"))
    with pytest.raises(FileFormatError, match="not UTF-8 text .* offset 11"):
        _files.read_text(p)
    p.write_bytes(b"\xef\xbb\xbfa = 1")
    assert _files.read_text(p) == "a = 1"
    scan = tmp_path / "scan.ply"  # a binary scan where a text file was expected: said so
    scan.write_bytes(b"ply\nformat binary_little_endian 1.0\nend_header\n\xf0\x9f\xff")
    with pytest.raises(FileFormatError, match=r"scan.ply: a binary \.ply file where a text machine file was expected "
                                              r"\(check the order of the arguments\)"):
        _files.read_text(scan, "machine file")


def test_errors_are_gagekit_and_os_errors():
    e = _files.os_error(PermissionError(13, "Permission denied"), "x.csv", "write")
    assert isinstance(e, GagekitError) and isinstance(e, OSError)
    assert str(e) == "x.csv: cannot write: permission denied"


@pytest.mark.parametrize("msg,cls,text", [
    ("database is locked", FileAccessError, "locked"),
    ("attempt to write a readonly database", FileAccessError, "read-only"),
    ("file is not a database", FileFormatError, "not a"),
])
def test_sqlite_mapping(msg, cls, text):
    import sqlite3

    e = _files.sqlite_error(sqlite3.OperationalError(msg), "h.sqlite", "history")
    assert type(e) is cls and text in str(e)


def test_output_paths(tmp_path):
    with pytest.raises(FileAccessError, match="does not exist"):
        _files.output_file(tmp_path / "missing" / "x.csv")
    with pytest.raises(FileAccessError, match="is a folder"):
        _files.output_file(tmp_path)
    ro = tmp_path / "ro.csv"
    ro.write_text("old")
    ro.chmod(0o444)
    with pytest.raises(FileAccessError, match="read-only"):
        _files.write_text(ro, "new")
    assert ro.read_text() == "old"
    folder = tmp_path / "rofolder"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        with pytest.raises(FileAccessError, match="read-only"):
            _files.output_file(folder / "x.csv")
    finally:
        folder.chmod(0o755)


def test_atomic_write_keeps_the_old_file_when_the_writer_fails(tmp_path):
    p = tmp_path / "out.csv"
    p.write_text("old\n")
    with pytest.raises(ZeroDivisionError):
        with _files.atomic_open(p) as fh:
            fh.write("half")
            1 / 0
    assert p.read_text() == "old\n"
    assert [x.name for x in tmp_path.iterdir()] == ["out.csv"]  # no temporary left
    with pytest.raises(KeyboardInterrupt):
        with _files.atomic_open(p) as fh:
            fh.write("half")
            raise KeyboardInterrupt
    assert p.read_text() == "old\n" and len(list(tmp_path.iterdir())) == 1
    _files.write_text(p, "new\n")
    assert p.read_text() == "new\n" and len(list(tmp_path.iterdir())) == 1


def test_atomic_path_keeps_the_suffix_and_the_mode(tmp_path):
    p = tmp_path / "fig.png"
    p.write_bytes(b"x")
    p.chmod(0o640)
    with _files.atomic_path(p) as tmp:
        assert tmp.suffix == ".png" and tmp.parent == tmp_path
        tmp.write_bytes(b"png")
    assert p.read_bytes() == b"png" and stat.S_IMODE(p.stat().st_mode) == 0o640


def test_atomic_dir_builds_beside_and_never_replaces_foreign_folders(tmp_path):
    out = tmp_path / "report"
    with _files.atomic_dir(out) as tmp:
        assert tmp.parent == tmp_path and not out.exists()
        (tmp / "a.txt").write_text("1")
    assert sorted(x.name for x in out.iterdir()) == [_files.REPORT_MARKER, "a.txt"]
    with pytest.raises(RuntimeError):  # a failed rewrite leaves the old report
        with _files.atomic_dir(out) as tmp:
            (tmp / "b.txt").write_text("2")
            raise RuntimeError("boom")
    assert sorted(x.name for x in out.iterdir()) == [_files.REPORT_MARKER, "a.txt"]
    with _files.atomic_dir(out) as tmp:  # a gagekit report folder is replaced as a whole
        (tmp / "c.txt").write_text("3")
    assert sorted(x.name for x in out.iterdir()) == [_files.REPORT_MARKER, "c.txt"]
    assert sorted(x.name for x in tmp_path.iterdir()) == ["report"]
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("precious")
    with pytest.raises(FileAccessError, match="holds other files"):
        _files.output_dir(mine)
    with pytest.raises(FileAccessError, match="a file of that name"):
        _files.output_dir(mine / "thesis.tex")


def test_a_signal_as_the_temporary_file_is_made_leaves_nothing(tmp_path, monkeypatch):
    """Ctrl-C (or SIGTERM, which the command line turns into the same) arriving just after the
    temporary file or folder exists but before its name is held: it is delivered once the name
    is held, and the file is removed (a SIGTERM there left '.obs.*.gk-tmp.csv' behind). A second
    thread is alive, as Rust's workers or Dask's are in a real run: a signal mask on the main
    thread alone let the kernel deliver the signal to it, and Python raised at once (CI)."""
    import signal
    import tempfile
    import threading

    real_mkstemp, real_mkdtemp = tempfile.mkstemp, tempfile.mkdtemp

    def mkstemp(*a, **k):
        r = real_mkstemp(*a, **k)
        os.kill(os.getpid(), signal.SIGINT)  # the signal lands here, the file just made
        return r

    def mkdtemp(*a, **k):
        r = real_mkdtemp(*a, **k)
        os.kill(os.getpid(), signal.SIGINT)
        return r

    monkeypatch.setattr(tempfile, "mkstemp", mkstemp)
    monkeypatch.setattr(tempfile, "mkdtemp", mkdtemp)
    stop = threading.Event()
    other = threading.Thread(target=stop.wait, daemon=True)
    other.start()
    request_stop = stop.set
    out = tmp_path / "obs.csv"
    out.write_text("old\n")
    with pytest.raises(KeyboardInterrupt):
        with _files.atomic_path(out) as tmp:
            tmp.write_text("new\n")
    rep = tmp_path / "rep"
    with pytest.raises(KeyboardInterrupt):
        with _files.atomic_dir(rep) as d:
            (d / "report.html").write_text("x")
    request_stop()
    other.join()
    assert out.read_text() == "old\n" and sorted(x.name for x in tmp_path.iterdir()) == ["obs.csv"]
