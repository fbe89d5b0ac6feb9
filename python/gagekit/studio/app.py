"""The studio's HTTP layer (Starlette): JSON in and out, over :class:`~.session.Session`.

Endpoints (all JSON unless said otherwise; errors are ``{"error": message}`` with a
4xx status, and spec errors also carry ``errors``: ``[{"table", "name", "index",
"message"}]``):

==========================  ==============================================================
``GET  /``                  the client (``static/index.html``)
``GET  /api/state``         scan information, the document (gage file or drawing), its validation,
                            the inspection's shapes and which characteristics apply to each
``GET  /api/scan/points``   the displayed points: float32 x, y, z (octet-stream)
``POST /api/scan``          ``{"path", "units"?}``: open another scan in the studio folder
``GET  /api/files``         scans and gage files in the studio folder
``POST /api/spec``          ``{"path", "kind"?}``: open (or start: kind "gage" or "part") a
                            gage file or a drawing (PART.toml) in the studio folder
``POST /api/regions``       ``{"doc"}``: every region's count over all points, the datum frame
``POST /api/select``        ``{"region"}``: count inside one box, the displayed points inside
                            (``indices`` or a bit ``mask``, whichever is smaller)
``POST /api/run``           ``{"doc", "groups"?}``: the gage check, T*, per-point distances;
                            for a drawing the inspection and per-point deviations
``POST /api/save``          ``{"doc", "path"?}``: write the gage file (atomic)
``POST /api/cad``           ``{"path"?, "units"?, "max_distance"?}``: open a CAD model beside the
                            scan (STEP with the ``cad`` extra, STL, OBJ, PLY with faces; no
                            path: the drawing's ``[part] cad``), or ``{"close": true}``
``GET  /api/cad/mesh``      the shown mesh (octet-stream): float32 x, y, z of ``X-Vertex-Count``
                            vertices minus ``X-Origin``, then uint32 corners of
                            ``X-Triangle-Count`` triangles; decimated above
                            :data:`~.cadview.MAX_CAD_TRIANGLES`
==========================  ==============================================================

After ``/api/run`` on a drawing, ``cad`` holds the open model's per-vertex colours
(:mod:`.cadview`: the colouring of ``gagekit compare --report``) and the colour scale.

Requests name files relative to the studio folder; a path that leads outside it is
refused (403), and so is a file that is not a regular file (a FIFO would block the
server: 400). Request bodies are limited to :data:`MAX_BODY` bytes (413); a body that is
not a JSON object is refused (400), and so is JSON nested deeper than :data:`MAX_DEPTH`,
a string that is not Unicode (a lone surrogate such as ``"\\ud800"``), a number that is
not finite or an integer beyond +-2^53 (the exact range of JSON numbers, RFC 8259 Sec. 6):
nothing a client sends reaches the library as a value it cannot hold. Every request must
carry the access token (query ``token``, header ``X-Studio-Token`` or the cookie set by
the first page load), on the loopback too, as Jupyter does: a local page must not be
readable by any other local user or by a web page in the browser.
"""

from __future__ import annotations

import json
import math
import os
import secrets
from pathlib import Path
from typing import Any, Optional

from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.exceptions import HTTPException
from starlette.middleware import Middleware
from starlette.middleware.trustedhost import TrustedHostMiddleware
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response
from starlette.routing import Mount, Route
from starlette.staticfiles import StaticFiles
from starlette.types import ASGIApp, Receive, Scope, Send

from ..cad import CAD_SUFFIXES as _CAD_SUFFIXES
from ..errors import ConfigError, GagekitError
from .cadview import ply_has_faces
from .session import OutsideError, Session, SpecError

STATIC = Path(__file__).with_name("static")
MAX_BODY = 4 * 1024 * 1024
"""Largest request body accepted (bytes): a gage document is a few kB."""
MAX_DEPTH = 32
"""Deepest nesting of a request's JSON (a gage document or a drawing is 4 levels deep)."""
MAX_INT = 2 ** 53
"""Largest integer magnitude accepted in a request (JSON's exact integers, RFC 8259 Sec. 6)."""
SCAN_SUFFIXES = {".ply", ".xyz", ".csv", ".txt", ".asc", ".pts", ".ds", ".npy", ".las", ".laz", ".e57"}
CAD_SUFFIXES = set(_CAD_SUFFIXES)
"""CAD models the studio opens (a ``.ply`` is a CAD model when it has faces)."""
COOKIE = "gagekit_studio"
LOOPBACK_HOSTS = ["127.0.0.1", "localhost", "::1", "[::1]"]


