"""HTTP fuzz of the console (issue 30): every endpoint with random and hostile bodies and headers.

The console's virtual rig runs on model time (:class:`flowcurve.clock.ModelClock`, devices
in-process). Two rigs are fuzzed:

* **heating** — a compression test heating to 300 °C, its clock then held still (``auto=False``):
  the procedure, the furnace and the record are frozen, so any change between two requests
  is the request's doing;
* **completed** — a test that ran to its end (so ``/api/post`` gets past its 409), fuzzed with
  bodies that are always wrong somewhere (a right one would identify the record: seconds each).

Most requests go through the test client (httpx, in-process); some are written by hand and sent
over a socket to the heating console served by uvicorn (latin-1 bytes in headers, which httpx
would not send, no Host or two, chunked bodies). A bare test client also fuzzes a console with
a token (logins, wrong tokens into the 429 limit). Issue 42 adds workspaces of links out of
--out and files an error message would quote (the records list and fits), and proxy headers
on wrong tokens sent over a socket (the limit keys on the sender, never on a header).

For every request: no answer ≥ 500, and a refused one (≥ 400) — or any GET — leaves the rig's
state (test, state, readings, samples, stop and abort flags, post values, result, heater relay,
model time) and the --out folder (every file's name, size and mtime) as they were. An accepted
stop or abort on the frozen rig is taken back (the procedure never saw it) so later refusals are
still measured against a rig that would show a change. The figures are printed at the end
(``pytest -s``) and written to ``artifacts/fuzz-summary.json``.
"""

from __future__ import annotations

import contextlib
import functools
import json
import socket
import time
import warnings
from collections import Counter

import pytest

pytest.importorskip("starlette", reason="starlette is not installed (pip install -e .[test])")
pytest.importorskip("httpx", reason="httpx is not installed (pip install -e .[test])")
hypothesis = pytest.importorskip("hypothesis", reason="hypothesis is not installed (pip install -e .[test])")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from starlette.testclient import TestClient  # noqa: E402

from flowcurve.acquisition import session  # noqa: E402
from flowcurve.clock import ModelClock  # noqa: E402
from flowcurve.console.request_guard import MAX_BODY_BYTES, MAX_TEXT_CHARS, NAMES, NUMBER  # noqa: E402
from flowcurve.console.server import FIT_FIELDS, LOGIN_FIELDS, POST_FIELDS, START_FIELDS, Console, create_app  # noqa: E402
from flowcurve.console.setup_form import validate  # noqa: E402

from .conftest import ARTIFACTS, free_port, login_over_socket, serving  # noqa: E402

PORT = free_port()  # the fuzzed consoles' port: in their allowlist, and the real server's for the raw requests
GOOD_HOSTS = (f"127.0.0.1:{PORT}", f"localhost:{PORT}", f"[::1]:{PORT}")
FOREIGN_HOSTS = (f"evil.example:{PORT}", f"127.0.0.1:{PORT + 1}", "localhost", f"127.0.0.1:{PORT}.evil.example", f"evil@127.0.0.1:{PORT}",
                 "", " ", "[::1]", "[::2]:8080", "127.0.0.1:0", "127.0.0.1:99999", "127.0.0.1:-1", "localhost:80 80", f"ö.example:{PORT}".encode("latin-1"),
                 "127.0.0.1:²".encode("latin-1"), f"[::1]:{PORT}²".encode("latin-1"))
FOREIGN_ORIGINS = (f"http://evil.example:{PORT}", "null", f"http://127.0.0.1:{PORT + 1}", f"file://127.0.0.1:{PORT}", f"http://127.0.0.1:{PORT}/x",
                   "http://", "127.0.0.1:8080", f"ws://localhost:{PORT}")
CONTENT_TYPES = ("application/json", "application/json; charset=utf-8", "APPLICATION/JSON", "text/plain",
                 "application/x-www-form-urlencoded", "multipart/form-data; boundary=x", "", "application/json-seq")
