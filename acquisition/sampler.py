"""Synchronized sampling: one worker thread per device, one clock, rows on the force clock.

Each device is read in its own thread at its own rate (:class:`Channel`). Every sample is
stamped on the test clock relative to the test start (one clock for all); the channels pace
themselves and watch for silence on a :class:`flowcurve.clock.Clock` (the wall clock on a
real rig, a model clock in the fast tests). The
load cell is the fastest channel and the reference: :func:`merge_block` turns each force
sample into exactly one record row, with the other channels **linearly interpolated** at
the force sample's time from their own streams. A force sample is released only once every
other stream has a sample at or after its time (so nothing is extrapolated); at the end of
the test the remaining ones are released with the last value held ("latest-before").
Before a stream's first sample its first value is held (the crosshead has not moved yet).

A device whose reads fail ``max_failures`` times in a row (a :class:`DeviceError` or a
port's ``OSError``/``SerialException``), or that gives nothing for ``silence_s``, puts the
sampler in a fault state naming the device; the procedure stops the test (heater off) and
keeps what was recorded. Any other exception from a read is a bug, not a device failure: it
is not retried, and faults the sampler at once with an :class:`InternalError`.
"""

from __future__ import annotations

import logging
import threading
from dataclasses import dataclass, field
from typing import Callable, Iterable, Sequence

import numpy as np

from flowcurve.acquisition.plausibility import ImplausibleReadings
from flowcurve.clock import WALL, Clock
from flowcurve.errors import DeviceError, FlowcurveError, InternalError, SafetyError

logger = logging.getLogger(__name__)

# what a failing device raises: the drivers' errors, a vanished port (SerialException is an OSError)
DEVICE_FAILURES = (DeviceError, OSError)
GAP_FACTOR = 3.0  # an interval between a polled stream's readings wider than this × its median one is a gap
SPEED_WINDOW = 16  # readings before a gap that give the crosshead's speed (quantized counts: a long baseline)

# A read function returns one value (stamped at the middle of the read: its request and reply
# bracket it), a list of values (a streamed block; each is stamped when the block arrives,
# spaced by ``spacing_s`` backwards), or a list of (t, value) pairs already stamped on the
# sampler's clock (the load cell's stream: on its own rhythm, rig.loadcell.stream_stamps).
ReadFn = Callable[[], "float | Sequence[float] | Sequence[tuple[float, float]] | None"]