class RequestError(Exception):
    """A bad request: status and message for the client."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.message = message


def cookie_name(token: str) -> str:
    """The token cookie's name: one per server (two studios on one host, on two ports,
    share the host's cookies; a name of their own keeps each one's token)."""
    import hashlib

    return f"{COOKIE}_{hashlib.sha256(token.encode()).hexdigest()[:10]}"


class TokenMiddleware:
    """Every request must carry the access token (constant-time comparison)."""

    def __init__(self, app: ASGIApp, token: str) -> None:
        self.app = app
        self.token = token
        self.cookie = cookie_name(token)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        request = Request(scope)
        given = (request.query_params.get("token") or request.headers.get("x-studio-token")
                 or request.cookies.get(self.cookie) or "")
        if not secrets.compare_digest(given.encode(), self.token.encode()):
            await JSONResponse({"error": "access token missing or wrong (see the terminal that started the studio)"},
                               status_code=401)(scope, receive, send)
            return
        if request.query_params.get("token") and scope["path"] == "/":
            async def send_with_cookie(message):
                if message["type"] == "http.response.start":
                    cookie = f"{self.cookie}={self.token}; Path=/; HttpOnly; SameSite=Strict"
                    message.setdefault("headers", []).append((b"set-cookie", cookie.encode()))
                await send(message)

            await self.app(scope, receive, send_with_cookie)
            return
        await self.app(scope, receive, send)


def _inside(root: Path, full: Path) -> bool:
    return full == root or root in full.parents


def confined(root: Path, rel: Any, suffixes: Optional[set] = None, what: str = "path", *,
             regular: bool = False) -> Path:
    """``root / rel`` if it stays inside ``root`` (after resolving links), else 403; with
    ``regular``, an existing path must be a regular file (a FIFO is refused before anything
    opens it: opening one blocks until a writer comes)."""
    if not isinstance(rel, str) or not rel or len(rel) > 1024 or "\x00" in rel:
        raise RequestError(400, f"{what}: expected a file name inside the studio folder")
    p = Path(rel)
    if p.is_absolute() or p.drive:
        raise RequestError(403, f"{what}: '{rel}' is outside the studio folder (give a relative name)")
    full = (root / p).resolve()
    if not _inside(root, full):
        raise RequestError(403, f"{what}: '{rel}' is outside the studio folder")
    if suffixes is not None and full.suffix.lower() not in suffixes:
        raise RequestError(400, f"{what}: '{rel}' must end in one of {', '.join(sorted(suffixes))}")
    if regular and full.exists():
        from .._files import input_file

        try:
            input_file(full, what)
        except GagekitError as exc:
            raise RequestError(400, f"{what}: '{rel}' {str(exc).split(': ', 1)[-1]}") from None
    return full


async def read_json(request: Request) -> dict:
    """The request's JSON object, or a RequestError (413 too large, 415, 400)."""
    ctype = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if ctype != "application/json":
        raise RequestError(415, "send the request body as application/json")
    length = request.headers.get("content-length")
    if length is not None:
        try:
            if int(length) > MAX_BODY:
                raise RequestError(413, f"request body of {int(length)} bytes is larger than {MAX_BODY}")
        except ValueError:
            raise RequestError(400, "bad Content-Length") from None
    body = bytearray()
    async for chunk in request.stream():
        body.extend(chunk)
        if len(body) > MAX_BODY:
            raise RequestError(413, f"request body larger than {MAX_BODY} bytes")
    try:
        data = json.loads(body.decode("utf-8"), parse_constant=_reject_constant)
    except (UnicodeDecodeError, ValueError) as exc:
        raise RequestError(400, f"malformed JSON: {exc}") from None
    except RecursionError:
        raise RequestError(400, f"JSON nested too deep (more than {MAX_DEPTH} levels)") from None
    if not isinstance(data, dict):
        raise RequestError(400, "expected a JSON object")
    check_values(data)
    return data


def check_values(data: Any) -> None:
    """Refuse (400, naming where) JSON nested deeper than :data:`MAX_DEPTH`, strings that
    are not Unicode (lone surrogates: nothing can encode them, not a file name, not a
    saved file), numbers that are not finite, integers beyond +-:data:`MAX_INT`."""
    stack = [(data, "request", 0)]
    while stack:
        v, where, depth = stack.pop()
        if depth > MAX_DEPTH:
            raise RequestError(400, f"JSON nested too deep (more than {MAX_DEPTH} levels) at {where}")
        if isinstance(v, dict):
            for k, x in v.items():
                _unicode(k, f"{where} key")
                stack.append((x, f"{where}.{k}", depth + 1))
        elif isinstance(v, list):
            stack.extend((x, f"{where}[{i}]", depth + 1) for i, x in enumerate(v))
        elif isinstance(v, str):
            _unicode(v, where)
        elif isinstance(v, bool) or v is None:
            pass
        elif isinstance(v, int):
            if abs(v) > MAX_INT:
                raise RequestError(400, f"{where}: the integer {v} is beyond +-2^53 (the exact range of JSON numbers)")
        elif isinstance(v, float) and not math.isfinite(v):
            raise RequestError(400, f"{where}: {v} is not a finite number")