# path → (method, the endpoint's fields, or None for a GET)
ENDPOINTS = {
    "/api/start": ("POST", START_FIELDS), "/api/post": ("POST", POST_FIELDS), "/api/fit": ("POST", FIT_FIELDS),
    "/api/login": ("POST", LOGIN_FIELDS), "/api/stop": ("POST", {}), "/api/abort": ("POST", {}),
    "/api/status": ("GET", None), "/api/records": ("GET", None), "/api/info": ("GET", None), "/api/events": ("GET", None),
    "/": ("GET", None), "/static/console.js": ("GET", None), "/files/": ("GET", None),
}
CHANGING = ("/api/stop", "/api/abort", "/api/post")  # what an accepted request may change
STATS: Counter = Counter()

url_text = st.text(st.characters(min_codepoint=33, max_codepoint=126), max_size=60)
header_text = st.text(st.characters(min_codepoint=32, max_codepoint=255, exclude_characters="\x7f"), max_size=60).map(lambda t: t.encode("latin-1"))
long_text = st.integers(MAX_TEXT_CHARS + 1, 3000).map(lambda n: "x" * n)
hostile_values = st.one_of(
    st.booleans(), st.lists(st.integers(), max_size=3), st.dictionaries(st.text(max_size=5), st.integers(), max_size=2),
    long_text, st.sampled_from(["\ud800", "a\x00b", "line\nbreak", "tab\there", "\x1b[31m", "\u2028"]),
    st.sampled_from([10 ** 400, -(10 ** 400)]),
)


@functools.lru_cache(maxsize=None)  # a strategy built once is validated once
def valid_values(kind: str):
    if kind == NUMBER:
        return st.one_of(st.none(), st.integers(-10**6, 10**6), st.floats(allow_nan=False, allow_infinity=False),
                         st.text(st.sampled_from("0123456789.-e "), max_size=12), st.text(max_size=20))
    if kind == NAMES:
        return st.lists(st.text(max_size=30), max_size=4)
    return st.one_of(st.none(), st.sampled_from(["compression", "tension", "steel45", "lsdyna"]), st.text(max_size=40))


def _nested(depth: int, kind: str) -> bytes:
    if kind == "[":
        return b"[" * depth + b"]" * depth
    return b'{"test":' * depth + b"1" + b"}" * depth


@functools.lru_cache(maxsize=None)
def bodies(path: str, hostile_only: bool):
    return _bodies(ENDPOINTS[path][1] or {}, hostile_only)


@st.composite
def _bodies(draw, fields: dict, hostile_only: bool) -> tuple[bytes, bool]:
    """(body, chunked): a JSON object of the endpoint's fields and strangers, or something else."""
    kind = draw(st.sampled_from(["object"] * 6 + ["raw", "deep", "huge", "non-object", "constant", "broken"]))
    if kind == "object":
        known = list(fields) or ["test"]
        values = st.one_of(hostile_values, *[valid_values(k) for k in set(fields.values())])
        data = draw(st.dictionaries(st.sampled_from(known), values, max_size=len(known)))
        if hostile_only or draw(st.booleans()):
            key = draw(st.one_of(st.sampled_from(known), st.text(min_size=1, max_size=20)))
            data[key] = draw(hostile_values)
        body = json.dumps(data).encode()
    elif kind == "raw":
        body = draw(st.binary(max_size=300))
    elif kind == "deep":
        body = _nested(draw(st.sampled_from([33, 40, 1000, 50_000])), draw(st.sampled_from(["[", "{"])))
    elif kind == "huge":
        body = b'{"material": "' + b"m" * (MAX_BODY_BYTES + draw(st.integers(0, 4096))) + b'"}'
    elif kind == "non-object":
        body = json.dumps(draw(st.one_of(st.lists(st.integers(), max_size=3), st.text(max_size=10), st.integers(), st.none()))).encode()
    elif kind == "constant":
        body = draw(st.sampled_from([b'{"d0": NaN}', b'{"temperature": Infinity}', b'{"post.hk_mm": -Infinity}', b"NaN"]))
    else:
        body = draw(st.sampled_from([b'{"test": "compression"', b'{"test": "\xff\xfe"}', b'{"test": "\\ud800"}', b"\xef\xbb\xbf{}",
                                     b'{"test": "compression",}', b"{'test': 'compression'}", b'{"a":1}{"b":2}']))
    return body, draw(st.booleans()) if len(body) > 0 else False


