"""The web app: FastAPI routes over a :class:`~motionlang.web.studio.Studio`, and the server.

FastAPI + uvicorn rather than gradio: the page is one hand-written HTML file with a canvas
viewer in plain JavaScript (``static/``), served from the package, so the app works offline
and pulls in two small libraries instead of gradio's tree; the routes are a small JSON API
(``/api/...``) that scripts can call as well. See ``docs/web.md``.

Every error comes back as ``{"error": "one line"}`` with status 400 (413 for an upload over
the limit, 403 for a request from another site's page, 500 for a bug, whose trace goes to
the server's log and never to the page). Requests whose ``Host`` is not the server's are
refused (``same_site.py``).
"""
from __future__ import annotations

import contextlib
import errno
import logging
import socket
import threading
from importlib import resources
from typing import Annotated, Any

from fastapi import FastAPI, File, Request, UploadFile
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, JSONResponse, Response
from pydantic import BaseModel
from starlette.exceptions import HTTPException as StarletteHTTPException

from motionlang.errors import MotionlangError
from motionlang.web.body_limit import BodyLimit
from motionlang.web.options import ServeOptions
from motionlang.web.same_site import SameSite, hosts_for
from motionlang.web.studio import Studio

log = logging.getLogger(__name__)
#: the page's files and their media types (nothing else is served from static/)
STATIC = {"viewer.js": "text/javascript", "app.js": "text/javascript",
          "style.css": "text/css"}
#: request bodies beyond the upload limit by this much (form fields, boundaries) are refused
FORM_SLACK = 64 << 10


Files = Annotated[list[UploadFile], File()]


class GenerateRequest(BaseModel):
    text: str
    model: str | None = None
    seconds: float | None = None
    seed: int = 0
    method: str | None = None
    rig: str | None = None


def _static(name: str) -> str:
    return (resources.files("motionlang.web") / "static" / name).read_text(encoding="utf-8")


def _error(status: int, message: str) -> JSONResponse:
    return JSONResponse({"error": message}, status_code=status)


async def _read(files: list[UploadFile], limit: int) -> list[tuple[str, bytes]]:
    """The uploaded files' names and bytes, reading no more than ``limit`` + 1 bytes."""
    out, left = [], limit + 1
    for f in files:
        data = await f.read(left)
        left -= len(data)
        out.append((f.filename or "upload", data))
    return out


def create_app(studio: Studio) -> FastAPI:
    """The app over ``studio`` (its models already loaded)."""
    app = FastAPI(title="motionlang", docs_url=None, redoc_url=None, openapi_url=None)
    limit = studio.options.max_upload_bytes

    app.add_middleware(BodyLimit, limit=limit + FORM_SLACK, message=lambda size: (
        f"the upload is {size / (1 << 20):.1f} MiB; the largest this server takes is "
        f"{limit / (1 << 20):.1f} MiB (motionlang serve --max-upload-mb)"))

    # added last, so it runs first: a foreign Host or a cross-site POST reads no body
    app.add_middleware(SameSite, hosts=hosts_for(studio.options.host))

    @app.exception_handler(StarletteHTTPException)
    async def http_error(_request: Request, exc: StarletteHTTPException):
        return _error(exc.status_code, str(exc.detail))

    @app.exception_handler(MotionlangError)
    async def one_line(_request: Request, exc: MotionlangError):
        return _error(400, str(exc))

    @app.exception_handler(RequestValidationError)
    async def bad_request(_request: Request, exc: RequestValidationError):
        first: dict[str, Any] = (exc.errors() or [{}])[0]
        where = ".".join(str(p) for p in first.get("loc", ()) if p != "body") or "request"
        return _error(400, f"{where}: {first.get('msg', 'invalid')}")

    @app.exception_handler(Exception)
    async def bug(_request: Request, exc: Exception):
        log.exception("motionlang serve: an unexpected error")
        return _error(500, f"internal error ({type(exc).__name__}); the server's log has "
                           "the details")

    @app.get("/", response_class=HTMLResponse)
    def page() -> str:
        return _static("index.html")

    @app.get("/static/{name}")
    def static(name: str) -> Response:
        if name not in STATIC:
            return _error(404, f"no file {name!r}")
        return Response(_static(name), media_type=STATIC[name])

    @app.get("/api/info")
    def info() -> dict:
        return studio.info()

    @app.post("/api/generate")
    def generate(req: GenerateRequest) -> dict:
        return studio.generate(req.text, req.model, req.seconds, req.seed, req.method,
                               req.rig)

    @app.post("/api/describe")
    async def describe(files: Files) -> JSONResponse:
        data = await _read(files, limit)
        return JSONResponse(await _in_thread(studio.describe, data))

    @app.post("/api/rig")
    async def rig(files: Files) -> JSONResponse:
        data = await _read(files, limit)
        return JSONResponse(await _in_thread(studio.add_rig, data))

    @app.get("/api/search")
    def search(q: str, k: int = 10, where: str | None = None,
               min_duration: str | None = None) -> list:
        return studio.search(q, max(1, min(k, 100)), where=where, min_duration=min_duration)

    @app.get("/api/take")
    def take(file: str, start: float, end: float) -> dict:
        return studio.search_take(file, start, end)

    @app.get("/api/export/{take}.{fmt}")
    def export(take: str, fmt: str, rig: str | None = None) -> Response:
        data, name, media = studio.export(take, fmt, rig)
        return Response(data, media_type=media,
                        headers={"Content-Disposition": f'attachment; filename="{name}"'})

    return app


