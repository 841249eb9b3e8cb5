"""What the page shows of a running test, kept by the server: state, readings, plot points.

:class:`ConsoleView` stands where ``flowcurve run`` puts its terminal :class:`LiveView`: the
procedure calls ``show(snapshot)`` about twenty times a second from its own thread. The view
keeps the state, the latest readings and the points of the two live plots (force against
crosshead displacement, temperature against test time) and wakes the pages that listen.

The plot buffers keep every record row until they hold :data:`MAX_POINTS`; then every second
point is dropped and only every ``stride``-th row is kept from there on (the page redraws from
the start when that happens), so a long test never grows the page's data without bound.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

# set by the console's runner only, once the test's outcome is known: each its own word (and colour on the page)
COMPLETE_STATE, ABORTED_STATE, FAILED_STATE = "complete", "aborted", "failed"
ENDED_STATES = (COMPLETE_STATE, ABORTED_STATE, FAILED_STATE)
PROCEDURE_ENDED = ("done", "fault")  # the procedure's own last snapshot: shown as "stopping" until the runner's state
STOPPING_STATE = "stopping"  # the procedure has ended, the runner is releasing the rig and taking the outcome
MAX_POINTS = 20_000  # per plot, before thinning
COLUMN_FORCE, COLUMN_CROSSHEAD = 1, 2  # record rows: time_s, force_N, crosshead_mm[, temperature_C]


@dataclass
class PlotBuffer:
    """Two growing columns, thinned by two when they reach ``limit``; ``generation`` counts thinnings."""

    limit: int = MAX_POINTS
    x: list[float] = field(default_factory=list)
    y: list[float] = field(default_factory=list)
    stride: int = 1
    generation: int = 0
    _seen: int = 0  # rows offered so far; row i is kept when i is a multiple of the stride

    def extend(self, xs: np.ndarray, ys: np.ndarray) -> None:
        """Add the rows of ``xs``, ``ys`` that fall on the buffer's stride."""
        first = (-self._seen) % self.stride  # the first row of this block on the stride
        self.x.extend(float(v) for v in xs[first::self.stride])
        self.y.extend(float(v) for v in ys[first::self.stride])
        self._seen += len(xs)
        if len(self.x) >= self.limit:  # kept rows are 0, s, 2s, …: every second one is on 2s
            self.x, self.y = self.x[::2], self.y[::2]
            self.stride *= 2
            self.generation += 1

    def since(self, generation: int, count: int) -> tuple[int, list[float], list[float], bool]:
        """(new count, xs, ys, reset): the points after ``count``, or all of them after a thinning."""
        if generation != self.generation or count > len(self.x):
            return len(self.x), list(self.x), list(self.y), True
        return len(self.x), self.x[count:], self.y[count:], False


def _finite(value) -> float | None:
    return float(value) if value is not None and math.isfinite(value) else None


