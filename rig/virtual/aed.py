"""Virtual HBM AED load-cell amplifier (AD103/AD104 class) on a pty — docs/protocols.md.

Behaviour implemented (command names are case-insensitive, end with ``;`` or LF):

* a bare terminator clears the input buffer; ``Snn`` selects the unit at address nn (the
  others ignore everything but ``Snn``); ``S98`` addresses all units: commands execute but
  nothing answers (a bus would collide) except ``BDR``; an ``MSV?`` under ``S98`` is held
  until the unit is selected by its own ``Snn``, which sends it (bus polling);
* ``IDN?``; ``MSV?`` one value, ``MSV?N`` N values, ``MSV?0`` a stream until ``STP``/``RES``,
  at the ``ICR`` rate (100, 50, 25, 12, 6, 3, 2, 1 /s), in the ``COF`` format (frames of
  :mod:`flowcurve.rig.virtual.wire_format`; binary frames can contain CR/LF). While it streams, settings are
  ignored without an answer (an answer would corrupt the stream); ``COF`` +128 streams
  from power-on (and after ``RES``);
* settings answer ``0`` (accepted) or ``?`` (refused; ``ESR?`` then tells why: 1 unknown
  command, 2 parameter out of range, 3 not allowed now — the virtual unit's own codes);
  queries ``COF? ICR? ASF? FMD? NOV? TAS? TAV? ADR? BDR? ESR?``; ``TAR`` tares (net
  output, ``TAS0``), ``TAS1`` gross; ``TDD1`` saves the settings that ``RES`` restores;
  ``RES`` and ``STP`` never answer;
* ``ASF1…8`` is a first-order low-pass at the FMD0 −3 dB point, run in model time;
* the stream keeps the amplifier's own rhythm: each frame carries the force at its due time
  (``source_at(due)``), so a twin thread the host's CPU held up sends its late frames late, in
  a burst, each with its own value (a real amplifier samples on its crystal whatever the line
  does); only frames due more than ``CATCH_UP_S`` ago, or further back than the model
  remembers, are skipped (``frames_skipped``);
* status byte: bit0 |net| > nominal, bit1 |gross| > nominal, bit2 ADC overflow
  (|gross| > 1.25 × nominal, i.e. beyond ±2.5 mV/V on a 2 mV/V bridge; the value clamps
  there), bit3 standstill (crosshead not moving). 2-byte binary codes |net| > nominal as
  ``7FFF``/``8000``. ``NOV`` > 0 sets the ASCII count of nominal load.
"""

from __future__ import annotations

import math
import re
import time
from typing import Callable

from flowcurve.rig.virtual.wire_format import (
    FILTER_CUTOFF_HZ, OUTPUT_RATES_PER_S, STATUS_ADC_OVERFLOW, STATUS_GROSS_OVERFLOW,
    STATUS_NET_OVERFLOW, STATUS_STANDSTILL, aed_frame, is_known_cof, is_two_byte_cof,
    nominal_counts,
)
from flowcurve.rig.virtual.pty_device import PtyDevice

# A sample of the amplifier's input: (model time s, force N, standstill).
Sample = tuple[float, float, bool]

BAUD_RATES = (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200)
ADC_LIMIT = 1.25  # ±2.5 mV/V input range on a 2 mV/V bridge, in units of nominal load

ESR_NONE, ESR_UNKNOWN, ESR_RANGE, ESR_BUSY = 0, 1, 2, 3

CATCH_UP_S = 1.0  # host seconds of late frames a held-up twin still sends (older ones are skipped)

DEFAULTS = {"cof": 3, "icr": 0, "asf": 5, "fmd": 0, "nov": 0, "tas": 0, "tare": 0.0}


