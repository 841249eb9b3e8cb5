"""The independent injector (pty_injector.py) does to bytes what its rules say: a device end and
a host end on real ptys, bytes counted on both sides."""

from __future__ import annotations

import os
import time
import tty

import pytest

from .pty_injector import (Fixed, Injector, Link, Rule, Terminated, aed_ascii_add, aed_binary4_add, dcon_readdress,
                           with_port)

FRAME = b"+0012345\r\n"


class Ends:
    """A fake device on a pty, the injector in front of it, a host on the injector's port."""

    def __init__(self, rules, *, to_host=None, to_device=None, seed=1):
        self.dev_master, dev_slave = os.openpty()
        tty.setraw(dev_slave)
        self._dev_slave = dev_slave
        self.link = Link("dev", os.ttyname(dev_slave), to_host=to_host or Terminated(b"\r\n"), to_device=to_device,
                         rules=rules, seed=seed)
        self.inj = Injector({"dev": self.link}).__enter__()
        self.host = os.open(self.inj.ports["dev"], os.O_RDWR | os.O_NOCTTY)
        tty.setraw(self.host)

    def device_sends(self, data: bytes):
        os.write(self.dev_master, data)

    def host_sends(self, data: bytes):
        os.write(self.host, data)

    @staticmethod
    def _read(fd, n_min, timeout_s):
        got, end = b"", time.monotonic() + timeout_s
        os.set_blocking(fd, False)
        while time.monotonic() < end and len(got) < n_min:
            try:
                got += os.read(fd, 65536)
            except BlockingIOError:
                time.sleep(0.005)
        return got

    def host_reads(self, n_min=1 << 30, timeout_s=1.0):
        return self._read(self.host, n_min, timeout_s)

    def device_reads(self, n_min=1 << 30, timeout_s=1.0):
        return self._read(self.dev_master, n_min, timeout_s)

    def close(self):
        self.inj.close()
        for fd in (self.host, self.dev_master, self._dev_slave):
            os.close(fd)


@pytest.fixture
def ends():
    made = []

    def make(*rules, **kw):
        e = Ends(list(rules), **kw)
        made.append(e)
        return e

    yield make
    for e in made:
        e.close()


def stream(e: Ends, n: int, frame: bytes = FRAME, chunk: int = 20):
    """``n`` frames from the device, ``chunk`` frames a write (as a stream arrives)."""
    for i in range(0, n, chunk):
        e.device_sends(frame * min(chunk, n - i))
        time.sleep(0.002)


def test_no_rule_passes_every_byte_both_ways(ends):
    e = ends()
    stream(e, 200)
    assert e.host_reads(200 * len(FRAME)) == FRAME * 200
    e.host_sends(b";MSV?;")
    assert e.device_reads(6) == b";MSV?;"