async def _in_thread(fn, *args):
    """Run a slow call off the event loop (as FastAPI runs plain ``def`` routes)."""
    from starlette.concurrency import run_in_threadpool
    return await run_in_threadpool(fn, *args)


def serve(options: ServeOptions, *, ready=None) -> None:
    """Load the models, then serve until interrupted; ``ready(url)`` is called once the
    server listens (the CLI prints the address)."""
    import uvicorn
    check_address(options.host, options.port)   # before minutes of loading models
    if not options.local:
        log.warning("motionlang serve: listening on %s: anyone who reaches this machine "
                    "can use the app (it has no login)", options.host)
    studio = Studio(options)
    config = uvicorn.Config(create_app(studio), host=options.host, port=options.port,
                            log_level="warning", access_log=False)
    server = uvicorn.Server(config)
    if ready is not None:
        _announce(server, ready)
    try:
        server.run()
    except KeyboardInterrupt:   # Ctrl-C is how a user stops the app: not a failure
        pass


def check_address(host: str, port: int) -> None:
    """Raise :class:`MotionlangError` (naming ``--host`` or ``--port``) where the server
    could not listen on ``host:port``: a name that does not resolve, an address this
    machine does not have, a port in use or not allowed."""
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except (socket.gaierror, UnicodeError, OverflowError) as exc:
        raise MotionlangError(f"--host {host}: not an address or name this machine can "
                              f"resolve ({exc})") from None
    family, kind, proto, _, address = infos[0]
    with socket.socket(family, kind, proto) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind(address)
        except OSError as exc:
            what = f"--port {port}" if exc.errno in (errno.EADDRINUSE, errno.EACCES) \
                else f"--host {host}"
            raise MotionlangError(f"{what}: cannot listen on {host}:{port} "
                                  f"({exc.strerror or exc})") from None


def _announce(server, ready) -> None:
    """Call ``ready(url)`` from the server's start-up, with the port it really bound."""
    started = server.startup

    async def startup(sockets=None):
        await started(sockets=sockets)
        if server.started:
            sock = server.servers[0].sockets[0]
            host, port = sock.getsockname()[:2]
            ready(f"http://{host}:{port}/")
    server.startup = startup


@contextlib.contextmanager
def running(studio: Studio, host: str = "127.0.0.1", port: int = 0, timeout: float = 30.0):
    """The app over ``studio`` served from a background thread while the block runs (tests,
    benchmarks); yields its URL. The server stops when the block ends."""
    import uvicorn
    server = uvicorn.Server(uvicorn.Config(create_app(studio), host=host, port=port,
                                           log_level="warning", access_log=False))
    thread = threading.Thread(target=server.run, name="motionlang-serve", daemon=True)
    thread.start()
    waited = 0.0
    while not server.started:
        if not thread.is_alive() or waited > timeout:
            raise MotionlangError(f"the server did not start on {host}:{port}")
        threading.Event().wait(0.05)
        waited += 0.05
    bound = server.servers[0].sockets[0].getsockname()
    try:
        yield f"http://{bound[0]}:{bound[1]}/"
    finally:
        server.should_exit = True
        thread.join(timeout)