class AEDAmplifier(PtyDevice):
    """The load-cell amplifier. ``source()`` returns (model time s, force N, standstill) now;
    ``source_at(t)`` the same at the clock time ``t`` (the stream's due times; None: the stream
    samples ``source()`` when it sends, or no sample is remembered that far back)."""

    name = "loadcell"

    def __init__(self, source: Callable[[], Sample], *, source_at: Callable[[float], Sample | None] | None = None,
                 nominal_load_N: float = 100e3,
                 address: int = 31, serial: str = "1234", model: str = "AED104",
                 firmware: str = "P20", settings: dict | None = None, **kw):
        super().__init__(**kw)
        self.source = source
        self.source_at = source_at
        self.frames_skipped = 0  # stream frames due so long ago that the model no longer remembers them
        self.nominal_load_N = float(nominal_load_N)
        self.address = address
        self.idn = f'HBM,"{model:<15}","{serial:<7}",{firmware}\r\n'.encode("ascii")
        self.saved = dict(DEFAULTS, **(settings or {}))
        self.s = dict(self.saved)
        self.baud, self.parity = 9600, 1
        self.selected, self.broadcast = True, False
        self.esr = ESR_NONE
        self._buffer = b""
        self._remaining = 0  # values still to stream (-1: until STP)
        self._next_due: float | None = None
        self._held: bytes | None = None  # MSV? under S98, sent when selected
        self._filtered: float | None = None
        self._last_t: float | None = None
        self._corrupt_N = 0.0
        self._power_on_stream()

    def corrupt_next(self, delta_N: float) -> None:
        """Fault 'corrupt': the next measured frame is off by ``delta_N`` (well-formed; AED
        frames carry no checksum)."""
        self._corrupt_N = float(delta_N)

    # -- values -----------------------------------------------------------------------
    def _power_on_stream(self) -> None:
        if self.s["cof"] & 128:
            self._remaining, self._next_due = -1, self.clock.now()

    def _filter(self, t: float, force: float) -> float:
        fc = FILTER_CUTOFF_HZ[self.s["asf"]] if self.s["fmd"] == 0 else None
        if fc is None or self._filtered is None or self._last_t is None or t <= self._last_t:
            y = force if fc is None or self._filtered is None else self._filtered
        else:
            alpha = 1.0 - math.exp(-2.0 * math.pi * fc * (t - self._last_t))
            y = self._filtered + alpha * (force - self._filtered)
        self._filtered, self._last_t = y, t
        return y

    def measured_frame(self, sample: Sample | None = None) -> bytes:
        """One measured value in the present COF format (``sample``: the input at the frame's
        due time; None: now)."""
        t, force, standstill = self.source() if sample is None else sample
        corrupt, self._corrupt_N = self._corrupt_N, 0.0
        gross = (self._filter(t, force) + corrupt) / self.nominal_load_N  # in units of nominal load
        status = STATUS_STANDSTILL if standstill else 0
        if abs(gross) > ADC_LIMIT:
            status |= STATUS_ADC_OVERFLOW
            gross = math.copysign(ADC_LIMIT, gross)
        if abs(gross) > 1.0:
            status |= STATUS_GROSS_OVERFLOW
        net = gross - self.s["tare"] if self.s["tas"] == 0 else gross
        if abs(net) > 1.0:
            status |= STATUS_NET_OVERFLOW
        cof = self.s["cof"]
        counts = int(round(net * nominal_counts(cof, self.s["nov"])))
        if is_two_byte_cof(cof) and status & STATUS_NET_OVERFLOW:
            counts = 0x7FFF if net > 0 else -0x8000
        return aed_frame(cof, counts, status=status, address=self.address)

    # -- input ------------------------------------------------------------------------
    def on_bytes(self, data: bytes) -> None:
        """Take bytes from the host and answer each complete command."""
        self._buffer += data
        while True:
            m = re.search(rb"[;\n]", self._buffer)
            if not m:
                break
            raw, self._buffer = self._buffer[:m.start()], self._buffer[m.end():]
            self._command(raw.strip(b"\r\n \t").decode("ascii", "replace").upper())
        if len(self._buffer) > 256:
            self._buffer = b""

    def _reply(self, text: str | bytes) -> None:
        if self.broadcast:
            return
        self.send(text if isinstance(text, bytes) else (text + "\r\n").encode("ascii"))

    def _ack(self, ok: bool, error: int = ESR_RANGE) -> None:
        if not ok:
            self.esr = error
        self._reply("0" if ok else "?")

    def _command(self, cmd: str) -> None:
        if not cmd:
            return  # a bare terminator clears the input buffer
        m = re.fullmatch(r"S(\d\d)", cmd)
        if m:
            n = int(m.group(1))
            self.broadcast = n == 98
            self.selected = n in (98, self.address)
            if n == self.address and self._held is not None:
                self.send(self._held)
                self._held = None
            return
        if not self.selected:
            return
        streaming = self._remaining != 0
        if cmd == "STP":
            self._remaining, self._next_due = 0, None
            return
        if cmd == "RES":
            self._remaining, self._next_due = 0, None
            self.s = dict(self.saved)
            self._filtered = None
            self._power_on_stream()
            return
        if streaming:
            self.esr = ESR_BUSY
            return
        if cmd == "IDN?":
            self._reply(self.idn)
        elif cmd.startswith("MSV?"):
            self._msv(cmd[4:])
        elif cmd == "ESR?":
            self._reply(str(self.esr))
            self.esr = ESR_NONE
        elif cmd.startswith("BDR"):
            self._bdr(cmd[3:])
        elif cmd == "TAR":
            t, force, _ = self.source()
            self.s["tare"], self.s["tas"] = self._filter(t, force) / self.nominal_load_N, 0
            self._ack(True)
        elif cmd == "TDD1":
            self.saved = dict(self.s)
            self._ack(True)
        elif cmd == "TDD0":
            self.s = dict(DEFAULTS)
            self._ack(True)
        else:
            self._setting(cmd)

    def _msv(self, arg: str) -> None:
        if arg == "":
            frame = self.measured_frame()
            if self.broadcast:
                self._held = frame
            else:
                self.send(frame)
            return
        if not arg.isdigit() or int(arg) > 65535:
            self._ack(False, ESR_RANGE)
            return
        self._remaining = -1 if int(arg) == 0 else int(arg)
        self._next_due = self.clock.now()
        self.on_tick(self._next_due)

    def _bdr(self, arg: str) -> None:
        if arg == "?":
            self.send(f"{self.baud},{self.parity}\r\n".encode("ascii"))  # answers even under S98
            return
        m = re.fullmatch(r"(\d+)(?:,([01]))?", arg)
        if not m or int(m.group(1)) not in BAUD_RATES:
            self.esr = ESR_RANGE
            self.send(b"?\r\n")
            return
        self.baud = int(m.group(1))
        if m.group(2) is not None:
            self.parity = int(m.group(2))
        self.send(b"0\r\n")  # at the new rate (a pty has none)

    _RANGES = {
        "COF": lambda v: is_known_cof(v),
        "ICR": lambda v: 0 <= v <= 7,
        "ASF": lambda v: 0 <= v <= 8,
        "FMD": lambda v: v in (0, 1),
        "NOV": lambda v: 0 <= v <= 1_600_000,
        "TAS": lambda v: v in (0, 1),
        "TAV": lambda v: abs(v) <= 1_250_000,
        "ADR": lambda v: 0 <= v <= 31,
    }

    def _setting(self, cmd: str) -> None:
        name, arg = cmd[:3], cmd[3:]
        if name not in self._RANGES:
            self._ack(False, ESR_UNKNOWN)
            return
        if arg == "?":
            if name == "TAV":
                self._reply(f"{int(round(self.s['tare'] * 1_000_000)):+08d}")
            elif name == "ADR":
                self._reply(f"{self.address:02d}")
            else:
                self._reply(str(self.s[name.lower()]))
            return
        if not re.fullmatch(r"[+-]?\d+", arg) or not self._RANGES[name](int(arg)):
            self._ack(False, ESR_RANGE)
            return
        value = int(arg)
        if name == "TAV":
            self.s["tare"] = value / 1_000_000
        elif name == "ADR":
            self.address = value
        else:
            self.s[name.lower()] = value
        self._ack(True)

    # -- continuous output ----------------------------------------------------------------
    def next_deadline(self) -> float | None:
        """The next streamed frame's time, None when not streaming."""
        return self._next_due if self._remaining != 0 else None

    def on_tick(self, now: float) -> None:
        """Send every frame due by ``now``, each with the input at its due time: late frames
        leave late, in order. Frames the input is no longer known for are skipped: due more
        than CATCH_UP_S ago (more than one period without ``source_at``)."""
        period = 1.0 / OUTPUT_RATES_PER_S[self.s["icr"]]
        keep_s = CATCH_UP_S if self.source_at is not None else period
        burst = []
        while self._remaining != 0 and self._next_due is not None and self._next_due <= now:
            if now - self._next_due > keep_s:  # held up this long: skip to the frames still known
                skip = math.ceil((now - self._next_due - keep_s) / period)
                self.frames_skipped += skip
                self._next_due += skip * period
                continue
            sample = None if self.source_at is None else self.source_at(self._next_due)
            if sample is None and self.source_at is not None:
                self.frames_skipped += 1
            else:
                burst.append(self.measured_frame(sample))
                if self._remaining > 0:
                    self._remaining -= 1
            self._next_due = self._next_due + period if self._remaining != 0 else None
        self.send(*burst)  # late frames in one write: the host finds them buffered together
