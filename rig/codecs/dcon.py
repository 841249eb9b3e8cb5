"""ICP DAS DCON ASCII protocol: frames, checksums and the replies of the I-7011 class.

Frame: ``<lead><AA hex address><command>[checksum]\\r``; replies start ``>`` (data), ``!``
(acknowledged) or ``?`` (refused). On a syntax error, a framing error or a wrong address
the module says nothing — silence is reported by the transport as a time-out. A ``!AA``/``?AA``
reply carrying another address than the one asked (another module answering on the line, or a
corrupted byte: DCON checksums are optional) raises :class:`WrongAddress`.
The checksum (when enabled) is the sum of all characters before CR, modulo 256, as two
upper-case hex digits: ``$012`` → ``$012B7``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from flowcurve.rig.codecs import ProtocolError

CR = b"\r"

BAUD_CODES = {0x03: 1200, 0x04: 2400, 0x05: 4800, 0x06: 9600, 0x07: 19200,
              0x08: 38400, 0x09: 57600, 0x0A: 115200}
# Thermocouple type codes of the family tables, with the full-scale temperature where known.
THERMOCOUPLE_TYPES = {0x0E: "J", 0x0F: "K", 0x10: "T", 0x11: "E", 0x12: "R", 0x13: "S",
                      0x14: "B", 0x15: "N", 0x16: "C"}
FULL_SCALE_C = {0x0E: 760.0, 0x0F: 1370.0, 0x10: 400.0, 0x11: 1000.0, 0x12: 1750.0,
                0x13: 1750.0, 0x14: 1800.0, 0x15: 1300.0, 0x16: 2320.0}
FORMAT_ENGINEERING, FORMAT_PERCENT, FORMAT_HEX = 0, 1, 2
WATCHDOG_TIMED_OUT = 0x04


def checksum(text: str) -> str:
    """Sum of the characters modulo 256 as two upper-case hex digits (``$012`` → ``B7``)."""
    return f"{sum(text.encode('ascii')) % 256:02X}"


def frame(lead: str, address: int | None, body: str = "", *, use_checksum: bool = False) -> bytes:
    """A command frame: ``frame('$', 1, '2')`` → ``b'$012\\r'`` (``address=None`` for ``**``)."""
    if address is not None and not 0 <= address <= 0xFF:
        raise ValueError(f"DCON address must be 0..255, got {address}")
    text = lead + ("**" if address is None else f"{address:02X}") + body
    if use_checksum:
        text += checksum(text)
    return text.encode("ascii") + CR


@dataclass(frozen=True)
class Reply:
    """A decoded reply: its lead character (``>``, ``!`` or ``?``) and the text after it."""

    lead: str
    body: str

    @property
    def refused(self) -> bool:
        """Whether the module refused the command ('?')."""
        return self.lead == "?"


def parse_reply(raw: bytes, *, use_checksum: bool = False) -> Reply:
    """Split a reply (with or without its CR) into lead and body, checking the checksum."""
    raw = raw.rstrip(CR)
    try:
        text = raw.decode("ascii")
    except UnicodeDecodeError:
        raise ProtocolError(f"reply is not ASCII: {raw!r}") from None
    if use_checksum:
        if len(text) < 3 or text[-2:] != checksum(text[:-2]):
            raise ProtocolError(f"bad checksum in reply {raw!r}")
        text = text[:-2]
    if not text or text[0] not in ">!?":
        raise ProtocolError(f"reply does not start with '>', '!' or '?': {raw!r}")
    return Reply(text[0], text[1:])


def expect_ack(reply: Reply, address: int | None = None, what: str = "command") -> str:
    """Check a ``!AA...`` acknowledgement and return what follows the address.

    ``address=None`` accepts a bare ``!`` (some commands acknowledge without the address).
    """
    if reply.refused:
        raise ProtocolError(f"{what} refused ('?')")
    if reply.lead != "!":
        raise ProtocolError(f"{what}: expected '!', got '{reply.lead}{reply.body}'")
    if address is None:
        return reply.body
    if reply.body[:2].upper() != f"{address:02X}":
        raise WrongAddress(what, reply.body[:2], address)
    return reply.body[2:]


class WrongAddress(ProtocolError):
    """A reply that carries another module's address (``!03`` to ``@01DO01``): ``answered`` (the
    two characters where the address stands) and ``expected``."""

    def __init__(self, what: str, answered: str, expected: int):
        self.what = what
        self.answered = answered.upper()
        self.expected = expected
        super().__init__(f"{what}: reply from address {answered!r}, expected {expected:02X}")


def check_address(reply: Reply, address: int, what: str = "command") -> None:
    """A ``!AA…``/``?AA…`` reply must carry ``address`` (a bare ``!`` or ``?`` carries none;
    ``>`` data never does): :class:`WrongAddress` otherwise."""
    if reply.lead in "!?" and reply.body and reply.body[:2].upper() != f"{address:02X}":
        raise WrongAddress(what, reply.body[:2], address)


@dataclass(frozen=True)
class Configuration:
    """``$AA2`` → ``!AATTCCFF``: address, input type, baud, data format, checksum flag."""

    address: int
    type_code: int
    baud: int | None
    data_format: int
    checksum: bool
    format_byte: int

    @property
    def thermocouple(self) -> str | None:
        """The thermocouple type of the input range code, None when not one."""
        return THERMOCOUPLE_TYPES.get(self.type_code)


def parse_configuration(reply: Reply) -> Configuration:
    """Decode the ``$AA2`` reply ``!AATTCCFF``."""
    body = expect_ack(reply, None, "$AA2")
    if not re.fullmatch(r"[0-9A-Fa-f]{8}", body):
        raise ProtocolError(f"$AA2 reply is not !AATTCCFF: '!{body}'")
    aa, tt, cc, ff = (int(body[i:i + 2], 16) for i in range(0, 8, 2))
    return Configuration(aa, tt, BAUD_CODES.get(cc), ff & 0x03, bool(ff & 0x40), ff)


def set_configuration_body(new_address: int, type_code: int, baud: int, format_byte: int) -> str:
    """The body of ``%AANNTTCCFF`` (address ``AA`` is added by :func:`frame`)."""
    codes = {v: k for k, v in BAUD_CODES.items()}
    if baud not in codes:
        raise ValueError(f"unsupported DCON baud rate {baud}")
    return f"{new_address:02X}{type_code:02X}{codes[baud]:02X}{format_byte:02X}"


def parse_analog(reply: Reply, *, data_format: int = FORMAT_ENGINEERING,
                 full_scale: float = FULL_SCALE_C[0x0F]) -> float:
    """Decode ``#AA`` → value; over range → +inf, under range → -inf.

    Engineering units: ``>+0025.12`` → 25.12; ``+9999`` over range, ``-0000`` under range.
    Hex (two's complement of full scale): ``>4C53`` → 0x4C53/0x7FFF × full scale; ``7FFF``
    over range, ``8000`` under range. Percent of FSR: ``>+050.00`` → 0.5 × full scale.
    """
    if reply.lead != ">":
        raise ProtocolError(f"#AA: expected '>', got '{reply.lead}{reply.body}'")
    body = reply.body.strip()
    if data_format == FORMAT_HEX:
        if not re.fullmatch(r"[0-9A-Fa-f]{4}", body):
            raise ProtocolError(f"#AA hex reading is not 4 hex digits: '>{body}'")
        raw = int(body, 16)
        if raw == 0x7FFF:
            return math.inf
        if raw == 0x8000:
            return -math.inf
        raw -= 0x10000 if raw & 0x8000 else 0
        return raw / 0x7FFF * full_scale
    if not re.fullmatch(r"[+-]\d+(\.\d*)?", body):
        raise ProtocolError(f"#AA reading is not a signed number: '>{body}'")
    if body in ("+9999", "+9999.9", "+99999"):
        return math.inf
    if body == "-0000":  # the under-range code (a real reading has decimals: -0000.00)
        return -math.inf
    value = float(body)
    if data_format == FORMAT_PERCENT:
        return value / 100.0 * full_scale
    return value


def parse_open_thermocouple(reply: Reply, address: int) -> bool:
    """``$AAB`` → ``!AAS``: True when S = 1 (thermocouple open)."""
    rest = expect_ack(reply, address, "$AAB")
    if rest not in ("0", "1"):
        raise ProtocolError(f"$AAB reply is not !AAS: '!{reply.body}'")
    return rest == "1"


def parse_digital_io(reply: Reply, address: int | None = None) -> dict[str, int]:
    """``@AADI`` → ``!AASOOII`` (I-7011 manual example ``!0100001``): alarm state S,
    digital outputs OO, digital inputs II. The address-less ``!SOOII`` of other family
    members is accepted too (pass ``address`` to check and strip it).
    """
    body = expect_ack(reply, None, "@AADI")
    if address is not None and len(body) == 7 and body[:2].upper() == f"{address:02X}":
        body = body[2:]
    if not re.fullmatch(r"[0-9A-Fa-f]{5}", body):
        raise ProtocolError(f"@AADI reply is not !SOOII: '!{reply.body}'")
    return {"alarm": int(body[0], 16), "outputs": int(body[1:3], 16), "inputs": int(body[3:5], 16)}


def digital_output_body(outputs: int) -> str:
    """The body of ``@AADOdd`` (outputs 00-03 on the I-7011: bit0 DO0, bit1 DO1)."""
    if not 0 <= outputs <= 0x03:
        raise ValueError(f"I-7011 digital outputs are 00..03, got {outputs:#x}")
    return f"DO{outputs:02X}"


def watchdog_body(enabled: bool, timeout_s: float) -> str:
    """The body of ``~AA3EVV``: enable flag and time-out in 0.1 s units (``~013164`` = 10.0 s)."""
    units = round(timeout_s * 10)
    if not 1 <= units <= 0xFF:
        raise ValueError(f"watchdog time-out must be 0.1..25.5 s, got {timeout_s} s")
    return f"3{int(bool(enabled))}{units:02X}"


def parse_watchdog_timeout(reply: Reply, address: int) -> tuple[bool | None, float]:
    """``~AA2`` → ``!AAEVV`` (or ``!AAVV``): (enabled or None if not reported, time-out s)."""
    rest = expect_ack(reply, address, "~AA2")
    if re.fullmatch(r"[01][0-9A-Fa-f]{2}", rest):
        return rest[0] == "1", int(rest[1:], 16) / 10.0
    if re.fullmatch(r"[0-9A-Fa-f]{2}", rest):
        return None, int(rest, 16) / 10.0
    raise ProtocolError(f"~AA2 reply is not !AAEVV: '!{reply.body}'")


def parse_watchdog_status(reply: Reply, address: int) -> int:
    """``~AA0`` → ``!AASS``: the status byte (0x04 = the host watchdog timed out)."""
    rest = expect_ack(reply, address, "~AA0")
    if not re.fullmatch(r"[0-9A-Fa-f]{2}", rest):
        raise ProtocolError(f"~AA0 reply is not !AASS: '!{reply.body}'")
    return int(rest, 16)


def safe_value_body(power_on: int, safe: int) -> str:
    """The body of ``~AA5PPSS``: digital outputs at power-on and when the watchdog trips."""
    for v in (power_on, safe):
        if not 0 <= v <= 0xFF:
            raise ValueError(f"digital output value must be 00..FF, got {v}")
    return f"5{power_on:02X}{safe:02X}"
