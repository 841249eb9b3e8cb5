"""Virtual crosshead encoder counter box on a pty — docs/encoder-protocol.md (version 1).

DCON framing and host watchdog from :class:`flowcurve.rig.virtual.dcon.DconDevice`; a 32-bit up/down
counter of quadrature counts that wraps modulo 2**32 (``initial_count`` lets a test start
it just below the wrap), read binary (``#AAN``), Gray-coded (``$AAGN``), latched by the
``#**`` broadcast and read back by ``$AAZN``, reset to zero by ``$AA6N``.
"""

from __future__ import annotations

import re
from typing import Callable

from flowcurve.rig.virtual.wire_format import gray_code
from flowcurve.rig.virtual.dcon import CHECKSUM_BIT, DconDevice

MASK32 = 0xFFFFFFFF


class EncoderBox(DconDevice):
    """``read_counts()`` returns the encoder's whole counts since the test start (an int)."""

    name = "encoder"

    def __init__(self, read_counts: Callable[[], int], *, address: int = 0x02,
                 checksum_on: bool = False, initial_count: int = 0, **kw):
        super().__init__(address=address, checksum_on=checksum_on, **kw)
        self.read_counts = read_counts
        self._offset = initial_count - read_counts()
        self.latched = 0
        self.counts_per_mm = 100.0  # the model's encoder resolution (VirtualRig sets it)
        self._corrupt_counts = 0

    def corrupt_next(self, delta_mm: float) -> None:
        """Fault 'corrupt': the next ``#AAN`` reply is off by ``delta_mm`` (well-formed)."""
        self._corrupt_counts = int(round(delta_mm * self.counts_per_mm))

    def jump(self, delta_mm: float) -> None:
        """Fault 'jump': the counter steps by ``delta_mm`` and stays stepped."""
        self._offset += int(round(delta_mm * self.counts_per_mm))

    def count(self) -> int:
        """The 32-bit counter value now (0 … 2**32 − 1)."""
        return (self._offset + self.read_counts()) & MASK32

    def broadcast(self, text: str) -> None:
        """Latch the count on the synchronised-sampling broadcast (#**)."""
        if text == "#**":
            self.latched = self.count()

    def command(self, lead: str, body: str) -> str | None:
        """The encoder module's reply to a command (``lead`` and ``body``), None when silent."""
        aa = self.aa
        if lead == "#" and body == "0":
            corrupt, self._corrupt_counts = self._corrupt_counts, 0
            return f">{(self.count() + corrupt) & MASK32:08X}"
        if lead == "$":
            if body == "G0":
                return f">{gray_code(self.count()):08X}"
            if body == "Z0":
                return f">{self.latched:08X}"
            if body == "60":
                self._offset = -self.read_counts()
                return f"!{aa}"
            if body == "2":
                return f"!{aa}0006{CHECKSUM_BIT if self.checksum_on else 0:02X}"
            if body == "M":
                return f"!{aa}7083FC"
            if body == "F":
                return f"!{aa}A1.0"
            return None
        if lead == "~" and re.fullmatch(r"[0-3].*", body):
            return self.watchdog_command(body)
        return None
