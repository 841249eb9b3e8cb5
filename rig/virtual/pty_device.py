"""A serial device served on a pseudo-terminal, so real drivers talk to it over a real port.

:class:`PtyDevice` opens ``os.openpty()``, puts the slave in raw mode and exposes its path
as :attr:`port` (``/dev/pts/N``; open it with pyserial like any serial port — baud and
parity are ignored by a pty). A thread serves the protocol: ``select`` with time-outs on
the master and a wake-up pipe, :meth:`on_bytes` for what the host sent, :meth:`on_tick` at
the deadline :meth:`next_deadline` asks for (continuous output, watchdogs). Replies go
through the device's :class:`~rig.virtual.faults.WireFaults`. :meth:`close` stops the
thread and closes every descriptor; ``unplug`` closes the master mid-test.
"""

from __future__ import annotations

import errno
import heapq
import os
import select
import threading
import time
import tty

from flowcurve.rig.virtual.faults import WireFaults


class PtyDevice:
    """Base of the virtual devices: a protocol served on a pty by one thread."""

    name = "device"

    def __init__(self, *, faults: WireFaults | None = None, seed: int = 0):
        self.faults = faults if faults is not None else WireFaults(seed)
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        self.port = os.ttyname(self._slave)
        os.set_blocking(self._master, False)
        self._wake_r, self._wake_w = os.pipe()
        self._stop = threading.Event()
        self._delayed: list[tuple[float, int, bytes]] = []  # (due, seq, bytes) for the delay fault
        self._seq = 0
        self.unplugged = False
        self._thread = threading.Thread(target=self._run, name=f"virtual-{self.name}", daemon=True)
        self._started = False

    # -- protocol hooks (subclasses) ---------------------------------------------------
    def on_bytes(self, data: bytes) -> None:
        """Bytes received from the host."""

    def next_deadline(self) -> float | None:
        """time.monotonic() at which :meth:`on_tick` must run next (None: no periodic work)."""
        return None

    def on_tick(self, now: float) -> None:
        """Periodic work (continuous output, watchdog)."""

    # -- output -----------------------------------------------------------------------
    def send(self, reply: bytes) -> None:
        """Send a reply to the host through the wire faults (called from the device thread)."""
        out = self.faults.apply(reply)
        if out is None:
            return
        if self.faults.delay_s > 0:
            self._seq += 1
            heapq.heappush(self._delayed, (time.monotonic() + self.faults.delay_s, self._seq, out))
            return
        self._write(out)

    def _write(self, data: bytes) -> None:
        if self._master < 0:
            return
        try:
            os.write(self._master, data)
        except BlockingIOError:
            pass  # host is not reading: the bytes are lost, as on a real line
        except OSError as exc:
            if exc.errno not in (errno.EIO, errno.EAGAIN):
                raise

    # -- life cycle -------------------------------------------------------------------
    def start(self) -> "PtyDevice":
        if not self._started:
            self._started = True
            self._thread.start()
        return self

    def wake(self) -> None:
        """Make the thread re-evaluate its deadline now (e.g. after a fault was injected)."""
        try:
            os.write(self._wake_w, b"x")
        except OSError:
            pass

    def unplug(self) -> None:
        """The cable is pulled: the port vanishes (the thread closes the pty and ends)."""
        self.faults.inject("unplug")
        self.wake()
        if self._started:
            self._thread.join(timeout=2.0)

    def close(self) -> None:
        """Stop the thread and close every descriptor (idempotent)."""
        self._stop.set()
        self.wake()
        if self._started:
            self._thread.join(timeout=2.0)
        self._close_pty()
        for fd in (self._wake_r, self._wake_w):
            if fd >= 0:
                try:
                    os.close(fd)
                except OSError:
                    pass
        self._wake_r = self._wake_w = -1

    def _close_pty(self) -> None:
        for attr in ("_master", "_slave"):
            fd = getattr(self, attr)
            if fd >= 0:
                try:
                    os.close(fd)
                except OSError:
                    pass
                setattr(self, attr, -1)

    def __enter__(self) -> "PtyDevice":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.close()

    # -- the thread -------------------------------------------------------------------
    def _run(self) -> None:
        while not self._stop.is_set():
            if self.faults.unplug_requested:
                self.unplugged = True
                self._close_pty()
                return
            now = time.monotonic()
            deadlines = [d for d in (self.next_deadline(),) if d is not None]
            if self._delayed:
                deadlines.append(self._delayed[0][0])
            timeout = 0.5 if not deadlines else max(0.0, min(min(deadlines) - now, 0.5))
            try:
                ready, _, _ = select.select([self._master, self._wake_r], [], [], timeout)
            except (OSError, ValueError):
                return
            if self._wake_r in ready:
                try:
                    os.read(self._wake_r, 4096)
                except OSError:
                    pass
            if self._master in ready:
                try:
                    data = os.read(self._master, 4096)
                except (BlockingIOError, InterruptedError):
                    data = b""
                except OSError:
                    data = b""
                    time.sleep(0.01)  # no slave open (EIO): wait for the host
                if data:
                    self.on_bytes(data)
            now = time.monotonic()
            while self._delayed and self._delayed[0][0] <= now:
                self._write(heapq.heappop(self._delayed)[2])
            deadline = self.next_deadline()
            if deadline is not None and deadline <= now:
                self.on_tick(now)
