"""A virtual serial device, served on a pseudo-terminal or in-process, on a clock.

:class:`PtyDevice` is the base of the virtual devices: the protocol hooks (:meth:`on_bytes`
for what the host sent, :meth:`on_tick` at the deadline :meth:`next_deadline` asks for —
continuous output, watchdogs), the replies through the device's
:class:`~rig.virtual.faults.WireFaults`, and one of two links to the host:

* ``link="pty"`` (the default): ``os.openpty()``, the slave in raw mode, its path in
  :attr:`port` (``/dev/pts/N``; open it with pyserial like any serial port — baud and parity
  are ignored by a pty). A thread serves the protocol: ``select`` with time-outs on the
  master and a wake-up pipe. Real time only (:data:`flowcurve.clock.WALL`): the host may be
  another process. ``unplug`` closes the master mid-test.
* ``link="inprocess"``: no descriptor and no thread. :attr:`port` is a ``virtual://`` URL
  that :func:`serial.serial_for_url` opens in this process
  (:mod:`flowcurve.rig.virtual.protocol_virtual`); bytes written by the host are handled at
  once, and the periodic work runs as timers on the device's clock — a
  :class:`flowcurve.clock.ModelClock` in the fast tests, so nothing waits on the wall clock.

:meth:`close` stops the thread or the timers and closes every descriptor.
"""

from __future__ import annotations

import errno
import heapq
import itertools
import os
import select
import termios
import threading
import time
import tty

from flowcurve.clock import WALL, Clock
from flowcurve.errors import ConfigError
from flowcurve.rig.virtual.faults import WireFaults

LINKS = ("pty", "inprocess")
IDLE_S = 0.1  # the pty thread looks around at least this often (faults due, the line parked)
INPROCESS_BUFFER_BYTES = 4096  # like a pty's: bytes the host does not read beyond it are lost
_NAMES = itertools.count(1)


