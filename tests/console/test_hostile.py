"""The console under hostile requests (issue 30): each of the seven findings of the probe, and
the limits that answer them. Every refusal here is a 4xx that starts no test and writes no file.
Issue 42: links out of --out, error messages that quoted a file, X-Forwarded-For."""

from __future__ import annotations

import time
import warnings
from pathlib import Path

import pytest

pytest.importorskip("starlette", reason="starlette is not installed (pip install -e .[test])")
pytest.importorskip("httpx", reason="httpx is not installed (pip install -e .[test])")

with warnings.catch_warnings():  # starlette's note about its test client's HTTP library
    warnings.simplefilter("ignore")
    from starlette.testclient import TestClient  # noqa: E402

from flowcurve.cli import main as cli_main  # noqa: E402
from flowcurve.console.server import Console, create_app  # noqa: E402

from .conftest import login_over_socket as login  # noqa: E402
from .test_api import start_then_abort  # noqa: E402

JSON = {"Content-Type": "application/json"}
BASE_URL = "http://127.0.0.1:8080"
FOREIGN = {"Host": "evil.example:8080", "Origin": "http://evil.example:8080"}  # a page whose name resolves to 127.0.0.1


def _client(tmp_path: Path, **kw) -> tuple[Console, TestClient]:
    console = Console(tmp_path / "out", time_scale=kw.pop("time_scale", 60.0), **kw)
    return console, TestClient(create_app(console), base_url=BASE_URL, raise_server_exceptions=False)


def _files(tmp_path: Path) -> list[Path]:
    return sorted(p for p in tmp_path.rglob("*") if p.is_file())


def assert_still_running_refuses(client: TestClient) -> None:
    assert client.post("/api/post", json={"post.lu_mm": "52"}, headers=JSON).status_code == 409


# 1. DNS rebinding -----------------------------------------------------------------------------------
def test_finding1_a_foreign_host_cannot_start_abort_or_read_anything(tmp_path):
    console, client = _client(tmp_path)
    (tmp_path / "out" / "records").mkdir(parents=True)
    (tmp_path / "out" / "records" / "a.csv").write_text("# flowcurve-record: 1\n")
    before = _files(tmp_path)
    r = client.post("/api/start", json={"test": "compression", "temperature": "600"}, headers={**JSON, **FOREIGN})
    assert r.status_code == 403, r.text
    assert console.runner.current is None  # nothing heats
    for method, path in (("GET", "/api/status"), ("GET", "/api/records"), ("GET", "/files/records/a.csv"), ("GET", "/"),
                         ("GET", "/api/info"), ("GET", "/api/events"), ("POST", "/api/abort"), ("POST", "/api/stop")):
        r = client.request(method, path, headers={**JSON, **FOREIGN}, content=b"{}" if method == "POST" else None)
        assert r.status_code == 403, (method, path, r.status_code)
        assert "flowcurve-record" not in r.text
    # the foreign name alone (no Origin, as a same-origin GET sends it) and a foreign Origin alone
    assert client.get("/api/status", headers={"Host": "evil.example:8080"}).status_code == 403
    assert client.get("/api/status", headers={"Origin": "http://evil.example:8080"}).status_code == 403
    assert client.get("/api/status", headers={"Origin": "null"}).status_code == 403
    assert _files(tmp_path) == before
    # this console's own names still answer
    for host in ("127.0.0.1:8080", "localhost:8080", "[::1]:8080"):
        assert client.get("/api/status", headers={"Host": host, "Origin": f"http://{host}"}).status_code == 200, host


def test_the_allowlist_holds_the_port_the_host_and_the_allowed_names(tmp_path):
    console = Console(tmp_path / "out", host="192.168.7.20", port=8090, allow_hosts=["lab-pc.example", "[fe80::7]"], token="t0ken")
    client = TestClient(create_app(console), base_url="http://127.0.0.1:8090", headers={"X-Flowcurve-Token": "t0ken"})
    ok = ("127.0.0.1:8090", "localhost:8090", "[::1]:8090", "192.168.7.20:8090", "LAB-PC.example:8090", "[fe80::7]:8090")
    for host in ok:
        assert client.get("/api/status", headers={"Host": host}).status_code == 200, host
    for host in ("127.0.0.1:8091", "localhost", "lab-pc.example.evil:8090", "127.0.0.1:8090@evil", "", "evil.example:8090"):
        assert client.get("/api/status", headers={"Host": host}).status_code == 403, host
    assert client.get("/api/status", headers={"Origin": "http://lab-pc.example:8090"}).status_code == 200
    assert client.get("/api/status", headers={"Origin": "http://lab-pc.example:8091"}).status_code == 403