@functools.lru_cache(maxsize=None)
def headers(token: str | None):
    return _headers(token)


@st.composite
def _headers(draw, token: str | None) -> dict:
    """This console's Host and Origin with JSON mostly; any of them foreign, odd or missing too."""
    out = {"Host": draw(st.one_of(st.sampled_from(GOOD_HOSTS), st.sampled_from(GOOD_HOSTS), st.sampled_from(FOREIGN_HOSTS), header_text))}
    origin = draw(st.one_of(st.none(), st.sampled_from(GOOD_HOSTS).map(lambda h: f"http://{h}"), st.sampled_from(FOREIGN_ORIGINS), header_text))
    if origin is not None:
        out["Origin"] = origin
    out["Content-Type"] = draw(st.one_of(st.sampled_from(CONTENT_TYPES[:1] * 4), st.sampled_from(CONTENT_TYPES), header_text))
    if token is not None:
        given = draw(st.one_of(st.just(token.encode()), st.just(token.encode()), st.none(), header_text))
        if given is not None:
            out[draw(st.sampled_from(["X-Flowcurve-Token", "Cookie"]))] = given if draw(st.booleans()) else b"flowcurve_token=" + given
    for name in draw(st.lists(st.sampled_from(["X-Forwarded-Host", "Forwarded", "X-Real-IP", "Referer", "Accept", "Cookie"]), max_size=2, unique=True)):
        out.setdefault(name, draw(header_text))
    return out


@st.composite
def requests(draw, paths, token=None, hostile_only=False, record_names=()):
    path = draw(st.sampled_from(paths))
    method = ENDPOINTS[path][0]
    method = draw(st.sampled_from([method] * 8 + ["GET", "POST", "PUT", "DELETE", "PATCH", "OPTIONS", "HEAD"]))
    url = path
    if path == "/files/":
        url += draw(st.one_of(st.sampled_from(record_names or ["records/x.csv"]), st.sampled_from(
            ["../../etc/passwd", "%2e%2e/%2e%2e/etc/passwd", "records/..%2f..%2fsecret", "records/%00.csv", "records"]), url_text))
    elif path == "/static/console.js":
        url = draw(st.sampled_from(["/static/console.js", "/static/../server.py", "/static/%2e%2e/server.py", "/static/index.html"]))
    return method, url, draw(headers(token)), draw(bodies(path, hostile_only))


def _head_value(value) -> bytes:
    return value if isinstance(value, bytes) else value.encode("latin-1")


@st.composite
def raw_requests(draw, paths, record_names=()):
    """(method, head, body) written by hand: odd bytes in headers, no Host or two, chunked bodies —
    what a client library would not send, to the console served by uvicorn."""
    method, url, hdrs, (body, chunked) = draw(requests(paths, record_names=record_names))
    lines = [f"{method} {url} HTTP/1.1".encode("latin-1", "replace")]
    hosts = draw(st.sampled_from(["as drawn"] * 4 + ["none", "two"]))  # no Host, or two: refused by uvicorn (h11) itself
    if hosts == "as drawn":
        lines.append(b"Host: " + _head_value(hdrs["Host"]))
    elif hosts != "none":
        pair = [f"127.0.0.1:{PORT}".encode(), _head_value(draw(st.sampled_from(FOREIGN_HOSTS)))]
        lines += [b"Host: " + h for h in pair]
    lines += [name.encode() + b": " + _head_value(value) for name, value in hdrs.items() if name != "Host"]
    if len(body) > MAX_BODY_BYTES:  # announced, not sent: the answer must not wait for it
        lines.append(f"Content-Length: {len(body)}".encode())
        body = b""
    elif chunked:
        lines.append(b"Transfer-Encoding: chunked")
        body = b"".join(f"{len(part):x}\r\n".encode() + part + b"\r\n" for part in (body[:7], body[7:]) if part) + b"0\r\n\r\n"
    else:
        lines.append(f"Content-Length: {len(body)}".encode())
    lines.append(b"Connection: close")
    return method, url, b"\r\n".join(lines) + b"\r\n\r\n", body


