"""A console served in a thread on a free port, and headless Chromium pages driven by selenium.

Screenshots go to ``$FLOWCURVE_ARTIFACTS`` or ``tests/console/artifacts/`` (git-ignored).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import socket
import threading
import time
from pathlib import Path

import pytest

ARTIFACTS = Path(os.environ.get("FLOWCURVE_ARTIFACTS") or Path(__file__).with_name("artifacts"))
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
CHROMEDRIVER = shutil.which("chromedriver")
BROWSER_TIME_SCALE = 10.0  # the virtual rig's compression test takes about 10 wall seconds


class ServedConsole:
    def __init__(self, console, server, thread, url):
        self.console, self.server, self.thread, self.url = console, server, thread, url


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextlib.contextmanager
def serving(app, port: int, lifespan: str = "on", log_level: str = "warning", forwarded_allow_ips: str | None = None):
    """``app`` served by uvicorn on 127.0.0.1:``port`` in a thread, until the block ends, with
    the proxy-header options ``flowcurve console`` serves with."""
    pytest.importorskip("uvicorn", reason="uvicorn is not installed (pip install -e .[test])")
    import uvicorn

    from flowcurve.console.server import proxy_options

    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level=log_level, lifespan=lifespan,
                                           **proxy_options(forwarded_allow_ips)))
    thread = threading.Thread(target=server.run, name="console-under-test", daemon=True)
    thread.start()
    end = time.monotonic() + 20
    while not server.started and time.monotonic() < end:
        time.sleep(0.05)
    assert server.started, "the console did not start"
    yield server, thread
    server.should_exit = True
    thread.join(30)
    assert not thread.is_alive()


def login_over_socket(port: int, token: str, source: str = "127.0.0.1", headers: dict | None = None) -> int:
    """POST /api/login to 127.0.0.1:``port`` from the address ``source`` (any 127.x.y.z is this
    computer) with extra ``headers`` (latin-1), over a socket of its own; the answer's status."""
    import json

    body = json.dumps({"token": token}).encode()
    extra = "".join(f"{k}: {v}\r\n" for k, v in (headers or {}).items()).encode("latin-1")
    head = (f"POST /api/login HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nContent-Type: application/json\r\n"
            f"Content-Length: {len(body)}\r\nConnection: close\r\n").encode() + extra + b"\r\n"
    with socket.create_connection(("127.0.0.1", port), timeout=30, source_address=(source, 0)) as sock:
        sock.sendall(head + body)
        answer = sock.recv(4096)
    return int(answer.split(b" ", 2)[1])


@pytest.fixture
def served_console(tmp_path):
    pytest.importorskip("uvicorn", reason="uvicorn is not installed (pip install -e .[test])")
    from flowcurve.console.server import Console, create_app

    port = free_port()
    console = Console(tmp_path / "out", time_scale=BROWSER_TIME_SCALE, port=port)
    with serving(create_app(console), port) as (server, thread):
        yield ServedConsole(console, server, thread, f"http://127.0.0.1:{port}/")


@pytest.fixture
def browser_factory():
    if CHROMIUM is None or CHROMEDRIVER is None:
        pytest.skip("chromium / chromedriver is not installed (apt-get install chromium chromium-driver)")
    pytest.importorskip("selenium", reason="selenium is not installed (pip install -e .[test])")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    drivers = []

    def open_browser(width: int = 1366, height: int = 900):
        options = webdriver.ChromeOptions()
        options.binary_location = CHROMIUM
        for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu", f"--window-size={width},{height}", "--hide-scrollbars"):
            options.add_argument(arg)
        driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
        driver.set_page_load_timeout(30)
        drivers.append(driver)
        return driver

    yield open_browser
    for d in drivers:
        try:
            d.quit()
        except Exception:  # already closed by the test
            pass


@pytest.fixture
def shot(request):
    """``shot(driver, "stage")`` saves a full-page PNG named after the test and the stage."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)

    def save(driver, stage: str) -> Path:
        path = ARTIFACTS / f"{request.node.name}-{stage}.png"
        height = driver.execute_script("return document.documentElement.scrollHeight")
        width = driver.execute_script("return window.innerWidth")
        driver.set_window_size(width, max(600, min(int(height) + 140, 4000)))
        driver.save_screenshot(str(path))
        return path

    return save


def identified_records(out: Path, temperatures_C=(300.0,), rates_per_s=(1.0, 1.0)) -> list[str]:
    """Records in OUT/records with their result folders written by hand in the documented format
    (result.json, true_curve.csv): a power law at each (temperature, rate), no modulus."""
    import json

    import numpy as np

    names = []
    for i, (T, rate) in enumerate((T, r) for T in temperatures_C for r in rates_per_s):
        name = f"t{i}.csv"
        (out / "records").mkdir(parents=True, exist_ok=True)
        (out / "records" / name).write_text("# flowcurve-record: 1\n")
        folder = out / "results" / f"t{i}"
        folder.mkdir(parents=True)
        block = {"path": name, "name": f"t{i}", "test": "tension", "material": "steel", "nominal_temperature_C": T,
                 "strain_rate_per_s": rate, "crosshead_speed_mm_per_s": rate * 30.0, "specimen": {"d0_mm": 6.0, "l0_mm": 30.0}}
        (folder / "result.json").write_text(json.dumps({"test": "tension", "E_MPa": None, "record": block}))
        eps = np.linspace(0.002, 0.3, 40)
        rows = "\n".join(f"{e:.6g},{300 + 500 * e ** 0.3 + i:.6g}" for e in eps)
        (folder / "true_curve.csv").write_text("true_plastic_strain,true_stress_MPa\n" + rows + "\n")
        names.append(name)
    return names
