"""Time for the rig, the acquisition and the virtual devices: the wall clock or a model clock.

Everything that waits or measures time in the acquisition path (the procedure's loop, the
sampler's channels, the serial transport's deadlines, the virtual devices' output periods
and watchdogs) asks a :class:`Clock` instead of :mod:`time`:

* :data:`WALL` (:class:`WallClock`) is :func:`time.monotonic` and real waits — what a real
  test and the pty-based virtual rig run on, exactly as before;
* :class:`ModelClock` is simulated time for the tests: it stands still while any thread that
  takes part in it is working, and jumps to the next deadline once every such thread waits
  (a discrete-event simulation), so a 30-minute virtual test costs only its computing time.
  A test may also move it by hand with :meth:`ModelClock.advance`.

A thread takes part in a model clock from its first wait on it (or from :meth:`enlist`, for
a thread about to start) until it ends. A waiter whose event was set (a reply arrived) acts at
that time before time moves on: the runs are repeatable to the sample. A thread that
blocks on something another thread's clock wait will release (a port's lock) says so with
``with clock.idle(): lock.acquire()``. One that blocks elsewhere unannounced would stop time
for good, so when nothing has happened for ``stall_s`` of wall time while the process was
(nearly) idle — it used under ``STALL_CPU_FRACTION`` of that time on the CPU — the clock moves on
to the next deadline anyway. A thread that is still computing, however slowly on a loaded
machine, holds time (so a run's samples fall at the same model times on a busy machine as on an
idle one) up to ``hard_stall_s`` of wall time, after which time moves on regardless.
"""

from __future__ import annotations

import heapq
import itertools
import math
import threading
import time
from contextlib import contextmanager, nullcontext
from typing import Callable, ContextManager, Protocol


class Clock(Protocol):
    """Monotonic seconds, waits and timers (see the module docstring)."""

    def now(self) -> float:
        """Monotonic time now, s."""
    def sleep(self, seconds: float) -> None:
        """Wait ``seconds`` on this clock."""
    def wait(self, event: threading.Event, timeout: float | None = None) -> bool:
        """Wait until ``event`` is set or ``timeout`` s pass on this clock; whether it was set."""
    def notify(self) -> None:
        """Wake the waiters to look at their events again (an event was set)."""
    def call_at(self, when: float, callback: Callable[[], None]) -> "Timer":
        """Run ``callback`` at time ``when`` on this clock; the Timer (cancel it to drop the call)."""
    def idle(self) -> ContextManager[None]:
        """A context in which the calling thread blocks on something another thread's wait will release."""
    def enlist(self, thread: threading.Thread) -> None:
        """Make ``thread`` take part in the clock before it starts."""


class Timer:
    """A callback scheduled on a clock; :meth:`cancel` before it runs to drop it."""

    def __init__(self, when: float, callback: Callable[[], None]):
        self.when = when
        self.callback = callback
        self.cancelled = False
        self._thread: threading.Timer | None = None

    def cancel(self) -> None:
        """Drop the callback if it has not run yet."""
        self.cancelled = True
        if self._thread is not None:
            self._thread.cancel()


class WallClock:
    """Real time: :func:`time.monotonic`, real sleeps, timers on threads."""

    def now(self) -> float:
        """:func:`time.monotonic`, s."""
        return time.monotonic()

    def sleep(self, seconds: float) -> None:
        """:func:`time.sleep` for ``seconds`` (none when not positive)."""
        if seconds > 0:
            time.sleep(seconds)

    def wait(self, event: threading.Event, timeout: float | None = None) -> bool:
        """``event.wait(timeout)``: whether the event was set."""
        return event.wait(timeout)

    def notify(self) -> None:
        """Nothing to do: threading.Event wakes its waiters itself."""

    def idle(self) -> ContextManager[None]:
        """A null context: the wall clock moves on while a thread blocks."""
        return nullcontext()

    def enlist(self, thread: threading.Thread) -> None:
        """Nothing to do: real time does not wait for anyone."""

    def call_at(self, when: float, callback: Callable[[], None]) -> Timer:
        """A :class:`Timer` firing ``callback`` at monotonic time ``when`` on a timer thread."""
        timer = Timer(when, callback)

        def fire() -> None:
            """Call the callback unless the timer was cancelled."""
            if not timer.cancelled:
                callback()

        timer._thread = threading.Timer(max(0.0, when - time.monotonic()), fire)
        timer._thread.daemon = True
        timer._thread.start()
        return timer

    def __repr__(self) -> str:
        return "WallClock()"


WALL = WallClock()

STALL_CPU_FRACTION = 0.05  # below this share of one core over the stall, no thread is computing: one is blocked


