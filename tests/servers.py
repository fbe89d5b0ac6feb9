"""Real servers for the tests: a PostgreSQL server and a Dask LocalCluster.

PostgreSQL: Debian's ``postgresql`` package (``/usr/lib/postgresql/*/bin``), ``initdb`` into
a fresh temporary folder, listening on 127.0.0.1 on a free port, trust authentication,
stopped and removed afterwards. PostgreSQL refuses to run as root; as root the server
runs as the ``postgres`` user (``runuser``).

A test that cannot get its server is skipped with the reason, except in CI (``CI=true``),
where it fails: CI installs PostgreSQL (``.ci/run``) and must not skip these tests.
"""

from __future__ import annotations

import glob
import os
import shutil
import socket
import subprocess
import tempfile
import time
from typing import Optional

import pytest


def unavailable(reason: str):
    """Skip with ``reason``, or fail in CI."""
    if os.environ.get("CI", "").lower() in ("1", "true", "yes"):
        pytest.fail(f"CI must run this test: {reason}")
    pytest.skip(reason)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _pg_bin() -> Optional[str]:
    found = sorted(glob.glob("/usr/lib/postgresql/*/bin/initdb"), key=lambda p: int(p.split("/")[4]) if p.split("/")[4].isdigit() else 0)
    if found:
        return os.path.dirname(found[-1])
    initdb = shutil.which("initdb")
    return os.path.dirname(initdb) if initdb else None


class PostgresServer:
    """``initdb`` + ``pg_ctl start`` in a temporary folder; :attr:`url` of database ``gagekit``."""

    def __init__(self) -> None:
        self.bin = _pg_bin()
        if self.bin is None:
            raise RuntimeError("PostgreSQL is not installed (Debian package 'postgresql'; .ci/run installs it)")
        self.as_user: Optional[str] = None
        if os.geteuid() == 0:
            import pwd

            try:
                pwd.getpwnam("postgres")
            except KeyError:
                raise RuntimeError("running as root and there is no 'postgres' user to run the server as") from None
            self.as_user = "postgres"
        self.dir = tempfile.mkdtemp(prefix="gagekit-pg-")
        self.data = os.path.join(self.dir, "data")
        if self.as_user:
            shutil.chown(self.dir, self.as_user)
        self.port = free_port()
        self.url = f"postgresql://gagekit@127.0.0.1:{self.port}/gagekit"

    def _run(self, *args: str, timeout: float = 120) -> subprocess.CompletedProcess:
        cmd = list(args)
        if self.as_user:
            cmd = ["runuser", "-u", self.as_user, "--", *cmd]
        return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=self.dir)

    def start(self) -> "PostgresServer":
        b = self.bin
        r = self._run(f"{b}/initdb", "-D", self.data, "-U", "gagekit", "--auth=trust", "-E", "UTF8", "--no-sync")
        if r.returncode != 0:
            raise RuntimeError(f"initdb failed: {r.stderr.strip()[-300:]}")
        opts = f"-h 127.0.0.1 -p {self.port} -k {self.dir} -c fsync=off -c max_connections=60"
        r = self._run(f"{b}/pg_ctl", "-D", self.data, "-o", opts, "-l", os.path.join(self.dir, "log"), "-w", "-t", "60", "start")
        if r.returncode != 0:
            log = ""
            try:
                log = open(os.path.join(self.dir, "log")).read()[-300:]
            except OSError:
                pass
            raise RuntimeError(f"pg_ctl start failed: {r.stderr.strip()[-300:]} {log}")
        r = self._run(f"{b}/createdb", "-h", "127.0.0.1", "-p", str(self.port), "-U", "gagekit", "gagekit")
        if r.returncode != 0:
            self.stop()
            raise RuntimeError(f"createdb failed: {r.stderr.strip()[-300:]}")
        return self

    def new_database(self, name: str) -> str:
        r = self._run(f"{self.bin}/createdb", "-h", "127.0.0.1", "-p", str(self.port), "-U", "gagekit", name)
        if r.returncode != 0:
            raise RuntimeError(f"createdb {name} failed: {r.stderr.strip()[-300:]}")
        return f"postgresql://gagekit@127.0.0.1:{self.port}/{name}"

    def stop(self) -> None:
        try:
            self._run(f"{self.bin}/pg_ctl", "-D", self.data, "-m", "immediate", "-w", "stop", timeout=60)
        finally:
            shutil.rmtree(self.dir, ignore_errors=True)