class FuzzedConsole:
    """A console on a model-time virtual rig, with the before/after check of each request."""

    def __init__(self, tmp, clock: ModelClock, token: str | None = None):
        self.out = tmp / "out"
        self.clock = clock
        self.console = Console(self.out, time_scale=1.0, port=PORT, token=token)
        self.client = TestClient(create_app(self.console), base_url=f"http://127.0.0.1:{PORT}", raise_server_exceptions=False)
        self.client.__enter__()  # one event loop for every request (and the app's lifespan: its end aborts a test)

    def close(self) -> None:
        self.clock.auto = True
        self.clock.notify()
        self.client.__exit__(None, None, None)
        run = self.console.runner.current
        assert run is None or not run.running

    def state(self):
        run = self.console.runner.current
        files = {str(p.relative_to(self.out)): (p.stat().st_size, p.stat().st_mtime_ns) for p in sorted(self.out.rglob("*"))}
        if run is None:
            return None, files
        status = {k: v for k, v in run.view.status().items() if k not in ("heater", "readings_age_s")}  # the heater: the relay itself, below; the age: the clock
        source = run.heater_source
        rig = (run.test_id, run.running, status, run.stop_reason, run.abort_reason, dict(run.post), json.dumps(run.result, default=str),
               getattr(run.outcome, "status", None), getattr(source, "relay_on", None), self.clock.now())
        return rig, files

    def send(self, method: str, url: str, hdrs: dict, body: tuple[bytes, bool], *, group: str, accepted_may_change: bool) -> int:
        """One request through the test client (httpx); checked as :meth:`_checked` says."""
        content, chunked = body

        def request() -> tuple[int, str]:
            r = self.client.request(method, url, headers=hdrs, content=iter([content]) if chunked else (content or None))
            return r.status_code, r.text[:300]

        return self._checked(method, url, request, group, accepted_may_change, what=(hdrs, content[:200]))

    def send_raw(self, method: str, url: str, head: bytes, body: bytes, *, group: str) -> int:
        """One hand-written request over a socket to the console served by uvicorn."""

        def request() -> tuple[int, str]:
            with socket.create_connection(("127.0.0.1", PORT), timeout=30) as sock:
                sock.sendall(head + body)
                answer = b""
                while b"\r\n" not in answer:
                    chunk = sock.recv(4096)
                    if not chunk:
                        break
                    answer += chunk
            return int(answer.split(b" ", 2)[1]), answer[:300].decode("latin-1")

        return self._checked(method, url, request, group, accepted_may_change=url in CHANGING, what=(head[:300], body[:200]))

    def _checked(self, method: str, url: str, request, group: str, accepted_may_change: bool, what) -> int:
        """``request()`` → (status, text): no answer >= 500; the console unchanged unless accepted
        by an endpoint that may change it."""
        before = self.state()
        if url == "/api/events":
            self.console.closing.set()  # the stream sends its greeting and ends (else a GET or HEAD would never return)
        try:
            status, text = request()
        finally:
            self.console.closing.clear()
        STATS["requests"] += 1
        STATS[f"{status // 100}xx"] += 1
        STATS[f"{group} requests"] += 1
        assert status < 500, (method, url, what, status, text)
        after = self.state()
        if after != before:
            if status >= 400 or method == "GET" or not accepted_may_change:
                STATS["state changes from refused or read-only requests"] += 1
                raise AssertionError(f"{method} {url} answered {status} and changed the console: {before} → {after}")
            STATS["state changes from accepted requests"] += 1
        return status


