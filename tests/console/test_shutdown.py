"""``flowcurve console`` stopped by a signal while a heated test runs and a page listens:
the test is aborted at once, the heater switched off, the record closed, the process ends."""

from __future__ import annotations

import json
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.request

import pytest

pytest.importorskip("uvicorn", reason="uvicorn is not installed (pip install -e .[test])")


def _post(url: str, body: dict) -> dict:
    req = urllib.request.Request(url, data=json.dumps(body).encode(), headers={"Content-Type": "application/json"}, method="POST")
    with urllib.request.urlopen(req, timeout=30) as resp:
        return json.loads(resp.read())


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, -signal.SIGTERM)])  # as run on Ctrl-C; SIGTERM re-raised
def test_a_signal_aborts_the_heated_test_even_with_a_page_open(tmp_path, sig, code):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "flowcurve", "console", "--out", str(out), "--port", str(port), "--time-scale", "5"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    base = f"http://127.0.0.1:{port}"
    try:
        for _ in range(300):
            try:
                urllib.request.urlopen(base + "/api/info", timeout=1).read()
                break
            except OSError:
                time.sleep(0.1)
        started = _post(base + "/api/start", {"test": "compression", "temperature": "300", "soak": "600"})
        record = out / "records" / started["test"]["record"]
        stream = urllib.request.urlopen(base + "/api/events", timeout=60)  # a page listening
        heater_seen, heard = [], []

        def listen():
            for line in stream:
                heard.append(line.decode().strip())
                if line.startswith(b"data:") and b'"heater":"on"' in line:
                    heater_seen.append(True)

        listener = threading.Thread(target=listen, daemon=True)
        listener.start()
        end = time.monotonic() + 30
        while not heater_seen and time.monotonic() < end:
            time.sleep(0.05)
        assert heater_seen, "the page never saw the heater on"
        proc.send_signal(sig)
        proc.wait(60)  # a bound for a hung process, not a speed check
        listener.join(10)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    text = record.read_text()
    assert "# status: aborted\n" in text
    assert "# abort_reason: stopped by the console shutting down\n" in text
    events = [line.split()[3] for line in text.splitlines() if line.startswith("# event:")]
    assert events == ["heater_on", "heater_off", "stop"]
    # the page's last word is the test's final state and the console closing, not "recording" (or "heating")
    events = [(heard[i][len("event: "):], json.loads(heard[i + 1][len("data: "):])) for i in range(len(heard) - 1)
              if heard[i].startswith("event: ") and heard[i + 1].startswith("data: ")]
    statuses = [data for name, data in events if name == "status"]
    assert statuses[-1]["state"] == "aborted" and statuses[-1]["heater"] == "off", statuses[-1]
    assert events[-1][0] == "closing" and "start it again" in events[-1][1]["message"]
    err = proc.stderr.read().decode()
    assert "Traceback" not in err, err
    assert proc.returncode == code


def test_a_server_that_came_back_from_ctrl_c_still_ends_as_interrupted(monkeypatch):
    """Once, in a CI rehearsal, the console ended a Ctrl-C with exit code 0 (uvicorn raises the SIGINT
    it caught again, through asyncio's handler). Here uvicorn's run comes back from a SIGINT as if
    that had been lost; the console must still end interrupted (130), the running test closed first."""
    import uvicorn

    from flowcurve.cli import main
    from flowcurve.console import server

    closed = []
    console = type("Stub", (), {"close": lambda self: closed.append(True), "forwarded_allow_ips": None})()
    monkeypatch.setattr(server, "create_app", lambda c: object())

    def run_and_miss(self, sockets=None):
        self.handle_exit(signal.SIGINT, None)  # what the signal handler does; then the server stops and returns

    monkeypatch.setattr(uvicorn.Server, "run", run_and_miss)
    with pytest.raises(KeyboardInterrupt):
        server.serve(console, "127.0.0.1", 8080)
    assert closed == [True]

    monkeypatch.setattr(server, "Console", lambda *a, **k: type("C", (), {"rig_name": "virtual rig", "close": lambda self: None, "forwarded_allow_ips": None,
                                                                          "workspace": type("W", (), {"records": "r"})()})())
    assert main(["console", "--out", "unused"]) == 130
    server.exit_as_signalled([])  # a server stopped without a signal: nothing raised
