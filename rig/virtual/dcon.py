"""Virtual DCON modules on a pty: the framing and host watchdog shared by the ICP DAS family
(:class:`DconDevice`) and the I-7011-class furnace module (:class:`I7011`) — docs/protocols.md.

Framing: ``<lead><AA hex><command>[CS]\\r``; replies ``>`` data, ``!`` acknowledged, ``?``
refused, then ``[CS]\\r``. With checksums on, CS = sum of the characters before CR mod 256
as two upper-case hex digits (``$012`` → ``$012B7``). **Silent** on a wrong address, a bad
or missing checksum, a non-ASCII frame or unknown syntax.

Host watchdog (I-7000 family behaviour): only the ``~**`` broadcast feeds it (other
commands do not); ``~AA3EVV`` arms it (E 0/1, VV time-out in 0.1 s, hex); when the host is
quiet longer than the time-out the module sets its outputs to the safe value of
``~AA5PPSS``, sets status 04 (``~AA0`` → ``!AA04``) and refuses output commands (``?AA``)
until ``~AA1`` clears the status. The watchdog runs on the device's clock (real time on a pty),
and an armed one outlives the virtual rig's session (:meth:`DconDevice.close`).

I-7011 replies chosen where docs/protocols.md leaves the format open, after the I-7011 manual:
``#AA`` → ``>+0025.12`` (engineering, ``+dddd.dd``), ``>+001.84`` (% of FSR), ``>0046`` (hex,
two's complement of full scale); ``+9999`` / ``7FFF`` over range or open thermocouple;
``$AA3`` → ``>+0025.0`` (cold junction); ``$AAB`` → ``!AAS``; ``$AAF`` → ``!AAA2.0``;
``$AAM`` → ``!AA7011``; ``@AADI`` → ``!AASOOII`` (alarm S, DO OO, DI II — manual example
``!0100001``); ``@AADOdd`` → ``!AA`` (dd 00–03; DO0 is the heater relay); ``~AA2`` →
``!AAEVV``; ``~AA4P``/``~AA4S`` → ``!AAVV`` (power-on / safe value).
"""

from __future__ import annotations

import math
import re
import time
from typing import Callable

from flowcurve.rig.virtual.wire_format import THERMOCOUPLE_FULL_SCALE_C, dcon_checksum
from flowcurve.rig.virtual.pty_device import PtyDevice

FORMAT_BITS = 0x03
CHECKSUM_BIT = 0x40
WATCHDOG_TIMED_OUT = 0x04
# the host's feeding gaps are host time: on a fast time scale the virtual watchdog waits at
# least this long in host seconds (a loaded PC cannot promise shorter gaps), i.e. it counts
# model time only while timeout / time_scale is longer than this
WATCHDOG_HOST_FLOOR_S = 1.0
TYPE_CODES = tuple(range(0x00, 0x07)) + tuple(range(0x0E, 0x17))  # mV/V ranges + thermocouples


