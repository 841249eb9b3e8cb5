"""An independent fault injector: a man-in-the-middle on pseudo-terminals between a host
(``flowcurve run``) and serial devices (the virtual rig's ptys), written apart from the twins'
own fault code (it imports nothing from rig/).

For each device the injector opens the device's port as a host would and serves a pty of its
own to the real host; bytes are forwarded both ways by one thread. A :class:`Rule` acts on one
direction (``"to_host"`` or ``"to_device"``) on whole frames (cut by a :class:`Framer`) or on
bytes: drop, garble, delay, split, corrupt (a frame transformed by a function of this module,
e.g. :func:`aed_ascii_add`) or re-address (:func:`dcon_readdress`) — by a seeded rate, on the
N-th matching frame, or from a time after :meth:`Injector.mark`. What each rule did is listed
in :attr:`Injector.hits`.
"""

from __future__ import annotations

import math
import os
import random
import re
import select
import termios
import threading
import time
import tty
from dataclasses import dataclass, field
from typing import Callable

DIRECTIONS = ("to_host", "to_device")
ACTIONS = ("drop", "garble", "delay", "split", "corrupt", "readdress")
HOLD_S = 0.05  # an unterminated tail older than this is passed on as it is (nothing sticks in the injector)
IDLE_S = 0.02


# -- frames ---------------------------------------------------------------------------------------


class Framer:
    """Cuts a byte stream into frames; :meth:`feed` returns the complete ones."""

    def __init__(self):
        self.buffer = b""

    def feed(self, data: bytes) -> list[bytes]:
        raise NotImplementedError

    def flush(self) -> bytes:
        tail, self.buffer = self.buffer, b""
        return tail


class Raw(Framer):
    """No framing: every chunk read is one frame."""

    def feed(self, data: bytes) -> list[bytes]:
        return [data] if data else []


class Terminated(Framer):
    """Frames end with ``terminator`` (AED ASCII ``\\r\\n``, DCON ``\\r``)."""

    def __init__(self, terminator: bytes):
        super().__init__()
        self.terminator = terminator

    def feed(self, data: bytes) -> list[bytes]:
        self.buffer += data
        frames = []
        while (i := self.buffer.find(self.terminator)) >= 0:
            end = i + len(self.terminator)
            frames.append(self.buffer[:end])
            self.buffer = self.buffer[end:]
        return frames


class Fixed(Framer):
    """Frames of ``length`` bytes (an AED binary stream: 4 or 2 bytes, + CR LF unless COF +32)."""

    def __init__(self, length: int):
        super().__init__()
        self.length = length

    def feed(self, data: bytes) -> list[bytes]:
        self.buffer += data
        n = len(self.buffer) // self.length * self.length
        frames = [self.buffer[i:i + self.length] for i in range(0, n, self.length)]
        self.buffer = self.buffer[n:]
        return frames


# -- frame transformations (own encoders: byte arithmetic, not the product's codecs) ---------------

AED_ASCII_VALUE = re.compile(rb"^([+-])(\d{7})(.*)$", re.S)  # COF 3: ±nnnnnnn CR LF


def aed_ascii_add(delta_counts: int) -> Callable[[bytes], bytes]:
    """A transform adding ``delta_counts`` to an AED ASCII measured value (``+0012345\\r\\n``)."""

    def add(frame: bytes) -> bytes:
        m = AED_ASCII_VALUE.match(frame)
        if not m:
            return frame
        value = int(m.group(2)) * (-1 if m.group(1) == b"-" else 1) + delta_counts
        return f"{'-' if value < 0 else '+'}{abs(value):07d}".encode() + m.group(3)

    return add


def aed_binary4_add(delta_counts: int, *, msb_first: bool = True) -> Callable[[bytes], bytes]:
    """A transform adding ``delta_counts`` to the signed 24-bit value of a 4-byte AED frame."""

    def add(frame: bytes) -> bytes:
        order = "big" if msb_first else "little"
        value_bytes = frame[:3]
        value = int.from_bytes(value_bytes, order, signed=True) + delta_counts
        return value.to_bytes(3, order, signed=True) + frame[3:]

    return add


def dcon_sum(text: bytes) -> bytes:
    """DCON checksum: the sum of the characters modulo 256, two upper-case hex digits."""
    return b"%02X" % (sum(text) % 256)


def dcon_readdress(address: int, *, checksum: bool = False) -> Callable[[bytes], bytes]:
    """A transform giving a DCON reply (``!01...\\r``, ``>01...``, ``?01``) another module's address."""

    def readdress(frame: bytes) -> bytes:
        body, end = (frame[:-1], frame[-1:]) if frame.endswith(b"\r") else (frame, b"")
        if len(body) < 3 or body[:1] not in b"!?>":
            return frame
        if checksum:
            body = body[:-2]
        body = body[:1] + b"%02X" % address + body[3:]
        return body + (dcon_sum(body) if checksum else b"") + end

    return readdress


