"""The console's HTTP side: a Starlette application served by uvicorn.

Endpoints (JSON unless said):

* ``GET /`` the page; ``GET /static/…`` its script, style and the vendored uPlot;
* ``GET /api/events`` server-sent events: ``status`` (state, readings, heater) and
  ``points`` (new plot points) about twenty times a second while a test runs, ``test``
  (the test's summary) when it changes; a page that connects gets everything so far;
* ``GET /api/status``; ``POST /api/start`` (the set-up form; on the virtual rig with its fault drills), ``/api/stop``, ``/api/abort``,
  ``/api/post`` (post-test measurements → record amended → identified);
* ``GET /api/records``; ``POST /api/fit`` (selected records → fit → card);
* ``GET /files/<path>`` a file under ``--out`` (read only); ``POST /api/login`` the token.

Security (:mod:`flowcurve.console.request_guard`): every request must name this console as
its Host (loopback names on its port, ``--host``, ``--allow-host``) and, when it sends an
Origin, come from one of those too (403 otherwise: another web site the operator has open,
even under a name that resolves to 127.0.0.1, cannot drive the rig). With a token (required
for any ``--host`` but the default) every ``/api`` and ``/files`` request needs it, as the
``X-Flowcurve-Token`` header or the cookie the login sets; wrong tokens are limited per client
(429). Every POST is ``application/json`` of at most 1 MiB (413), a JSON object of typed
fields (400), and names files only by bare names checked against ``--out``
(:mod:`flowcurve.console.workspace`). A refused request changes nothing. The limit keys on
the socket's peer: proxy headers (``X-Forwarded-For``) are ignored unless ``--forwarded-allow-ips``
names the proxy in front (:func:`proxy_options`), so a client cannot choose its own key.
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

from flowcurve.acquisition.procedure import POST_KEYS, POST_PROMPTS, face_asked, post_prompts
from flowcurve.console.request_guard import (MAX_BODY_BYTES, NAMES, NUMBER, TEXT, FailedLogins, HostAllowlist, Refused,
                                             check_fields, read_json_object)
from flowcurve.console.runner import SHUTDOWN_SIGNAME, BusyError, TestRunner
from flowcurve.console.setup_form import FAULT_FIELD, NUMERIC_FIELDS, TEXT_FIELDS, FormError, post_values, validate
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
FINAL_STATE_WAIT_S = 3.0  # a stream waits this long for an aborted test's final state before it closes
DEFAULT_HOST = "127.0.0.1"  # any other --host needs a token
# each POST endpoint's fields and their types (request_guard.check_fields)
START_FIELDS = {"test": TEXT, **{k: NUMBER for k in NUMERIC_FIELDS}, **{k: TEXT for k in (*TEXT_FIELDS, FAULT_FIELD)}}
POST_FIELDS = {k: NUMBER for keys in POST_KEYS.values() for k in keys}
FIT_FIELDS = {"records": NAMES, **{k: NUMBER for k in ("melt_temp", "fix_C", "fix_m", "ref_rate", "ref_temp", "poisson", "density", "cp", "E_MPa")},
              **{k: TEXT for k in ("method", "format", "units", "law", "lsdyna_material")}}
LOGIN_FIELDS = {"token": TEXT}
IDLE_STATUS = {"state": "idle", "heater": "off"}


class Console:
    """Everything one console process serves: the rig's runner and the --out folder."""

    def __init__(self, out: Path, *, config=None, time_scale: float | None = None, token: str | None = None, rig_name: str = "", virtual_setup=None, open_rig=None,
                 host: str = DEFAULT_HOST, port: int | None = None, allow_hosts=(), forwarded_allow_ips: str | None = None):
        """``host``, ``port`` and ``allow_hosts`` make the Host allowlist (``port`` None: the
        loopback names on any port, for a console embedded in a test or a benchmark);
        ``forwarded_allow_ips`` the proxies trusted to name the client (:func:`proxy_options`)."""
        self.workspace = Workspace(out)
        self.runner = TestRunner(self.workspace.records, config=config, virtual_setup=virtual_setup, open_rig=open_rig)
        self.time_scale = time_scale
        self.token = token
        self.hosts = HostAllowlist([host, *allow_hosts], port)
        self.forwarded_allow_ips = forwarded_allow_ips
        self.failed_logins = FailedLogins()
        self.rig_name = rig_name or ("virtual rig" if config is None else "configured rig")
        self.closing = threading.Event()  # set when the process is asked to stop: pages' streams end

    def close(self) -> None:
        """The process is stopping: abort a running test now (heater off), end the event streams."""
        self.closing.set()
        self.runner.abort(SHUTDOWN_SIGNAME)

    def test_summary(self) -> dict | None:
        """The current test as the pages show it, or None."""
        run = self.runner.current
        if run is None:
            return None
        out = run.summary()
        try:
            out["record_url"] = self.workspace.url(self.workspace.within(run.record)) if run.record.exists() else None
        except PathError:  # the record was made a link out of --out: not served, not a 500
            out["record_url"] = None
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
    """Before routing: Host and Origin on the allowlist, POSTs as JSON of at most 1 MiB (read here
    and handed on), the token (when set) on /api and /files with wrong ones limited per client."""

    def __init__(self, app, console: Console):
        self.app = app
        self.console = console

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        try:
            receive = await self._check(scope, receive)
        except Refused as exc:
            response = _refusal(exc)
            if exc.status in (401, 429) and TOKEN_COOKIE in Request(scope).cookies:
                # a stale cookie (the console restarted with a new token) is sent once, not by every poll
                # of the page into the limit: the operator's login stays open
                response.delete_cookie(TOKEN_COOKIE, httponly=True, samesite="strict")
            return await response(scope, receive, send)
        return await self.app(scope, receive, send)

    async def _check(self, scope, receive):
        """The request's ``receive`` (its body replayed once read), or :class:`Refused`."""
        request = Request(scope)
        hosts = self.console.hosts
        host = request.headers.get("host")
        if not hosts.allows_host(host):
            raise Refused(f"refused: this console does not answer to the Host {host!r} (flowcurve console --allow-host NAME)", 403)
        origin = request.headers.get("origin")
        if origin is not None and not hosts.allows_origin(origin):
            raise Refused(f"refused: a request from {origin!r}, not from this console's page", 403)
        length = request.headers.get("content-length")
        if length is not None and (not (length.isascii() and length.isdigit()) or int(length) > MAX_BODY_BYTES):
            raise Refused(f"the request is larger than {MAX_BODY_BYTES} bytes", 413)
        if request.method == "POST":
            if request.headers.get("content-type", "").split(";")[0].strip().lower() != "application/json":
                raise Refused("refused: send JSON (application/json)", 415)
            receive = await _read_body(receive)
        path = scope["path"]
        guarded = path.startswith("/api/") and path != "/api/login" or path.startswith("/files/")
        if guarded and self.console.token:
            given = request.headers.get(TOKEN_HEADER) or request.cookies.get(TOKEN_COOKIE) or ""
            if given:  # a token given is a guess when wrong: counted as a failed login
                _check_token(self.console, _client(scope), given)
            else:
                raise Refused("token required", 401)
        return receive


