"""HBM AED command set (AD103/AD104/AD105/FIT amplifiers): commands, replies, measured values.

Facts from docs/protocols.md: commands are ASCII ending with ``;``; a bare ``;`` clears the
device's input buffer, so every command is sent as ``;CMD;``. Settings answer ``0\\r\\n``
(accepted) or ``?\\r\\n`` (refused). ``MSV?`` answers in the output format chosen by ``COF``:

====================  =====================================  ===============
COF                   frame                                  nominal counts
====================  =====================================  ===============
0 / 4                 4 bytes (value in bytes 1-3) + CR LF   5 120 000
8 / 12                4 bytes, byte 4 = status, + CR LF      5 120 000
2 / 6                 2 bytes + CR LF                        20 000
3 / 7                 ``±nnnnnnn`` + CR LF (10 bytes)        1 000 000
1 / 5                 value,address (13 bytes)               1 000 000
9                     value,address,status (17 bytes)        1 000 000
11                    value,status (14 bytes)                1 000 000
====================  =====================================  ===============

0/8/2 send the most significant byte first, 4/12/6 the least significant first; +32 drops
the CR LF of binary frames; +128 (stream from power-on) does not change the frame.
4-byte binary: the first three bytes are a signed 24-bit count (MSB first for 0/8, LSB first
for 4/12); the fourth is the status byte in 8/12 and is ignored in 0/4.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from flowcurve.rig.codecs import ProtocolError

CRLF = b"\r\n"

# Status byte bits.
NET_OVERFLOW = 0x01
GROSS_OVERFLOW = 0x02
ADC_OVERFLOW = 0x04  # beyond +-2.5 mV/V
STANDSTILL = 0x08
NOT_COHERENT = 0xC0  # bits 7-6
OVERFLOW_BITS = NET_OVERFLOW | GROSS_OVERFLOW | ADC_OVERFLOW

NOMINAL_COUNTS_4BYTE = 5_120_000
NOMINAL_COUNTS_2BYTE = 20_000
NOMINAL_COUNTS_ASCII = 1_000_000

# ICR0..7 output rates with FMD0 (AD104 class), values per second.
ICR_RATES_PER_S = (100.0, 50.0, 25.0, 12.0, 6.0, 3.0, 2.0, 1.0)
# ASF1..8 -3 dB cut-off with FMD0, Hz (ASF0 = filter off).
ASF_CUTOFF_HZ = {0: None, 1: 8.0, 2: 3.5, 3: 1.5, 4: 0.7, 5: 0.3, 6: 0.2, 7: 0.1, 8: 0.05}
BAUD_RATES = (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200)  # tried in a recovery
PARITY_CODES = {"N": 0, "E": 1}  # BDR's parity digit
BINARY_COFS = (0, 2, 4, 6, 8, 12)
ASCII_COFS = (1, 3, 5, 7, 9, 11)


def command(text: str) -> bytes:
    """One command as sent: a leading ``;`` clears the input buffer, ``;`` ends it."""
    text = text.strip().rstrip(";")
    if not text or ";" in text or not text.isascii():
        raise ValueError(f"not a single AED command: {text!r}")
    return f";{text};".encode("ascii")


def parse_ack(reply: bytes) -> bool:
    """``0`` → accepted (True), ``?`` → refused (False); anything else is garbled."""
    body = reply.strip()
    if body == b"0":
        return True
    if body == b"?":
        return False
    raise ProtocolError(f"expected '0' or '?', got {reply!r}")


@dataclass(frozen=True)
class OutputFormat:
    """What a ``COF`` code means for the ``MSV?`` frame."""

    code: int
    kind: str  # "binary4", "binary2" or "ascii"
    msb_first: bool
    has_status: bool
    has_address: bool
    crlf: bool

    @property
    def frame_length(self) -> int:
        """Bytes in one measured value, terminator included."""
        if self.kind == "binary4":
            n = 4
        elif self.kind == "binary2":
            n = 2
        else:
            n = 8 + (3 if self.has_address else 0) + (4 if self.has_status else 0)
        return n + (2 if self.crlf else 0)

    @property
    def nominal_counts(self) -> int:
        """The count that nominal load reads in this format (NOV0)."""
        return {"binary4": NOMINAL_COUNTS_4BYTE, "binary2": NOMINAL_COUNTS_2BYTE}.get(
            self.kind, NOMINAL_COUNTS_ASCII
        )


def output_format(cof: int) -> OutputFormat:
    """Decode a ``COF`` code (with the +32 and +128 flags) into an :class:`OutputFormat`."""
    if not isinstance(cof, int) or cof < 0 or cof > 255:
        raise ValueError(f"COF code must be an integer 0..255, got {cof!r}")
    base = cof & ~(32 | 128)
    no_crlf = bool(cof & 32)
    if base in (0, 4, 8, 12):
        return OutputFormat(cof, "binary4", base in (0, 8), base in (8, 12), False, not no_crlf)
    if base in (2, 6):
        return OutputFormat(cof, "binary2", base == 2, False, False, not no_crlf)
    if base in ASCII_COFS and not no_crlf:
        return OutputFormat(cof, "ascii", True, base in (9, 11), base in (1, 5, 9), True)
    raise ValueError(f"unknown COF output format {cof}")


@dataclass(frozen=True)
class MeasuredValue:
    """One decoded ``MSV?`` frame: the count, the status byte (None if the format has none)."""

    counts: int
    status: int | None
    address: int | None = None

    @property
    def overflow(self) -> bool:
        """Net, gross or ADC overflow reported in the status byte."""
        return bool(self.status is not None and self.status & OVERFLOW_BITS)


def decode_msv(frame: bytes, fmt: OutputFormat) -> MeasuredValue:
    """Decode one measured-value frame of exactly ``fmt.frame_length`` bytes.

    Binary frames may contain CR/LF bytes inside the value, which is why framing is done
    by length. In 2-byte binary, ``7FFF``/``8000`` are the overflow codes (reported as
    status bit0 set, since that format has no status byte).
    """
    if len(frame) != fmt.frame_length:
        raise ProtocolError(f"measured value must be {fmt.frame_length} bytes, got {len(frame)}: {frame!r}")
    if fmt.crlf and frame[-2:] != CRLF:
        raise ProtocolError(f"measured value does not end with CR LF: {frame!r}")
    body = frame[:-2] if fmt.crlf else frame
    if fmt.kind == "binary4":
        value_bytes = body[:3] if fmt.msb_first else body[2::-1]
        counts = int.from_bytes(value_bytes, "big", signed=True)
        return MeasuredValue(counts, body[3] if fmt.has_status else None)
    if fmt.kind == "binary2":
        counts = int.from_bytes(body, "big" if fmt.msb_first else "little", signed=True)
        status = NET_OVERFLOW if counts in (0x7FFF, -0x8000) else None
        return MeasuredValue(counts, status)
    return _decode_ascii(body, fmt)


_ASCII_VALUE = re.compile(rb"^\s*([+-]?\s*\d+)$")


def _decode_ascii(body: bytes, fmt: OutputFormat) -> MeasuredValue:
    fields = body.split(b",")
    expected = 1 + fmt.has_address + fmt.has_status
    if len(fields) != expected:
        raise ProtocolError(f"expected {expected} comma-separated fields, got {body!r}")
    match = _ASCII_VALUE.match(fields[0])
    if not match:
        raise ProtocolError(f"measured value is not a number: {fields[0]!r}")
    counts = int(match.group(1).replace(b" ", b""))
    address = status = None
    try:
        if fmt.has_address:
            address = int(fields[1])
        if fmt.has_status:
            status = int(fields[-1])
    except ValueError:
        raise ProtocolError(f"address/status field is not a number: {body!r}") from None
    if status is not None and not 0 <= status <= 255:
        raise ProtocolError(f"status {status} is not a byte: {body!r}")
    return MeasuredValue(counts, status, address)


def encode_msv(counts: int, fmt: OutputFormat, *, status: int = 0, address: int = 31) -> bytes:
    """Inverse of :func:`decode_msv` (used by tests; the virtual amplifier has its own encoder)."""
    if fmt.kind == "binary4":
        value = counts.to_bytes(3, "big", signed=True)
        body = (value if fmt.msb_first else value[::-1]) + bytes([status if fmt.has_status else 0])
    elif fmt.kind == "binary2":
        body = counts.to_bytes(2, "big" if fmt.msb_first else "little", signed=True)
    else:
        parts = [f"{counts:+08d}"]
        if fmt.has_address:
            parts.append(f"{address:02d}")
        if fmt.has_status:
            parts.append(f"{status:03d}")
        body = ",".join(parts).encode("ascii")
    return body + (CRLF if fmt.crlf else b"")


def nominal_counts(fmt: OutputFormat, nov: int = 0) -> int:
    """Counts at nominal load: ``NOV`` > 0 rescales the ASCII formats, binary keeps its own."""
    return nov if fmt.kind == "ascii" and nov > 0 else fmt.nominal_counts


def counts_to_newtons(counts, fmt: OutputFormat, nominal_load_N: float, nov: int = 0):
    """Force from counts: nominal load reads :func:`nominal_counts` (works on arrays too)."""
    return counts * (nominal_load_N / nominal_counts(fmt, nov))


_IDN = re.compile(r'^\s*([^,]+),"([^"]*)","([^"]*)",(.*?)\s*$')


def parse_idn(reply: bytes) -> dict[str, str]:
    """``HBM,"AED104         ","1234   ",P20`` → manufacturer, model, serial, firmware."""
    try:
        text = reply.decode("ascii")
    except UnicodeDecodeError:
        raise ProtocolError(f"IDN? answer is not ASCII: {reply!r}") from None
    match = _IDN.match(text)
    if not match:
        raise ProtocolError(f"IDN? answer is not manufacturer,\"model\",\"serial\",firmware: {reply!r}")
    manufacturer, model, serial, firmware = (g.strip() for g in match.groups())
    return {"manufacturer": manufacturer, "model": model, "serial": serial, "firmware": firmware}


def parse_baud(reply: bytes) -> tuple[int, str]:
    """``BDR?`` answer ``9600,1`` → (9600, "E"); parity 0 = none, 1 = even."""
    try:
        rate, parity = reply.strip().decode("ascii").split(",")
        return int(rate), {str(v): k for k, v in PARITY_CODES.items()}[parity.strip()]
    except (ValueError, KeyError, UnicodeDecodeError):
        raise ProtocolError(f"BDR? answer is not 'rate,parity': {reply!r}") from None


def parse_int_reply(reply: bytes) -> int:
    """A query answered by one integer (``COF?`` → ``3``, ``ASF?`` → ``5``)."""
    try:
        return int(reply.strip())
    except ValueError:
        raise ProtocolError(f"expected an integer, got {reply!r}") from None