@dataclass
class Stream:
    """A growing, thread-safe series of (time_s, value) samples of one channel."""

    name: str
    _t: list[float] = field(default_factory=list)
    _v: list[float] = field(default_factory=list)
    _lock: threading.Lock = field(default_factory=threading.Lock)

    def extend(self, times: Iterable[float], values: Iterable[float]) -> None:
        """Append the readings (``times`` s, ``values``)."""
        times, values = list(times), list(values)
        with self._lock:
            self._t.extend(times)
            self._v.extend(values)

    def snapshot(self, start: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """Copies of the samples from index ``start`` on."""
        with self._lock:
            return np.array(self._t[start:], dtype=float), np.array(self._v[start:], dtype=float)

    def __len__(self) -> int:
        with self._lock:
            return len(self._t)

    def last(self) -> tuple[float, float] | None:
        """The last (time, value), or None before the first reading."""
        with self._lock:
            return (self._t[-1], self._v[-1]) if self._t else None

    def last_time(self) -> float:
        """The last reading's time, s (-inf before the first)."""
        with self._lock:
            return self._t[-1] if self._t else -np.inf


def interpolate_at(t: np.ndarray, ts: np.ndarray, vs: np.ndarray, *, hold_ends: bool = False) -> np.ndarray:
    """Linear interpolation of the stream (ts, vs) at times t; NaN if empty. Its ends are held for
    GAP_FACTOR × its median interval (a poll due but not yet read), no further: a stream that stopped
    answering (a silent furnace) leaves the rows after it unread, not its last value repeated.
    ``hold_ends``: held however far (a crosshead stands after its last reading at a stop)."""
    if ts.size == 0:
        return np.full(t.shape, np.nan)
    out = np.interp(t, ts, vs)  # holds the first/last value outside the stream
    if ts.size >= 4 and not hold_ends:
        reach = GAP_FACTOR * float(np.median(np.diff(ts)))
        out[(t > ts[-1] + reach) | (t < ts[0] - reach)] = np.nan
    return out


def releasable(force_t: np.ndarray, other_last_t: Sequence[float], final: bool) -> int:
    """How many leading force samples every other stream already brackets (all at the end)."""
    if final or not len(other_last_t):
        return force_t.size
    horizon = min(other_last_t)
    return int(np.searchsorted(force_t, horizon, side="right"))


def speed_before(ts: np.ndarray, vs: np.ndarray, j: int, window: int = SPEED_WINDOW) -> float:
    """The stream's least-squares slope over its readings up to index ``j`` (at most ``window``
    back); NaN with fewer than 3 readings."""
    lo = max(0, j - window)
    if j - lo < 2:
        return float("nan")
    t, v = ts[lo:j + 1], vs[lo:j + 1]
    tc = t - t.mean()
    return float(np.dot(tc, v - v.mean()) / np.dot(tc, tc))  # slope = Σ(t−t̄)(v−v̄) / Σ(t−t̄)²


def is_gap(ts: np.ndarray) -> np.ndarray:
    """For each interval between readings: wider than GAP_FACTOR × the stream's median interval
    (a retried or lost poll) — one entry per ``np.diff(ts)``; none with fewer than 4 readings."""
    dt = np.diff(ts)
    if dt.size < 3:
        return np.zeros(dt.shape, dtype=bool)
    return dt > GAP_FACTOR * np.median(dt)


def run_or_stand_at(t: np.ndarray, ts: np.ndarray, vs: np.ndarray) -> np.ndarray:
    """A crosshead stream at times ``t``: linear between its readings, except across a gap
    (:func:`is_gap`) that it crossed slower than it ran before: there it runs on at its speed
    before the gap and then stands at the reading after it — a crosshead moves at its speed or
    stands, so a stop inside the gap is not smeared over it. x(t) = x0 + sign(Δ)·min(|v|(t − t0), |Δ|)."""
    out = interpolate_at(t, ts, vs, hold_ends=True)
    for j in np.flatnonzero(is_gap(ts)):
        delta, span = vs[j + 1] - vs[j], ts[j + 1] - ts[j]
        v = speed_before(ts, vs, j)
        if not (v * delta > 0 and abs(v) * span > abs(delta)):  # as fast as before (or no speed known): linear
            continue
        inside = (t > ts[j]) & (t < ts[j + 1])
        out[inside] = vs[j] + np.sign(delta) * np.minimum(abs(v) * (t[inside] - ts[j]), abs(delta))
    return out


def merge_block(force_t: np.ndarray, force: np.ndarray, others: Sequence[tuple[np.ndarray, np.ndarray]],
                stands: Sequence[bool] = ()) -> np.ndarray:
    """Rows ``[time_s, force, other_1, ...]``: one per force sample, others interpolated
    (:func:`run_or_stand_at` for the streams flagged in ``stands``, e.g. the crosshead)."""
    flags = list(stands) + [False] * (len(others) - len(stands))
    cols = [force_t, force] + [(run_or_stand_at if flag else interpolate_at)(force_t, ts, vs)
                               for (ts, vs), flag in zip(others, flags)]
    return np.column_stack(cols) if force_t.size else np.empty((0, len(cols)))


class Channel(threading.Thread):
    """Reads one device in its own thread and appends stamped samples to its stream.

    ``clock`` stamps the samples (test seconds); the pacing ``period_s`` and the
    ``silence_s`` fault limit are host seconds on ``timebase`` (the wall clock on a real
    rig), so a time-scaled virtual rig does not change how patient the host is. Values returned as a
    bare list are stamped ``spacing_s`` (clock units) apart, ending at the arrival time.
    ``stands``: the value runs at a steady speed or stands (the crosshead): the rows cross a gap in
    its readings with :func:`run_or_stand_at`, not a straight line. ``heard``: the count of readings
    the device gave, including those its driver holds back a while (rig.loadcell's deferred gap rule);
    ``flush``: returns those at the stop.
    """

    def __init__(self, name: str, read: ReadFn, clock: Callable[[], float], *, period_s: float = 0.0, spacing_s: float = 0.0, max_failures: int = 3, silence_s: float = 2.0, on_fault: Callable[[str, str, Exception | None], None] | None = None, timebase: Clock = WALL, stands: bool = False, heard: Callable[[], int] | None = None, flush: ReadFn | None = None):
        super().__init__(name=f"flowcurve-{name}", daemon=True)
        self.heard = heard  # frames the device has sent so far, returned or held back by its driver (a held frame is no silence)
        self.flush = flush  # at the stop: what the driver still holds
        self.timebase = timebase
        self.device = name
        self.read = read
        self.clock = clock
        self.period_s = period_s
        self.spacing_s = spacing_s
        self.stands = stands
        self.max_failures = max_failures
        self.silence_s = silence_s
        self.on_fault = on_fault
        self.stream = Stream(name)
        self.guard = None  # an acquisition.plausibility.RateGuard: impossible readings rejected
        self.last_error: str | None = None  # the last failed read (for a silence fault's message)
        self.failing = 0  # reads failed in a row since the last one that answered
        self.half_width_s = 0.0  # the widest bracket (request .. reply) of a bare value's stamp, clock units
        self.reads = 0
        self.last_data_wall_s = timebase.now()
        self.error: str | None = None
        self._heard_count: int | None = None
        self._stop_event = threading.Event()

    def stop(self) -> None:
        """Ask the channel's thread to stop."""
        self._stop_event.set()
        self.timebase.notify()

    def run(self) -> None:
        """The channel's thread: read the device on its period into the stream until stopped or failed."""
        tb = self.timebase
        failures = 0
        self.last_data_wall_s = tb.now()
        next_due = tb.now()
        while not self._stop_event.is_set():
            asked = self.clock()  # a polled reading lies between its request and its reply
            try:
                got = self.read()
            except SafetyError as exc:  # over-temperature, open thermocouple: stop at once
                self._fault(str(exc), exc)
                return
            except DEVICE_FAILURES as exc:  # count it, then give up
                failures += 1
                self.failing = failures
                self.last_error = _one_line(exc)
                logger.debug("%s: read %d failed: %s", self.device, failures, _one_line(exc))
                if failures >= self.max_failures:
                    self._fault(f"{failures} reads in a row failed; last: {_one_line(exc)}", exc if isinstance(exc, DeviceError) else None)
                    return
                continue
            except Exception as exc:  # a bug in the read code: no retry, stop the test safely
                logger.debug("%s: internal error while reading", self.device, exc_info=True)  # -vv: the traceback
                self._fault(f"internal error: {_one_line(exc)}",
                            InternalError(f"{self.device}: internal error while reading: {_one_line(exc)} "
                                          f"(a bug in flowcurve, please report it; -vv shows the traceback)"))
                return
            failures = self.failing = 0
            try:
                n = self._store(got, self.clock(), asked)
            except ImplausibleReadings as exc:  # readings no machine makes, again and again
                self._fault(str(exc), exc)
                return
            wall = tb.now()
            heard = self.heard() if self.heard is not None else None
            if heard is not None and heard != self._heard_count:
                self._heard_count = heard
                self.last_data_wall_s = wall  # the device answers; its driver holds the readings a while
            if n:
                self.last_data_wall_s = wall
                self.reads += 1
            elif wall - self.last_data_wall_s > self.silence_s:
                self._fault(f"no data for {wall - self.last_data_wall_s:.1f} s")
                return
            if self.period_s > 0:
                next_due += self.period_s
                delay = next_due - tb.now()
                if delay > 0:
                    tb.wait(self._stop_event, delay)
                else:
                    next_due = tb.now()
        if self.flush is not None and self.error is None:  # what the driver held back
            try:
                self._store(self.flush(), self.clock())
            except (ImplausibleReadings, *DEVICE_FAILURES) as exc:
                logger.debug("%s: flushing the held readings failed: %s", self.device, _one_line(exc))
        if self.guard is not None and self.error is None:  # a fall held for its next sample passes
            held = self.guard.flush()
            self.stream.extend([p[0] for p in held], [p[1] for p in held])

    def _store(self, got, now: float, asked: float | None = None) -> int:
        """Stamp and keep what a read returned (through the guard); how many values came. A bare
        value is stamped at the middle of its read (``asked`` .. ``now``: the request and the reply
        bracket it; the largest half-width is kept in :attr:`half_width_s`)."""
        if got is None:
            return 0
        if np.isscalar(got):
            asked = now if asked is None else min(asked, now)
            self.half_width_s = max(self.half_width_s, 0.5 * (now - asked))
            pairs = [(0.5 * (asked + now), float(got))]
        else:
            items = list(got)
            if not items:
                return 0
            if isinstance(items[0], tuple):
                pairs = [(p[0], float(p[1])) for p in items]
            else:
                k = len(items)
                pairs = [(now - (k - 1 - i) * self.spacing_s, float(v)) for i, v in enumerate(items)]
        kept = self.guard.feed(pairs) if self.guard is not None else pairs
        self.stream.extend([p[0] for p in kept], [p[1] for p in kept])
        return len(pairs)

    def _fault(self, message: str, error: Exception | None = None) -> None:
        self.error = message
        logger.info("%s: fault: %s", self.device, message)  # the procedure reports it to the operator
        if self.on_fault:
            self.on_fault(self.device, message, error)


def _one_line(exc: BaseException) -> str:
    """An exception as one readable line (errno-style ``(5, 'Input/output error')`` unpacked)."""
    args = getattr(exc, "args", ())
    if len(args) == 2 and isinstance(args[0], int) and isinstance(args[1], str):
        return f"{args[1]} (errno {args[0]})"
    text = " ".join(str(exc).split())
    if isinstance(exc, DeviceError):
        return text
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


class Sampler:
    """Runs the channels and merges their streams on the reference (force) channel.

    ``channels`` maps column name → Channel; the first one is the reference. Use
    :meth:`take_rows` periodically to get the newly complete rows, and :meth:`finish`
    at the end to stop the threads and get the rest.
    """

    def __init__(self, channels: dict[str, Channel]):
        if not channels:
            raise ValueError("a sampler needs at least the force channel")
        self.channels = channels
        self.columns = list(channels)
        self._ref = channels[self.columns[0]]
        self._others = [channels[c] for c in self.columns[1:]]
        self._released = 0
        self._other_start = [0] * len(self._others)
        self._fault: FlowcurveError | None = None
        self._fault_lock = threading.Lock()
        for ch in channels.values():
            ch.on_fault = self._on_fault

    @property
    def row_columns(self) -> list[str]:
        """Column names of the rows :meth:`take_rows` returns: time_s, then the channels."""
        return ["time_s", *self.columns]

    def _on_fault(self, device: str, message: str, error: Exception | None = None) -> None:
        with self._fault_lock:
            if self._fault is None:
                self._fault = error if isinstance(error, (DeviceError, InternalError)) else DeviceError(device, message)

    @property
    def fault(self) -> FlowcurveError | None:
        """The first device failure (or internal error), or None."""
        return self._fault

    @property
    def released(self) -> int:
        """The rows released so far."""
        return self._released

    def start(self) -> "Sampler":
        """Start every channel's thread; the sampler."""
        # on a model clock, time waits for every channel (and the caller) to take part:
        # a channel started first must not run ahead while the others start
        for ch in self.channels.values():
            ch.timebase.enlist(threading.current_thread())
            ch.timebase.enlist(ch)
        for ch in self.channels.values():
            ch.start()
        return self

    def take_rows(self, final: bool = False) -> np.ndarray:
        """Rows for the force samples not yet released that all streams now bracket."""
        ft, fv = self._ref.stream.snapshot(self._released)
        n = releasable(ft, [ch.stream.last_time() for ch in self._others], final)
        if n == 0:
            return np.empty((0, len(self.columns) + 1))
        others = [ch.stream.snapshot(start) for ch, start in zip(self._others, self._other_start)]
        rows = merge_block(ft[:n], fv[:n], others, [ch.stands for ch in self._others])
        self._released += n
        # keep only the stream tails the next force samples can need (one sample before, and the
        # SPEED_WINDOW before it that give the speed before a gap)
        for i, (ts, _) in enumerate(others):
            self._other_start[i] += max(0, int(np.searchsorted(ts, ft[n - 1], side="right")) - 1 - SPEED_WINDOW)
        return rows

    def check_silence(self) -> FlowcurveError | None:
        """Fault a channel whose read hangs (no data for its ``silence_s``); the first fault."""
        for ch in self.channels.values():
            now = ch.timebase.now()
            if ch.is_alive() and now - ch.last_data_wall_s > ch.silence_s:
                last = f" (last: {ch.last_error})" if ch.last_error else ""
                self._on_fault(ch.device, f"no answer for {now - ch.last_data_wall_s:.1f} s{last}")
        return self._fault

    def failing_at_end(self) -> FlowcurveError | None:
        """At the end of recording: a channel whose latest reads all failed (not one answered since)
        left the record's end without its values — a fault naming the device, as a silence is, even
        when the test ended before the channel's silence limit (a compressed time scale)."""
        for ch in list(self.channels.values())[1:]:
            if ch.failing:
                self._on_fault(ch.device, f"no answer since {ch.last_data_wall_s:.1f} s (host) when the test ended: "
                                          f"{ch.failing} reads failed in a row (last: {ch.last_error})")
        return self._fault

    def request_stop(self) -> None:
        """Ask every channel to stop after its current read (does not wait)."""
        for ch in self.channels.values():
            ch.stop()

    def stop(self, timeout_s: float = 2.0) -> None:
        """Stop the channels and wait up to ``timeout_s`` for each."""
        self.request_stop()
        for ch in self.channels.values():
            if ch.is_alive() and ch is not threading.current_thread():
                with ch.timebase.idle():  # a channel may finish its read on the clock first
                    ch.join(timeout_s)

    def finish(self) -> np.ndarray:
        """Stop the threads and release every remaining force sample (last values held)."""
        self.stop()
        return self.take_rows(final=True)

    def latest(self) -> dict[str, float]:
        """The newest value of each channel (for the live view); NaN when none yet."""
        out = {}
        for name, ch in self.channels.items():
            last = ch.stream.last()
            out[name] = last[1] if last else float("nan")
        return out