def _unicode(s: str, where: str) -> None:
    try:
        s.encode("utf-8")
    except UnicodeEncodeError as exc:
        bad = s[exc.start]
        raise RequestError(400, f"{where}: {ascii(bad)} is a lone surrogate, not valid Unicode") from None


def _reject_constant(name: str):
    raise ValueError(f"{name} is not a number")


def _doc(data: dict) -> dict:
    doc = data.get("doc")
    if not isinstance(doc, dict):
        raise RequestError(400, "expected 'doc': the gage document as a JSON object")
    return doc


def create_app(session: Session, root: Path, *, token: Optional[str] = None,
               allowed_hosts: Optional[list] = None) -> Starlette:
    """The studio application over ``session``; files named by requests must lie in ``root``."""
    root = root.resolve()
    session.root = root  # a drawing's CAD model too

    async def index(request: Request) -> Response:
        return FileResponse(STATIC / "index.html", headers={"Cache-Control": "no-store"})

    async def state(request: Request) -> Response:
        from ..inspect import APPLIES_TO, SHAPES

        return JSONResponse({"scan": session.scan.info(), "spec": await run_in_threadpool(session.spec_model),
                             "cad": await run_in_threadpool(session.cad_state),
                             "root": str(root), "max_body": MAX_BODY,
                             "inspection": {"shapes": list(SHAPES), "applies_to": APPLIES_TO}})

    async def scan_points(request: Request) -> Response:
        scan = session.scan
        data = await run_in_threadpool(scan.lod_buffer)
        return Response(data, media_type="application/octet-stream",
                        headers={"X-Point-Count": str(len(scan.lod)), "Cache-Control": "no-store"})

    async def open_scan(request: Request) -> Response:
        data = await read_json(request)
        path = confined(root, data.get("path"), SCAN_SUFFIXES, "scan", regular=True)
        units = data.get("units")
        if units is not None and not isinstance(units, str):
            raise RequestError(400, "units: expected a unit name such as \"mm\"")
        return JSONResponse(await run_in_threadpool(session.replace_scan, path, units))

    async def files(request: Request) -> Response:
        def listing() -> dict:
            """Regular files under ``root`` (symbolic links to folders not followed, links
            to files listed only when they resolve inside ``root``; hidden names skipped)."""
            found: list[Path] = []
            for top, dirs, names in os.walk(root, followlinks=False):
                dirs[:] = sorted(d for d in dirs if not d.startswith("."))
                found += [Path(top) / n for n in names if not n.startswith(".")]
                if len(found) > 5000:
                    break
            scans, specs, cads = [], [], []
            for p in sorted(found)[:5000]:
                suffix = p.suffix.lower()
                if suffix not in SCAN_SUFFIXES and suffix not in CAD_SUFFIXES and suffix != ".toml":
                    continue
                if not p.is_file() or (p.is_symlink() and not _inside(root, p.resolve())):
                    continue
                rel = p.relative_to(root).as_posix()
                if suffix in SCAN_SUFFIXES:
                    scans.append(rel)
                if suffix in CAD_SUFFIXES and (suffix != ".ply" or ply_has_faces(p)):
                    cads.append(rel)
                if suffix == ".toml":
                    specs.append(rel)
            return {"scans": scans, "specs": specs, "cads": cads}

        return JSONResponse(await run_in_threadpool(listing))

    async def open_spec(request: Request) -> Response:
        data = await read_json(request)
        path = confined(root, data.get("path"), {".toml"}, "gage file", regular=True)
        kind = data.get("kind", "gage")
        if kind not in ("gage", "part"):
            raise RequestError(400, "kind: expected \"gage\" (a gage file) or \"part\" (a drawing, PART.toml)")
        return JSONResponse(await run_in_threadpool(session.open_spec, path, kind))

    async def regions(request: Request) -> Response:
        doc = _doc(await read_json(request))
        return JSONResponse(await run_in_threadpool(session.regions, doc))

    async def select(request: Request) -> Response:
        data = await read_json(request)
        return JSONResponse(await run_in_threadpool(session.select, data.get("region")))

    async def run(request: Request) -> Response:
        data = await read_json(request)
        groups = data.get("groups", True)
        if not isinstance(groups, bool):
            raise RequestError(400, "groups: expected true or false")
        return JSONResponse(await run_in_threadpool(session.run, _doc(data), groups))

    async def save(request: Request) -> Response:
        data = await read_json(request)
        doc = _doc(data)
        path = None if data.get("path") in (None, "") else confined(root, data.get("path"), {".toml"}, "gage file",
                                                                   regular=True)
        if path is not None and not path.parent.is_dir():
            raise RequestError(400, f"gage file: folder '{path.parent.name}' does not exist")
        return JSONResponse(await run_in_threadpool(session.save, doc, path))

    async def open_cad(request: Request) -> Response:
        data = await read_json(request)
        if data.get("close") is True:
            return JSONResponse(await run_in_threadpool(session.close_cad))
        rel = data.get("path")
        path = None if rel is None else confined(root, rel, CAD_SUFFIXES, "CAD file", regular=True)
        units = data.get("units")
        if units is not None and not isinstance(units, str):
            raise RequestError(400, "units: expected a unit name such as \"mm\"")
        limit = data.get("max_distance")
        if limit is not None and (isinstance(limit, bool) or not isinstance(limit, (int, float)) or not limit > 0):
            raise RequestError(400, "max_distance: expected a positive number of mm (or null: every point)")
        return JSONResponse(await run_in_threadpool(session.open_cad, path, units,
                                                    None if limit is None else float(limit)))

    async def cad_mesh(request: Request) -> Response:
        view = session.cad_mesh()
        if view is None:
            raise RequestError(404, "no CAD model is open (POST /api/cad first)")
        data = await run_in_threadpool(view.buffer)
        return Response(data, media_type="application/octet-stream",
                        headers={"X-Vertex-Count": str(len(view.vertices)), "X-Triangle-Count": str(len(view.triangles)),
                                 "X-Origin": ",".join(repr(float(x)) for x in view.origin), "X-Cad-Key": str(view.key),
                                 "Cache-Control": "no-store"})

    async def request_error(request: Request, exc: RequestError) -> Response:
        return JSONResponse({"error": exc.message}, status_code=exc.status)

    async def spec_error(request: Request, exc: SpecError) -> Response:
        return JSONResponse({"error": str(exc), "errors": exc.check.errors, "warnings": exc.check.warnings},
                            status_code=422)

    async def gagekit_error(request: Request, exc: GagekitError) -> Response:
        if isinstance(exc, OutsideError):
            return JSONResponse({"error": str(exc)}, status_code=403)
        status = 422 if isinstance(exc, ConfigError) else 400
        body: dict = {"error": str(exc)}
        if isinstance(exc, ConfigError):
            from .specdoc import locate

            body["errors"] = [locate(str(exc), session.source)]
        return JSONResponse(body, status_code=status)

    async def http_error(request: Request, exc: HTTPException) -> Response:
        return JSONResponse({"error": exc.detail}, status_code=exc.status_code)

    async def server_error(request: Request, exc: Exception) -> Response:
        return JSONResponse({"error": f"internal error: {type(exc).__name__}: {exc}"}, status_code=500)

    routes = [
        Route("/", index),
        Route("/api/state", state),
        Route("/api/scan/points", scan_points),
        Route("/api/scan", open_scan, methods=["POST"]),
        Route("/api/files", files),
        Route("/api/spec", open_spec, methods=["POST"]),
        Route("/api/regions", regions, methods=["POST"]),
        Route("/api/select", select, methods=["POST"]),
        Route("/api/run", run, methods=["POST"]),
        Route("/api/save", save, methods=["POST"]),
        Route("/api/cad", open_cad, methods=["POST"]),
        Route("/api/cad/mesh", cad_mesh),
        Mount("/static", StaticFiles(directory=STATIC), name="static"),
    ]
    middleware = []
    if allowed_hosts:
        middleware.append(Middleware(TrustedHostMiddleware, allowed_hosts=allowed_hosts))
    if token:
        middleware.append(Middleware(TokenMiddleware, token=token))
    return Starlette(routes=routes, middleware=middleware, exception_handlers={
        RequestError: request_error, SpecError: spec_error, GagekitError: gagekit_error,
        HTTPException: http_error, Exception: server_error})


__all__ = ["create_app", "confined", "read_json", "check_values", "cookie_name", "RequestError", "MAX_BODY", "MAX_DEPTH"]