@pytest.fixture(scope="module", autouse=True)
def fuzz_summary():
    yield
    if STATS:
        summary = dict(sorted({"5xx": 0, "state changes from refused or read-only requests": 0, **STATS}.items()))
        print("\nconsole fuzz:", summary)
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        (ARTIFACTS / "fuzz-summary.json").write_text(json.dumps(summary, indent=1) + "\n")


def _model_time_rig(monkeypatch, clock: ModelClock) -> None:
    """The console's virtual rig on ``clock``, devices in-process, the fast physics."""
    monkeypatch.setattr(session, "run_virtual_test", functools.partial(session.run_virtual_test, clock=clock, link="inprocess",
                                                                       compression_response="slab", tension_response="bridgman"))


@contextlib.contextmanager
def _console_with(tmp_path_factory, form: dict, ready, served: bool = False):
    """A console on a model-time rig with a test of ``form`` started; ``ready(run, clock)`` waits for
    it; ``served``: on PORT over a socket too (raw requests)."""
    with pytest.MonkeyPatch.context() as mp:
        clock = ModelClock()
        _model_time_rig(mp, clock)
        fuzzed = FuzzedConsole(tmp_path_factory.mktemp("fuzz"), clock)
        run = fuzzed.console.runner.start(validate(form, virtual=True, time_scale=1.0))
        ready(run, clock)
        with serving(fuzzed.client.app, PORT, lifespan="off", log_level="error") if served else contextlib.nullcontext():
            yield fuzzed
        fuzzed.close()


def _heating_then_frozen(run, clock: ModelClock) -> None:
    end = time.monotonic() + 60
    while not (run.view.state == "heating" and run.heater_source is not None and run.heater_source.relay_on) and time.monotonic() < end:
        time.sleep(0.005)
    clock.auto = False
    assert run.running and run.view.state == "heating", run.view.status()
    time.sleep(0.5)  # a thread between two waits reaches its next one


def _completed(run, clock: ModelClock) -> None:
    run.thread.join(120)
    assert run.outcome is not None and run.outcome.status == "complete", run.summary()


@pytest.fixture(scope="module")
def heating(tmp_path_factory):
    """A console whose test is heating, its model clock held still."""
    with _console_with(tmp_path_factory, {"test": "compression", "temperature": "300", "soak": "600"}, _heating_then_frozen,
                       served=True) as fuzzed:
        yield fuzzed


@pytest.fixture(scope="module")
def completed(tmp_path_factory):
    """A console whose last test ran to its end (a short compression at room temperature)."""
    with _console_with(tmp_path_factory, {"test": "compression", "target": "0.5", "specimen_id": "fuzz"}, _completed) as fuzzed:
        yield fuzzed


def fuzz(examples: int):
    return settings(max_examples=examples, deadline=None, database=None, suppress_health_check=list(HealthCheck))
GROUPS = {  # group → (paths, examples): 13 endpoints on the heating rig, the POSTs again on the completed one
    "start": (["/api/start"], 260), "post": (["/api/post"], 160), "fit": (["/api/fit"], 160), "login": (["/api/login"], 120),
    "stop+abort": (["/api/stop", "/api/abort"], 200), "reads": ([p for p, (m, _f) in ENDPOINTS.items() if m == "GET"], 350),
}


