"""pyserial URL handler ``virtual://NAME``: a virtual device opened in this process.

In the manner of pyserial's ``loop://``: :func:`serial.serial_for_url` looks the scheme up
as ``<package>.protocol_virtual`` in ``serial.protocol_handler_packages``, to which this
module adds ``flowcurve.rig.virtual`` on import. A device created with
``link="inprocess"`` (:class:`~flowcurve.rig.virtual.pty_device.PtyDevice`) registers its URL
here; the drivers then open it like any port and talk through the real codecs and
:class:`~flowcurve.rig.transport.SerialTransport`, without a pty or a thread.

Bytes written reach the device at once; its replies and its streamed frames wait in the
port's input buffer. A read waits on the device's clock (:attr:`Serial.clock`, which the
transport uses for its deadlines too), so on a :class:`flowcurve.clock.ModelClock` a silent
device costs no wall time. An unplugged device raises ``OSError(EIO)`` on every call, as a
pty whose other end vanished does. Unlike a pty, what a device sends while no port is open
is lost (nothing holds it).
"""

from __future__ import annotations

import errno
import os
import threading
import weakref

import serial
from serial.serialutil import PortNotOpenError, SerialBase, SerialException

from flowcurve.clock import WALL

PACKAGE = "flowcurve.rig.virtual"
BITS_PER_BYTE = 10  # start, 8 data, stop: the line time of a byte is 10 / baud
if PACKAGE not in serial.protocol_handler_packages:
    serial.protocol_handler_packages.append(PACKAGE)

_DEVICES: "weakref.WeakValueDictionary[str, object]" = weakref.WeakValueDictionary()
_DEVICES_LOCK = threading.Lock()


def register(url: str, device) -> None:
    """Make ``url`` (``virtual://NAME``) open ``device``."""
    with _DEVICES_LOCK:
        _DEVICES[url.lower()] = device


def unregister(url: str) -> None:
    """Forget the device at ``url``."""
    with _DEVICES_LOCK:
        _DEVICES.pop(url.lower(), None)


class Serial(SerialBase):
    """The host's end of an in-process virtual device (pyserial's SerialBase interface)."""

    def __init__(self, *args, **kwargs):
        self._device = None
        self._rx = bytearray()
        self._rx_event = threading.Event()
        self._rx_lock = threading.Lock()
        self.clock = WALL
        super().__init__(*args, **kwargs)

    # -- life cycle -------------------------------------------------------------------
    def open(self) -> None:
        """Attach to the registered device (SerialException when open or unknown)."""
        if self.is_open:
            raise SerialException("Port is already open.")
        if self._port is None:
            raise SerialException("Port must be configured before it can be used.")
        with _DEVICES_LOCK:
            device = _DEVICES.get(str(self._port).lower())
        if device is None or device.lost:
            raise SerialException(errno.ENOENT, f"could not open port {self._port}: no such virtual device")
        self._device = device
        self.clock = device.clock
        self._rx.clear()
        self._rx_event.clear()
        device.attach(self, BITS_PER_BYTE / self._baudrate)
        self.is_open = True

    def close(self) -> None:
        """Detach from the device."""
        if self._device is not None:
            self._device.detach(self)
        self.is_open = False
        self._rx_event.set()  # a waiting read returns
        self.clock.notify()

    def _reconfigure_port(self, *args, **kwargs) -> None:
        """Line settings mean nothing in-process (as on a pty)."""

    # -- the device's side ------------------------------------------------------------
    def deliver(self, data: bytes, limit: int) -> None:
        """Bytes from the device; beyond ``limit`` unread bytes the rest is lost (a full buffer)."""
        with self._rx_lock:
            room = limit - len(self._rx)
            if room > 0:
                self._rx += data[:room]
                self._rx_event.set()

    # -- the host's side --------------------------------------------------------------
    def _check(self):
        if not self.is_open:
            raise PortNotOpenError()
        if self._device.lost:
            raise OSError(errno.EIO, os.strerror(errno.EIO))
        return self._device

    def write(self, data) -> int:
        """Send ``data`` to the device at the baud rate's pace; the bytes written."""
        device = self._check()
        data = bytes(data)
        device.host_write(data, BITS_PER_BYTE / self._baudrate)
        return len(data)

    def flush(self) -> None:
        """Nothing to flush (checks the port is open)."""
        self._check()

    def read(self, size: int = 1) -> bytes:
        """``size`` bytes, or fewer when the time-out (on the device's clock) runs out first."""
        self._check()
        deadline = None if self._timeout is None else self.clock.now() + self._timeout
        data = bytearray()
        while True:
            with self._rx_lock:
                take = size - len(data)
                data += self._rx[:take]
                del self._rx[:take]
                if not self._rx:
                    self._rx_event.clear()
            if len(data) >= size or not self.is_open:
                return bytes(data)
            self._check()
            if deadline is None:
                self.clock.wait(self._rx_event)
            elif self.clock.now() >= deadline:
                return bytes(data)
            else:
                self.clock.wait(self._rx_event, deadline - self.clock.now())

    @property
    def in_waiting(self) -> int:
        """Bytes waiting to be read."""
        self._check()
        with self._rx_lock:
            return len(self._rx)

    def reset_input_buffer(self) -> None:
        """Drop the bytes waiting to be read."""
        self._check()
        with self._rx_lock:
            self._rx.clear()
            self._rx_event.clear()

    def reset_output_buffer(self) -> None:
        """Nothing to drop (checks the port is open)."""
        self._check()

    @property
    def out_waiting(self) -> int:
        """Always 0: writes are delivered at once."""
        return 0

    def _update_break_state(self) -> None:
        pass

    def _update_rts_state(self) -> None:
        pass

    def _update_dtr_state(self) -> None:
        pass

    @property
    def cts(self) -> bool:
        """Always True (no handshake lines)."""
        return True

    @property
    def dsr(self) -> bool:
        """Always True (no handshake lines)."""
        return True

    @property
    def ri(self) -> bool:
        """Always False (no handshake lines)."""
        return False

    @property
    def cd(self) -> bool:
        """Always True (no handshake lines)."""
        return True