# -- rules ----------------------------------------------------------------------------------------


@dataclass
class Rule:
    """One fault on one direction of one link.

    ``action``: drop / garble / delay (``value`` s) / split (into two writes ``value`` s apart) /
    corrupt and readdress (``transform(frame) -> frame``). ``per``: "frame" or "byte" (drop and
    garble only). Which: each with probability ``rate`` (seeded), or the ``count``-th matching
    frame (1-based, counted from ``start_s``), or every one; only frames matching ``match`` and
    replies to a request matching ``request``; from ``start_s`` after :meth:`Injector.mark`;
    at most ``limit`` times.
    """

    direction: str
    action: str
    rate: float | None = None
    count: int | None = None
    start_s: float = 0.0
    per: str = "frame"
    value: float = 0.0
    transform: Callable[[bytes], bytes] | None = None
    match: bytes | None = None
    request: bytes | None = None
    limit: int | None = None
    seen: int = field(default=0, init=False)
    hits: int = field(default=0, init=False)

    def __post_init__(self):
        if self.direction not in DIRECTIONS or self.action not in ACTIONS or self.per not in ("frame", "byte"):
            raise ValueError(f"bad rule: {self.direction} {self.action} per {self.per}")
        if self.per == "byte" and self.action not in ("drop", "garble"):
            raise ValueError("only drop and garble act per byte")
        if self.action in ("corrupt", "readdress") and self.transform is None:
            raise ValueError(f"{self.action} needs a transform")


