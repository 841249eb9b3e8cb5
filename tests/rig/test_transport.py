"""The transport: framing by length and terminator, time-outs, retries, vanished ports."""

import pytest
import serial

from flowcurve.errors import DeviceError
from flowcurve.rig.transport import SerialTransport


def make(fake, name="load cell", timeout_s=0.05):
    return SerialTransport("fake://x", name=name, timeout_s=timeout_s, opener=fake.opener).open()


def test_opens_with_the_line_settings(fake_port):
    fake = fake_port()
    SerialTransport("fake://x", name="dev", baudrate=4800, parity="E", opener=fake.opener).open()
    assert fake.open_kwargs["baudrate"] == 4800 and fake.open_kwargs["parity"] == "E"


def test_read_until_keeps_bytes_after_the_terminator(fake_port):
    fake = fake_port([(b"Q", b"one\r\ntwo\r\n")])
    t = make(fake)
    assert t.exchange(b"Q", terminator=b"\r\n") == b"one\r\n"
    assert t.read_until(b"\r\n") == b"two\r\n"


def test_read_exactly_frames_binary_containing_crlf(fake_port):
    fake = fake_port([(b"B", b"\r\n\r\x00\r\nXY")])
    t = make(fake)
    assert t.exchange(b"B", length=6) == b"\r\n\r\x00\r\n"
    assert t.read_exactly(2) == b"XY"


def test_timeout_names_device_and_command(fake_port):
    fake = fake_port([(b";MSV?;", None)])
    t = make(fake)
    with pytest.raises(DeviceError, match=r"^load cell: no answer to 'MSV\?' within 0.05 s$"):
        t.exchange(b";MSV?;", length=10)


def test_partial_reply_is_reported(fake_port):
    fake = fake_port([(b"Q", b"+10")])
    with pytest.raises(DeviceError, match=r"^load cell: incomplete answer to 'Q' within 0.05 s \(3 bytes: b'\+10'\)$"):
        make(fake).exchange(b"Q", length=10)


def test_retry_after_silence_when_allowed(fake_port):
    fake = fake_port([(b"R", None), (b"R", b"ok\r")])
    assert make(fake).exchange(b"R", retries=1) == b"ok\r"
    assert fake.log == [b"R", b"R"]


def test_no_retry_by_default(fake_port):
    fake = fake_port([(b"R", None)])
    with pytest.raises(DeviceError):
        make(fake).exchange(b"R")
    assert fake.log == [b"R"]


def test_garbled_reply_retried_then_reported(fake_port):
    def parse(raw):
        if raw != b"ok\r":
            raise ValueError(f"bad {raw!r}")
        return "parsed"

    fake = fake_port([(b"R", b"zz\r"), (b"R", b"ok\r")])
    assert make(fake).exchange(b"R", retries=1, parse=parse) == "parsed"
    fake2 = fake_port([(b"R", b"zz\r")])
    with pytest.raises(DeviceError, match="garbled answer to 'R': bad"):
        make(fake2).exchange(b"R", parse=parse)


def test_stale_input_is_discarded_before_a_command(fake_port):
    fake = fake_port([(b"Q", b"fresh\r")])
    t = make(fake)
    fake.feed(b"stale\r")
    assert t.exchange(b"Q") == b"fresh\r"


def test_unplugged_port_is_a_device_error(fake_port):
    fake = fake_port()
    t = make(fake)
    fake.unplug()
    with pytest.raises(DeviceError, match=r"^load cell: port fake://x disappeared$"):
        t.exchange(b"Q")


def test_missing_port_is_a_device_error(tmp_path):
    missing = tmp_path / "ttyUSB9"
    with pytest.raises(DeviceError, match=rf"^furnace: cannot open port {missing}: No such file or directory$"):
        SerialTransport(str(missing), name="furnace").open()


def test_one_owner_per_port(tmp_path):
    import os
    import pty

    master, slave = pty.openpty()
    try:
        path = os.ttyname(slave)
        with SerialTransport(path, name="load cell"):
            with pytest.raises(DeviceError, match="already open by 'load cell'"):
                SerialTransport(path, name="furnace").open()
        with SerialTransport(path, name="furnace"):  # free again after close
            pass
    finally:
        os.close(master)
        os.close(slave)


def test_loop_url_round_trip():
    with SerialTransport("loop://", name="loop", timeout_s=0.2) as t:
        assert t.exchange(b"PING\r") == b"PING\r"
        with SerialTransport("loop://", name="other loop"):  # loop:// ports are independent
            pass


def test_serial_exception_on_open_is_reported():
    def opener(url, **kw):
        raise serial.SerialException("could not open port /dev/ttyS99: [Errno 2] No such file")

    with pytest.raises(DeviceError, match="cannot open port /dev/ttyS99"):
        SerialTransport("/dev/ttyS99", name="encoder", opener=opener).open()
