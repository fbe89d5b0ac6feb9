"""Batches refuse what cannot run before the first scan, and never block (issue 22 sections
3 and 4): an unknown form criterion stops `form batch` with one line and exit 2 (it stored
every scan as an error), and a FIFO among the scans is refused as a failed scan, as single
commands refuse it, instead of blocking the batch forever."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from gagekit.samples import data_path


def gk(*args, timeout=300):
    return subprocess.run([sys.executable, "-m", "gagekit", *map(str, args)], capture_output=True, text=True, timeout=timeout)


def _rounds(tmp_path, n=2):
    rng = np.random.default_rng(1)
    files = []
    for k in range(n):
        t = rng.uniform(0, 2 * np.pi, 60)
        f = tmp_path / f"round{k}.csv"
        np.savetxt(f, np.c_[10 * np.cos(t) + rng.normal(0, 1e-3, 60), 10 * np.sin(t)], delimiter=",")
        files.append(f)
    return files


@pytest.mark.parametrize("shape, criterion", [("circle", "bogus"), ("plane", "max-inscribed"), ("line", "min-circumscribed")])
def test_form_batch_refuses_an_unknown_criterion_up_front(tmp_path, shape, criterion):
    db = tmp_path / "r.db"
    p = gk("form", "batch", shape, *_rounds(tmp_path), "-c", criterion, "--db", f"sqlite:///{db}", "--json")
    assert p.returncode == 2 and p.stdout == "", p.stdout + p.stderr
    err = p.stderr.splitlines()
    assert len(err) == 1 and err[0].startswith("gagekit: error: ") and f'"{criterion}"' in err[0], err
    assert not db.exists()  # nothing was stored


def test_a_fifo_among_the_scans_is_a_failed_scan_not_a_hang(tmp_path):
    files = _rounds(tmp_path)
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    p = gk("form", "batch", "circle", *files, fifo, "--db", f"sqlite:///{tmp_path / 'r.db'}", "--json", "-w", "1", timeout=120)
    assert p.returncode == 0, p.stderr
    out = [json.loads(line) for line in p.stdout.splitlines()]
    assert out[-1]["summary"] == {"scans": 3, "ok": 2, "failed": 1, "skipped": 0}
    bad = next(d for d in out[:-1] if d["scan"] == str(fifo))
    assert bad["status"] == "error" and bad["error"] == f"{fifo}: is a FIFO (named pipe); gagekit reads regular files only"


def test_gage_batch_with_a_fifo_as_a_scan_returns(tmp_path):
    fifo = tmp_path / "scan.ply"
    os.mkfifo(fifo)
    p = gk("gage", "batch", data_path("casting_ok.toml"), fifo, "--db", f"sqlite:///{tmp_path / 'r.db'}", "--json", "-w", "1",
           timeout=120)
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout.splitlines()[-1])["summary"]["failed"] == 1
