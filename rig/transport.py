"""Serial transport: one owner and one lock per port, explicit time-outs, framing helpers.

Every port is opened through :func:`serial.serial_for_url`, so a driver runs unchanged on a
real port, a pseudo-terminal (``/dev/pts/N``), ``loop://``, ``spy://`` (traffic log) or
``socket://host:port`` or an in-process virtual device (``virtual://``). Replies are framed by length (binary: :meth:`read_exactly`) or by
terminator (ASCII: :meth:`read_until`), each against a deadline. A missing reply raises
``DeviceError(device, "no answer to 'MSV?' within 0.2 s")``; a port that vanishes (OSError,
SerialException) raises ``DeviceError(device, "port /dev/... disappeared")``.

Deadlines run on the port's clock (the ``clock`` attribute of the port object, e.g. a
virtual device's :class:`flowcurve.clock.ModelClock`; :data:`flowcurve.clock.WALL` for
every real port), exposed as :attr:`SerialTransport.clock` for the drivers' own timing.

Retries are the caller's decision: :meth:`exchange` repeats a command only when told it is
safe (reads and idempotent settings), never for commands with one-off side effects.

:class:`DconDevice` is the DCON exchange layer over a transport (framing, checksum,
silence-means-error, the commands every DCON module shares); the furnace module and the
encoder box derive from it.
"""

from __future__ import annotations

import logging
import os
import threading
from contextlib import contextmanager
from typing import Callable

import serial

try:
    from termios import error as TermiosError  # a pty whose other end vanished
except ImportError:  # not on POSIX
    class TermiosError(Exception):
        pass

from flowcurve.clock import WALL, Clock
from flowcurve.errors import DeviceError

PORT_ERRORS = (OSError, serial.SerialException, TermiosError)  # what a vanished port raises
from flowcurve.rig.codecs import dcon
from flowcurve.rig.port_lock import PortLock

logger = logging.getLogger(__name__)

# Ports currently open, by URL → the owning transport. One owner per port.
_OWNERS: dict[str, "SerialTransport"] = {}
_OWNERS_LOCK = threading.Lock()
_UNSHARED_SCHEMES = ("loop://",)
# A command whose reply did not come within its time-out may still be answered late: before
# the next command the port waits for that reply up to this many time-outs after the command
# was sent, and discards it, so that a late (stale) reply is never taken for the next one's
LATE_REPLY_TIMEOUTS = 3
READ_SLICE_S = 0.01  # the port's own read time-out; exchanges loop on their own deadline  # every loop:// open is a port of its own


def _owned_key(url: str, opener: Callable | None) -> object | None:
    """The key of a port in the owner table (a custom opener is a port namespace of its own)."""
    if url.startswith(_UNSHARED_SCHEMES):
        return None
    return url if opener is None else (opener, url)


