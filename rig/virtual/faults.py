"""Fault injection for the virtual devices, switchable at run time.

Wire faults (:class:`WireFaults`, applied by :class:`rig.virtual.pty_device.PtyDevice` to
every reply it sends):

* ``silence`` — the device reads commands but never answers (the host times out);
* ``drop`` — a fraction of replies is lost (``fraction=0.5``);
* ``garble`` — a fraction of replies is corrupted so that no decoder can take it for a
  good frame: one byte is replaced by a non-ASCII byte and one extra byte is inserted
  (ASCII replies fail to decode; binary frames lose their length, so the framing breaks);
* ``delay`` — replies leave ``seconds`` late;
* ``unplug`` — the port vanishes mid-test: the pty master is closed, the host's next read
  or write fails with EIO (pyserial raises ``SerialException``, an ``OSError``).

Model faults (handled by :class:`rig.virtual.rig.VirtualRig`): ``open_thermocouple``
(reading ``+9999``, ``$AAB`` → ``!AA1``) and ``relay_stuck`` (heater on whatever the DO says).
One reply off (scheduled with ``--fault``, :mod:`rig.virtual.fault_spec`; the rig applies them
through the device's ``corrupt_next``): ``corrupt`` on any device, and ``spike`` on the load cell —
one frame a little high (900 N by default: below the 1 % of the frame's capacity the plausibility
rules' tolerance allows, so only the signal's own noise tells it from the force).
"""

from __future__ import annotations

import threading

import numpy as np

from flowcurve.errors import ConfigError

WIRE_FAULTS = ("silence", "drop", "garble", "delay", "unplug")
MODEL_FAULTS = {"furnace": ("open_thermocouple", "relay_stuck")}


class WireFaults:
    """The wire faults active on one device (thread-safe; deterministic given the seed)."""

    def __init__(self, seed: int = 0):
        self._lock = threading.Lock()
        self._rng = np.random.default_rng(seed)
        self.silent = False
        self.drop_fraction = 0.0
        self.garble_fraction = 0.0
        self.delay_s = 0.0
        self.unplug_requested = False
        self.replies_hit = 0  # replies a drop or garble fraction took (a rare fault may take none in a short test)

    def inject(self, fault: str, **kw) -> None:
        """Switch a fault on: ``silence``, ``drop(fraction=1.0)``, ``garble(fraction=1.0)``,
        ``delay(seconds=...)``, ``unplug``."""
        with self._lock:
            if fault == "silence":
                self.silent = True
            elif fault == "drop":
                self.drop_fraction = _fraction(kw.get("fraction", 1.0), fault)
            elif fault == "garble":
                self.garble_fraction = _fraction(kw.get("fraction", 1.0), fault)
            elif fault == "delay":
                self.delay_s = float(kw.get("seconds", 1.0))
            elif fault == "unplug":
                self.unplug_requested = True
            else:
                raise ConfigError(f"fault: unknown wire fault '{fault}' (known: {', '.join(WIRE_FAULTS)})")

    def clear(self) -> None:
        """All wire faults off (an unplugged port stays unplugged)."""
        with self._lock:
            self.silent = False
            self.drop_fraction = self.garble_fraction = self.delay_s = 0.0

    def apply(self, reply: bytes) -> bytes | None:
        """The bytes that actually leave the device for ``reply`` (None: nothing leaves)."""
        with self._lock:
            if self.silent or not reply:
                return None
            if self.drop_fraction and self._rng.random() < self.drop_fraction:
                self.replies_hit += 1
                return None
            if self.garble_fraction and self._rng.random() < self.garble_fraction:
                self.replies_hit += 1
                return garble(reply, self._rng)
            return reply


def garble(reply: bytes, rng: np.random.Generator) -> bytes:
    """Corrupt a reply beyond recognition: one byte replaced by a non-ASCII byte (0x80–0xFF)
    and one non-ASCII byte inserted, so both the content and the length are wrong."""
    data = bytearray(reply)
    i = int(rng.integers(0, len(data)))
    data[i] = 0x80 | (data[i] ^ 0x5A) & 0x7F
    j = int(rng.integers(0, len(data) + 1))
    data.insert(j, int(rng.integers(0x80, 0x100)))
    return bytes(data)


def _fraction(value, fault: str) -> float:
    value = float(value)
    if not 0.0 <= value <= 1.0:
        raise ConfigError(f"fault {fault}: fraction must be within 0..1, got {value}")
    return value
