"""Batches from the command line: same JSON as the single-scan commands, failures recorded,
restartable without duplicates, local workers, a real Dask LocalCluster (with a worker
killed mid-batch) and a real PostgreSQL server."""

import json
import os
import shutil
import signal
import subprocess
import sys

import pytest
import sqlalchemy as sa

from gagekit.store import models as m
from gagekit.store.schema import create_engine


def gk(*args, env=None, timeout=600):
    e = dict(os.environ, **(env or {}))
    return subprocess.run([sys.executable, "-m", "gagekit", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, env=e)


def lines(proc):
    assert proc.returncode == 0, proc.stderr
    out = [json.loads(ln) for ln in proc.stdout.splitlines()]
    assert "summary" in out[-1]
    return out[:-1], out[-1]["summary"]


def counts(url):
    engine = create_engine(url)
    with engine.connect() as conn:
        res = conn.execute(sa.select(sa.func.count()).select_from(m.Result)).scalar()
        dup = conn.execute(sa.select(m.Result.scan_id, m.Result.spec_id).group_by(m.Result.scan_id, m.Result.spec_id)
                           .having(sa.func.count() > 1)).all()
        paths = conn.execute(sa.select(sa.func.count()).select_from(m.ScanPath)).scalar()
        allow = conn.execute(sa.select(sa.func.count()).select_from(m.GageAllowance)).scalar()
    engine.dispose()
    assert dup == []
    return res, paths, allow


def test_gage_batch_gives_the_gage_check_json_and_restarts(scans_copy, tmp_path):
    gages, scans = scans_copy
    folder = scans[0].parent
    shutil.copy(scans[0], folder / "same_content.ply")  # two paths, one content
    (folder / "broken.ply").write_bytes(b"ply\nformat nonsense\n")  # unreadable: recorded, batch goes on
    url = f"sqlite:///{tmp_path / 'r.db'}"
    got, summary = lines(gk("gage", "batch", gages, folder, "--db", url, "--json", "--workers", "2"))
    n = len(scans) + 2
    assert summary == {"scans": n, "ok": len(scans) + 1, "failed": 1, "skipped": 0}
    by = {os.path.basename(d["scan"]): d for d in got}
    assert set(by) == {p.name for p in scans} | {"same_content.ply", "broken.ply"}
    assert by["broken.ply"]["status"] == "error" and "broken.ply" in by["broken.ply"]["error"]
    single = json.loads(gk("gage", "check", scans[0], gages, "--json").stdout)
    assert by[scans[0].name] == {"scan": str(scans[0]), "status": "ok", "result": single}
    assert by["same_content.ply"]["result"] == single
    assert counts(url) == (len(scans) + 1, n, 8 * len(scans))  # the copy is processed once, both paths kept

    # rerun with two more scans: only they are evaluated, nothing duplicated
    from castings import write_scans

    write_scans(folder, 2, start=50)
    got2, summary2 = lines(gk("gage", "batch", gages, str(folder / "*.ply"), "--db", url, "--json", "-w", "1"))
    assert summary2 == {"scans": n + 2, "ok": 2, "failed": 0, "skipped": n}
    assert {d["scan"] for d in got2 if d["status"] == "ok"} == {str(folder / "casting_050.ply"), str(folder / "casting_051.ply")}
    skipped = {os.path.basename(d["scan"]): d for d in got2 if d["status"] == "skipped"}
    assert skipped[scans[0].name]["result"] == single and "error" in skipped["broken.ply"]
    assert counts(url) == (len(scans) + 3, n + 2, 8 * (len(scans) + 2))

    # a changed drawing is a new spec: everything is evaluated again, alongside
    g2 = tmp_path / "tighter.toml"
    g2.write_text(gages.read_text().replace("max_shift = 20.0", "max_shift = 19.0"))
    _, summary3 = lines(gk("gage", "batch", g2, folder, "--db", url, "--json"))
    assert summary3["skipped"] == 0 and summary3["ok"] == len(scans) + 3


def test_interrupted_batch_is_finished_by_the_rerun(scans_copy, tmp_path):
    gages, scans = scans_copy
    url = f"sqlite:///{tmp_path / 'r.db'}"
    cmd = [sys.executable, "-m", "gagekit", "gage", "batch", str(gages), str(scans[0].parent), "--db", url, "--json", "-w", "1"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    first = proc.stdout.readline()
    assert json.loads(first)["status"] == "ok"
    os.killpg(proc.pid, signal.SIGKILL)  # the batch and its workers, as a lost node would be
    proc.wait(timeout=60)
    proc.stdout.close()
    proc.stderr.close()
    done_before = counts(url)[0]
    assert 1 <= done_before < len(scans)
    _, summary = lines(gk("gage", "batch", gages, scans[0].parent, "--db", url, "--json"))
    assert summary == {"scans": len(scans), "ok": len(scans) - done_before, "failed": 0, "skipped": done_before}
    assert counts(url)[0] == len(scans)


def test_form_batch_gives_the_form_fit_json(tmp_path):
    import numpy as np

    rng = np.random.default_rng(3)
    files = []
    for k in range(4):
        t = rng.uniform(0, 2 * np.pi, 200)
        r = 10 + 0.01 * k + rng.normal(0, 0.002, 200)
        f = tmp_path / f"ring{k}.csv"
        np.savetxt(f, np.c_[r * np.cos(t), r * np.sin(t)], delimiter=",")
        files.append(f)
    url = f"sqlite:///{tmp_path / 'f.db'}"
    got, summary = lines(gk("form", "batch", "circle", *files, "-c", "minimum-zone", "--db", url, "--json", "-w", "2"))
    assert summary == {"scans": 4, "ok": 4, "failed": 0, "skipped": 0}
    for d in got:
        assert d["result"] == json.loads(gk("form", "fit", "circle", d["scan"], "-c", "minimum-zone", "--json").stdout)
    engine = create_engine(url)
    with engine.connect() as conn:
        rows = conn.execute(sa.select(m.FormResult.shape, m.FormResult.criterion, m.FormResult.form_error)).all()
    engine.dispose()
    assert len(rows) == 4 and all(r[0] == "circle" and r[1] == "minimum-zone" and r[2] > 0 for r in rows)


@pytest.mark.parametrize("args, message", [
    (["nowhere/*.ply", "--db", "{db}"], "nowhere/*.ply: the pattern matches no file"),
    (["{scans}", "--db", "{db}", "--scheduler", "tcp://127.0.0.1:{port}"],
     "cannot reach the Dask scheduler at tcp://127.0.0.1:{port}"),
    (["{scans}", "--db", "postgresql://gk@127.0.0.1:{port}/x"],
     "cannot open the database postgresql+psycopg://gk@127.0.0.1:{port}/x"),
    (["{scans}", "--db", "{db}", "--workers", "0"], "--workers must be at least 1"),
])
def test_batch_that_cannot_run_says_why_in_one_line(casting_set, tmp_path, args, message):
    from servers import free_port

    gages, scans = casting_set
    fill = {"port": free_port(), "scans": str(scans[0].parent), "db": f"sqlite:///{tmp_path / 'r.db'}"}
    proc = gk("gage", "batch", gages, *[a.format(**fill) for a in args], "--json",
              env={"DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "2s"})
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert proc.stdout == ""
    err = proc.stderr.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("gagekit: error: ") and message.format(**fill) in err[0], err


def _dask_process(without_gagekit: bool, module: str, *args: str) -> subprocess.Popen:
    """``dask scheduler`` / ``dask worker`` (``module``) in a process of its own, optionally
    one that cannot import gagekit."""
    block = "sys.modules['gagekit'] = None; " if without_gagekit else ""
    code = f"import sys; {block}from {module} import main; sys.argv = ['dask', *{list(args)!r}]; main()"
    return subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


@pytest.mark.parametrize("where", ["scheduler", "worker"])
def test_a_cluster_without_gagekit_is_refused_at_connect(casting_set, tmp_path, where):
    """A scheduler (it unpickles every task) or a worker that cannot import gagekit: one
    error line naming the cluster and the node, exit 2, nothing stored - not every scan
    failing with Dask's deserialization message."""
    from servers import free_port

    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    # the worker and the batch's client retry until the scheduler listens
    procs = [_dask_process(where == "scheduler", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port",
                           str(port), "--no-dashboard"),
             _dask_process(where == "worker", "distributed.cli.dask_worker", address, "--nthreads", "1", "--no-nanny",
                           "--no-dashboard")]
    try:
        gages, scans = casting_set
        proc = gk("gage", "batch", gages, *scans[:2], "--scheduler", address, "--db",
                  f"sqlite:///{tmp_path / 'r.db'}", "--json")
    finally:
        for p in reversed(procs):
            p.terminate()
            p.wait(timeout=30)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert proc.stdout == ""
    err = proc.stderr.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"gagekit: error: the Dask cluster at {address} cannot run gagekit"), err
    named = "the scheduler cannot import gagekit" if where == "scheduler" else "worker tcp://127.0.0.1:"
    assert named in err[0] and "install gagekit" in err[0], err


def test_gage_batch_on_dask_and_postgresql(casting_set, dask_cluster, postgres_url):
    """The same results on a real LocalCluster (2 worker processes) into a real PostgreSQL."""
    gages, scans = casting_set
    got, summary = lines(gk("gage", "batch", gages, *scans[:4], "--scheduler", dask_cluster.scheduler_address,
                            "--db", postgres_url, "--json"))
    assert summary == {"scans": 4, "ok": 4, "failed": 0, "skipped": 0}
    single = json.loads(gk("gage", "check", scans[1], gages, "--json").stdout)
    assert next(d for d in got if d["scan"] == str(scans[1]))["result"] == single
    assert counts(postgres_url) == (4, 4, 32)


def test_killing_a_dask_worker_mid_batch_loses_nothing(casting_set, dask_cluster, tmp_path):
    """One of the two workers is killed after the first result: the scheduler reruns its
    task elsewhere, the batch completes, and the rerun finds everything stored once."""
    from distributed import Client

    gages, scans = casting_set
    url = f"sqlite:///{tmp_path / 'r.db'}"
    with Client(dask_cluster.scheduler_address) as client:
        pids = list(client.run(os.getpid).values())
    cmd = [sys.executable, "-m", "gagekit", "gage", "batch", str(gages), *map(str, scans), "--db", url, "--json",
           "--scheduler", dask_cluster.scheduler_address]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    out = [proc.stdout.readline()]
    os.kill(pids[0], signal.SIGKILL)
    rest, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    got = [json.loads(ln) for ln in out + rest.splitlines()]
    summary = got[-1]["summary"]
    assert summary["scans"] == len(scans) and summary["ok"] + summary["failed"] == len(scans)
    stored = counts(url)[0]
    assert stored == summary["ok"]
    _, again = lines(gk("gage", "batch", gages, *scans, "--db", url, "--json", "--scheduler", dask_cluster.scheduler_address))
    assert again["skipped"] == stored and again["ok"] == len(scans) - stored and again["failed"] == 0
    assert counts(url)[0] == len(scans)


def test_units_are_passed_to_every_scan(tmp_path):
    import numpy as np

    t = np.linspace(0, 2 * np.pi, 90, endpoint=False)
    f = tmp_path / "ring_cm.csv"
    np.savetxt(f, np.c_[2.5 * np.cos(t), 2.5 * np.sin(t) + 0.001 * np.sin(5 * t)], delimiter=",")
    url = f"sqlite:///{tmp_path / 'u.db'}"
    got, _ = lines(gk("form", "batch", "circle", f, "--units", "cm", "--db", url, "--json", "-w", "1"))
    single = json.loads(gk("form", "fit", "circle", f, "--units", "cm", "--json").stdout)
    assert got[0]["result"] == single and single["radius"] == pytest.approx(25.0, abs=0.02)
    # another unit is another spec: evaluated again, not skipped
    got_mm, summary = lines(gk("form", "batch", "circle", f, "--db", url, "--json"))
    assert summary["ok"] == 1 and got_mm[0]["result"]["radius"] == pytest.approx(2.5, abs=0.002)
    bad = gk("form", "batch", "circle", f, "--units", "furlong", "--db", url)
    assert bad.returncode == 2 and bad.stderr.startswith("gagekit: error: unknown unit 'furlong'")


def test_dask_workers_sharing_a_host_cap_their_kernel_threads(dask_cluster):
    """2 workers of 1 thread on this host: each runs its kernels (Rayon, BLAS) on
    cores // 2 threads, as 2 local workers do."""
    from distributed import Client

    from gagekit.batch import DaskCluster

    # a worker an earlier test stopped may still be restarting on a loaded machine
    with Client(dask_cluster.scheduler_address) as client:
        client.wait_for_workers(2, timeout=300)
    cluster = DaskCluster(dask_cluster.scheduler_address)
    try:
        cores = len(os.sched_getaffinity(0))
        assert sorted(cluster.thread_caps.values()) == [max(1, cores // 2)] * 2
        env = cluster.client.run(lambda: os.environ.get("RAYON_NUM_THREADS"))
        assert set(env.values()) == {str(max(1, cores // 2))}
    finally:
        cluster.close()


def _thread_pools(_):
    from threadpoolctl import threadpool_info

    return os.environ.get("RAYON_NUM_THREADS"), sorted({d["num_threads"] for d in threadpool_info()})


def test_local_workers_cap_rayon_and_the_already_started_blas_pool():
    """N workers on N cores run their kernels on one thread each: Rayon through the
    environment (read at its first use), BLAS, which numpy started when the worker
    imported gagekit, resized at run time."""
    from gagekit.batch import LocalPool

    cores = len(os.sched_getaffinity(0))
    pool = LocalPool(cores)
    try:
        got = pool._pool.submit(_thread_pools, 0).result(timeout=120)
    finally:
        pool.close()
    assert got == ("1", [1])


def test_the_human_line_of_a_failed_scan_names_its_path_once(tmp_path):
    bad = tmp_path / "notes.xyz"
    bad.write_text("0 1 0\n1 0 0\n0 -1 x\n")
    proc = gk("form", "batch", "circle", bad, "--db", f"sqlite:///{tmp_path / 'r.db'}")
    assert proc.returncode == 0, proc.stderr
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("error"))
    assert line.count(str(bad)) == 1 and "line 3" in line, line


def test_gage_batch_with_uncertainty_stores_u_and_decisions(casting_set, tmp_path):
    """`gage batch --uncertainty`: each scan's result is `gage check --uncertainty --json`'s
    (same seed: same numbers, the batch's workers each on one thread), and every allowance row
    stores u, U, the decision and the rule (issue 26)."""
    gages, scans = casting_set
    url = f"sqlite:///{tmp_path / 'gu.db'}"
    opts = ["--uncertainty", "10", "--noise", "0.002", "--seed", "4"]
    got, summary = lines(gk("gage", "batch", gages, *scans[:2], "--db", url, "--json", "-w", "2", *opts))
    assert summary == {"scans": 2, "ok": 2, "failed": 0, "skipped": 0}
    single = json.loads(gk("gage", "check", scans[1], gages, "--json", *opts, "--threads", "2").stdout)
    result = next(d for d in got if d["scan"] == str(scans[1]))["result"]
    assert result["decision"] == single["decision"] and result["decision_rule"] == single["decision_rule"]
    assert [g["uncertainty"] for g in result["gages"]] == [g["uncertainty"] for g in single["gages"]]
    assert [g["decision"] for g in result["gages"]] == [g["decision"] for g in single["gages"]]
    t = m.GageAllowance.__table__
    engine = create_engine(url)
    with engine.connect() as conn:
        rows = [dict(r._mapping) for r in conn.execute(sa.select(t.c.gage, t.c.u, t.c.expanded_u, t.c.decision,
                                                                 t.c.decision_rule))]
    engine.dispose()
    assert len(rows) == 2 * len(single["gages"])
    assert all(r["u"] is not None and r["u"] >= 0 and r["expanded_u"] >= 0 for r in rows)
    assert {r["decision"] for r in rows} <= {"conforming", "not-proven", "nonconforming"}
    assert {r["decision_rule"] for r in rows} == {"iso14253"}
