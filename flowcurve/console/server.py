"""The console's HTTP side: a Starlette application served by uvicorn.

Endpoints (JSON unless said):

* ``GET /`` the page; ``GET /static/…`` its script, style and the vendored uPlot;
* ``GET /api/events`` server-sent events: ``status`` (state, readings, heater) and
  ``points`` (new plot points) about twenty times a second while a test runs, ``test``
  (the test's summary) when it changes; a page that connects gets everything so far;
* ``GET /api/status``; ``POST /api/start`` (the set-up form), ``/api/stop``, ``/api/abort``,
  ``/api/post`` (post-test measurements → record amended → identified);
* ``GET /api/records``; ``POST /api/fit`` (selected records → fit → card);
* ``GET /files/<path>`` a file under ``--out`` (read only); ``POST /api/login`` the token.

Security: with a token (required when listening on anything but the loopback) every
``/api`` and ``/files`` request needs it, as the ``X-Flowcurve-Token`` header or the cookie
the login sets. Every POST must be ``application/json`` from the page's own origin (so
another web site the operator has open cannot drive the rig), and names files only by
bare names checked against ``--out`` (:mod:`flowcurve.console.workspace`).
"""

from __future__ import annotations

import asyncio
import hmac
import json
import logging
import math
import signal
import threading
from contextlib import asynccontextmanager
from pathlib import Path

from starlette.applications import Starlette
from starlette.middleware import Middleware
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response, StreamingResponse
from starlette.routing import Mount, Route
from starlette.staticfiles import StaticFiles

from flowcurve.acquisition.procedure import POST_KEYS, POST_PROMPTS
from flowcurve.console.runner import SHUTDOWN_SIGNAME, BusyError, TestRunner
from flowcurve.console.setup_form import FormError, post_values, validate
from flowcurve.console.workspace import PathError, Workspace, inside
from flowcurve.errors import FlowcurveError

log = logging.getLogger(__name__)

STATIC = Path(__file__).resolve().parent / "static"
TOKEN_HEADER = "x-flowcurve-token"
TOKEN_COOKIE = "flowcurve_token"
EVENT_PERIOD_S = 0.05  # at most 20 updates a second per page
KEEPALIVE_S = 10.0
WAKE_S = 0.5  # an idle stream looks at least this often whether the console is closing
GRACEFUL_SHUTDOWN_S = 5.0  # then uvicorn closes connections that are still open
LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1")


class Console:
    """Everything one console process serves: the rig's runner and the --out folder."""

    def __init__(self, out: Path, *, config=None, time_scale: float | None = None, token: str | None = None, rig_name: str = "", virtual_setup=None, open_rig=None):
        self.workspace = Workspace(out)
        self.runner = TestRunner(self.workspace.records, config=config, virtual_setup=virtual_setup, open_rig=open_rig)
        self.time_scale = time_scale
        self.token = token
        self.rig_name = rig_name or ("virtual rig" if config is None else "configured rig")
        self.closing = threading.Event()  # set when the process is asked to stop: pages' streams end

    def close(self) -> None:
        """The process is stopping: abort a running test now (heater off), end the event streams."""
        self.closing.set()
        self.runner.abort(SHUTDOWN_SIGNAME)

    def test_summary(self) -> dict | None:
        run = self.runner.current
        if run is None:
            return None
        out = run.summary()
        out["record_url"] = self.workspace.url(run.record) if run.record.exists() else None
        return out


def _clean(value):
    """JSON without NaN (the page's JSON.parse refuses it)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    return value


def _json(data, status: int = 200) -> JSONResponse:
    return JSONResponse(_clean(data), status_code=status)


def _error(message: str, status: int = 400, **extra) -> JSONResponse:
    return _json({"error": message, **extra}, status)


class GuardMiddleware:
    """Token (when set) on /api and /files; POSTs only as JSON from the page's own origin."""

    def __init__(self, app, console: Console):
        self.app = app
        self.console = console

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        request = Request(scope)
        path = scope["path"]
        refusal = None
        if request.method == "POST":
            origin = request.headers.get("origin")
            host = request.headers.get("host", "")
            if origin is not None and origin.split("://", 1)[-1] != host:
                refusal = _error(f"refused: a request from {origin} to {host}", 403)
            elif request.headers.get("content-type", "").split(";")[0].strip() != "application/json":
                refusal = _error("refused: send JSON (application/json)", 415)
        guarded = path.startswith("/api/") and path != "/api/login" or path.startswith("/files/")
        if refusal is None and guarded and self.console.token:
            given = request.headers.get(TOKEN_HEADER) or request.cookies.get(TOKEN_COOKIE) or ""
            if not hmac.compare_digest(given.encode(), self.console.token.encode()):
                refusal = _error("token required", 401, token_required=True)
        if refusal is not None:
            return await refusal(scope, receive, send)
        return await self.app(scope, receive, send)