@pytest.mark.parametrize("group", list(GROUPS))
def test_fuzz_a_heating_rig(heating, group):
    paths, examples = GROUPS[group]
    record = heating.console.runner.current.record
    names = (f"records/{record.name}",)

    @fuzz(examples)
    @given(requests(paths, record_names=names))
    def one(request):
        method, url, hdrs, body = request
        status = heating.send(method, url, hdrs, body, group=f"heating {group}", accepted_may_change=url in CHANGING)
        run = heating.console.runner.current
        if status < 300 and url in ("/api/stop", "/api/abort"):  # take the button back: the frozen procedure never read it
            run.stop_reason = run.abort_reason = None
        assert run.running and not (status < 300 and url == "/api/start"), "a test started on a running rig"

    before = STATS[f"heating {group} requests"]
    one()
    assert STATS[f"heating {group} requests"] - before >= examples


@pytest.mark.parametrize("paths, examples", [(["/api/post"], 150), (["/api/start", "/api/fit", "/api/stop", "/api/abort"], 200),
                                             (["/files/", "/api/records", "/api/status"], 100)], ids=["post", "start+fit+stop+abort", "reads"])
def test_fuzz_a_completed_test(completed, paths, examples):
    record = completed.console.runner.current.record
    text = record.read_bytes()

    @fuzz(examples)
    @given(requests(paths, hostile_only=True, record_names=(f"records/{record.name}",)))
    def one(request):
        method, url, hdrs, body = request
        status = completed.send(method, url, hdrs, body, group="completed", accepted_may_change=False)
        assert not (status < 300 and method == "POST" and url in ("/api/post", "/api/start", "/api/fit")), (url, body[0][:200])

    before = STATS["completed requests"]
    one()
    assert STATS["completed requests"] - before >= examples
    assert record.read_bytes() == text  # the record never amended


def test_fuzz_a_console_with_a_token(tmp_path):
    """Logins and token headers: wrong ones run into the limit (429), none gets past or fails."""
    fuzzed = FuzzedConsole(tmp_path, ModelClock(), token="t0ken-fuzz")

    @fuzz(200)
    @given(requests(["/api/login", "/api/status", "/api/records", "/files/", "/api/abort", "/api/start"], token="t0ken-fuzz", hostile_only=True))
    def one(request):
        method, url, hdrs, body = request
        status = fuzzed.send(method, url, hdrs, body, group="token", accepted_may_change=False)
        if url == "/api/login" and status == 200:
            assert "t0ken-fuzz" in body[0].decode("utf-8", "replace")

    one()
    fuzzed.close()
    assert fuzzed.console.runner.current is None and not fuzzed.out.exists()
    assert STATS["token requests"] >= 200


@pytest.mark.parametrize("group, paths, examples", [("raw posts", ["/api/start", "/api/stop", "/api/abort", "/api/login", "/api/post"], 200),
                                                    ("raw reads", [p for p, (m, _f) in ENDPOINTS.items() if m == "GET"], 150)])
def test_fuzz_a_heating_rig_over_a_socket(heating, group, paths, examples):
    """Requests a client library would not send (latin-1 bytes in headers, no Host or two, chunked
    bodies) to the heating console served by uvicorn."""
    names = (f"records/{heating.console.runner.current.record.name}",)

    @fuzz(examples)
    @given(raw_requests(paths, record_names=names))
    def one(request):
        method, url, head, body = request
        status = heating.send_raw(method, url, head, body, group=f"heating {group}")
        run = heating.console.runner.current
        if status < 300 and url in ("/api/stop", "/api/abort"):
            run.stop_reason = run.abort_reason = None
        assert run.running and not (status < 300 and url == "/api/start"), "a test started on a running rig"

    before = STATS[f"heating {group} requests"]
    one()
    assert STATS[f"heating {group} requests"] - before >= examples


# issue 42: links out of --out and unreadable files; X-Forwarded-For -----------------------------------------
GOOD_RECORD = ARTIFACTS.parents[2] / "examples" / "data" / "compression-steel45.csv"
CANARY = "CANARY-5e1d"  # text of files no answer may quote
RECORD_KINDS = ("good", "link out", "link to /etc/passwd", "link to nothing", "link inside", "link to nothing inside", "canary columns",
                "canary bytes", "canary header", "folder")