class _TooMany(Refused):
    def __init__(self, retry_after_s: float):
        super().__init__(f"too many wrong tokens from this client: try again in {math.ceil(retry_after_s)} s", 429)
        self.retry_after = math.ceil(retry_after_s)


def _refusal(exc: Refused) -> JSONResponse:
    """The answer to a refused request: its status and reason (a token's refusal says so)."""
    response = _error(str(exc), exc.status, **({"token_required": True} if exc.status in (401, 429) else {}))
    if isinstance(exc, _TooMany):
        response.headers["Retry-After"] = str(exc.retry_after)
    return response


def _client(scope) -> str:
    client = scope.get("client")
    return client[0] if client else "unknown"


def _check_token(console: Console, client: str, given: str) -> None:
    """The token, compared in constant time; a wrong one counts against ``client`` (then 429)."""
    limiter = console.failed_logins
    wait = limiter.retry_after_s(client)
    if wait > 0:
        raise _TooMany(wait)
    if not console.token or not hmac.compare_digest(given.encode("utf-8", "surrogatepass"), console.token.encode("utf-8", "surrogatepass")):
        if console.token:
            limiter.failed(client)
        raise Refused("wrong token" if console.token else "this console has no token", 401)
    limiter.succeeded(client)


async def _read_body(receive):
    """Read the whole body (refused past MAX_BODY_BYTES, without reading on) and give a
    ``receive`` that hands it to the application once, then listens as before."""
    chunks, size = [], 0
    while True:
        message = await receive()
        if message["type"] == "http.disconnect":
            raise Refused("the client went away", 400)
        size += len(message.get("body", b""))
        if size > MAX_BODY_BYTES:
            raise Refused(f"the request is larger than {MAX_BODY_BYTES} bytes", 413)
        chunks.append(message.get("body", b""))
        if not message.get("more_body", False):
            break
    replay = [{"type": "http.request", "body": b"".join(chunks), "more_body": False}]

    async def replayed():
        """The body already read, then what the client sends next."""
        return replay.pop() if replay else await receive()

    return replayed


async def _body(request: Request, schema: dict[str, str]) -> dict:
    """The request's JSON object with its fields checked against ``schema`` (Refused / FormError)."""
    data = read_json_object(await request.body())
    check_fields(data, schema)
    return data


