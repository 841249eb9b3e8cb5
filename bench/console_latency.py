"""Console latency and CPU: from a sample arriving to the page drawing it, during a 150 Hz test.

The console runs in a child process (``--serve``) exactly as ``flowcurve console`` serves it,
with one difference: its rig is a synthetic one whose load cell is read 150 times a second
(the virtual amplifier's fastest output, ICR0, is 100/s) — the test itself runs through the
real :class:`Procedure` and :class:`Sampler`, the record is written as usual. A headless
Chromium (selenium, the system's chromium and chromedriver) opens the page, starts the test
through the form and watches it for ``--seconds``.

Printed figures:

* latency: for every redraw of the force–displacement plot, the page's clock at the draw
  minus the wall time the newest drawn sample was stamped (the sampler's stamp, on the
  same machine's clock) — median, 90th percentile and maximum, in ms;
* plot updates per second (redraws of the force–displacement plot) and samples per second;
* CPU share of the console process (user + system time from /proc over wall time), and of
  the browser's processes for comparison.

With ``--virtual`` the console runs the in-process virtual rig (real drivers over ptys, 100/s)
instead of the synthetic 150 Hz rig. No assertion: figures only.

Usage: python bench/console_latency.py [--seconds 20] [--virtual]
"""

from __future__ import annotations

import argparse
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

RATE_HZ = 150.0


class SyntheticRig:
    """A RigIO with a load cell read at 150 Hz and an encoder at 50 Hz; no furnace.

    Force: elastic (200 kN/mm) up to 10 kN, then hardening 5 kN/mm, crosshead 0.05 mm/s.
    """

    has_furnace = False
    can_drive = True
    max_temperature_C = float("inf")
    frame_stiffness_N_per_um = None
    max_force_N = 100e3

    def __init__(self, time_scale: float = 1.0):
        self.time_scale = time_scale
        self.loadcell_period_s = 1.0 / RATE_HZ
        self._clock = time.monotonic
        self._t_start = None
        self._lock = threading.Lock()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return None

    def _x_mm(self) -> float:
        with self._lock:
            return 0.0 if self._t_start is None else 0.05 * (self._clock() - self._t_start)

    def _force_N(self) -> float:
        x = self._x_mm()
        return 200e3 * x if x < 0.05 else 10e3 + 5e3 * (x - 0.05)

    def set_clock(self, clock) -> None:
        self._clock = clock

    def channels(self, clock, to_clock):
        from flowcurve.acquisition.sampler import Channel

        return {
            "force_N": Channel("synthetic load cell", self._force_N, clock, period_s=1.0 / RATE_HZ, silence_s=2.0),
            "crosshead_mm": Channel("synthetic encoder", self._x_mm, clock, period_s=0.02, silence_s=2.0),
        }

    def read_temperature_C(self) -> float:
        return 20.0

    def hold_temperature(self, setpoint_C: float) -> float:
        return 20.0

    def heater_off(self) -> None:
        return None

    def arm_watchdog(self) -> None:
        return None

    def host_ok(self) -> None:
        return None

    def tare(self) -> None:
        return None

    def start_crosshead(self, speed_mm_per_s: float, direction: int) -> None:
        with self._lock:
            self._t_start = self._clock()

    def stop_crosshead(self) -> None:
        with self._lock:
            self._t_start = None

    def post_test_measurements(self):
        return None


def serve(out: Path, port: int, virtual: bool) -> None:
    import uvicorn

    from flowcurve.console.server import Console, create_app

    if virtual:
        console = Console(out, time_scale=1.0)
    else:
        console = Console(out, open_rig=lambda scale: SyntheticRig(scale), rig_name="synthetic 150 Hz rig")
    uvicorn.run(create_app(console), host="127.0.0.1", port=port, log_level="warning")


def cpu_seconds(pids: list[int]) -> float:
    """user + system CPU seconds of these processes (from /proc/<pid>/stat)."""
    tick = os.sysconf("SC_CLK_TCK")
    total = 0.0
    for pid in pids:
        try:
            fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        except (FileNotFoundError, ProcessLookupError):
            continue
        total += (int(fields[11]) + int(fields[12])) / tick  # utime, stime
    return total