async def _body(request: Request) -> dict:
    try:
        data = await request.json()
    except (ValueError, UnicodeDecodeError):
        raise FlowcurveError("the request is not valid JSON") from None
    if not isinstance(data, dict):
        raise FlowcurveError("the request must be a JSON object")
    return data


def create_app(console: Console) -> Starlette:
    runner, workspace = console.runner, console.workspace

    async def index(request: Request) -> Response:
        return FileResponse(STATIC / "index.html", headers={"Cache-Control": "no-store"})

    async def info(request: Request) -> Response:
        return _json({"rig": console.rig_name, "virtual": runner.virtual, "out": str(workspace.root), "time_scale": console.time_scale,
                      "token_required": bool(console.token), "post": POST_KEYS, "prompts": POST_PROMPTS})

    async def login(request: Request) -> Response:
        data = await _body(request)
        given = str(data.get("token") or "")
        if not console.token or not hmac.compare_digest(given.encode(), console.token.encode()):
            return _error("wrong token", 401, token_required=bool(console.token))
        response = _json({"ok": True})
        response.set_cookie(TOKEN_COOKIE, given, httponly=True, samesite="strict")
        return response

    async def status(request: Request) -> Response:
        run = runner.current
        return _json({"status": run.view.status() if run else {"state": "idle", "heater": "off"}, "test": console.test_summary()})

    async def start(request: Request) -> Response:
        data = await _body(request)
        try:
            setup = validate(data, virtual=runner.virtual, time_scale=console.time_scale)
            run = runner.start(setup, {k: v for k, v in data.items() if isinstance(v, (str, int, float))})
        except FormError as exc:
            return _error(str(exc), 400, fields=exc.errors)
        except BusyError as exc:
            return _error(str(exc), 409)
        # a test the procedure refuses at once (set-point above the furnace maximum) goes back to the form
        for _ in range(20):
            if not run.running or run.view.state not in ("starting",):
                break
            await asyncio.sleep(0.05)
        if not run.running and run.error and run.outcome is None:
            from flowcurve.console.setup_form import field_of

            return _error(run.error, 400, fields={field_of(run.error): run.error})
        return _json({"test": console.test_summary()})

    async def stop(request: Request) -> Response:
        return _json({"stopping": runner.stop()})

    async def abort(request: Request) -> Response:
        return _json({"aborting": runner.abort()})

    async def post(request: Request) -> Response:
        data = await _body(request)
        run = runner.current
        if run is None or run.running or run.outcome is None or not run.record.exists():
            return _error("no finished test to annotate", 409)
        from flowcurve.record.format import amend_record

        try:
            values = post_values(run.setup.spec.test, data)
        except FormError as exc:
            return _error(str(exc), 400, fields=exc.errors)
        if values:
            amend_record(run.record, {k: repr(v) for k, v in values.items()})
            run.post.update(values)
        try:
            run.result = await asyncio.to_thread(workspace.identify, run.record)
        except FlowcurveError as exc:
            run.result = {"error": str(exc)}
        run.view.set_state(run.view.state, run.view.message)  # wake the pages: the test's summary changed
        return _json({"test": console.test_summary()})

    async def records(request: Request) -> Response:
        return _json({"records": await asyncio.to_thread(workspace.list_records)})

    async def fit(request: Request) -> Response:
        data = await _body(request)
        names = data.get("records") or []
        if not isinstance(names, list):
            return _error("records: give a list of record names")
        try:
            result = await asyncio.to_thread(workspace.fit_and_card, [str(n) for n in names], data)
        except FlowcurveError as exc:
            return _error(str(exc))
        return _json(result)

    async def files(request: Request) -> Response:
        try:
            path = inside(workspace.root, request.path_params["path"])
        except PathError as exc:
            return _error(str(exc), 404)
        if not path.is_file():
            return _error("no such file", 404)
        download = request.query_params.get("download") is not None
        return FileResponse(path, filename=path.name if download else None,
                            content_disposition_type="attachment" if download else "inline",
                            media_type="text/plain; charset=utf-8" if path.suffix in (".csv", ".k", ".inp", ".rad", ".txt") else None)

    async def events(request: Request) -> Response:
        return StreamingResponse(_event_stream(console, request), media_type="text/event-stream",
                                 headers={"Cache-Control": "no-store", "X-Accel-Buffering": "no"})

    @asynccontextmanager
    async def lifespan(app):
        yield
        console.close()
        await asyncio.to_thread(runner.shutdown)  # a running test is aborted: heater off, record closed

    routes = [
        Route("/", index),
        Route("/api/info", info),
        Route("/api/login", login, methods=["POST"]),
        Route("/api/status", status),
        Route("/api/events", events),
        Route("/api/start", start, methods=["POST"]),
        Route("/api/stop", stop, methods=["POST"]),
        Route("/api/abort", abort, methods=["POST"]),
        Route("/api/post", post, methods=["POST"]),
        Route("/api/records", records),
        Route("/api/fit", fit, methods=["POST"]),
        Route("/files/{path:path}", files),
        Mount("/static", StaticFiles(directory=STATIC), name="static"),
    ]

    async def flowcurve_error(request: Request, exc: FlowcurveError) -> Response:
        return _error(str(exc))

    return Starlette(routes=routes, middleware=[Middleware(GuardMiddleware, console=console)], lifespan=lifespan,
                     exception_handlers={FlowcurveError: flowcurve_error})


