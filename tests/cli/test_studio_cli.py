"""`gagekit studio` on the command line: bad arguments are one error line and exit 2;
a foreign address needs the printed token."""

import re
import socket
import subprocess
import sys
import urllib.error
import urllib.request

from gagekit.samples import data_path


def run(*args):
    return subprocess.run([sys.executable, "-m", "gagekit", "studio", *args, "--no-browser"],
                          capture_output=True, text=True, timeout=120)


def test_bad_arguments_are_one_line_errors(tmp_path):
    for args, words in ((["missing.ply"], "no such file"),
                        ([str(data_path("casting_ok.ply")), str(tmp_path / "g.txt")], ".toml"),
                        ([str(data_path("casting_ok.ply")), str(tmp_path / "nowhere" / "g.toml")], "does not exist"),
                        ([str(data_path("casting_ok.ply")), "--port", "70000"], "--port"),
                        ([str(data_path("casting_ok.ply")), "--units", "furlong"], "furlong")):
        proc = run(*args)
        assert proc.returncode == 2, (args, proc.stderr)
        lines = proc.stderr.strip().splitlines()
        assert lines[-1].startswith("gagekit: error:") and words in lines[-1], (args, proc.stderr)
        assert "Traceback" not in proc.stderr


def test_port_in_use_is_an_error():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen(1)
        port = s.getsockname()[1]
        proc = run(str(data_path("casting_ok.ply")), "--port", str(port))
    assert proc.returncode == 2 and "choose another --port" in proc.stderr


def test_host_needs_the_printed_token(tmp_path):
    proc = subprocess.Popen([sys.executable, "-m", "gagekit", "studio", str(data_path("casting_ok.ply")),
                             "--no-browser", "--port", "0", "--host", "127.0.0.2"],
                            stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
    try:
        token = url = None
        for line in proc.stderr:
            m = re.search(r"access token: (\S+)", line)
            token = token or (m.group(1) if m else None)
            m = re.search(r"open (http://\S+)", line)
            if m:
                url = m.group(1)
                break
        assert token and url and f"?token={token}" in url
        base = url.split("?")[0]
        try:
            urllib.request.urlopen(base + "api/state", timeout=10)
            raise AssertionError("served without the token")
        except urllib.error.HTTPError as exc:
            assert exc.code == 401
        req = urllib.request.Request(base + "api/state", headers={"X-Studio-Token": token})
        assert urllib.request.urlopen(req, timeout=10).status == 200
    finally:
        proc.terminate()
        proc.wait(timeout=10)