def children(pid: int) -> list[int]:
    out = [pid]
    for task in Path(f"/proc/{pid}/task").iterdir():
        try:
            kids = (task / "children").read_text().split()
        except FileNotFoundError:
            continue
        for kid in kids:
            out.extend(children(int(kid)))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=float, default=20.0, help="how long to watch the running test (default 20)")
    ap.add_argument("--virtual", action="store_true", help="the in-process virtual rig (100/s) instead of the synthetic 150 Hz rig")
    ap.add_argument("--serve", nargs=2, metavar=("OUT", "PORT"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.serve:
        serve(Path(args.serve[0]), int(args.serve[1]), args.virtual)
        return 0

    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    tmp = Path(tempfile.mkdtemp(prefix="console-bench-"))
    cmd = [sys.executable, __file__, "--serve", str(tmp / "out"), str(port)] + (["--virtual"] if args.virtual else [])
    server = subprocess.Popen(cmd)
    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium")
    for a in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu", "--window-size=1366,900"):
        options.add_argument(a)
    driver = None
    try:
        url = f"http://127.0.0.1:{port}/"
        for _ in range(200):
            try:
                socket.create_connection(("127.0.0.1", port), 0.2).close()
                break
            except OSError:
                time.sleep(0.1)
        driver = webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=options)
        driver.get(url)
        time.sleep(1.0)
        driver.find_element(By.NAME, "d0").send_keys("6")
        driver.find_element(By.NAME, "h0").send_keys("7")
        driver.find_element(By.NAME, "speed").send_keys("0.05")
        driver.find_element(By.ID, "btn-start").click()
        end = time.monotonic() + 30
        while driver.execute_script("return window.fcStats.fdPoints") < 10 and time.monotonic() < end:
            time.sleep(0.1)
        driver.execute_script("window.fcStats.latencies_ms = []; window.fcStats.fdDraws = 0;")
        browser_pids = children(driver.service.process.pid)
        cpu0, bcpu0, t0 = cpu_seconds(children(server.pid)), cpu_seconds(browser_pids), time.monotonic()
        n0 = int(driver.find_element(By.ID, "r-samples").text or 0)
        time.sleep(args.seconds)
        cpu1, bcpu1, t1 = cpu_seconds(children(server.pid)), cpu_seconds(browser_pids), time.monotonic()
        n1 = int(driver.find_element(By.ID, "r-samples").text or 0)
        stats = driver.execute_script("return window.fcStats")
        driver.find_element(By.ID, "btn-stop").click()
        time.sleep(1.0)
    finally:
        if driver is not None:
            driver.quit()
        server.terminate()
        server.wait(30)
    wall = t1 - t0
    lat = np.array(stats["latencies_ms"], dtype=float)
    rig = "virtual rig (real drivers over ptys, load cell 100/s)" if args.virtual else f"synthetic rig, load cell read at {RATE_HZ:g} Hz"
    print(f"console latency bench — {rig}, {wall:.1f} s watched, one headless Chromium page, {os.cpu_count()} CPUs (load avg {os.getloadavg()[0]:.1f})")
    print(f"  samples recorded: {(n1 - n0) / wall:.0f} /s")
    print(f"  force–displacement redraws: {stats['fdDraws'] / wall:.1f} /s")
    if lat.size:
        print(f"  latency sample stamped → drawn: median {np.median(lat):.0f} ms, 90th percentile {np.percentile(lat, 90):.0f} ms, "
              f"max {lat.max():.0f} ms ({lat.size} draws)")
    print(f"  CPU share of the console process: {100 * (cpu1 - cpu0) / wall:.1f} % of one core (test, record, server, events)")
    print(f"  CPU share of the browser (all its processes): {100 * (bcpu1 - bcpu0) / wall:.1f} % of one core")
    shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