async def _start(request: Request) -> Response:
    console = request.app.state.console
    runner, workspace = console.runner, console.workspace
    try:
        data = await _body(request, START_FIELDS)
        workspace.within(workspace.records)  # the record is written only inside --out
        setup = validate(data, virtual=runner.virtual, time_scale=console.time_scale, config=runner.config)
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
        from flowcurve.console.setup_form import labelled

        runner.discard(run)
        field = run.error_field or "form"  # the field the service's FieldError names; else the test as a whole
        return _error(run.error, 400, fields={field: labelled(field, run.error)})
    return _json({"test": console.test_summary()})


async def _post(request: Request) -> Response:
    console = request.app.state.console
    runner, workspace = console.runner, console.workspace
    data = await _body(request, POST_FIELDS)
    run = runner.current
    if run is None or run.running or getattr(run.outcome, "status", None) != "complete" or not run.record.exists():
        return _error("no completed test to annotate (post-test values go with a test that ran to its end)", 409)
    from flowcurve.record.format import amend_record

    try:
        values = post_values(run.setup.spec.test, data)
    except FormError as exc:
        return _error(str(exc), 400, fields=exc.errors)
    spec = run.setup.spec
    if face_asked(spec.test, spec.geometry_mm) and "post.dface_mm" not in {**run.post, **values}:
        prompt = post_prompts(spec.test, spec.geometry_mm)["post.dface_mm"]
        return _error("post.dface_mm: the original end face's diameter is needed on this specimen", 400,
                      fields={"post.dface_mm": f"required — {prompt}"})
    if values:
        workspace.within(run.record)  # amended only inside --out (PathError: 400)
        try:
            amend_record(run.record, {k: repr(v) for k, v in values.items()})
        except FlowcurveError as exc:
            return _error(workspace.public_error(exc))
        run.post.update(values)
    try:
        run.result = await asyncio.to_thread(workspace.identify, run.record)
    except FlowcurveError as exc:
        run.result = {"error": str(exc)}
    run.view.set_state(run.view.state, run.view.message)  # wake the pages: the test's summary changed
    return _json({"test": console.test_summary()})


async def _fit(request: Request) -> Response:
    workspace = request.app.state.console.workspace
    data = await _body(request, FIT_FIELDS)
    names = data.get("records") or []
    if not isinstance(names, list):
        return _error("records: give a list of record names")
    try:
        result = await asyncio.to_thread(workspace.fit_and_card, [str(n) for n in names], data)
    except FormError as exc:  # every input the fit and card lack, each beside its field
        return _error(exc.errors.get("fit", str(exc)), 400, fields=exc.errors)
    except FlowcurveError as exc:
        return _error(str(exc))
    return _json(result)


async def _files(request: Request) -> Response:
    workspace = request.app.state.console.workspace
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