@pytest.fixture(scope="session")
def postgres():
    """A running PostgreSQL server (session-wide); skipped (failed in CI) when it cannot start."""
    try:
        server = PostgresServer().start()
    except (RuntimeError, OSError, subprocess.TimeoutExpired) as exc:
        unavailable(f"no PostgreSQL server: {exc}")
    yield server
    server.stop()


_DB_COUNTER = iter(range(1, 10_000))


@pytest.fixture
def postgres_url(postgres):
    """The URL of a new, empty database on the session's server."""
    return postgres.new_database(f"t{next(_DB_COUNTER)}_{os.getpid()}")


@pytest.fixture(scope="session")
def dask_cluster():
    """A real ``dask.distributed.LocalCluster``: 2 worker processes, 1 thread each."""
    try:
        from distributed import LocalCluster
    except ImportError as exc:
        unavailable(f"dask.distributed is not installed ({exc})")
    t0 = time.perf_counter()
    try:
        # the dashboard on a free loopback port: None still binds :8787, and two test
        # workers' clusters then collide there (a UserWarning in every full run)
        cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address="127.0.0.1:0",
                               host="127.0.0.1", env={"RAYON_NUM_THREADS": "1"})
    except Exception as exc:  # pragma: no cover - depends on the machine
        unavailable(f"cannot start a Dask LocalCluster: {exc}")
    cluster.started_in = time.perf_counter() - t0
    yield cluster
    cluster.close()


class StudioServer:
    """`gagekit studio` in a child process (a real uvicorn server on 127.0.0.1, a free port):
    :attr:`url` is the address it prints (with its access token), :meth:`request` sends one
    HTTP request with the token and returns (status, parsed JSON or None, seconds)."""

    def __init__(self, *args: str, env: Optional[dict] = None, browser: bool = False) -> None:
        import re
        import sys

        cmd = [sys.executable, "-m", "gagekit", "studio", *args, "--port", "0"] + ([] if browser else ["--no-browser"])
        self.proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True,
                                     env=env if env is not None else dict(os.environ))
        self.url = self.token = None
        self.lines: list = []
        for line in self.proc.stderr:
            self.lines.append(line)
            m = re.search(r"access token: (\S+)", line)
            self.token = self.token or (m.group(1) if m else None)
            m = re.search(r"open (http://\S+)", line)
            if m:
                self.url = m.group(1)
                break
        assert self.url, "".join(self.lines)
        self.base = self.url.split("?")[0]

    def request(self, method: str, path: str, body: Optional[bytes] = None, *, token: bool = True,
                timeout: float = 30.0, content_type: str = "application/json"):
        import json
        import urllib.error
        import urllib.request

        headers = {"Content-Type": content_type} if body is not None else {}
        if token and self.token:
            headers["X-Studio-Token"] = self.token
        req = urllib.request.Request(self.base + path.lstrip("/"), data=body, method=method, headers=headers)
        t0 = time.monotonic()
        try:
            with urllib.request.urlopen(req, timeout=timeout) as r:
                status, data, ctype = r.status, r.read(), r.headers.get("content-type", "")
        except urllib.error.HTTPError as exc:
            status, data, ctype = exc.code, exc.read(), exc.headers.get("content-type", "")
        seconds = time.monotonic() - t0
        return status, (json.loads(data) if ctype.startswith("application/json") else None), seconds

    def interrupt(self, timeout: float = 15.0) -> Optional[int]:
        """Ctrl-C (SIGINT); the exit status, or None if it did not stop within ``timeout``."""
        import signal

        self.proc.send_signal(signal.SIGINT)
        try:
            return self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            return None

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


def body(obj) -> bytes:
    """A JSON request body."""
    import json

    return json.dumps(obj).encode()


def assert_4xx(answer, *words, status: Optional[int] = None):
    """``answer`` of :meth:`StudioServer.request` is a 4xx JSON error (``status`` if given)
    whose message holds ``words``; returns its JSON."""
    code, data, _ = answer
    assert 400 <= code < 500 and (status is None or code == status), answer
    assert isinstance(data, dict) and isinstance(data.get("error"), str) and data["error"], answer
    for w in words:
        assert w in data["error"], answer
    return data