def test_allow_host_is_given_on_the_command_line(monkeypatch, tmp_path, capsys):
    seen = {}
    import flowcurve.console.server as server

    monkeypatch.setattr(server, "serve", lambda console, host, port: seen.update(console=console))
    assert cli_main(["console", "--out", str(tmp_path), "--allow-host", "lab-pc", "--allow-host", "10.0.0.5"]) == 0
    hosts = seen["console"].hosts
    assert hosts.allows_host("lab-pc:8080") and hosts.allows_host("10.0.0.5:8080") and not hosts.allows_host("lab-pc:8081")
    assert cli_main(["console", "--out", str(tmp_path), "--allow-host", "evil.example:80"]) != 0
    assert "--allow-host" in capsys.readouterr().err


# 2. deep JSON ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("path", ["/api/login", "/api/start", "/api/post", "/api/fit", "/api/stop", "/api/abort"])
def test_finding2_json_nested_50000_deep_is_a_400_not_a_recursion_error(tmp_path, path, caplog):
    console, client = _client(tmp_path, token="s3cret")
    client.headers["X-Flowcurve-Token"] = "s3cret"
    for body in ("[" * 50_000 + "]" * 50_000, '{"a":' * 50_000 + "1" + "}" * 50_000, '{"test": ' + "[" * 100_000):
        r = client.post(path, content=body, headers=JSON)
        assert r.status_code == 400, (r.status_code, r.text[:200])
    assert "RecursionError" not in caplog.text
    assert console.runner.current is None and _files(tmp_path) == []


def test_json_deeper_than_32_is_refused_and_32_is_read(tmp_path):
    _console, client = _client(tmp_path)
    deep = {"records": []}
    inner = deep["records"]
    for _ in range(31):  # the object, then 32 nested lists: depth 33
        inner.append([])
        inner = inner[0]
    r = client.post("/api/fit", json=deep, headers=JSON)
    assert r.status_code == 400 and "deeper than 32" in r.json()["error"]
    r = client.post("/api/fit", json={"records": [[[[]]]]}, headers=JSON)  # shallow: refused for its type, not its depth
    assert r.status_code == 400 and "deeper" not in r.text


# 3. body size ----------------------------------------------------------------------------------------
def test_finding3_a_body_over_1_MB_is_413_and_starts_nothing(tmp_path):
    console, client = _client(tmp_path)
    r = client.post("/api/start", json={"test": "compression", "material": "x" * 50_000_000}, headers=JSON)
    assert r.status_code == 413, r.text[:200]

    def chunks():  # no Content-Length: the body is counted as it comes
        yield b'{"test": "compression", "material": "'
        for _ in range(2048):
            yield b"y" * 1024
        yield b'"}'

    r = client.post("/api/start", content=chunks(), headers=JSON)
    assert r.status_code == 413
    assert console.runner.current is None and _files(tmp_path) == []


def test_names_are_at_most_200_characters(tmp_path):
    console, client = _client(tmp_path)
    r = client.post("/api/start", json={"test": "compression", "material": "steel45", "specimen_id": "s" * 201}, headers=JSON)
    assert r.status_code == 400 and "specimen_id" in r.json()["fields"]
    r = client.post("/api/start", json={"test": "compression", "operator": "a\nb"}, headers=JSON)  # no header lines smuggled into a record
    assert r.status_code == 400 and "operator" in r.json()["fields"]
    r = client.post("/api/start", json={"test": "compression", "nonsense": "1"}, headers=JSON)
    assert r.status_code == 400 and "unknown field" in r.json()["fields"]["nonsense"]
    assert console.runner.current is None and _files(tmp_path) == []