def create_app(console: Console) -> Starlette:
    """The console's web application: its pages, /api endpoints, /files and the event stream, behind
    the guard (:class:`GuardMiddleware`); a running test is aborted when it shuts down.

    Parameters
    ----------
    console : Console
        The runner (one test at a time), the workspace (the ``--out`` folder) and the live state.

    Returns
    -------
    Starlette
        The ASGI application (served by uvicorn in ``flowcurve console``).
    """
    runner, workspace = console.runner, console.workspace

    async def index(request: Request) -> Response:
        """GET /: the console's page."""
        return FileResponse(STATIC / "index.html", headers={"Cache-Control": "no-store"})

    async def info(request: Request) -> Response:
        """GET /api/info: the rig, the run form's choices and the card formats."""
        from flowcurve.console.workspace import fit_choices
        from flowcurve.reports.card_formats import WRITERS
        from flowcurve.rig.virtual.fault_spec import help_text

        return _json({"rig": console.rig_name, "virtual": runner.virtual, "out": str(workspace.root), "time_scale": console.time_scale,
                      "token_required": bool(console.token), "post": POST_KEYS, "prompts": POST_PROMPTS,
                      "fault_help": help_text() if runner.virtual else None,
                      "card_formats": [[f.name, f.display_name] for f in WRITERS.values()], **fit_choices()})  # the fit form's choices

    async def login(request: Request) -> Response:
        """POST /api/login: check the token and set its cookie."""
        data = await _body(request, LOGIN_FIELDS)
        given = str(data.get("token") or "")
        try:
            _check_token(console, _client(request.scope), given)
        except Refused as exc:
            return _refusal(exc)
        response = _json({"ok": True})
        response.set_cookie(TOKEN_COOKIE, given, httponly=True, samesite="strict")
        return response

    async def status(request: Request) -> Response:
        """GET /api/status: the running test's status, or idle."""
        run = runner.current
        return _json({"status": run.view.status() if run else IDLE_STATUS, "test": console.test_summary()})

    async def stop(request: Request) -> Response:
        """POST /api/stop: an operator stop of the running test."""
        await _body(request, {})
        return _json({"stopping": runner.stop()})

    async def abort(request: Request) -> Response:
        """POST /api/abort: abort the running test."""
        await _body(request, {})
        return _json({"aborting": runner.abort()})

    async def records(request: Request) -> Response:
        """GET /api/records: the records of the workspace."""
        return _json({"records": await asyncio.to_thread(workspace.list_records)})

    async def events(request: Request) -> Response:
        """GET /api/events: the live state as server-sent events."""
        return StreamingResponse(_event_stream(console, request), media_type="text/event-stream",
                                 headers={"Cache-Control": "no-store", "X-Accel-Buffering": "no"})

    @asynccontextmanager
    async def lifespan(app):
        """On shutdown: close the console and abort a running test."""
        yield
        console.close()
        await asyncio.to_thread(runner.shutdown)  # a running test is aborted: heater off, record closed

    routes = [
        Route("/", index),
        Route("/api/info", info),
        Route("/api/login", login, methods=["POST"]),
        Route("/api/status", status),
        Route("/api/events", events),
        Route("/api/start", _start, methods=["POST"]),
        Route("/api/stop", stop, methods=["POST"]),
        Route("/api/abort", abort, methods=["POST"]),
        Route("/api/post", _post, methods=["POST"]),
        Route("/api/records", records),
        Route("/api/fit", _fit, methods=["POST"]),
        Route("/files/{path:path}", _files),
        Mount("/static", StaticFiles(directory=STATIC), name="static"),
    ]

    async def flowcurve_error(request: Request, exc: FlowcurveError) -> Response:
        """A FlowcurveError as a JSON error (400, or the error's status)."""
        if isinstance(exc, FormError):
            return _error(str(exc), 400, fields=exc.errors)
        return _error(str(exc), getattr(exc, "status", 400))

    app = Starlette(routes=routes, middleware=[Middleware(GuardMiddleware, console=console)], lifespan=lifespan,
                    exception_handlers={FlowcurveError: flowcurve_error})
    app.state.console = console  # the handlers defined outside find it here
    return app


def _sse(event: str, data) -> bytes:
    return f"event: {event}\ndata: {json.dumps(_clean(data), separators=(',', ':'))}\n\n".encode()


async def _event_stream(console: Console, request: Request):
    """Status and new plot points whenever the test changes (at most every EVENT_PERIOD_S)."""
    loop = asyncio.get_running_loop()
    changed = asyncio.Event()

    def wake() -> None:
        """Set ``changed`` from the view's thread."""
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
            elif last_status != IDLE_STATUS:  # none yet, or a test refused before it began was forgotten
                last_status = IDLE_STATUS
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
        if console.closing.is_set():
            async for chunk in _last_words(console):
                yield chunk
    finally:
        if forget:
            forget()


async def _last_words(console: Console):
    """The console is shutting down: the aborted test's final state and outcome (once its thread has
    switched the heater off and closed the record, within FINAL_STATE_WAIT_S), then ``closing`` — so
    a page's last word is not "recording" from a console that is gone."""
    run = console.runner.current
    if run is not None:
        await asyncio.to_thread(run.ended.wait, FINAL_STATE_WAIT_S)
        yield _sse("test", console.test_summary())
        yield _sse("status", run.view.status())
    yield _sse("closing", {"message": "the console has shut down: a running test was aborted (heater off, record closed); "
                                      "start it again (flowcurve console) and reload this page"})


def proxy_options(forwarded_allow_ips: str | None = None) -> dict:
    """uvicorn's proxy-header options: ``X-Forwarded-For`` read only from the proxies named
    (then a request's client, and the wrong-token limit's key, is the forwarded one), else never
    — uvicorn's default trusts it from 127.0.0.1, where any local client could name itself."""
    if not forwarded_allow_ips:
        return {"proxy_headers": False}
    return {"proxy_headers": True, "forwarded_allow_ips": forwarded_allow_ips}


def serve(console: Console, host: str, port: int) -> None:
    """Serve until SIGINT/SIGTERM; the signal aborts a running test at once (the heater goes
    off within a tick), and open pages do not hold the shutdown up. Proxy headers are read only
    from ``console.forwarded_allow_ips`` (:func:`proxy_options`)."""
    import uvicorn

    class ConsoleServer(uvicorn.Server):
        def handle_exit(self, sig, frame) -> None:
            """Note the signal, close the console, then uvicorn's own shutdown."""
            signals.append(sig)
            console.close()
            super().handle_exit(sig, frame)

    signals: list[int] = []
    config = uvicorn.Config(create_app(console), host=host, port=port, log_level="warning", timeout_graceful_shutdown=GRACEFUL_SHUTDOWN_S,
                            **proxy_options(console.forwarded_allow_ips))
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