class Link:
    """One device: the host's pty (served here) and the device's port (opened here as a host)."""

    def __init__(self, name: str, device_port: str, *, to_host: Framer | None = None,
                 to_device: Framer | None = None, rules=(), seed: int = 0):
        self.name = name
        self.device_port = device_port
        self.framers = {"to_host": to_host or Raw(), "to_device": to_device or Raw()}
        self.rules = list(rules)
        self.rng = random.Random(seed)
        self.last_request = b""
        self.held_since = {d: None for d in DIRECTIONS}
        self.queue = {d: [] for d in DIRECTIONS}  # (due, bytes) in order
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        self.port = os.ttyname(self.slave)
        os.set_blocking(self.master, False)
        self.device = os.open(device_port, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        _raw(self.device)
        self.park()

    def park(self) -> None:
        """The host's line parked at 50 baud (as the virtual devices do): any host's open changes it."""
        try:
            attrs = termios.tcgetattr(self.slave)
            if attrs[4] != termios.B50 or attrs[5] != termios.B50:
                attrs[4] = attrs[5] = termios.B50
                termios.tcsetattr(self.slave, termios.TCSANOW, attrs)
        except (termios.error, OSError):
            pass

    def source(self, direction: str) -> int:
        return self.device if direction == "to_host" else self.master

    def sink(self, direction: str) -> int:
        return self.master if direction == "to_host" else self.device

    def close(self) -> None:
        for fd in (self.master, self.slave, self.device):
            try:
                os.close(fd)
            except OSError:
                pass


def _raw(fd: int) -> None:
    try:
        tty.setraw(fd)
        attrs = termios.tcgetattr(fd)
        attrs[4] = attrs[5] = termios.B9600  # a change of speed: accepted by every pty
        termios.tcsetattr(fd, termios.TCSANOW, attrs)
    except (termios.error, OSError):
        pass


@dataclass(frozen=True)
class Hit:
    """What a rule did: host monotonic time, link, rule index, the frame before and after."""

    t: float
    link: str
    rule: int
    action: str
    before: bytes
    after: bytes


class Injector:
    """The man-in-the-middle: ``with Injector({"loadcell": Link(...), ...}) as inj:`` — the host
    opens ``inj.ports[name]``; :meth:`mark` sets the time the rules' ``start_s`` count from
    (``marked=False``: no rule acts before the first mark)."""

    def __init__(self, links: dict[str, Link], *, marked: bool = True):
        self.links = links
        self.t0 = time.monotonic() if marked else math.inf
        self.hits: list[Hit] = []
        self.frames = {(name, d): 0 for name in links for d in DIRECTIONS}  # complete frames forwarded or acted on
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._run, name="pty-injector", daemon=True)

    @property
    def ports(self) -> dict[str, str]:
        return {name: link.port for name, link in self.links.items()}

    def mark(self) -> None:
        """Time zero of the rules' ``start_s`` (e.g. the crosshead start)."""
        self.t0 = time.monotonic()

    def __enter__(self) -> "Injector":
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        for link in self.links.values():
            link.close()

    # -- the forwarding thread -----------------------------------------------------------------
    def _run(self) -> None:
        while not self._stop.is_set():
            fds = {}
            for link in self.links.values():
                link.park()
                for d in DIRECTIONS:
                    fds[link.source(d)] = (link, d)
            try:
                ready, _, _ = select.select(list(fds), [], [], IDLE_S)
            except (OSError, ValueError):
                return
            now = time.monotonic()
            for fd in ready:
                link, d = fds[fd]
                try:
                    data = os.read(fd, 4096)
                except OSError:  # nobody on the other end yet
                    data = b""
                if data:
                    self.feed(link, d, data, now)
            for link in self.links.values():
                for d in DIRECTIONS:
                    self._flush_tail(link, d, now)
                    self._write_due(link, d, now)

    def feed(self, link: Link, direction: str, data: bytes, now: float) -> None:
        """Bytes read from one side: framed, acted on, queued for the other side."""
        framer = link.framers[direction]
        for frame in framer.feed(data):
            self._frame(link, direction, frame, now)
        link.held_since[direction] = (link.held_since[direction] or now) if framer.buffer else None

    def _flush_tail(self, link: Link, direction: str, now: float) -> None:
        since = link.held_since[direction]
        if since is not None and now - since > HOLD_S:
            link.held_since[direction] = None
            tail = link.framers[direction].flush()
            if tail:
                self._queue(link, direction, self._bytes_rules(link, direction, tail, now), now)

    def _frame(self, link: Link, direction: str, frame: bytes, now: float) -> None:
        self.frames[(link.name, direction)] += 1
        if direction == "to_device":
            link.last_request = frame
        delay = 0.0
        for i, rule in enumerate(link.rules):
            if rule.direction != direction or rule.per != "frame" or not self._applies(link, rule, frame, now):
                continue
            before = frame
            if rule.action == "drop":
                frame = b""
            elif rule.action == "garble":
                frame = _garble_one(frame, link.rng)
            elif rule.action in ("corrupt", "readdress"):
                frame = rule.transform(frame)
            elif rule.action == "delay":
                delay += rule.value
            self.hits.append(Hit(now, link.name, i, rule.action, before, frame))
            if rule.action == "split" and len(frame) > 1:
                half = len(frame) // 2
                self._queue(link, direction, frame[:half], now + delay)
                frame, delay = frame[half:], delay + rule.value
            if not frame:
                return
        self._queue(link, direction, self._bytes_rules(link, direction, frame, now), now + delay)

    def _applies(self, link: Link, rule: Rule, frame: bytes, now: float) -> bool:
        if now - self.t0 < rule.start_s or (rule.limit is not None and rule.hits >= rule.limit):
            return False
        if rule.match is not None and not re.search(rule.match, frame):
            return False
        if rule.request is not None and not re.search(rule.request, link.last_request):
            return False
        rule.seen += 1
        if rule.count is not None:
            take = rule.seen == rule.count
        elif rule.rate is not None:
            take = link.rng.random() < rule.rate
        else:
            take = True
        rule.hits += take
        return take

    def _bytes_rules(self, link: Link, direction: str, data: bytes, now: float) -> bytes:
        for i, rule in enumerate(link.rules):
            if rule.direction != direction or rule.per != "byte" or now - self.t0 < rule.start_s:
                continue
            out = bytearray()
            for b in data:
                if rule.limit is not None and rule.hits >= rule.limit or link.rng.random() >= (rule.rate or 0.0):
                    out.append(b)
                    continue
                rule.hits += 1
                if rule.action == "garble":
                    out.append(b ^ link.rng.randrange(1, 256))
            if bytes(out) != data:
                self.hits.append(Hit(now, link.name, i, rule.action, data, bytes(out)))
            data = bytes(out)
        return data

    def _queue(self, link: Link, direction: str, data: bytes, due: float) -> None:
        if data:
            q = link.queue[direction]
            q.append((max(due, q[-1][0]) if q else due, data))  # bytes leave in order
            self._write_due(link, direction, time.monotonic())

    def _write_due(self, link: Link, direction: str, now: float) -> None:
        q = link.queue[direction]
        while q and q[0][0] <= now:
            _, data = q.pop(0)
            try:
                os.write(link.sink(direction), data)
            except OSError:
                pass  # nobody reading: lost, as on a line


def _garble_one(frame: bytes, rng: random.Random) -> bytes:
    """One byte of the frame changed (XOR with a non-zero value)."""
    if not frame:
        return frame
    i = rng.randrange(len(frame))
    return frame[:i] + bytes([frame[i] ^ rng.randrange(1, 256)]) + frame[i + 1:]


def with_port(config_text: str, ports: dict[str, str]) -> str:
    """A rig configuration (TOML text) with each named device's ``port`` replaced."""
    out, section = [], None
    for line in config_text.splitlines():
        m = re.match(r"\s*\[(\w+)\]", line)
        if m:
            section = m.group(1)
        elif section in ports and re.match(r"\s*port\s*=", line):
            line = f'port = "{ports[section]}"'
        out.append(line)
    return "\n".join(out) + "\n"