class DconDevice(PtyDevice):
    """DCON framing, checksum, addressing and host watchdog; subclasses answer commands."""

    name = "dcon"

    def __init__(self, *, address: int, checksum_on: bool = False, **kw):
        super().__init__(**kw)
        self.address = address
        self.checksum_on = checksum_on
        self._buffer = b""
        self.watchdog_enabled = False
        self.watchdog_timeout_s = 0.0
        self.watchdog_status = 0
        self._last_host_ok = self.clock.now()
        # model seconds per host second: the watchdog counts its time-out on the model's
        # time, as the real module would see the test (VirtualRig sets it)
        self.time_scale = 1.0
        self.reply_address: int | None = None  # fault 'wrong_address': answer as this module

    # -- framing ----------------------------------------------------------------------
    def on_bytes(self, data: bytes) -> None:
        """Take bytes from the host and answer each complete command."""
        self._buffer += data
        while b"\r" in self._buffer:
            raw, self._buffer = self._buffer.split(b"\r", 1)
            self._frame(raw)
        if len(self._buffer) > 256:
            self._buffer = b""

    def _frame(self, raw: bytes) -> None:
        try:
            text = raw.decode("ascii")
        except UnicodeDecodeError:
            return
        text = text.lstrip("\n")
        if self.checksum_on:
            if len(text) < 3 or text[-2:].upper() != dcon_checksum(text[:-2]):
                return
            text = text[:-2]
        if text == "~**":
            self._last_host_ok = self.clock.now()
            return
        if text.startswith("#**"):
            self.broadcast(text)
            return
        if len(text) < 3 or text[0] not in "#$%@~":
            return
        try:
            addr = int(text[1:3], 16)
        except ValueError:
            return
        if addr != self.address:
            return
        reply = self.command(text[0], text[3:])
        if reply is not None:
            self.reply(reply)

    def reply(self, text: str) -> None:
        """Send ``text`` to the host (its address and checksum as configured)."""
        if self.reply_address is not None and text[:1] in "!?" and text[1:3] == self.aa:
            text = f"{text[0]}{self.reply_address:02X}{text[3:]}"
        if self.checksum_on:
            text += dcon_checksum(text)
        self.send(text.encode("ascii") + b"\r")

    @property
    def aa(self) -> str:
        """The module's address as two hex digits."""
        return f"{self.address:02X}"

    # -- to override ------------------------------------------------------------------
    def command(self, lead: str, body: str) -> str | None:
        """Reply text (without checksum and CR) to a command for this module; None: silent."""
        if lead == "~":
            return self.watchdog_command(body)
        return None

    def broadcast(self, text: str) -> None:
        """A ``#**`` broadcast (no reply)."""

    def watchdog_tripped(self) -> None:
        """The host went quiet: put outputs to their safe values."""

    # -- host watchdog ----------------------------------------------------------------
    def watchdog_command(self, body: str) -> str | None:
        """The reply to a host-watchdog command ``body`` (status, reset, read, set …), None when not one."""
        aa = self.aa
        if body == "0":
            return f"!{aa}{self.watchdog_status:02X}"
        if body == "1":
            self.watchdog_status = 0
            self._last_host_ok = self.clock.now()  # the time-out counts again from now
            return f"!{aa}"
        if body == "2":
            return f"!{aa}{int(self.watchdog_enabled)}{round(self.watchdog_timeout_s * 10):02X}"
        m = re.fullmatch(r"3([01])([0-9A-Fa-f]{2})", body)
        if m:
            units = int(m.group(2), 16)
            if m.group(1) == "1" and units == 0:
                return f"?{aa}"
            self.watchdog_enabled = m.group(1) == "1"
            self.watchdog_timeout_s = units / 10.0
            self._last_host_ok = self.clock.now()
            return f"!{aa}"
        return None

    @property
    def watchdog_host_s(self) -> float:
        """The watchdog's time-out in host seconds: its model-time time-out / time scale, but
        not below :data:`WATCHDOG_HOST_FLOOR_S` (nor above the time-out itself)."""
        return max(self.watchdog_timeout_s / self.time_scale, min(self.watchdog_timeout_s, WATCHDOG_HOST_FLOOR_S))

    def next_deadline(self) -> float | None:
        """When the host watchdog trips next, None when disarmed or tripped."""
        if self.watchdog_enabled and not self.watchdog_status & WATCHDOG_TIMED_OUT:
            return self._last_host_ok + self.watchdog_host_s
        return None

    def on_tick(self, now: float) -> None:
        """Trip the host watchdog when the host was silent too long at ``now``."""
        if (self.watchdog_enabled and not self.watchdog_status & WATCHDOG_TIMED_OUT
                and now - self._last_host_ok >= self.watchdog_host_s):
            self.watchdog_status |= WATCHDOG_TIMED_OUT
            self.watchdog_tripped()

    def close(self) -> None:
        """The virtual rig closes, but a real module stays powered: a watchdog still armed (the
        host is gone without disarming it: unplugged, silent, killed) runs its time-out out on
        its own clock, as the pty's thread or a real module would, so the outputs end at their
        safe value. In-process nothing moves the clock after the run: the trip is taken here."""
        with self._lock:
            if self.watchdog_enabled and not self.watchdog_status & WATCHDOG_TIMED_OUT:
                self.watchdog_status |= WATCHDOG_TIMED_OUT
                self.watchdog_tripped()
        super().close()