# 4. a token off the default host ------------------------------------------------------------------------
@pytest.mark.parametrize("host", ["127.0.0.3", "0.0.0.0", "localhost"])
def test_finding4_a_host_other_than_the_default_refuses_to_serve_without_a_token(monkeypatch, tmp_path, capsys, host):
    served = []
    import flowcurve.console.server as server

    monkeypatch.setattr(server, "serve", lambda *a: served.append(a))
    assert cli_main(["console", "--host", host, "--token", "", "--out", str(tmp_path)]) != 0
    err = capsys.readouterr().err.strip()
    assert served == [] and len(err.splitlines()) == 1 and "--token" in err, err
    assert cli_main(["console", "--host", host, "--token", "  ", "--out", str(tmp_path)]) != 0
    assert served == []
    assert cli_main(["console", "--host", host, "--token", "k3y", "--out", str(tmp_path)]) == 0
    assert served[0][0].token == "k3y"


# 5. failed logins ----------------------------------------------------------------------------------------
def test_finding5_wrong_logins_are_limited_to_5_a_minute_per_client(tmp_path):
    console, client = _client(tmp_path, token="s3cret")
    answers = [client.post("/api/login", json={"token": f"guess{i}"}, headers=JSON).status_code for i in range(100)]
    assert answers[:5] == [401] * 5 and set(answers[5:]) == {429}, answers[:10]
    r = client.post("/api/login", json={"token": "s3cret"}, headers=JSON)  # even the right one waits
    assert r.status_code == 429 and 0 < int(r.headers["Retry-After"]) <= 60
    # a token guessed through the header of any request counts too
    assert client.get("/api/status", headers={"X-Flowcurve-Token": "guess"}).status_code == 429
    other = TestClient(client.app, base_url=BASE_URL, client=("10.0.0.9", 5000))  # another client is not held up
    assert other.post("/api/login", json={"token": "s3cret"}, headers=JSON).status_code == 200
    console.failed_logins.clock = lambda: time.monotonic() + 61.0  # a minute later
    assert client.post("/api/login", json={"token": "s3cret"}, headers=JSON).status_code == 200
    assert client.get("/api/status").status_code == 200


def test_a_stale_cookie_does_not_lock_the_operator_out(tmp_path):
    """The console restarted with a new token: the page's old cookie is refused once and cleared,
    so the page's polls do not run into the limit before the operator logs in."""
    _console, client = _client(tmp_path, token="new-t0ken")
    client.cookies.set("flowcurve_token", "old-t0ken", domain="127.0.0.1")  # as a login there set it
    answers = [client.get("/api/status").status_code for _ in range(20)]
    assert answers == [401] * 20
    assert "flowcurve_token" not in client.cookies
    assert client.post("/api/login", json={"token": "new-t0ken"}, headers=JSON).status_code == 200
    assert client.get("/api/status").status_code == 200


def test_the_token_is_compared_in_constant_time(tmp_path, monkeypatch):
    import hmac

    calls = []
    real = hmac.compare_digest
    monkeypatch.setattr(hmac, "compare_digest", lambda a, b: calls.append((a, b)) or real(a, b))
    _console, client = _client(tmp_path, token="s3cret")
    assert client.post("/api/login", json={"token": "nope"}, headers=JSON).status_code == 401
    assert client.get("/api/status", headers={"X-Flowcurve-Token": "s3cret"}).status_code == 200
    assert calls == [(b"nope", b"s3cret"), (b"s3cret", b"s3cret")]


# 6. post-test values only for a completed test ---------------------------------------------------------------
def test_finding6_post_test_values_for_an_aborted_test_are_refused(tmp_path):
    console, client = _client(tmp_path, time_scale=5.0)
    start_then_abort(console, client, while_running=lambda: assert_still_running_refuses(client))
    run = console.runner.current
    assert run.outcome.status == "aborted"
    before = {p: p.read_bytes() for p in _files(tmp_path)}
    r = client.post("/api/post", json={"post.lu_mm": "52", "post.dk_mm": "6"}, headers=JSON)
    assert r.status_code == 409, r.text
    assert {p: p.read_bytes() for p in _files(tmp_path)} == before  # the record not amended, nothing identified
    assert run.post == {} and run.result is None


