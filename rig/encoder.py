"""The crosshead encoder box (docs/encoder-protocol.md): counts → crosshead position.

DCON framing over :class:`~rig.transport.SerialTransport`; the counter is 32-bit and wraps,
so every reading goes through an :class:`~rig.codecs.encoder.Unwrapper` and the position is
an unbounded Python int of counts since :meth:`CrossheadEncoder.zero`.
"""

from __future__ import annotations

from typing import Iterator

from flowcurve.rig.codecs import dcon
from flowcurve.rig.codecs import encoder as codec
from flowcurve.rig.transport import DconDevice


class CrossheadEncoder(DconDevice):
    """The encoder counter box: ``read_counts()`` unwrapped, ``position_mm()``, ``zero()``."""

    def __init__(self, port_url, *, name: str = "crosshead encoder", address: int = 2,
                 gear_ratio: float = 1.0, screw_lead_mm: float = 100.0,
                 counts_per_rev: int = codec.COUNTS_PER_REV, baudrate: int = 9600,
                 parity: str = "N", timeout_s: float = 0.2, checksum: bool = False,
                 channel: int = 0, opener=None):
        super().__init__(port_url, name=name, address=address, baudrate=baudrate, parity=parity,
                         timeout_s=timeout_s, checksum=checksum, opener=opener)
        if not (gear_ratio > 0 and screw_lead_mm > 0 and counts_per_rev > 0):
            raise ValueError("gear ratio, screw lead and counts per revolution must be positive")
        self.gear_ratio = float(gear_ratio)
        self.screw_lead_mm = float(screw_lead_mm)
        self.counts_per_rev = int(counts_per_rev)
        self.channel = channel
        self._unwrapper = codec.Unwrapper()

    @classmethod
    def from_config(cls, section, **kw) -> "CrossheadEncoder":
        """The encoder box of a rig file's ``[encoder]`` section (:class:`rig.config.EncoderConfig`)."""
        return cls(section.port, address=section.address, checksum=section.checksum,
                   counts_per_rev=section.counts_per_rev, gear_ratio=section.gear_ratio,
                   screw_lead_mm=section.screw_lead_mm, **section.transport_kwargs("crosshead encoder"), **kw)

    def check_lines(self, section) -> Iterator[str]:
        """What ``flowcurve rig check`` prints of the open encoder box: identity, settings (a note
        where the checksum differs from the rig file's ``section``) and one reading in mm."""
        cfg = self.configuration()
        yield f"  identity: module {self.module_name()}, firmware {self.firmware()}"
        yield f"  settings: address {cfg.address:02X}, {cfg.baud} baud, checksum {'on' if cfg.checksum else 'off'}"
        if cfg.checksum != section.checksum:
            yield (f"  note: module checksum {'on' if cfg.checksum else 'off'}, configuration says "
                   f"{'on' if section.checksum else 'off'}")
        counts = self.read_counts()
        mm = counts / self.counts_per_rev / self.gear_ratio * self.screw_lead_mm
        yield f"  reading: {counts} counts = {mm:.3f} mm; Gray check {'ok' if self.gray_check() else 'FAILED'}"

    def read_raw(self) -> int:
        """``#AAN``: the raw 32-bit counter value (0 .. 2**32-1)."""
        return self.query("#", f"{self.channel}", codec.parse_count)

    def read_counts(self) -> int:
        """Counts as an unbounded int, unwrapped across the 32-bit wrap-around."""
        return self._unwrapper.update(self.read_raw())

    def position_mm(self) -> float:
        """Crosshead displacement: counts / counts_per_rev / gear_ratio × screw_lead_mm."""
        return float(codec.counts_to_mm(self.read_counts(), gear_ratio=self.gear_ratio,
                                        screw_lead_mm=self.screw_lead_mm,
                                        counts_per_rev=self.counts_per_rev))

    def zero(self) -> None:
        """``$AA6N``: reset the counter to zero (idempotent), and restart the unwrapping."""
        self.query("$", f"6{self.channel}", dcon.expect_ack, self.address, "$AA6N")
        self._unwrapper.reset()

    def gray_check(self) -> bool:
        """``$AAGN`` vs ``#AAN``: the box's Gray→binary conversion holds (count must not move)."""
        gray = self.query("$", f"G{self.channel}", codec.parse_count)
        raw = self.read_raw()
        return codec.gray_to_binary(gray) == raw

    def latch_all(self) -> None:
        """``#**``: latch every counter on the line at once (broadcast, no reply)."""
        self.send("#", broadcast=True)

    def read_latched(self) -> int:
        """``$AAZN``: the latched raw count, unwrapped like :meth:`read_counts`."""
        return self._unwrapper.update(self.query("$", f"Z{self.channel}", codec.parse_count))