class I7011(DconDevice):
    """Thermocouple input + two digital outputs; DO0 switches the heater relay.

    ``read_temperature()`` returns the thermocouple's temperature in °C (``inf`` when
    open); ``set_heater(on)`` receives every change of DO0; ``cold_junction_C()`` the
    terminal temperature.
    """

    name = "furnace"

    def __init__(self, read_temperature: Callable[[], float], set_heater: Callable[[bool], None], *,
                 address: int = 0x01, type_code: int = 0x0F, baud_code: int = 0x06,
                 data_format: int = 0, checksum_on: bool = False, init_pin: bool = False,
                 cold_junction_C: Callable[[], float] = lambda: 25.0,
                 power_on_do: int = 0, safe_do: int = 0, **kw):
        super().__init__(address=address, checksum_on=checksum_on, **kw)
        self.read_temperature = read_temperature
        self.set_heater = set_heater
        self.cold_junction_C = cold_junction_C
        self.type_code = type_code
        self.baud_code = baud_code
        self.data_format = data_format
        self.init_pin = init_pin
        self.power_on_do, self.safe_do = power_on_do, safe_do
        self.do = power_on_do & 0x03
        self.set_heater(bool(self.do & 1))
        self._corrupt_C = 0.0

    def corrupt_next(self, delta_C: float) -> None:
        """Fault 'corrupt': the next reading is off by ``delta_C`` (a well-formed reply)."""
        self._corrupt_C = float(delta_C)

    @property
    def format_byte(self) -> int:
        """The configuration's data-format byte (checksum bit included)."""
        return (self.data_format & FORMAT_BITS) | (CHECKSUM_BIT if self.checksum_on else 0)

    def reading_text(self, temperature_C: float) -> str:
        """The ``#AA`` data in the present format."""
        full_scale = THERMOCOUPLE_FULL_SCALE_C.get(self.type_code, 1370.0)
        over = not math.isfinite(temperature_C) or temperature_C > full_scale
        if self.data_format == 2:
            if over:
                return "7FFF"
            return f"{int(round(temperature_C / full_scale * 0x7FFF)) & 0xFFFF:04X}"
        if over:
            return "+9999"
        if self.data_format == 1:
            return f"{temperature_C / full_scale * 100.0:+07.2f}"
        return f"{temperature_C:+08.2f}"

    def _set_do(self, value: int) -> None:
        self.do = value & 0x03
        self.set_heater(bool(self.do & 1))

    def watchdog_tripped(self) -> None:
        """Outputs to their safe values on a watchdog trip."""
        self._set_do(self.safe_do)

    def command(self, lead: str, body: str) -> str | None:
        """The I-7011's reply to a command (``lead`` and ``body``), None when silent."""
        aa = self.aa
        if lead == "#" and body == "":
            corrupt, self._corrupt_C = self._corrupt_C, 0.0
            return ">" + self.reading_text(self.read_temperature() + corrupt)
        if lead == "$":
            if body == "2":
                return f"!{aa}{self.type_code:02X}{self.baud_code:02X}{self.format_byte:02X}"
            if body == "3":
                return f">{self.cold_junction_C():+07.1f}"
            if body == "B":
                return f"!{aa}{int(not math.isfinite(self.read_temperature()))}"
            if body == "F":
                return f"!{aa}A2.0"
            if body == "M":
                return f"!{aa}7011"
            return None
        if lead == "%":
            return self._configure(body)
        if lead == "@":
            if body == "DI":
                return f"!{aa}0{self.do:02X}00"
            m = re.fullmatch(r"DO([0-9A-Fa-f]{2})", body)
            if m:
                value = int(m.group(1), 16)
                if value > 0x03 or self.watchdog_status & WATCHDOG_TIMED_OUT:
                    return f"?{aa}"
                self._set_do(value)
                return f"!{aa}"
            return None
        if lead == "~":
            m = re.fullmatch(r"4([PS])", body)
            if m:
                return f"!{aa}{(self.power_on_do if m.group(1) == 'P' else self.safe_do):02X}"
            m = re.fullmatch(r"5([0-9A-Fa-f]{2})([0-9A-Fa-f]{2})", body)
            if m:
                self.power_on_do, self.safe_do = int(m.group(1), 16), int(m.group(2), 16)
                return f"!{aa}"
            return self.watchdog_command(body)
        return None

    def _configure(self, body: str) -> str | None:
        m = re.fullmatch(r"([0-9A-Fa-f]{2})([0-9A-Fa-f]{2})([0-9A-Fa-f]{2})([0-9A-Fa-f]{2})", body)
        if not m:
            return None
        nn, tt, cc, ff = (int(g, 16) for g in m.groups())
        if tt not in TYPE_CODES or (ff & FORMAT_BITS) == 3:
            return f"?{self.aa}"
        if (cc != self.baud_code or bool(ff & CHECKSUM_BIT) != self.checksum_on) and not self.init_pin:
            return f"?{self.aa}"
        self.address, self.type_code, self.baud_code = nn, tt, cc
        self.data_format, self.checksum_on = ff & FORMAT_BITS, bool(ff & CHECKSUM_BIT)
        return f"!{nn:02X}"
