"""How the virtual devices put their replies on the wire, written from the manuals' tables.

The drivers decode with :mod:`flowcurve.rig.codecs`; the virtual devices encode with this
module, written again from the manuals' facts in docs/protocols.md (HBM AED, ICP DAS DCON) and
docs/encoder-protocol.md without looking at — or importing — the drivers' code. A mistake
made on one side then shows as a failing test instead of cancelling out on both.

AED ``COF`` output formats (docs/protocols.md, "Output format COF" and "Scaling"):

=====  ===================================  ==============  ==========
COF    bytes before CR LF                   byte order      nominal
=====  ===================================  ==============  ==========
0 / 4  24-bit value + 1 unused byte         MSB / LSB first 5 120 000
8 / 12 24-bit value + status byte           MSB / LSB first 5 120 000
2 / 6  16-bit value (7FFF/8000 overflow)    MSB / LSB first 20 000
3 / 7  ``±nnnnnnn``                         —               1 000 000
1 / 5  ``±nnnnnnn,aa``                      —               1 000 000
9      ``±nnnnnnn,aa,sss``                  —               1 000 000
11     ``±nnnnnnn,sss``                     —               1 000 000
=====  ===================================  ==============  ==========

+32 drops the CR LF of the binary formats (not allowed for ASCII), +128 streams from
power-on and does not change the frame.
"""

from __future__ import annotations

import struct

# -- HBM AED (load-cell amplifier) ----------------------------------------------------------
# status byte bits: net overflow, gross overflow, ADC overflow (beyond ±2.5 mV/V), standstill
STATUS_NET_OVERFLOW = 1 << 0
STATUS_GROSS_OVERFLOW = 1 << 1
STATUS_ADC_OVERFLOW = 1 << 2
STATUS_STANDSTILL = 1 << 3

# ICR0..ICR7 output rates with FMD0, values per second
OUTPUT_RATES_PER_S = [100.0, 50.0, 25.0, 12.0, 6.0, 3.0, 2.0, 1.0]
# ASF1..ASF8 -3 dB points with FMD0, Hz; ASF0 is no filter
FILTER_CUTOFF_HZ = [None, 8.0, 3.5, 1.5, 0.7, 0.3, 0.2, 0.1, 0.05]

# COF base code → (layout, most significant byte first, fields)
_COF_TABLE = {
    0: ("bin24", True, ()), 4: ("bin24", False, ()),
    8: ("bin24", True, ("status",)), 12: ("bin24", False, ("status",)),
    2: ("bin16", True, ()), 6: ("bin16", False, ()),
    3: ("text", True, ()), 7: ("text", True, ()),
    1: ("text", True, ("address",)), 5: ("text", True, ("address",)),
    9: ("text", True, ("address", "status")),
    11: ("text", True, ("status",)),
}
_NOMINAL = {"bin24": 5_120_000, "bin16": 20_000, "text": 1_000_000}
NO_CRLF, STREAM_AT_POWER_ON = 32, 128


def _cof_entry(cof: int) -> tuple[str, bool, tuple[str, ...], bool]:
    """(layout, MSB first, extra fields, CR LF) of a COF code; KeyError when not in the table."""
    if not 0 <= cof <= 255:
        raise KeyError(cof)
    base = cof & ~(NO_CRLF | STREAM_AT_POWER_ON)
    layout, msb_first, fields = _COF_TABLE[base]
    crlf = not cof & NO_CRLF
    if layout == "text" and not crlf:
        raise KeyError(cof)  # ASCII frames always end with CR LF
    return layout, msb_first, fields, crlf


def is_known_cof(cof: int) -> bool:
    """Whether ``cof`` is a known output format code."""
    try:
        _cof_entry(cof)
    except KeyError:
        return False
    return True


def is_binary_cof(cof: int) -> bool:
    """Whether output format ``cof`` is binary."""
    return _cof_entry(cof)[0] != "text"


def is_two_byte_cof(cof: int) -> bool:
    """Whether output format ``cof`` is two bytes a value."""
    return _cof_entry(cof)[0] == "bin16"


def nominal_counts(cof: int, nov: int = 0) -> int:
    """The count nominal load reads in this format; ``NOV`` > 0 rescales the ASCII formats."""
    layout = _cof_entry(cof)[0]
    return nov if layout == "text" and nov > 0 else _NOMINAL[layout]


def aed_frame(cof: int, counts: int, *, status: int = 0, address: int = 31) -> bytes:
    """One ``MSV?`` measured value in output format ``cof``."""
    layout, msb_first, fields, crlf = _cof_entry(cof)
    if layout == "bin24":
        # a signed 32-bit big-endian word whose top byte is dropped is the 24-bit value
        value = struct.pack(">i", counts)[1:]
        if not msb_first:
            value = bytes(reversed(value))
        body = value + bytes([status & 0xFF if "status" in fields else 0])
    elif layout == "bin16":
        body = struct.pack(">h" if msb_first else "<h", counts)
    else:
        text = ("-" if counts < 0 else "+") + str(abs(counts)).rjust(7, "0")
        if "address" in fields:
            text += f",{address:02d}"
        if "status" in fields:
            text += f",{status:03d}"
        body = text.encode("ascii")
    return body + (b"\r\n" if crlf else b"")


# -- ICP DAS DCON (furnace module, encoder box) ---------------------------------------------
def dcon_checksum(text: str) -> str:
    """Sum of the characters before CR, modulo 256, two upper-case hex digits ($012 → B7)."""
    total = 0
    for character in text:
        total = (total + ord(character)) & 0xFF
    return "%02X" % total


# thermocouple type code → full-scale temperature, °C (family tables; 0F K = +1370.0 °C)
THERMOCOUPLE_FULL_SCALE_C = {0x0E: 760.0, 0x0F: 1370.0, 0x10: 400.0, 0x11: 1000.0,
                             0x12: 1750.0, 0x13: 1750.0, 0x14: 1800.0, 0x15: 1300.0,
                             0x16: 2320.0}


# -- encoder box ----------------------------------------------------------------------------
def gray_code(count: int) -> int:
    """The Gray-coded form of a count, g = b ^ (b >> 1) (docs/encoder-protocol.md)."""
    return count ^ (count >> 1)
