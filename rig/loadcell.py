"""The load-cell amplifier (HBM AED command set): identity, settings, tare, force readings.

A thin device class over :class:`~rig.transport.SerialTransport` and the pure codec
:mod:`rig.codecs.aed`. Counts become newtons by the stored calibration: nominal load reads
5 120 000 counts in 4-byte binary, 1 000 000 in ASCII and 20 000 in 2-byte binary.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

from flowcurve.errors import DeviceError
from flowcurve.rig.codecs import ProtocolError
from flowcurve.rig.codecs import aed
from flowcurve.rig.transport import SerialTransport

logger = logging.getLogger(__name__)

SETTING_RETRIES = 2  # ICR/ASF/COF/TAR are idempotent: safe to repeat
READ_RETRIES = 2


@dataclass(frozen=True)
class ForceSample:
    """One force reading: host monotonic time (the port's clock), force, raw status byte and overload flag."""

    t_monotonic_s: float
    force_N: float
    status: int | None
    overload: bool
    counts: int


class LoadCell:
    """HBM AED-class load-cell amplifier.

    Give the calibration either as ``nominal_load_N`` (the force that reads nominal counts)
    or as ``calibration_N_per_count`` (newtons per count on the 4-byte binary scale, where
    nominal reads 5 120 000). ``raise_on_overload`` makes an overloaded reading raise
    :class:`DeviceError` instead of only flagging the sample.
    """

    def __init__(self, port_url, *, name: str = "load cell", address: int | None = 31,
                 calibration_N_per_count: float | None = None, nominal_load_N: float | None = None,
                 baudrate: int = 9600, parity: str = "E", timeout_s: float = 0.2,
                 output_format: int = 3, select_address: bool = False,
                 raise_on_overload: bool = False, output_rate_per_s: float | None = None,
                 opener=None):
        if (calibration_N_per_count is None) == (nominal_load_N is None):
            raise ValueError("give exactly one of calibration_N_per_count and nominal_load_N")
        if calibration_N_per_count is not None:
            nominal_load_N = calibration_N_per_count * aed.NOMINAL_COUNTS_4BYTE
        if not nominal_load_N > 0:
            raise ValueError(f"nominal load must be positive, got {nominal_load_N}")
        self.name = name
        self.address = address
        self.nominal_load_N = float(nominal_load_N)
        self.raise_on_overload = raise_on_overload
        self.select_address = select_address
        self.fmt = aed.output_format(output_format)
        if isinstance(port_url, SerialTransport):
            self.transport = port_url
        else:
            self.transport = SerialTransport(port_url, name=name, baudrate=baudrate, parity=parity,
                                             timeout_s=timeout_s, opener=opener)
        self.output_rate_per_s = output_rate_per_s  # set by configure(rate_code=...)
        self.nov = 0  # NOV scale, read by configure() / read_scale()
        self.streaming = False
        self.stream_silence_s = 1.0
        self.max_resyncs = 3  # stream restarts in a row before a garbled stream is an error
        self.stream_resyncs = 0  # restarts so far (for the record's warnings)
        self.frames_received = 0  # good stream frames since the first start_stream
        self._first_arrival: float | None = None
        self._last_arrival: float | None = None
        self._resyncs_in_a_row = 0
        self._last_frame_t = 0.0
        self._last_sample_t = -math.inf
        self._selected = False

    # -- life cycle -------------------------------------------------------------------
    def open(self) -> "LoadCell":
        self.transport.open()
        if self.select_address and not self._selected and self.address is not None:
            self.transport.send(aed.command(f"S{self.address:02d}"))  # never answers
            self._selected = True
        return self

    def close(self) -> None:
        if self.transport.is_open and self.streaming:
            try:
                self.stop_stream()
            except DeviceError as exc:  # the port is closed next anyway
                logger.warning("%s: stopping the stream on close failed: %s", self.name, exc)
        self.transport.close()

    def __enter__(self) -> "LoadCell":
        return self.open()

    def __exit__(self, *exc) -> None:
        self.close()

    # -- exchanges --------------------------------------------------------------------
    def _query(self, text: str, *, retries: int = READ_RETRIES, parse=None, length=None):
        self._not_streaming(text)
        self.open()
        term = None if length else b"\r\n"
        return self.transport.exchange(aed.command(text), length=length, terminator=term,
                                       retries=retries, what=f"'{text}'", parse=parse)

    def _set(self, text: str, *, retries: int = SETTING_RETRIES) -> None:
        accepted = self._query(text, retries=retries, parse=aed.parse_ack)
        if not accepted:
            raise DeviceError(self.name, f"refused '{text}' (answered '?'; see ESR?)")

    def _not_streaming(self, text: str) -> None:
        if self.streaming:
            raise DeviceError(self.name, f"cannot send '{text}' while streaming (stop_stream first)")

    # -- commands ---------------------------------------------------------------------
    def identify(self) -> dict[str, str]:
        """``IDN?`` → manufacturer, model, serial, firmware."""
        return self._query("IDN?", parse=aed.parse_idn)

    def settings(self) -> dict[str, object]:
        """Read back baud/parity, output format, rate and filter codes."""
        baud, parity = self._query("BDR?", parse=aed.parse_baud)
        return {"baud": baud, "parity": parity,
                "output_format": self._query("COF?", parse=aed.parse_int_reply),
                "rate_code": self._query("ICR?", parse=aed.parse_int_reply),
                "filter": self._query("ASF?", parse=aed.parse_int_reply),
                "nov": self.read_scale()}

    def read_scale(self) -> int:
        """``NOV?``: the ASCII count of nominal load (0 = factory 1 000 000), kept for scaling.

        An amplifier that refuses the query is taken to be at the factory scale.
        """
        reply = self._query("NOV?")
        self.nov = 0 if reply.strip() == b"?" else aed.parse_int_reply(reply)
        if self.nov < 0:
            raise DeviceError(self.name, f"NOV? answered {self.nov}, not a count")
        return self.nov

    def configure(self, *, rate_code: int | None = None, filter: int | None = None,
                  fmt: int | None = None) -> None:
        """Set the output rate (``ICR0..7``), the filter (``ASF0..8``) and the format (``COF``);
        then read the ``NOV`` scale the force conversion needs."""
        if rate_code is not None:
            if rate_code not in range(len(aed.ICR_RATES_PER_S)):
                raise ValueError(f"rate code must be 0..7, got {rate_code}")
            self._set(f"ICR{rate_code}")
            self.output_rate_per_s = aed.ICR_RATES_PER_S[rate_code]
        if filter is not None:
            if filter not in aed.ASF_CUTOFF_HZ:
                raise ValueError(f"filter must be 0..8, got {filter}")
            self._set(f"ASF{filter}")
        if fmt is not None:
            new = aed.output_format(fmt)
            self._set(f"COF{fmt}")
            self.fmt = new
        self.read_scale()  # a NOV left set by someone would scale ASCII forces wrongly

    def tare(self) -> None:
        """``TAR``: take the present load as zero (switches to net)."""
        self._set("TAR")

    def read(self) -> ForceSample:
        """One ``MSV?`` measured value as a :class:`ForceSample`."""
        frame = self._query("MSV?", length=self.fmt.frame_length, parse=self._check_frame)
        return self._sample(frame, self.transport.clock.now())

    def _check_frame(self, frame: bytes) -> bytes:
        aed.decode_msv(frame, self.fmt)  # raises ProtocolError (a ValueError) → retried
        return frame

    def _sample(self, frame: bytes, t: float) -> ForceSample:
        try:
            value = aed.decode_msv(frame, self.fmt)
        except ProtocolError as exc:
            raise DeviceError(self.name, f"garbled measured value: {exc}") from None
        return self._to_sample(value, t)

    def _to_sample(self, value: aed.MeasuredValue, t: float) -> ForceSample:
        force = float(aed.counts_to_newtons(value.counts, self.fmt, self.nominal_load_N, self.nov))
        sample = ForceSample(t, force, value.status, value.overflow, value.counts)
        if sample.overload and self.raise_on_overload:
            raise DeviceError(self.name, f"overload: status {value.status:#04x}, {force:.0f} N")
        return sample

    def recover_line(self, bauds=aed.BAUD_RATES, parities=("E", "N")) -> dict[str, str]:
        """Bring an amplifier left at an unknown baud rate back to this driver's line settings.

        docs/protocols.md: send ``;S98;BDR<rate>,<parity>;`` at each rate in turn (``S98``
        addresses every unit, so a wrong address does not matter either), then select this
        unit (``S<address>``) at the wanted rate and ask ``IDN?``. Returns the identity.
        """
        if self.streaming:
            raise DeviceError(self.name, "cannot recover the line while streaming")
        baud, parity = self.transport.settings["baudrate"], self.transport.settings["parity"]
        if parity not in aed.PARITY_CODES:
            raise ValueError(f"the AED line has parity E or N, not {parity!r}")
        command = f";S98;BDR{baud},{aed.PARITY_CODES[parity]};".encode("ascii")
        self.transport.close()
        for trial_baud in bauds:
            for trial_parity in parities:
                with self.transport.with_line(baudrate=trial_baud, parity=trial_parity) as trial:
                    trial.send(command)
                    trial.clock.sleep(len(command) * 11 / trial_baud)  # let it leave the UART
        self.transport.open()
        if self.address is not None:
            self.transport.send(aed.command(f"S{self.address:02d}"))  # leave broadcast mode
        return self.identify()

    # -- continuous measurement -------------------------------------------------------
    def start_stream(self) -> None:
        """``MSV?0``: the amplifier sends values continuously until ``STP``."""
        self._not_streaming("MSV?0")
        self.open()
        self.transport.discard_input()
        self.transport.send(aed.command("MSV?0"))
        self.streaming = True
        self._last_frame_t = self.transport.clock.now()

    def read_stream(self, max_samples: int, timeout: float) -> list[ForceSample]:
        """Up to ``max_samples`` frames (by length) arriving within ``timeout`` seconds.

        Returns early when ``max_samples`` are in; a frame cut by the deadline stays
        buffered for the next call, so framing never slips. Timestamps are host times of
        arrival, back-dated by one output period per complete frame still buffered behind
        (known once ``configure(rate_code=...)`` ran). A frame that fails its check (a lost
        or extra byte: no CR LF where one is due) restarts the stream (``STP``, ``MSV?0``)
        to regain the framing — formats without CR LF (+32) cannot be checked. More than
        ``max_resyncs`` restarts in a row, or a stream silent for more than
        ``stream_silence_s``, raise DeviceError.
        """
        if not self.streaming:
            raise DeviceError(self.name, "read_stream without start_stream")
        deadline = self.transport.clock.now() + timeout
        samples: list[ForceSample] = []
        n = self.fmt.frame_length
        while len(samples) < max_samples:
            remaining = deadline - self.transport.clock.now()
            if remaining <= 0:
                break
            try:
                frame = self.transport.read_exactly(n, remaining, what="'MSV?0' stream")
            except DeviceError:
                if not self.transport.is_open:  # the port disappeared
                    raise
                break
            now = self.transport.clock.now()
            try:
                value = aed.decode_msv(frame, self.fmt)
            except ProtocolError as exc:
                self._resync(exc)
                continue
            self._resyncs_in_a_row = 0
            self.frames_received += 1
            t = self._stream_time(now)  # its arrival, back-dated past the frames already behind it
            self._first_arrival = t if self._first_arrival is None else self._first_arrival
            self._last_arrival = t
            samples.append(self._to_sample(value, t))
            self._last_frame_t = now
        silent = self.transport.clock.now() - self._last_frame_t
        if not samples and silent > self.stream_silence_s:
            raise DeviceError(self.name, f"stream ('MSV?0') silent for {silent:.1f} s")
        return samples

    @property
    def frames_lost(self) -> int:
        """Frames the amplifier sent (its rate × the time between the first and the last good
        frame's arrival, each back-dated past the frames buffered behind it) that did not arrive
        good: lost on the line, garbled, or skipped by restarts."""
        if self._first_arrival is None or not self.output_rate_per_s:
            return 0
        sent = round((self._last_arrival - self._first_arrival) * self.output_rate_per_s) + 1
        return max(0, sent - self.frames_received)

    def _resync(self, exc: ProtocolError) -> None:
        self.stream_resyncs += 1
        self._resyncs_in_a_row += 1
        logger.info("%s: garbled stream (%s), restarting it (%d in a row)", self.name, exc, self._resyncs_in_a_row)
        if self._resyncs_in_a_row > self.max_resyncs:
            raise DeviceError(self.name, f"garbled stream: {self._resyncs_in_a_row} restarts in a row "
                                         f"did not regain the framing ({exc})")
        self.stop_stream()
        self.start_stream()

    def _stream_time(self, now: float) -> float:
        # a frame read while later ones already wait in the buffer arrived earlier: back-date
        # it by one output period per complete frame behind it (a burst read at once keeps
        # its spacing); never before the previous sample
        t = now
        if self.output_rate_per_s:
            t -= (self.transport.buffered() // self.fmt.frame_length) / self.output_rate_per_s
        t = max(t, self._last_sample_t + 1e-6)
        self._last_sample_t = t
        return t

    def stop_stream(self) -> None:
        """``STP`` (never answers), then discard the frames still in flight."""
        self.transport.send(aed.command("STP"))
        self.streaming = False
        self.transport.clock.sleep(min(0.05, self.transport.timeout_s))
        self.transport.discard_input()