# 7. a boolean is not a number ------------------------------------------------------------------------------------
def test_finding7_d0_true_is_refused_not_read_as_1_mm(tmp_path):
    console, client = _client(tmp_path)
    r = client.post("/api/start", json={"test": "compression", "d0": True}, headers=JSON)
    assert r.status_code == 400, r.text
    assert "d0" in r.json()["fields"]
    for field, value in (("h0", False), ("temperature", [600]), ("speed", {"v": 1}), ("d0", 10**400)):
        r = client.post("/api/start", content=f'{{"test": "compression", "{field}": {_dump(value)}}}', headers=JSON)
        assert r.status_code == 400 and field in r.json()["fields"], (field, r.text)
    assert client.post("/api/start", content='{"test": "compression", "d0": NaN}', headers=JSON).status_code == 400
    assert console.runner.current is None and _files(tmp_path) == []


def _dump(value) -> str:
    import json

    return json.dumps(value)


# over a real socket (uvicorn) -----------------------------------------------------------------------------
def _raw(url: str, head: str, body: bytes = b"", timeout_s: float = 10.0) -> int:
    """Send a hand-written request (its head as latin-1 bytes, as HTTP allows); the answer's status code."""
    import socket
    from urllib.parse import urlsplit

    parts = urlsplit(url)
    with socket.create_connection((parts.hostname, parts.port), timeout=timeout_s) as sock:
        sock.sendall(head.replace("\n", "\r\n").encode("latin-1") + b"\r\n" + body)
        answer = sock.recv(4096)
    return int(answer.split(b" ", 2)[1])


def test_a_served_console_refuses_a_foreign_host_and_a_200_MB_body_before_reading_it(served_console):
    port = served_console.url.rstrip("/").rsplit(":", 1)[1]
    assert _raw(served_console.url, f"GET /api/status HTTP/1.1\nHost: evil.example:{port}\n") == 403
    assert _raw(served_console.url, f"GET /api/status HTTP/1.1\nHost: 127.0.0.1:{port}\n") == 200
    assert _raw(served_console.url, "GET /api/status HTTP/1.1\nHost: 127.0.0.1:\u00b2\n") == 403  # a digit to str.isdigit, not to int()
    # a 200 MB body announced, 1 kB of it sent: the answer comes without the console waiting for the rest
    head = (f"POST /api/start HTTP/1.1\nHost: 127.0.0.1:{port}\nContent-Type: application/json\n"
            f"Content-Length: {200 * 1024 * 1024}\n")
    assert _raw(served_console.url, head, b'{"material": "' + b"m" * 1024) == 413
    assert served_console.console.runner.current is None


# issue 42: links out of --out, file text in error messages, X-Forwarded-For ------------------------------
GOOD_RECORD = Path(__file__).resolve().parents[2] / "examples" / "data" / "compression-steel45.csv"
CANARY = "CANARY-7f3a"  # text of files the answers must never quote


def hostile_workspace(tmp_path: Path) -> tuple[Path, Path]:
    """OUT with a good record beside links out of it (to a file, to /etc/passwd, to a folder of
    results), a link to nothing, a link inside, and a record whose column row holds CANARY;
    and the outside folder those links reach. (out, outside)"""
    out, outside = tmp_path / "out", tmp_path / "outside"
    (out / "records").mkdir(parents=True)
    (out / "results").mkdir()
    (outside / "result").mkdir(parents=True)
    secret = outside / "secret.csv"
    secret.write_text(f"{CANARY}:x:0:0:root:/root:/bin/bash\n{CANARY},1,2\n")
    (outside / "result" / "result.json").write_text(f'{{"test": "compression", "note": "{CANARY}", ')
    (out / "records" / "good.csv").write_bytes(GOOD_RECORD.read_bytes())
    (out / "records" / "x.csv").symlink_to(secret)
    (out / "records" / "passwd.csv").symlink_to("/etc/passwd")
    (out / "records" / "nothing.csv").symlink_to(tmp_path / "gone.csv")
    (out / "records" / "same.csv").symlink_to("good.csv")  # a link inside --out is a record like any
    (out / "records" / "bad.csv").write_text(f"# flowcurve-record: 1\n# test: compression\ntime_s,{CANARY}_N\n0,1\n")
    (out / "results" / "good").symlink_to(outside / "result")  # good.csv's result folder, out of --out
    return out, outside


def assert_quotes_nothing(text: str) -> None:
    assert CANARY not in text and "root:x:0:0" not in text and ":/bin/" not in text and "Traceback" not in text, text


