"""Readings the machine cannot physically make between two samples are rejected as corrupt.

A frame can be well formed and still wrong (AED frames carry no checksum; a counter can
step). :class:`RateGuard` sits between a channel's reads and its stream:

* a **rise** of ``|value|`` faster than ``max_rate`` per second (plus ``tolerance``) from the
  last accepted sample is impossible (force: the machine loads at most at frame stiffness ×
  crosshead speed; crosshead: it moves at most at its speed) — rejected;
* with ``falls_freely`` (force), a **fall** of any size is physical (a fracture), but a fall
  that the very next sample undoes by an impossible rise is a one-sample spike — rejected
  (the guard holds each sample until the next arrives); without it (crosshead) a fall is
  judged like a rise;
* ``persist`` rejections in a row are no glitch but a broken channel: :class:`ImplausibleReadings`
  (a :class:`DeviceError`) stops the test.

Every rejection is kept in :attr:`RateGuard.rejected` (time, value, why) for the record's events.
"""

from __future__ import annotations

from flowcurve.errors import DeviceError


class ImplausibleReadings(DeviceError):
    """A channel whose readings stay physically impossible: the test stops."""


class RateGuard:
    """One channel's plausibility filter (see the module docstring); ``unit`` names values."""

    def __init__(self, device: str, *, max_rate: float, tolerance: float, unit: str, falls_freely: bool = False,
                 persist: int = 5, advice: str = "check the device and its cable", time_slack: float = 0.0):
        self.device = device
        self.max_rate = float(max_rate)
        self.time_slack = float(time_slack)  # how wrong two time stamps' difference may be
        self.tolerance = float(tolerance)
        self.unit = unit
        self.falls_freely = falls_freely
        self.persist = persist
        self.advice = advice
        self.rejected: list[tuple[float, float, str]] = []
        self._last: tuple[float, float] | None = None  # last accepted (t, v)
        self._held: tuple[float, float] | None = None  # a fall waiting for the next sample
        self._in_a_row = 0

    def limit(self, dt: float) -> float:
        """The largest physical change of ``|value|`` in ``dt`` seconds (stamps as uncertain as ``time_slack``)."""
        return self.max_rate * (max(dt, 0.0) + self.time_slack) + self.tolerance

    def feed(self, samples: list[tuple[float, float]]) -> list[tuple[float, float]]:
        """The samples that pass, in order (a held fall comes out with the next sample)."""
        out: list[tuple[float, float]] = []
        for t, v in samples:
            self._one(t, v, out)
        return out

    def flush(self) -> list[tuple[float, float]]:
        """At the end: a held fall passes (nothing contradicts it)."""
        held, self._held = self._held, None
        return [held] if held is not None else []

    def _one(self, t: float, v: float, out: list) -> None:
        if self._last is None:
            self._accept(t, v, out)
            return
        t0, v0 = self._last
        if self._held is not None:
            th, vh = self._held
            if abs(v) - abs(vh) > self.limit(t - th) and abs(abs(v) - abs(v0)) <= self.limit(t - t0):
                self._held = None  # back where it was: the fall was a one-sample spike
                self._reject(th, vh, f"fell {abs(v0) - abs(vh):.4g} {self.unit} for one sample")
            else:
                self._held = None
                self._accept(th, vh, out)
                t0, v0 = th, vh
        change = abs(v) - abs(v0)
        if change > self.limit(t - t0) or (not self.falls_freely and -change > self.limit(t - t0)):
            self._reject(t, v, f"{'rose' if change > 0 else 'fell'} {abs(change):.4g} {self.unit} in {t - t0:.3g} s "
                               f"(at most {self.limit(t - t0):.4g} possible)")
            return
        if self.falls_freely and -change > self.limit(t - t0):
            self._held = (t, v)
            return
        self._accept(t, v, out)

    def _accept(self, t: float, v: float, out: list) -> None:
        self._last = (t, v)
        self._in_a_row = 0
        out.append((t, v))

    def _reject(self, t: float, v: float, why: str) -> None:
        self.rejected.append((t, v, why))
        self._in_a_row += 1
        if self._in_a_row >= self.persist:
            raise ImplausibleReadings(self.device, f"{self._in_a_row} readings in a row physically impossible "
                                                   f"(last {v:.6g} {self.unit}: {why}) — {self.advice}")