class SerialTransport:
    """The single owner of one serial port.

    ``opener`` (default :func:`serial.serial_for_url`) is called as
    ``opener(url, baudrate=..., parity=..., bytesize=..., stopbits=..., timeout=...)``;
    tests pass a fake that checks the bytes written and feeds replies.
    """

    def __init__(self, url: str, *, name: str = "device", baudrate: int = 9600,
                 parity: str = "N", bytesize: int = 8, stopbits: float = 1,
                 timeout_s: float = 0.2, opener: Callable | None = None):
        self.url = url
        self.name = name
        self.settings = dict(baudrate=baudrate, parity=parity, bytesize=bytesize, stopbits=stopbits)
        self.timeout_s = timeout_s
        self.lock = threading.RLock()
        self._opener = opener or serial.serial_for_url
        self._key = _owned_key(url, opener)
        self._port = None
        self._lock_file = None  # rig.port_lock.PortLock while open
        self._pending = bytearray()  # bytes read past the end of the last frame
        self.clock: Clock = WALL  # the port's clock once open (see the module docstring)
        self._unanswered: tuple[float, int | None, bytes | None] | None = None  # (sent, length, terminator)
        self.late_replies = 0  # replies that came after their time-out, discarded
        self.retried_exchanges = 0  # retries made after a silent, garbled or wrongly addressed reply
        self.failed_after_retry = 0  # exchanges whose retries failed too (no reply taken: the caller's read failed)
        self.last_request_s: float | None = None  # clock time the last exchange's last attempt was sent
        self.last_late_s: float | None = None  # how late the last of them was

    def with_line(self, *, baudrate: int, parity: str, timeout_s: float | None = None) -> "SerialTransport":
        """A new (closed) transport on the same port and opener with other line settings."""
        return SerialTransport(self.url, name=self.name, baudrate=baudrate, parity=parity,
                               bytesize=self.settings["bytesize"], stopbits=self.settings["stopbits"],
                               timeout_s=self.timeout_s if timeout_s is None else timeout_s,
                               opener=None if self._opener is serial.serial_for_url else self._opener)

    # -- life cycle -------------------------------------------------------------------
    def open(self) -> "SerialTransport":
        """Open (and lock) the serial port; the transport."""
        if self._port is not None:
            return self
        key = self._key
        with _OWNERS_LOCK:
            owner = _OWNERS.get(key) if key is not None else None
            if owner is not None and owner is not self:
                raise DeviceError(self.name, f"port {self.url} is already open by '{owner.name}'")
            lock = PortLock(self.url, self.name) if self._opener is serial.serial_for_url else None
            if lock is not None:
                lock.acquire()  # another process holding the port: PortBusyError naming it
            try:
                # a short fixed read slice: deadlines are kept here, because changing a
                # pyserial port's timeout re-configures the line (tcsetattr) every time
                self._port = self._open_port()
            except (OSError, serial.SerialException, ValueError, TermiosError) as exc:
                if lock is not None:
                    lock.release()
                raise DeviceError(self.name, f"cannot open port {self.url}: {_reason(exc)}") from None
            self._lock_file = lock
            self.clock = getattr(self._port, "clock", WALL)
            if key is not None:
                _OWNERS[key] = self
        return self

    def _open_port(self):
        try:
            return self._opener(self.url, timeout=READ_SLICE_S, **self.settings)
        except TermiosError as exc:
            # some kernels refuse (EINVAL) a pty's tcsetattr with parity that keeps the
            # speed: open at another speed, then set the real one (a change, accepted)
            if self._opener is not serial.serial_for_url or getattr(exc, "args", (None,))[0] != 22:
                raise
            hop = 1200 if self.settings["baudrate"] != 1200 else 2400
            port = serial.serial_for_url(self.url, timeout=READ_SLICE_S, do_not_open=True, **{**self.settings, "baudrate": hop})
            port.open()
            port.baudrate = self.settings["baudrate"]
            return port

    def close(self) -> None:
        """Release the lock and close the port."""
        port, self._port = self._port, None
        lock, self._lock_file = self._lock_file, None
        if lock is not None:
            lock.release()
        with _OWNERS_LOCK:
            if self._key is not None and _OWNERS.get(self._key) is self:
                del _OWNERS[self._key]
        if port is not None:
            try:
                port.close()
            except PORT_ERRORS:
                pass

    @property
    def is_open(self) -> bool:
        """Whether the port is open."""
        return self._port is not None

    def __enter__(self) -> "SerialTransport":
        return self.open()

    def __exit__(self, *exc) -> None:
        self.close()

    @contextmanager
    def locked(self):
        """Hold the port for a sequence of exchanges that must not be interleaved."""
        with self._holding():
            yield self

    @contextmanager
    def _holding(self):
        """The port's lock; while another thread's exchange holds it, this thread is idle on
        the clock (on a model clock, time then moves on without it)."""
        if not self.lock.acquire(blocking=False):
            with self.clock.idle():
                self.lock.acquire()
        try:
            yield
        finally:
            self.lock.release()

    # -- raw I/O ----------------------------------------------------------------------
    def _require_port(self):
        if self._port is None:
            self.open()
        return self._port

    def write(self, data: bytes) -> None:
        """Write ``data`` to the port; DeviceError on a port failure."""
        port = self._require_port()
        try:
            port.write(data)
            port.flush()
        except PORT_ERRORS:
            raise self._disappeared() from None

    def discard_input(self) -> None:
        """Forget anything received but not yet read (stale frames, late replies)."""
        port = self._require_port()
        self._pending.clear()
        try:
            port.reset_input_buffer()
        except PORT_ERRORS:
            raise self._disappeared() from None

    def buffered(self) -> int:
        """Bytes received and not yet framed (ours and the port's)."""
        port = self._require_port()
        try:
            return len(self._pending) + port.in_waiting
        except PORT_ERRORS:
            raise self._disappeared() from None

    def _read_some(self, size: int, deadline: float) -> bytes:
        port = self._require_port()
        remaining = deadline - self.clock.now()
        if remaining <= 0:
            return b""
        try:
            waiting = port.in_waiting
            return port.read(max(size, min(waiting, 4096)) if waiting else size)
        except PORT_ERRORS + (TypeError,):
            # TypeError: pyserial's posix read on a vanished file descriptor
            raise self._disappeared() from None

    def read_exactly(self, n: int, timeout: float | None = None, *, what: str = "a reply") -> bytes:
        """Exactly ``n`` bytes before the deadline, else :class:`DeviceError` (framing by length)."""
        timeout = self.timeout_s if timeout is None else timeout
        self._require_port()
        deadline = self.clock.now() + timeout
        with self._holding():
            while len(self._pending) < n:
                chunk = self._read_some(n - len(self._pending), deadline)
                if not chunk and self.clock.now() >= deadline:
                    # a partial frame stays buffered: a stream keeps its framing, and an
                    # exchange discards input before it writes anyway
                    raise self._timeout(what, timeout, bytes(self._pending))
                self._pending += chunk
            frame = bytes(self._pending[:n])
            del self._pending[:n]
            return frame

    def read_until(self, terminator: bytes = b"\r", timeout: float | None = None, *,
                   what: str = "a reply", max_bytes: int = 256) -> bytes:
        """Bytes up to and including ``terminator`` before the deadline (framing by terminator)."""
        timeout = self.timeout_s if timeout is None else timeout
        self._require_port()
        deadline = self.clock.now() + timeout
        with self._holding():
            while True:
                end = self._pending.find(terminator)
                if end >= 0:
                    end += len(terminator)
                    frame = bytes(self._pending[:end])
                    del self._pending[:end]
                    return frame
                if len(self._pending) > max_bytes:
                    got = bytes(self._pending)
                    self._pending.clear()
                    raise DeviceError(self.name, f"garbled answer to {what}: no {terminator!r} "
                                                 f"in {len(got)} bytes ({got[:40]!r}...)")
                chunk = self._read_some(1, deadline)
                if not chunk and self.clock.now() >= deadline:
                    got = bytes(self._pending)
                    self._pending.clear()
                    raise self._timeout(what, timeout, got)
                self._pending += chunk

    # -- exchanges --------------------------------------------------------------------
    def exchange(self, command: bytes, *, length: int | None = None, terminator: bytes | None = b"\r",
                 timeout: float | None = None, retries: int = 0, what: str | None = None,
                 parse: Callable[[bytes], object] | None = None):
        """Send ``command`` and read its reply (by ``length`` if given, else by ``terminator``).

        ``retries`` > 0 repeats the whole exchange after a time-out or a reply that ``parse``
        rejects (ValueError) — pass it only for reads and idempotent settings. Returns the
        reply bytes, or ``parse(reply)``. ``terminator=None`` with no length: nothing is read.
        """
        what = what or _describe(command)
        with self._holding():
            for attempt in range(retries + 1):
                last = attempt == retries
                self._await_unanswered()
                self.discard_input()
                self.last_request_s = self.clock.now()  # a retried reply is bracketed by its own attempt
                self.write(command)
                if length is None and terminator is None:
                    return None
                sent = self.clock.now()
                try:
                    if length is not None:
                        raw = self.read_exactly(length, timeout, what=what)
                    else:
                        raw = self.read_until(terminator, timeout, what=what)
                    return parse(raw) if parse else raw
                except DeviceError as exc:
                    if "disappeared" not in str(exc):
                        self._unanswered = (sent, length, terminator)
                        if self.last_late_s is not None:
                            exc = DeviceError(self.name, f"{str(exc).split(': ', 1)[-1]}; a reply came "
                                                         f"{self.last_late_s:.2f} s late and was discarded "
                                                         f"(stale replies are never taken) — line too slow for "
                                                         f"timeout_s = {self.timeout_s:g}?")
                    if last or "disappeared" in str(exc):
                        self.failed_after_retry += attempt > 0
                        raise exc from None
                    self.retried_exchanges += 1
                    logger.debug("%s: %s (attempt %d of %d), retrying", self.name, exc, attempt + 1, retries + 1)
                except ValueError as exc:
                    if last:
                        self.failed_after_retry += attempt > 0
                        failed = DeviceError(self.name, f"garbled answer to {what}: {exc}")
                        failed.reply_error = exc  # what the last reply was refused for (a caller may say it better)
                        raise failed from None
                    self.retried_exchanges += 1
                    logger.debug("%s: garbled answer to %s (attempt %d of %d), retrying", self.name, what, attempt + 1, retries + 1)
        raise AssertionError("unreachable")

    def _await_unanswered(self) -> None:
        """Wait for the late reply of an earlier command that timed out (up to
        :data:`LATE_REPLY_TIMEOUTS` time-outs after it was sent) and discard it."""
        if self._unanswered is None:
            return
        sent, length, terminator = self._unanswered
        self._unanswered = None
        horizon = sent + LATE_REPLY_TIMEOUTS * self.timeout_s
        got = bytearray(self._pending)
        self._pending.clear()
        while self.clock.now() < horizon:
            if (length is not None and len(got) >= length) or (length is None and terminator and terminator in got):
                self.late_replies += 1
                self.last_late_s = self.clock.now() - sent
                logger.info("%s: a reply came %.2f s after its command (time-out %g s): discarded",
                            self.name, self.last_late_s, self.timeout_s)
                return
            got += self._read_some(4096, horizon)

    def send(self, command: bytes) -> None:
        """Send a command that has no reply (``STP``, ``~**``, ``#**``, address selection)."""
        with self._holding():
            self.write(command)

    # -- errors -----------------------------------------------------------------------
    def _timeout(self, what: str, timeout: float, got: bytes) -> DeviceError:
        if got:
            return DeviceError(self.name, f"incomplete answer to {what} within {timeout:g} s "
                                          f"({len(got)} bytes: {got[:40]!r})")
        return DeviceError(self.name, f"no answer to {what} within {timeout:g} s")

    def _disappeared(self) -> DeviceError:
        self.close()
        return DeviceError(self.name, f"port {self.url} disappeared")