def test_a_link_out_of_out_is_refused_in_the_list_and_the_rest_of_the_list_holds(tmp_path):
    """A symlink records/x.csv → /etc/passwd answered 500 with a traceback: the whole list broke."""
    out, outside = hostile_workspace(tmp_path)
    console, client = _client(tmp_path)
    r = client.get("/api/records")
    assert r.status_code == 200, r.text[:300]
    assert_quotes_nothing(r.text)
    rows = {row["name"]: row for row in r.json()["records"]}
    assert set(rows) == {"good.csv", "x.csv", "passwd.csv", "nothing.csv", "same.csv", "bad.csv"}
    for name in ("x.csv", "passwd.csv"):
        assert rows[name]["refused"] and "link out of the console's folder" in rows[name]["error"] and rows[name]["url"] is None
    for name in ("good.csv", "same.csv"):  # read as records; good.csv's result folder (a link out) refused
        assert rows[name]["test"] == "compression" and rows[name]["samples"] > 500, rows[name]
    assert "link out" in rows["good.csv"]["result"]["error"]
    assert rows["bad.csv"]["error"].startswith("records/bad.csv") and rows["nothing.csv"]["error"]
    assert client.get("/files/records/x.csv").status_code == 404


@pytest.mark.parametrize("name", ["x.csv", "passwd.csv", "bad.csv", "good.csv", "nothing.csv"])
def test_a_fit_naming_a_link_out_or_an_unreadable_record_quotes_no_line_of_it(tmp_path, name):
    """POST /api/fit naming records/x.csv → /etc/passwd answered 400 quoting a line of /etc/passwd."""
    out, outside = hostile_workspace(tmp_path)
    before = sorted((p, p.stat().st_mtime_ns) for p in outside.rglob("*"))
    _console, client = _client(tmp_path)
    r = client.post("/api/fit", json={"records": [name], "melt_temp": 1400, "format": "lsdyna"}, headers=JSON)
    assert r.status_code == 400, r.text[:300]
    assert_quotes_nothing(r.text)
    error = r.json()["error"]
    if name in ("x.csv", "passwd.csv", "good.csv"):  # good.csv: its result folder is the link out
        assert "refused: a link out of the console's folder" in error, error
    if name == "bad.csv":  # file and line named, not its text
        assert error.startswith("records/bad.csv, line "), error
    assert sorted((p, p.stat().st_mtime_ns) for p in outside.rglob("*")) == before
    assert not (out / "fits").exists() or not any((out / "fits").iterdir())