def test_drop_a_fraction_of_frames_whole(ends):
    e = ends(Rule("to_host", "drop", rate=0.2))
    stream(e, 1000)
    got = e.host_reads(timeout_s=0.5)
    assert got == FRAME * (len(got) // len(FRAME))  # whole frames only
    n = len(got) // len(FRAME)
    assert 1000 - n == e.link.rules[0].hits and 150 < 1000 - n < 250  # ≈ 20 %, the hits counted


def test_garble_a_fraction_of_bytes(ends):
    e = ends(Rule("to_host", "garble", rate=0.005, per="byte"))
    stream(e, 1000)
    got = e.host_reads(1000 * len(FRAME))
    assert len(got) == 1000 * len(FRAME)
    changed = sum(a != b for a, b in zip(got, FRAME * 1000))
    assert changed == e.link.rules[0].hits and 25 < changed < 80  # 0.5 % of 10 000 bytes


def test_corrupt_the_nth_frame_only_from_the_mark(ends):
    e = ends(Rule("to_host", "corrupt", count=3, start_s=0.2, transform=aed_ascii_add(9000)))
    stream(e, 5)
    time.sleep(0.25)
    stream(e, 5)
    frames = e.host_reads(10 * len(FRAME)).split(b"\n")[:-1]
    assert [f + b"\n" for f in frames] == [FRAME] * 7 + [b"+0021345\r\n"] + [FRAME] * 2


def test_delay_holds_the_frame_and_what_follows_it(ends):
    e = ends(Rule("to_host", "delay", count=1, value=0.3))
    t0 = time.monotonic()
    stream(e, 2, chunk=1)
    first = e.host_reads(len(FRAME), timeout_s=2.0)
    assert time.monotonic() - t0 > 0.28 and first.startswith(FRAME)
    assert (first + e.host_reads(2 * len(FRAME) - len(first))) == FRAME * 2  # order kept


def test_split_writes_a_frame_in_two_parts_apart(ends):
    e = ends(Rule("to_host", "split", count=1, value=0.2))
    e.device_sends(FRAME)
    first = e.host_reads(len(FRAME), timeout_s=0.15)
    assert first == FRAME[:5]
    assert first + e.host_reads(5, timeout_s=0.5) == FRAME


def test_readdress_only_the_reply_to_the_named_command(ends):
    e = ends(Rule("to_host", "readdress", request=rb"^@01DO01", transform=dcon_readdress(3)),
             to_host=Terminated(b"\r"), to_device=Terminated(b"\r"))
    replies = []
    for command, reply in ((b"@01DI\r", b"!0100\r"), (b"@01DO01\r", b"!01\r"), (b"$012\r", b"!01400600\r")):
        e.host_sends(command)
        assert e.device_reads(len(command)) == command
        e.device_sends(reply)
        replies.append(e.host_reads(len(reply)))
    assert replies == [b"!0100\r", b"!03\r", b"!01400600\r"]


def test_fixed_frames_of_a_binary_stream():
    framer = Fixed(6)
    assert framer.feed(b"\x00\x01\x02\x08\r\n\x00") == [b"\x00\x01\x02\x08\r\n"]
    assert framer.feed(b"\x00\x00\x08\r\n") == [b"\x00\x00\x00\x08\r\n"]


def test_frame_transforms_against_hand_made_frames():
    assert aed_ascii_add(9000)(b"-0001000\r\n") == b"+0008000\r\n"
    assert aed_ascii_add(1)(b"0\r\n") == b"0\r\n"  # an acknowledgement is not a value
    assert aed_binary4_add(256)(bytes([0xFF, 0xFF, 0x00, 0x08]) + b"\r\n") == bytes([0x00, 0x00, 0x00, 0x08]) + b"\r\n"  # −256 + 256
    assert aed_binary4_add(1, msb_first=False)(bytes([0xFF, 0x00, 0x00, 0x00])) == bytes([0x00, 0x01, 0x00, 0x00])
    assert dcon_readdress(3)(b"!01\r") == b"!03\r"
    assert dcon_readdress(3, checksum=True)(b"!0182\r") == b"!0384\r"  # 0x21+0x30+0x31 = 0x82; with 3: 0x84
    assert dcon_readdress(3)(b"garbage\r") == b"garbage\r"


def test_with_port_replaces_only_the_named_sections():
    text = '[loadcell]\nport = "/dev/pts/1"\nbaud = 9600\n[encoder]\nport = "/dev/pts/2"\n'
    assert with_port(text, {"loadcell": "/dev/pts/9"}) == text.replace("/dev/pts/1", "/dev/pts/9")


def test_an_unmarked_injector_acts_only_after_its_mark(ends):
    e = ends(Rule("to_host", "drop"))
    e.inj.t0 = float("inf")  # as Injector(..., marked=False)
    stream(e, 3)
    assert e.host_reads(3 * len(FRAME)) == FRAME * 3
    e.inj.mark()
    stream(e, 3)
    assert e.host_reads(timeout_s=0.3) == b""


def test_bad_rules_are_refused():
    with pytest.raises(ValueError):
        Rule("to_host", "split", per="byte")
    with pytest.raises(ValueError):
        Rule("to_host", "corrupt")