REFUSED_KINDS = ("link out", "link to /etc/passwd", "link to nothing")  # links that leave --out
RESULT_KINDS = ("none", "link out", "result.json out", "garbage result.json", "a plot out")


def _outside(tmp) -> dict:
    outside = tmp / "outside"
    (outside / "result").mkdir(parents=True)
    (outside / "secret.csv").write_text(f"{CANARY}:x:0:0:root:/root:/bin/bash\n{CANARY},1,2\n")
    (outside / "result" / "result.json").write_text(f'{{"test": "compression", "warnings": ["{CANARY}"], "E_MPa": 1}}')
    (outside / "plot.png").write_text(CANARY)
    return {"file": outside / "secret.csv", "result": outside / "result"}


def _make_record(records, name: str, kind: str, outside: dict) -> None:
    path = records / name
    if kind == "good":
        path.write_bytes(GOOD_RECORD.read_bytes())
    elif kind == "link out":
        path.symlink_to(outside["file"])
    elif kind == "link to /etc/passwd":
        path.symlink_to("/etc/passwd")
    elif kind == "link to nothing":
        path.symlink_to(outside["file"].parent / "gone.csv")
    elif kind == "link to nothing inside":
        path.symlink_to(records / "gone.csv")
    elif kind == "link inside":
        (records.parent / "inside.csv").write_bytes(GOOD_RECORD.read_bytes())
        path.symlink_to(records.parent / "inside.csv")
    elif kind == "canary columns":
        path.write_text(f"time_s;{CANARY} [kN]\n0;{CANARY}\n")
    elif kind == "canary bytes":
        path.write_bytes(b"# flowcurve-record: 1\n# test: compression\ntime_s,force_N,crosshead_mm\n0,\xff" + CANARY.encode() + b",1\n")
    elif kind == "canary header":
        path.write_text(f"# flowcurve-record: 1\n# test: compression\n# specimen.d0_mm: {CANARY}\ntime_s,force_N,crosshead_mm\n0,1,2\n")
    else:
        path.mkdir()


def _make_result(results, stem: str, kind: str, outside: dict) -> None:
    folder = results / stem
    if kind == "link out":
        folder.symlink_to(outside["result"])
        return
    folder.mkdir()
    if kind == "result.json out":
        (folder / "result.json").symlink_to(outside["result"] / "result.json")
    elif kind == "garbage result.json":
        (folder / "result.json").write_text(f'{{"test": {CANARY}')
    elif kind == "a plot out":
        (folder / "result.json").write_text('{"test": "compression", "E_MPa": 200000}')
        (folder / "plot.png").symlink_to(outside["result"].parent / "plot.png")


def _tree(root) -> list:
    return sorted((str(p), p.lstat().st_size, p.lstat().st_mtime_ns) for p in root.rglob("*"))


@fuzz(40)
@given(st.lists(st.tuples(st.sampled_from(RECORD_KINDS), st.sampled_from(RESULT_KINDS)), min_size=1, max_size=5),
       st.lists(st.integers(0, 4), max_size=3), st.booleans())