def _cli_console(tmp_path: Path, *options: str):
    """``flowcurve console`` as an operator starts it, on a free port, with a token: (process, port)."""
    import socket
    import subprocess
    import sys

    from .conftest import free_port

    port = free_port()
    proc = subprocess.Popen([sys.executable, "-m", "flowcurve", "console", "--out", str(tmp_path / "out"), "--port", str(port),
                             "--token", "s3cret", *options], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    end = time.monotonic() + 60
    while time.monotonic() < end:
        assert proc.poll() is None, proc.stderr.read().decode()
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            return proc, port
        except OSError:
            time.sleep(0.1)
    proc.kill()
    raise AssertionError("flowcurve console did not start")


def xff(address: str) -> dict:
    return {"X-Forwarded-For": address}


def _stopped(proc) -> None:
    proc.terminate()
    proc.wait(30)


def test_x_forwarded_for_is_ignored_so_a_client_cannot_choose_its_limit_key(tmp_path):
    """The ASGI server trusted X-Forwarded-For from 127.0.0.1: a header changed on every try was
    never limited (12 wrong tokens, no 429), and five wrong tokens sent with X-Forwarded-For:
    127.0.0.9 locked the real client at 127.0.0.9 out."""
    proc, port = _cli_console(tmp_path)
    try:
        answers = [login(port, "wrong", headers=xff("127.0.0.9")) for _ in range(5)]
        assert login(port, "s3cret", source="127.0.0.9") == 200  # the real 127.0.0.9 is not locked out
        answers += [login(port, "wrong", headers={**xff(f"10.9.{i}.{i}"), "X-Real-IP": f"10.8.{i}.1", "Forwarded": f"for=10.7.{i}.1"})
                    for i in range(7)]
        assert answers == [401] * 5 + [429] * 7, answers
        assert login(port, "s3cret", headers=xff("10.1.1.1")) == 429  # the sender, 127.0.0.1, waits
    finally:
        _stopped(proc)


def test_forwarded_allow_ips_names_the_proxy_whose_client_is_limited(tmp_path):
    proc, port = _cli_console(tmp_path, "--forwarded-allow-ips", "127.0.0.1")
    try:  # 127.0.0.1 is the proxy: the limit keys on the client it names
        assert [login(port, "wrong", headers=xff("10.0.0.7")) for _ in range(6)] == [401] * 5 + [429]
        assert login(port, "s3cret", headers=xff("10.0.0.8")) == 200  # another client behind the proxy
        assert login(port, "s3cret", headers=xff("10.0.0.7")) == 429
        # a client that is not the proxy names nobody: five wrong tokens count against its own address
        assert [login(port, "wrong", source="127.0.0.5", headers=xff("10.0.0.8")) for _ in range(6)] == [401] * 5 + [429]
        assert login(port, "s3cret", headers=xff("10.0.0.8")) == 200
    finally:
        _stopped(proc)


@pytest.mark.parametrize("value", ["*", "nonsense", "10.0.0.1,", "10.0.0.300"])
def test_forwarded_allow_ips_takes_addresses_and_networks_only(monkeypatch, tmp_path, capsys, value):
    seen = {}
    import flowcurve.console.server as server

    monkeypatch.setattr(server, "serve", lambda console, host, port: seen.update(console=console))
    assert cli_main(["console", "--out", str(tmp_path), "--forwarded-allow-ips", value]) != 0
    err = capsys.readouterr().err.strip()
    assert not seen and len(err.splitlines()) == 1 and "--forwarded-allow-ips" in err, err
    assert cli_main(["console", "--out", str(tmp_path), "--forwarded-allow-ips", "10.0.0.5/24, ::1"]) == 0
    assert seen["console"].forwarded_allow_ips == "10.0.0.0/24,::1"
    assert cli_main(["console", "--out", str(tmp_path)]) == 0
    assert seen["console"].forwarded_allow_ips is None
    assert server.proxy_options(None) == {"proxy_headers": False}


def test_post_test_values_identify_into_out_only(tmp_path_factory, tmp_path):
    """A completed test whose result folder was made a link out of --out: the identification is
    refused (named in the test's result), and nothing is written where the link leads."""
    pytest.importorskip("hypothesis", reason="hypothesis is not installed (pip install -e .[test])")
    from .test_fuzz import _completed, _console_with

    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    with _console_with(tmp_path_factory, {"test": "compression", "target": "0.5", "specimen_id": "linked"}, _completed) as fuzzed:
        record = fuzzed.console.runner.current.record
        results = fuzzed.console.workspace.results
        results.mkdir(parents=True, exist_ok=True)
        (results / record.stem).symlink_to(elsewhere)
        r = fuzzed.client.post("/api/post", json={}, headers=JSON)  # the virtual rig's own hk and dmax: it identifies
        assert r.status_code == 200, r.text
        assert "refused: a link out of the console's folder" in r.json()["test"]["result"]["error"], r.text
    assert list(elsewhere.iterdir()) == []


def test_a_record_made_a_link_out_after_its_test_is_neither_served_nor_amended(tmp_path_factory, tmp_path):
    """The test's record replaced by a link to a file outside --out: the status still answers (no
    500, no link to it), and post-test values are refused without touching the outside file."""
    pytest.importorskip("hypothesis", reason="hypothesis is not installed (pip install -e .[test])")
    from .test_fuzz import _completed, _console_with

    with _console_with(tmp_path_factory, {"test": "compression", "target": "0.5", "specimen_id": "moved"}, _completed) as fuzzed:
        record = fuzzed.console.runner.current.record
        outside = tmp_path / "outside.csv"
        text = record.read_bytes()
        outside.write_bytes(text)
        record.unlink()
        record.symlink_to(outside)
        r = fuzzed.client.get("/api/status")
        assert r.status_code == 200 and r.json()["test"]["record_url"] is None, r.text[:300]
        r = fuzzed.client.post("/api/post", json={"post.hk_mm": "6.25"}, headers=JSON)
        assert r.status_code == 400 and "refused: a link out of the console's folder" in r.json()["error"], r.text[:300]
        assert outside.read_bytes() == text