class ModelClock:
    """Simulated seconds that move only when every participating thread waits (or by hand).

    ``auto=False`` leaves time entirely to :meth:`advance` (the test's hand on the clock).
    """

    def __init__(self, start_s: float = 0.0, *, auto: bool = True, stall_s: float = 0.25, hard_stall_s: float = 5.0):
        self._now = float(start_s)
        self.auto = auto
        self.stall_s = stall_s
        self.hard_stall_s = max(hard_stall_s, stall_s)
        self.stalls = 0  # times time moved on because a participant was stuck (diagnostics)
        self._cond = threading.Condition(threading.Lock())
        self._advancing = threading.Lock()  # one thread runs timers at a time, in order
        self._timers: list[tuple[float, int, Timer]] = []
        self._seq = itertools.count()
        self._actors: set[threading.Thread] = set()
        self._waiting: dict[threading.Thread, float] = {}
        self._events: dict[threading.Thread, threading.Event] = {}  # what a waiter waits for besides its deadline
        self._progress_wall = time.monotonic()
        self._progress_cpu = time.process_time()

    def __repr__(self) -> str:
        return f"ModelClock(now={self._now:.6f})"

    # -- reading and moving time ------------------------------------------------------------
    def now(self) -> float:
        """The model time now, s."""
        return self._now

    def advance(self, seconds: float) -> None:
        """Move time forward by ``seconds``, running the timers due on the way, in order."""
        if seconds < 0:
            raise ValueError("time runs forward only")
        self.advance_to(self._now + seconds)

    def advance_to(self, when: float) -> None:
        """Move time to ``when`` (no-op if it is not later), running the timers due on the way."""
        with self._advancing:
            while True:
                with self._cond:
                    timer = None
                    while self._timers and self._timers[0][0] <= when:
                        _, _, candidate = heapq.heappop(self._timers)
                        if not candidate.cancelled:
                            timer = candidate
                            break
                    if timer is None:
                        if when > self._now:
                            self._now = when
                        self._progressed()
                        return
                    if timer.when > self._now:
                        self._now = timer.when
                    self._progressed()
                timer.callback()  # outside the lock: it may schedule timers or notify

    def call_at(self, when: float, callback: Callable[[], None]) -> Timer:
        """Run ``callback`` when the clock reaches ``when`` (in the thread that moves it; a
        callback must not wait on the clock)."""
        timer = Timer(when, callback)
        with self._cond:
            heapq.heappush(self._timers, (when, next(self._seq), timer))
            self._cond.notify_all()  # a waiter may now have an earlier deadline to jump to
        return timer

    def notify(self) -> None:
        """Wake the waiters to look at their events again (call after setting one)."""
        with self._cond:
            self._progressed()

    # -- waiting ------------------------------------------------------------------------------
    def enlist(self, thread: threading.Thread) -> None:
        """Count ``thread`` (about to start) as taking part from now: time waits for it to
        reach its first wait instead of running ahead while it starts."""
        with self._cond:
            self._actors.add(thread)

    @contextmanager
    def idle(self):
        """The calling thread blocks on something (a lock) that only the clock's other
        threads can release: time may move on without it meanwhile."""
        me = threading.current_thread()
        with self._cond:
            self._actors.add(me)
            self._waiting[me] = math.inf
            self._cond.notify_all()  # the others may now be all that is left: one of them jumps
        try:
            yield
        finally:
            with self._cond:
                del self._waiting[me]

    def sleep(self, seconds: float) -> None:
        """Wait ``seconds`` of model time."""
        self.wait_until(self._now + max(0.0, seconds))

    def wait(self, event: threading.Event, timeout: float | None = None) -> bool:
        """Like :meth:`threading.Event.wait` on this clock: True once ``event`` is set."""
        deadline = math.inf if timeout is None else self._now + max(0.0, timeout)
        return self.wait_until(deadline, event)

    def wait_until(self, deadline: float, event: threading.Event | None = None) -> bool:
        """Block until the clock reaches ``deadline`` (False) or ``event`` is set (True)."""
        me = threading.current_thread()
        while True:
            jump = None
            with self._cond:
                self._actors.add(me)
                if event is not None and event.is_set():
                    return True
                if self._now >= deadline:
                    return False
                self._waiting[me] = deadline
                if event is not None:
                    self._events[me] = event
                try:
                    jump = self._jump_target()
                    if jump is None:
                        seen = self._progress_wall
                        self._cond.wait(self.stall_s)
                        if self._progress_wall == seen and self.auto and self._stalled():
                            jump = self._next_deadline()  # someone is stuck: time goes on
                            self.stalls += 1
                finally:
                    del self._waiting[me]
                    self._events.pop(me, None)
            if jump is not None and math.isfinite(jump):
                self.advance_to(jump)

    # -- internals (called with the condition held) -------------------------------------------
    def _progressed(self) -> None:
        self._progress_wall = time.monotonic()
        self._progress_cpu = time.process_time()
        self._cond.notify_all()

    def _stalled(self) -> bool:
        """No progress for ``stall_s`` of wall time with the process nearly idle (a thread blocked
        outside the clock), or for ``hard_stall_s`` whatever the CPU did."""
        wall = time.monotonic() - self._progress_wall
        if wall >= self.hard_stall_s:
            return True
        return wall >= self.stall_s and time.process_time() - self._progress_cpu < STALL_CPU_FRACTION * wall

    def _next_deadline(self) -> float:
        due = [d for d in self._waiting.values()]
        while self._timers and self._timers[0][2].cancelled:
            heapq.heappop(self._timers)
        if self._timers:
            due.append(self._timers[0][0])
        return min(due, default=math.inf)

    def _jump_target(self) -> float | None:
        """The next deadline when every participating thread waits; None otherwise."""
        if not self.auto:
            return None
        self._actors = {t for t in self._actors if t.is_alive() or t.ident is None}  # (or starting)
        if any(t not in self._waiting for t in self._actors):
            return None
        if any(e.is_set() for e in self._events.values()):  # woken by its event, not yet run: it acts at this time
            return None
        target = self._next_deadline()
        # a deadline already reached belongs to a waiter that was woken and has yet to run
        return target if self._now < target < math.inf else None