class _Decoded:
    """A decoded DCON reply value (distinguishes it from a bare Reply)."""

    def __init__(self, value):
        self.value = value


DCON_READ_RETRIES = 2  # reads and idempotent DCON settings may be repeated


class WrongAddressError(DeviceError):
    """A DCON reply that carries another module's address (``answered``) than the one asked
    (``expected``) for ``command``. ``commanded``: the command switches an output (the heater's
    ``@AADO``) — another module acknowledged it, so the output's state is unknown and the test
    must stop; a read's wrongly addressed reply is never taken (the read is repeated)."""

    def __init__(self, device: str, command: str, answered: str, expected: int, *, commanded: bool = False,
                 section: str | None = None):
        self.command = command
        self.answered = answered
        self.expected = expected
        self.commanded = commanded
        where = f"[{section}] address" if section else "its configured address"
        super().__init__(device, f"reply to {command} from address {answered}, not {expected:02X} — another module "
                                 f"answers on this line, or {where} is wrong ('flowcurve rig check' reads the module's "
                                 f"address)")


class _AnsweredByAnother(Exception):
    """Raised through an exchange (neither a DeviceError nor a ValueError: not retried)."""

    def __init__(self, wrong: dcon.WrongAddress):
        self.wrong = wrong


class DconDevice:
    """What the DCON devices share: framing, checksum, silent-on-error time-outs, and every
    reply from another module's address kept in :attr:`wrong_address_replies` as
    ``(port clock s, command, address that answered, commanded)`` for the record's events."""

    config_section: str | None = None  # the rig configuration's section, named in a wrong-address message
    probe_parities = ("N",)  # rig check --probe: DCON modules run 8N1

    def __init__(self, port_url, *, name: str, address: int, baudrate: int, parity: str,
                 timeout_s: float, checksum: bool, opener=None):
        if not 0 <= address <= 0xFF:
            raise ValueError(f"DCON address must be 0..255, got {address}")
        self.name = name
        self.address = address
        self.checksum = checksum
        self.wrong_address_replies: list[tuple[float, str, str, bool]] = []
        if isinstance(port_url, SerialTransport):
            self.transport = port_url
        else:
            self.transport = SerialTransport(port_url, name=name, baudrate=baudrate, parity=parity,
                                             timeout_s=timeout_s, opener=opener)

    def open(self):
        """Open the transport; the device."""
        self.transport.open()
        return self

    def close(self) -> None:
        """Close the transport."""
        self.transport.close()

    def __enter__(self):
        return self.open()

    def __exit__(self, *exc) -> None:
        self.close()

    def query(self, lead: str, body: str = "", decoder=None, *args,
              retries: int = DCON_READ_RETRIES, timeout: float | None = None,
              addressed: bool | Callable[[dcon.Reply], bool] = False, commanded: bool = False):
        """Send one framed command; return ``decoder(reply, *args)`` (or the :class:`dcon.Reply`).

        Silence (the DCON answer to a wrong address, syntax or checksum) and garbled replies
        are retried ``retries`` times, then raise DeviceError; a ``?`` is a definite refusal:
        DeviceError at once (or the refused Reply when there is no decoder).

        A reply from another module's address (``addressed``: the ``!AA``/``?AA`` reply carries
        it — or a predicate saying which replies do; decoders that check it with
        :func:`dcon.expect_ack` count too) is noted in :attr:`wrong_address_replies` and never
        taken: a read is repeated like a garbled reply (:class:`WrongAddressError` when every
        try was answered so); with ``commanded`` (the command switches an output) it is not
        repeated — :class:`WrongAddressError` at once.
        """
        raw_command = dcon.frame(lead, self.address, body, use_checksum=self.checksum)
        what = "'" + raw_command.decode("ascii").strip() + "'"

        def parse(raw: bytes):
            """The reply ``raw`` checked (its address when asked) and decoded; WrongAddress when another module answered."""
            reply = dcon.parse_reply(raw, use_checksum=self.checksum)
            try:
                if addressed is True or (callable(addressed) and addressed(reply)):
                    dcon.check_address(reply, self.address, what)
                if reply.refused or decoder is None:
                    return reply
                return _Decoded(decoder(reply, *args))
            except dcon.WrongAddress as wrong:
                self.wrong_address_replies.append((self.transport.clock.now(), what, wrong.answered, commanded))
                logger.warning("%s: reply to %s from address %s, not %02X%s", self.name, what, wrong.answered,
                               self.address, "" if commanded else " (not taken; asked again)")
                if commanded:
                    raise _AnsweredByAnother(wrong) from None
                raise

        self.open()
        try:
            got = self.transport.exchange(raw_command, terminator=dcon.CR, retries=retries,
                                          timeout=timeout, what=what, parse=parse)
        except _AnsweredByAnother as stop:
            raise WrongAddressError(self.name, what, stop.wrong.answered, self.address, commanded=True,
                                    section=self.config_section) from None
        except DeviceError as exc:
            wrong = getattr(exc, "reply_error", None)
            if isinstance(wrong, dcon.WrongAddress):
                raise WrongAddressError(self.name, what, wrong.answered, self.address, section=self.config_section) from None
            raise
        if isinstance(got, _Decoded):
            return got.value
        if got.refused and decoder is not None:
            raise DeviceError(self.name, f"refused {what} (answered '?')")
        return got

    def send(self, lead: str, body: str = "", *, broadcast: bool = False) -> None:
        """A command without reply (``~**``, ``#**``)."""
        self.open()
        self.transport.send(dcon.frame(lead, None if broadcast else self.address, body,
                                       use_checksum=self.checksum))

    def answers(self) -> None:
        """One exchange that names the module (``$AA2``); raises :class:`DeviceError` when silent."""
        self.configuration()

    def configuration(self) -> dcon.Configuration:
        """``$AA2``: address, type, baud, format and checksum flag as the module reports them."""
        return self.query("$", "2", dcon.parse_configuration, addressed=True)

    def module_name(self) -> str:
        """``$AAM`` → e.g. ``7011`` (the text after the address)."""
        return self.query("$", "M", dcon.expect_ack, self.address, "$AAM")

    def firmware(self) -> str:
        """``$AAF`` → the firmware version text."""
        return self.query("$", "F", dcon.expect_ack, self.address, "$AAF")

    def set_configuration(self, *, new_address: int | None = None, type_code: int | None = None,
                          baud: int | None = None, format_byte: int | None = None,
                          settle_timeout_s: float = 3.0) -> dcon.Configuration:
        """``%AANNTTCCFF``: change address, input type, baud or data format (unchanged fields
        keep the module's present values). Baud and checksum changes need the module's INIT
        pin, else it refuses. A module may be silent for seconds after the write: the reply
        gets ``settle_timeout_s``. Returns the configuration read back with ``$AA2``."""
        now = self.configuration()
        body = dcon.set_configuration_body(
            now.address if new_address is None else new_address,
            now.type_code if type_code is None else type_code,
            now.baud if baud is None else baud,
            now.format_byte if format_byte is None else format_byte)
        target = int(body[:2], 16)
        acked = self.query("%", body, dcon.expect_ack, None, "%AANNTTCCFF", timeout=settle_timeout_s)
        if acked.upper() != f"{target:02X}":
            raise DeviceError(self.name, f"%AANNTTCCFF acknowledged for address {acked!r}, not {target:02X}")
        self.address = target
        self.checksum = bool((now.format_byte if format_byte is None else format_byte) & 0x40)
        return self.configuration()

    def watchdog_timeout(self) -> tuple[bool | None, float]:
        """``~AA2`` → (enabled, time-out in s) of the host watchdog."""
        return self.query("~", "2", dcon.parse_watchdog_timeout, self.address)

    def host_ok(self) -> None:
        """``~**``: tell every module on the line that the host is alive (no reply)."""
        self.send("~", broadcast=True)

    def watchdog_status(self) -> int:
        """``~AA0`` → status byte; ``dcon.WATCHDOG_TIMED_OUT`` (04) when the host went silent."""
        return self.query("~", "0", dcon.parse_watchdog_status, self.address)

    def clear_watchdog(self) -> None:
        """``~AA1``: clear the watchdog status (idempotent)."""
        self.query("~", "1", dcon.expect_ack, self.address, "~AA1")

    def set_watchdog(self, enabled: bool, timeout_s: float) -> None:
        """``~AA3EVV``: host watchdog on/off with its time-out (idempotent)."""
        self.query("~", dcon.watchdog_body(enabled, timeout_s), dcon.expect_ack, self.address, "~AA3EVV")


def _describe(command: bytes) -> str:
    text = command.decode("ascii", "replace").strip("\r\n;").replace(";", " ")
    return f"'{text}'"


def _reason(exc: Exception) -> str:
    errno = getattr(exc, "errno", None)
    if isinstance(errno, int):
        return os.strerror(errno)
    text = str(exc).strip() or type(exc).__name__
    return text.splitlines()[0]