class ConsoleView:
    """The procedure's view for the console (``show``/``say`` like LiveView), thread-safe.

    heater: returns True/False for the heater relay, None when the rig has no furnace.
    """

    def __init__(self, test_id: int, heater: Callable[[], bool | None] | None = None, time_scale: float = 1.0, heater_window_s: float = 0.0):
        self.test_id = test_id
        self.time_scale = time_scale  # test seconds per wall second
        # the furnace controller switches the relay on for a share of each control period:
        # the heater shows "on" while the relay was on within this many wall seconds
        self.heater_window_s = heater_window_s
        self._heater_on_wall_s: float | None = None
        self.heater = heater or (lambda: None)
        self.lock = threading.Lock()
        self.state = "starting"
        self.message = ""
        self.readings: dict[str, float | None] = {"time_s": 0.0, "force_N": None, "crosshead_mm": None, "temperature_C": None, "rate_per_s": None}
        self.samples = 0
        self.progress: float | None = None
        self.messages: list[str] = []
        self.force_displacement = PlotBuffer()
        self.temperature_time = PlotBuffer()
        self.last_sample_epoch_s: float | None = None  # wall time (epoch) the newest plotted sample was stamped
        self.readings_wall_s = time.monotonic()  # when the procedure last showed readings (their age goes to the page)
        self._listeners: set[Callable[[], None]] = set()

    # the procedure's side --------------------------------------------------------------------
    def _heater_state(self, ended: bool) -> bool | None:
        """The relay now; while the test runs, on if it was on within the controller's window, and
        on throughout "heating" (the controller is driving it up; between its pulses the relay rests)."""
        now_on = self.heater()
        if now_on is None:
            return None
        now = time.monotonic()
        if now_on:
            self._heater_on_wall_s = now
        if ended:
            return now_on
        return now_on or self.state == "heating" or (self._heater_on_wall_s is not None and now - self._heater_on_wall_s < self.heater_window_s)

    def show(self, s, force: bool = False) -> None:
        """Take the procedure's snapshot ``s`` as the pages' state (the procedure's LiveView call)."""
        self._heater_state(ended=False)  # catch the short on-pulses between the pages' looks
        with self.lock:
            # the procedure's "done" comes before the rig is released and its outcome returned:
            # the page hears "complete", "aborted" or "failed" from the runner, with the outcome (runner._end)
            self.state = STOPPING_STATE if s.state in PROCEDURE_ENDED else s.state
            self.message = s.message
            self.progress = s.progress
            self.samples = max(self.samples, int(s.samples or 0))
            readings = {
                "time_s": _finite(s.time_s), "force_N": _finite(s.force_N), "crosshead_mm": _finite(s.crosshead_mm),
                "temperature_C": _finite(s.temperature_C), "rate_per_s": _finite(s.rate_per_s),
            }
            if s.state in ("done", "tare"):  # these snapshots carry no readings: the last ones stay on show
                readings = {**self.readings, "time_s": readings["time_s"]}
            else:
                self.readings_wall_s = time.monotonic()
            self.readings = readings
            rows = getattr(s, "rows", None)
            if rows is not None and len(rows):
                self.force_displacement.extend(rows[:, COLUMN_CROSSHEAD], rows[:, COLUMN_FORCE])
                if rows.shape[1] > 3:
                    self.temperature_time.extend(rows[:, 0], rows[:, 3])
                # the row's stamp is test time; the snapshot's time_s is the procedure's clock now
                self.last_sample_epoch_s = time.time() - (float(s.time_s) - float(rows[-1, 0])) / self.time_scale
            elif s.state in ("heating", "soaking") and math.isfinite(s.temperature_C):
                self.temperature_time.extend(np.array([s.time_s]), np.array([s.temperature_C]))
        self._notify()

    def say(self, text: str) -> None:
        """Add a message for the pages."""
        with self.lock:
            self.messages.append(text)
        self._notify()

    # the server's side -----------------------------------------------------------------------
    def set_state(self, state: str, message: str = "") -> None:
        """Set the run's ``state`` and its ``message``."""
        with self.lock:
            self.state, self.message = state, message
        self._notify()

    def listen(self, wake: Callable[[], None]) -> Callable[[], None]:
        """Call ``wake`` (from any thread) on every change; returns the function that stops it."""
        with self.lock:
            self._listeners.add(wake)
        return lambda: self._forget(wake)

    def _forget(self, wake) -> None:
        with self.lock:
            self._listeners.discard(wake)

    def _notify(self) -> None:
        with self.lock:
            listeners = list(self._listeners)
        for wake in listeners:
            wake()

    def status(self) -> dict:
        """The state and readings as JSON-ready values (heater included)."""
        heater = self._heater_state(ended=self.state in ENDED_STATES)
        with self.lock:
            return {
                "test_id": self.test_id,
                "state": self.state,
                "message": self.message,
                "heater": "none" if heater is None else ("on" if heater else "off"),
                "samples": self.samples,
                "progress": self.progress,
                "messages": list(self.messages[-5:]),
                **self.readings,
                # wall seconds since the readings were taken: the page marks them stale once they stop
                # updating (after the test, the rig is released and nothing reads the furnace any more)
                "readings_age_s": round(time.monotonic() - self.readings_wall_s, 2),
                "time_scale": self.time_scale,
            }

    def points_since(self, cursor: dict | None) -> tuple[dict, dict]:
        """The plot points the page does not have yet, and the page's new cursor."""
        cursor = cursor or {}
        out: dict = {"test_id": self.test_id}
        new_cursor: dict = {}
        with self.lock:
            for name, buf in (("fd", self.force_displacement), ("tt", self.temperature_time)):
                gen, count = cursor.get(name, (-1, 0))
                n, xs, ys, reset = buf.since(gen, count)
                out[name] = {"x": xs, "y": ys, "reset": reset}
                new_cursor[name] = (buf.generation, n)
            if out["fd"]["x"]:
                out["last_sample_epoch_s"] = self.last_sample_epoch_s
        return out, new_cursor
