"""The console's live buffers: thinning keeps exactly every stride-th row, and a page that
follows the cursor holds what the server holds."""

from __future__ import annotations

import numpy as np

from flowcurve.acquisition.live import Snapshot
from flowcurve.console.live_state import ConsoleView, PlotBuffer


def test_thinned_buffer_is_every_stride_th_row_whatever_the_blocks():
    rng = np.random.default_rng(3)
    rows = np.arange(25_013, dtype=float)
    buf = PlotBuffer(limit=1000)
    start = 0
    while start < rows.size:
        n = int(rng.integers(0, 37))
        buf.extend(rows[start:start + n], -rows[start:start + n])
        start += n
    assert buf.stride == 32 and buf.generation == 5  # 25013 rows / 1000 → thinned five times
    assert buf.x == list(rows[::buf.stride]) and buf.y == list(-rows[::buf.stride])
    assert len(buf.x) < 1000


def test_a_page_following_the_cursor_ends_with_the_servers_points():
    view = ConsoleView(1, time_scale=10.0)
    view.force_displacement.limit = 300
    page_x: list[float] = []
    cursor = None
    t = 0.0
    for block in range(200):
        rows = np.column_stack([t + np.arange(7) * 0.01, np.arange(7) * 10.0 + block, np.arange(7) * 0.001 + block, np.full(7, 20.0)])
        t += 0.07
        view.show(Snapshot("recording", time_s=t + 0.02, rows=rows))
        if block % 3 == 0:
            points, cursor = view.points_since(cursor)
            page_x = (points["fd"]["x"] if points["fd"]["reset"] else page_x + points["fd"]["x"])
    points, cursor = view.points_since(cursor)
    page_x = points["fd"]["x"] if points["fd"]["reset"] else page_x + points["fd"]["x"]
    assert page_x == view.force_displacement.x
    assert view.force_displacement.generation >= 2


def test_the_newest_samples_wall_time_comes_from_its_age_on_the_test_clock():
    import time

    view = ConsoleView(1, time_scale=10.0)
    rows = np.array([[4.0, 100.0, 0.1, 20.0], [4.5, 110.0, 0.2, 20.0]])
    before = time.time()
    view.show(Snapshot("recording", time_s=5.0, rows=rows))  # the last row is 0.5 test s = 0.05 wall s old
    after = time.time()
    assert before - 0.05 <= view.last_sample_epoch_s <= after - 0.05
    points, _ = view.points_since(None)
    assert points["last_sample_epoch_s"] == view.last_sample_epoch_s and points["fd"]["x"] == [0.1, 0.2]


def test_done_keeps_the_last_readings_and_the_heater_shows_the_relay_once_ended():
    relay = {"on": True}
    view = ConsoleView(1, heater=lambda: relay["on"], heater_window_s=60.0)
    view.show(Snapshot("recording", time_s=5.0, force_N=1234.0, crosshead_mm=0.5, temperature_C=300.0))
    relay["on"] = False
    assert view.status()["heater"] == "on"  # within the controller's window while the test runs
    view.show(Snapshot("done", time_s=6.0, samples=10))
    assert view.status()["state"] == "stopping"  # the procedure's end: "done" comes from the runner, with the outcome
    view.set_state("complete")
    status = view.status()
    assert status["heater"] == "off"  # ended: the relay itself
    assert (status["force_N"], status["crosshead_mm"], status["time_s"]) == (1234.0, 0.5, 6.0)
    assert ConsoleView(2).status()["heater"] == "none"  # no furnace


def test_the_heater_shows_on_throughout_heating_even_between_the_relays_pulses():
    """At time scale 60 the relay pulses within 33 ms: the badge read "off" in 4 of 8 looks while heating."""
    relay = {"on": False}
    view = ConsoleView(1, heater=lambda: relay["on"], heater_window_s=0.0)
    view.show(Snapshot("heating", time_s=1.0, temperature_C=25.0, progress=0.02))
    assert view.status()["heater"] == "on"  # the controller is driving it, the relay between pulses
    view.show(Snapshot("soaking", time_s=2.0, temperature_C=300.0, progress=1.0))
    assert view.status()["heater"] == "off"  # holding: the relay itself (within its window)
    view.set_state("aborted")
    assert view.status()["heater"] == "off"