def test_fuzz_links_out_and_unreadable_files_never_break_the_list_or_quote_a_file(layout, fit_picks, records_linked_out):
    """Any mix of records and result folders — links out of --out, to nothing, inside it, files
    whose text would be quoted — gives a whole list (each file listed, links out refused), fits that
    answer < 500, and no answer quotes a file's text; nothing outside --out is read into an answer
    or written."""
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        outside = _outside(tmp)
        out = tmp / "out"
        records = out / "records"
        if records_linked_out:  # the records folder itself a link out of --out
            out.mkdir()
            (tmp / "outside" / "records").mkdir()
            records.symlink_to(tmp / "outside" / "records")
        else:
            records.mkdir(parents=True)
        (out / "results").mkdir()
        names = [f"r{i}.csv" for i in range(len(layout))]
        for name, (kind, result) in zip(names, layout):
            _make_record(records, name, kind, outside)
            _make_result(out / "results", name[:-4], result, outside)
        before = _tree(tmp / "outside")
        console = Console(out, time_scale=1.0, port=PORT)
        client = TestClient(create_app(console), base_url=f"http://127.0.0.1:{PORT}", raise_server_exceptions=False)
        r = client.get("/api/records")
        STATS["link requests"] += 1
        assert r.status_code == 200, r.text[:300]
        assert CANARY not in r.text and "root:x:" not in r.text, r.text
        rows = {row["name"]: row for row in r.json()["records"]}
        if records_linked_out:
            assert list(rows) == ["records"] and rows["records"]["refused"]
        else:
            assert set(rows) == set(names)
            for name, (kind, result) in zip(names, layout):
                row = rows[name]
                if kind in REFUSED_KINDS:
                    assert row["refused"] and row["url"] is None and "link out" in row["error"], row
                elif kind in ("good", "link inside"):
                    assert row["test"] == "compression" and "error" not in row, row
                    if result in ("link out", "result.json out"):
                        assert "link out" in row["result"]["error"], row
                    if result == "a plot out":  # listed without the plot that leaves --out
                        assert row["result"]["plots"] == [] and "figures" in row["result"], row
                elif kind != "canary header":  # a header value is read as text: the record lists
                    assert row["error"].startswith(f"records/{name}"), row
        picked = [names[i % len(names)] for i in fit_picks]
        r = client.post("/api/fit", json={"records": picked, "melt_temp": 1400}, headers={"Content-Type": "application/json"})
        STATS["link requests"] += 1
        assert r.status_code < 500 and CANARY not in r.text and "root:x:" not in r.text, r.text
        assert _tree(tmp / "outside") == before


ip_text = st.tuples(*[st.integers(0, 255)] * 4).map(lambda t: ".".join(map(str, t)))
forwarded_values = st.one_of(st.just("127.0.0.9"), ip_text, st.lists(ip_text, min_size=2, max_size=4).map(", ".join),
                             header_text.map(lambda b: b.decode("latin-1").strip()).filter(lambda t: t and ":" not in t[:1]))


@pytest.fixture(scope="module")
def served_with_token(tmp_path_factory):
    """A console with a token served by uvicorn as ``flowcurve console`` serves it (no proxy named)."""
    from flowcurve.console.request_guard import FailedLogins

    port = free_port()
    console = Console(tmp_path_factory.mktemp("xff") / "out", time_scale=1.0, port=port, token="t0ken-xff")
    with serving(create_app(console), port, lifespan="off", log_level="error"):
        yield console, port, FailedLogins


@fuzz(40)
@given(st.lists(st.dictionaries(st.sampled_from(["X-Forwarded-For", "X-Real-IP", "Forwarded", "X-Forwarded-Host"]), forwarded_values,
                                min_size=1, max_size=3), min_size=1, max_size=12))
def test_fuzz_proxy_headers_never_choose_the_wrong_token_limits_key(served_with_token, tries):
    """Wrong tokens from 127.0.0.1 with any proxy headers: the limit counts them against 127.0.0.1
    (429 from the sixth), and the client at 127.0.0.9 they name logs in."""
    console, port, FailedLogins = served_with_token
    console.failed_logins = FailedLogins()
    answers = []
    for headers in tries:
        answers.append(login_over_socket(port, "wrong", headers=headers))
        STATS["proxy-header requests"] += 1
    assert answers == [401] * min(5, len(tries)) + [429] * max(0, len(tries) - 5), (tries, answers)
    assert set(console.failed_logins._failures) == {"127.0.0.1"}
    assert login_over_socket(port, "t0ken-xff", source="127.0.0.9") == 200
