"""gagekit studio: set up virtual gages and inspections on the scan itself, in the browser.

The dissertation's closing recommendation (Sec. 7.2, item 5): "a better user
interface that helps the user to define virtual gages should be developed". The
studio is a local web application: the scan in 3-D (a level-of-detail subsample
for display; every computation on all points), sampling regions as boxes moved,
rotated and resized with handles or typed numbers, each region a gage (Table 5.1:
plane, weights) or a datum of the 3-2-1 alignment (Eqs. 5.13-5.19), the gage
check of Eq. 5.11 run on the server, its allowances as a table and a colour map,
T* applied to the view, and the gage file saved in the format ``gage check`` reads.
With a drawing (PART.toml) the regions are inspection features instead (shape,
outward side or hole/shaft, datum letter, tolerance callouts with datums and
nominals), inspected on the server with :func:`gagekit.inspect` (ISO 1101 /
ISO 5459): the callout table, each feature's deviations as a colour map, and the
drawing saved in the format ``gagekit inspect`` reads.

The server (:mod:`.app`, Starlette on uvicorn) is a thin layer over
:mod:`gagekit.cloud` and :mod:`gagekit.gage` (:mod:`.session`); the client is plain
ES modules over three.js, shipped in ``static/`` (no network at run time).
"""

from __future__ import annotations

import ipaddress
import secrets
import socket
import threading
import webbrowser
from pathlib import Path
from typing import Callable, Optional

from ..errors import ConfigError, FileFormatError
from .app import LOOPBACK_HOSTS, create_app
from .session import LOD_MAX, Session, load_scan


def _is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def serve(scan: Path, spec: Optional[Path] = None, *, units: Optional[str] = None, port: int = 8765,
          host: Optional[str] = None, open_browser: bool = True, root: Optional[Path] = None,
          lod_max: int = LOD_MAX, echo: Callable[[str], None] = print, kind: str = "gage") -> None:
    """Load ``scan`` (and ``spec``), then serve the studio until interrupted.

    ``kind`` is what a ``spec`` that does not exist yet becomes: a gage file
    (``"gage"``) or a drawing (``"part"``). Without ``host`` the server listens on 127.0.0.1 only and accepts only loopback
    Host headers (no DNS rebinding); with ``host`` it listens there. On every address each
    request must carry a freshly generated access token, as Jupyter's server does: any
    local user can connect to a loopback port, and any web page can make the browser
    send requests to it. The address printed, and opened in the browser, carries it
    (``?token=...``); the first page load turns it into a cookie of this server.
    """
    import uvicorn

    scan = Path(scan)
    if not scan.is_file():
        raise FileFormatError(f"{scan}: no such file")
    if spec is not None and spec.suffix.lower() != ".toml":
        raise ConfigError(f"{spec}: a gage file is a .toml file")
    if spec is not None and not spec.parent.is_dir():
        raise ConfigError(f"{spec}: folder {spec.parent} does not exist")
    if not 0 <= port <= 65535:
        raise ConfigError(f"--port {port}: must be between 0 and 65535")
    root = (root or scan.resolve().parent).resolve()
    token = secrets.token_urlsafe(24)
    allowed = LOOPBACK_HOSTS
    bind = "127.0.0.1"
    if host is not None:
        bind = host
        allowed = None
    echo(f"gagekit studio: reading {scan} ...")
    loaded = load_scan(scan.resolve(), units, lod_max)
    session = Session(loaded, spec.resolve() if spec is not None else None, lod_max, kind=kind, root=root)
    app = create_app(session, root, token=token, allowed_hosts=allowed)

    family = socket.AF_INET6 if ":" in bind.strip("[]") else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((bind.strip("[]"), port))
        sock.listen(128)  # connections queue from now on, before uvicorn takes the socket
    except OSError as exc:
        sock.close()
        raise ConfigError(f"cannot listen on {bind}:{port} ({exc.strerror or exc}); choose another --port") from None
    port = sock.getsockname()[1]
    shown = "127.0.0.1" if bind in ("0.0.0.0", "::") else bind
    shown = f"[{shown}]" if ":" in shown and not shown.startswith("[") else shown
    url = f"http://{shown}:{port}/?token={token}"
    config = uvicorn.Config(app, log_level="warning", lifespan="off", timeout_graceful_shutdown=2)
    server = uvicorn.Server(config)
    info = loaded.info()
    echo(f"gagekit studio: {info['count']:,} points ({info['lod_count']:,} shown) read in {info['load_seconds']:.2f} s")
    echo(f"gagekit studio: listening on {bind}:{port}; access token: {token}")
    echo(f"gagekit studio: open {url}  (Ctrl+C to stop)")

    if open_browser:
        def _open() -> None:
            for _ in range(200):
                if server.started:
                    break
                threading.Event().wait(0.05)
            webbrowser.open(url)

        threading.Thread(target=_open, daemon=True).start()
    try:
        server.run(sockets=[sock])
    finally:
        sock.close()


__all__ = ["serve", "create_app", "Session", "load_scan"]
