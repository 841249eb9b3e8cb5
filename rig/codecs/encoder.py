"""The crosshead encoder box (docs/encoder-protocol.md): counts, Gray code, wrap-around.

The box speaks DCON framing (see :mod:`rig.codecs.dcon`); this module holds what is
specific to it: the 8-hex-digit count, Gray↔binary conversion, unwrapping of the 32-bit
counter into an unbounded Python int, and counts → crosshead millimetres.
"""

from __future__ import annotations

import re

from flowcurve.rig.codecs import ProtocolError
from flowcurve.rig.codecs.dcon import Reply

COUNTER_BITS = 32
COUNTS_PER_REV = 10_000  # 2500 pulses/rev with x4 quadrature decoding


def gray_to_binary(gray: int) -> int:
    """Gray code → binary: ``b = g; while g := g >> 1: b ^= g``."""
    b = gray
    while gray := gray >> 1:
        b ^= gray
    return b


def binary_to_gray(b: int) -> int:
    """Binary → Gray code: ``g = b ^ (b >> 1)``."""
    return b ^ (b >> 1)


def parse_count(reply: Reply) -> int:
    """``>0000001E`` → 30, the raw 32-bit counter value (0 .. 2**32-1, not sign-extended)."""
    if reply.lead != ">" or not re.fullmatch(r"[0-9A-Fa-f]{8}", reply.body):
        raise ProtocolError(f"count reply is not >HHHHHHHH: '{reply.lead}{reply.body}'")
    return int(reply.body, 16)


def wrap_delta(new: int, old: int, bits: int = COUNTER_BITS) -> int:
    """Signed change of an N-bit counter: ``((new − old + 2**(N−1)) % 2**N) − 2**(N−1)``."""
    half = 1 << (bits - 1)
    return ((new - old + half) % (1 << bits)) - half


def to_signed(raw: int, bits: int = COUNTER_BITS) -> int:
    """Two's-complement reading of an N-bit counter value."""
    return raw - (1 << bits) if raw & (1 << (bits - 1)) else raw


class Unwrapper:
    """Accumulates successive raw counter readings into an unbounded count.

    The first reading is taken as the signed (two's-complement) count; each later one adds
    :func:`wrap_delta`, valid while the change between two reads stays under 2**(N−1).
    """

    def __init__(self, bits: int = COUNTER_BITS):
        self.bits = bits
        self.last_raw: int | None = None
        self.count: int | None = None

    def update(self, raw: int) -> int:
        """The unwrapped count after raw reading ``raw``."""
        if self.last_raw is None:
            self.count = to_signed(raw, self.bits)
        else:
            self.count += wrap_delta(raw, self.last_raw, self.bits)
        self.last_raw = raw
        return self.count

    def reset(self) -> None:
        """Forget the last reading and the count."""
        self.last_raw = self.count = None


def counts_to_mm(counts, *, gear_ratio: float, screw_lead_mm: float,
                 counts_per_rev: int = COUNTS_PER_REV):
    """crosshead_mm = counts / counts_per_rev / gear_ratio × screw_lead_mm (arrays too)."""
    return counts / counts_per_rev / gear_ratio * screw_lead_mm