class PtyDevice:
    """Base of the virtual devices: a protocol served on a pty or in-process (see the module)."""

    name = "device"

    def __init__(self, *, faults: WireFaults | None = None, seed: int = 0,
                 clock: Clock = WALL, link: str = "pty"):
        if link not in LINKS:
            raise ConfigError(f"link: must be one of {', '.join(LINKS)}, got {link!r}")
        if link == "pty" and clock is not WALL:
            raise ConfigError("link: a device on a pty runs in real time (the host may be another process)")
        self.faults = faults if faults is not None else WireFaults(seed)
        self.clock = clock
        self.link = link
        self._delayed: list[tuple[float, int, bytes]] = []  # (due, seq, bytes) still on their way
        self._seq = 0
        self._last_due = 0.0
        self._command_bytes = 0  # in-process: the command being answered ...
        self._byte_time_s = 0.0  # ... and the line's time per byte (from the host's port)
        self.unplugged = False
        self._started = False
        self._closed = False
        self._lock = threading.RLock()  # in-process: the host's calls and the timers
        self._timer = None
        self._host = None  # in-process: the open port object (protocol_virtual.Serial)
        self._master = self._slave = self._wake_r = self._wake_w = -1
        if link == "pty":
            self._master, self._slave = os.openpty()
            tty.setraw(self._slave)
            self._park_line()
            self.port = os.ttyname(self._slave)
            os.set_blocking(self._master, False)
            self._wake_r, self._wake_w = os.pipe()
            self._stop = threading.Event()
            self._thread = threading.Thread(target=self._run, name=f"virtual-{self.name}", daemon=True)
        else:
            from flowcurve.rig.virtual import protocol_virtual  # registers the virtual:// scheme

            self.port = f"virtual://{self.name}-{next(_NAMES)}"
            protocol_virtual.register(self.port, self)

    # -- protocol hooks (subclasses) ---------------------------------------------------
    def on_bytes(self, data: bytes) -> None:
        """Bytes received from the host."""

    def next_deadline(self) -> float | None:
        """Clock time at which :meth:`on_tick` must run next (None: no periodic work)."""
        return None

    def on_tick(self, now: float) -> None:
        """Periodic work (continuous output, watchdog)."""

    # -- output -----------------------------------------------------------------------
    def send(self, *replies: bytes) -> None:
        """Send replies to the host, each through the wire faults, in one write (called from the
        device's side; a burst of late stream frames reaches the host at once, as frames buffered
        while it was busy do).

        Bytes leave in order: a reply that is due later holds back what follows it.
        In-process, bytes also take the line's time (10 bits a byte at the host port's baud
        rate; a reply counts its command too): the host's exchanges then take time on the
        clock, as on a real line.
        """
        out = b"".join(o for o in map(self.faults.apply, replies) if o is not None)
        if not out:
            return
        now = self.clock.now()
        due = now + self.faults.delay_s + (self._command_bytes + len(out)) * self._byte_time_s
        if self._delayed:
            due = max(due, self._last_due)
        if due > now:
            self._seq += 1
            self._last_due = due
            heapq.heappush(self._delayed, (due, self._seq, out))
            return
        self._write(out)

    def _write(self, data: bytes) -> None:
        if self.link == "inprocess":
            if self._host is not None and not self.lost:
                self._host.deliver(data, INPROCESS_BUFFER_BYTES)
            return
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
        """Start serving the device (its pty or in-process link); the device."""
        if not self._started:
            self._started = True
            if self.link == "pty":
                self._thread.start()
            else:
                self._reschedule()
        return self

    def wake(self) -> None:
        """Make the device re-evaluate its deadline now (e.g. after a fault was injected)."""
        if self.link == "inprocess":
            with self._lock:
                self._reschedule()
            return
        try:
            os.write(self._wake_w, b"x")
        except OSError:
            pass

    def unplug(self) -> None:
        """The cable is pulled: the port vanishes (a pty's thread closes it and ends)."""
        self.faults.inject("unplug")
        if self.link == "inprocess":
            with self._lock:
                self.unplugged = True
                self._reschedule()  # the module's own timing (a watchdog) goes on unplugged
            return
        self.wake()
        if self._started:
            self._thread.join(timeout=2.0)

    def close(self) -> None:
        """Stop the thread (or the timers) and close every descriptor (idempotent)."""
        if self.link == "inprocess":
            from flowcurve.rig.virtual import protocol_virtual

            with self._lock:
                self._closed = True
                self._cancel_timer()
            protocol_virtual.unregister(self.port)
            return
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

    # -- the in-process link (called by protocol_virtual.Serial and the clock) ----------------
    @property
    def lost(self) -> bool:
        """The port is gone for the host (unplugged or closed)."""
        return self.unplugged or self._closed or self.faults.unplug_requested

    def attach(self, host, byte_time_s: float = 0.0) -> None:
        """A host port opened this device (one at a time, like a serial port)."""
        with self._lock:
            self._host = host
            self._byte_time_s = byte_time_s

    def detach(self, host) -> None:
        """Detach ``host`` when it is the attached one."""
        with self._lock:
            if self._host is host:
                self._host = None

    def host_write(self, data: bytes, byte_time_s: float = 0.0) -> None:
        """Bytes from the host, handled at once (after any periodic work now due); the
        replies arrive after the line's time for command and reply (``byte_time_s`` a byte)."""
        with self._lock:
            self._catch_up()
            self._command_bytes, self._byte_time_s = len(data), byte_time_s
            try:
                self.on_bytes(data)
            finally:
                self._command_bytes = 0
            self._reschedule()

    def _catch_up(self) -> None:
        now = self.clock.now()
        while self._delayed and self._delayed[0][0] <= now:
            self._write(heapq.heappop(self._delayed)[2])
        deadline = self.next_deadline()
        if deadline is not None and deadline <= now and not self._closed:
            self.on_tick(now)  # as the pty thread does: a late tick catches up by itself

    def _on_timer(self) -> None:
        with self._lock:
            self._timer = None
            if self._closed:
                return
            self._catch_up()
            self._reschedule()

    def _cancel_timer(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def _reschedule(self) -> None:
        """One timer at the earliest of the periodic deadline and the delayed replies."""
        if not self._started or self._closed:
            return
        due = [d for d in (self.next_deadline(),) if d is not None]
        if self._delayed:
            due.append(self._delayed[0][0])
        when = min(due) if due else None
        if when is not None and when <= self.clock.now():  # a tick that did not move its deadline
            when = self.clock.now() + 1e-9  # (rounding: last + timeout − last < timeout)
        if self._timer is not None and self._timer.when == when:
            return
        self._cancel_timer()
        if when is not None:
            self._timer = self.clock.call_at(when, self._on_timer)

    # -- the pty thread ---------------------------------------------------------------
    def _park_line(self) -> None:
        """Keep the pty's line at 50 baud, a speed no host asks for: on some kernels a pty
        refuses (EINVAL) a host's ``tcsetattr`` with parity that does not change the speed, so
        a second host opening the port at the first one's settings failed (issue 29, defect
        10). Parked, every host's open changes the speed and succeeds: one host after another."""
        try:
            attrs = termios.tcgetattr(self._slave)
            if attrs[4] != termios.B50 or attrs[5] != termios.B50:
                attrs[4] = attrs[5] = termios.B50
                termios.tcsetattr(self._slave, termios.TCSANOW, attrs)
        except (termios.error, OSError):
            pass

    def _run(self) -> None:
        while not self._stop.is_set():
            self._park_line()
            if self.faults.unplug_requested:
                self.unplugged = True
                self._close_pty()
                self._run_unplugged()
                return
            now = time.monotonic()
            deadlines = [d for d in (self.next_deadline(),) if d is not None]
            if self._delayed:
                deadlines.append(self._delayed[0][0])
            timeout = IDLE_S if not deadlines else max(0.0, min(min(deadlines) - now, IDLE_S))
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

    def _run_unplugged(self) -> None:
        """The cable is out but the module is powered: its own timing (a watchdog) goes on."""
        while not self._stop.is_set():
            deadline = self.next_deadline()
            now = time.monotonic()
            if deadline is not None and deadline <= now:
                self.on_tick(now)
                continue
            timeout = 0.5 if deadline is None else min(deadline - now, 0.5)
            try:
                if select.select([self._wake_r], [], [], max(0.0, timeout))[0]:
                    os.read(self._wake_r, 4096)
            except (OSError, ValueError):
                return
