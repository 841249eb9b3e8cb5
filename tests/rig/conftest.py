"""A fake serial port that checks the bytes a driver writes and feeds the device's replies.

In the manner of PyMeasure's ``expected_protocol``: the test lists (command, reply) pairs;
the driver must write exactly those commands in that order; ``reply=None`` is a device that
stays silent. ``fake.feed(data)`` adds unsolicited bytes (a measurement stream) and
``fake.unplug()`` makes the port vanish. The port keeps model time (:attr:`clock`, which the
transport takes for its deadlines): a read with nothing to give advances it by the read's
time-out instead of sleeping.
"""

from __future__ import annotations

import pytest
import serial

from flowcurve.clock import ModelClock


class FakePort:
    def __init__(self, pairs=(), *, strict=True):
        self.pairs = list(pairs)
        self.strict = strict
        self.written = bytearray()  # bytes of the command being matched
        self.log: list[bytes] = []  # every write, in order
        self.rx = bytearray()
        self.timeout = 0.01  # the transport opens ports with a 0.01 s read slice
        self.open_kwargs: dict = {}
        self.unplugged = False
        self.closed = False
        self.clock = ModelClock()

    # -- what the transport calls --------------------------------------------------------
    def write(self, data: bytes) -> int:
        self._check()
        self.log.append(bytes(data))
        self.written += data
        while self.pairs and self.written.startswith(self.pairs[0][0]):
            command, reply = self.pairs.pop(0)
            del self.written[: len(command)]
            if reply:
                self.rx += reply
        if self.strict and self.written:
            expected = self.pairs[0][0] if self.pairs else b"(nothing)"
            if not expected.startswith(bytes(self.written)):
                raise AssertionError(f"driver wrote {bytes(self.written)!r}, expected {expected!r}")
        return len(data)

    def flush(self) -> None:
        self._check()

    def read(self, size: int = 1) -> bytes:
        self._check()
        if not self.rx:
            self.clock.sleep(self.timeout or 0)
            return b""
        data = bytes(self.rx[:size])
        del self.rx[:size]
        return data

    @property
    def in_waiting(self) -> int:
        self._check()
        return len(self.rx)

    def reset_input_buffer(self) -> None:
        self._check()
        self.rx.clear()

    def close(self) -> None:
        self.closed = True

    # -- test helpers --------------------------------------------------------------------
    def feed(self, data: bytes) -> None:
        self.rx += data

    def unplug(self) -> None:
        self.unplugged = True

    def _check(self) -> None:
        if self.unplugged:
            raise serial.SerialException("device reports readiness to read but returned no data")

    def opener(self, url, **kwargs):
        self.open_kwargs = dict(kwargs, url=url)
        self.timeout = kwargs.get("timeout", self.timeout)
        return self

    def assert_done(self) -> None:
        assert not self.pairs, f"commands never sent: {[c for c, _ in self.pairs]!r}"
        assert not self.written, f"unexpected trailing bytes written: {bytes(self.written)!r}"


@pytest.fixture
def fake_port():
    """``fake_port(pairs)`` → a FakePort; every pair must have been used by the end."""
    made = []

    def make(pairs=(), **kwargs):
        port = FakePort(pairs, **kwargs)
        made.append(port)
        return port

    yield make
    for port in made:
        port.assert_done()


@pytest.fixture
def fake_port_class():
    """The FakePort class itself, for tests that build ports inside an opener."""
    return FakePort