def _sse(event: str, data) -> bytes:
    return f"event: {event}\ndata: {json.dumps(_clean(data), separators=(',', ':'))}\n\n".encode()


async def _event_stream(console: Console, request: Request):
    """Status and new plot points whenever the test changes (at most every EVENT_PERIOD_S)."""
    loop = asyncio.get_running_loop()
    changed = asyncio.Event()

    def wake() -> None:
        loop.call_soon_threadsafe(changed.set)

    listening_to = None
    forget = None
    cursor: dict | None = None
    last_summary = None
    last_status = None
    yield _sse("hello", {"rig": console.rig_name})
    sent_at = loop.time()
    try:
        while not console.closing.is_set() and not await request.is_disconnected():
            changed.clear()  # before reading: a change from here on wakes the next round (none is lost while sending)
            run = console.runner.current
            if run is not None and run is not listening_to:
                if forget:
                    forget()
                forget, listening_to, cursor = run.view.listen(wake), run, None
            # the state before the summary: a "done" read here was set after the outcome (runner._end),
            # so the summary read next carries that outcome, and the page gets both in one round
            status = run.view.status() if run is not None else None
            summary = console.test_summary()
            if summary != last_summary:
                last_summary = summary
                yield _sse("test", summary)
            if run is not None:
                if status != last_status:
                    last_status = status
                    yield _sse("status", status)
                points, cursor = run.view.points_since(cursor)
                if points["fd"]["x"] or points["tt"]["x"] or points["fd"]["reset"] or points["tt"]["reset"]:
                    yield _sse("points", points)
            elif last_status is None:
                last_status = {"state": "idle", "heater": "off"}
                yield _sse("status", last_status)
            sent_at = loop.time()
            while not changed.is_set() and not console.closing.is_set() and console.runner.current is listening_to:
                try:
                    await asyncio.wait_for(changed.wait(), WAKE_S)
                except asyncio.TimeoutError:
                    if loop.time() - sent_at >= KEEPALIVE_S:
                        sent_at = loop.time()
                        yield b": keep-alive\n\n"
            await asyncio.sleep(max(0.0, sent_at + EVENT_PERIOD_S - loop.time()))  # at most one update per period
    finally:
        if forget:
            forget()


def serve(console: Console, host: str, port: int) -> None:
    """Serve until SIGINT/SIGTERM; the signal aborts a running test at once (the heater goes
    off within a tick), and open pages do not hold the shutdown up."""
    import uvicorn

    class ConsoleServer(uvicorn.Server):
        def handle_exit(self, sig, frame) -> None:
            signals.append(sig)
            console.close()
            super().handle_exit(sig, frame)

    signals: list[int] = []
    config = uvicorn.Config(create_app(console), host=host, port=port, log_level="warning", timeout_graceful_shutdown=GRACEFUL_SHUTDOWN_S)
    ConsoleServer(config).run()  # uvicorn raises the signal it caught again once it has stopped
    exit_as_signalled(signals)


def exit_as_signalled(signals) -> None:
    """End the process as the signals that stopped the server would have, when the server came
    back from them without doing so itself. uvicorn raises a caught signal again once it has
    stopped, a SIGINT through asyncio's own handler; once, in a CI rehearsal, the console still
    ended a Ctrl-C with exit code 0 instead of 130 (not reproduced in 18 runs since, on an idle or a
    loaded machine). Ctrl-C ends as KeyboardInterrupt (the CLI's 130), another signal by its
    default action."""
    for sig in reversed(signals):
        if sig == signal.SIGINT:
            raise KeyboardInterrupt
        signal.signal(sig, signal.SIG_DFL)
        signal.raise_signal(sig)
