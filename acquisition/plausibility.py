"""Readings the machine cannot physically make between two samples are rejected as corrupt.

A frame can be well formed and still wrong (AED frames carry no checksum; a counter can
step). :class:`RateGuard` sits between a channel's reads and its stream:

* a **one-sample spike** — a sample further from both neighbours than ``max_rate`` × their
  time apart (plus ``tolerance``) allows, while the neighbours agree, or further from their
  chord than they differ from each other plus ``tolerance`` (samples sparse in time) — is
  rejected (the guard holds each sample until the next arrives);
* a lasting **rise** of ``|value|`` faster than ``max_rate`` per second (plus ``tolerance``, and
  ``time_slack`` for uncertain stamps) from the last accepted sample is impossible (force: the
  machine loads at most at frame stiffness × crosshead speed; crosshead: it moves at most at
  its speed) — rejected; with ``falls_freely`` (force) a lasting **fall** of any size is
  physical (a fracture), without it (crosshead) a fall is judged like a rise;
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

    def limit(self, dt: float, slack: bool = True) -> float:
        """The largest physical change of ``|value|`` in ``dt`` seconds (with ``slack``: the time
        stamps as uncertain as ``time_slack``)."""
        return self.max_rate * (max(dt, 0.0) + (self.time_slack if slack else 0.0)) + self.tolerance

    def feed(self, samples: list[tuple[float, float]]) -> list[tuple[float, float]]:
        """The samples that pass, in order (each is judged when the next one arrives)."""
        out: list[tuple[float, float]] = []
        for t, v in samples:
            self._one(t, v, out)
        return out

    def flush(self) -> list[tuple[float, float]]:
        """At the end: the held sample is judged against the last accepted one alone."""
        held, self._held = self._held, None
        out: list[tuple[float, float]] = []
        if held is not None:
            self._judge(held, None, out)
        return out

    def _one(self, t: float, v: float, out: list) -> None:
        if self._last is None:
            self._accept(t, v, out)
            return
        held, self._held = self._held, (t, v)
        if held is not None:
            self._judge(held, (t, v), out)

    def _judge(self, c: tuple[float, float], n: tuple[float, float] | None, out: list) -> None:
        (tp, vp), (tc, vc) = self._last, c
        # a one-sample spike: far from both neighbours, which agree with each other
        if n is not None:
            tn, vn = n
            # ... or, where the samples are too far apart in time for the rate to tell, off the chord of its
            # neighbours by more than they differ (a fracture's fall, a knee stay within it)
            chord = vp + (vn - vp) * (tc - tp) / (tn - tp) if tn > tp else vp
            if ((abs(vc - vp) > self.limit(tc - tp, False) and abs(vn - vc) > self.limit(tn - tc, False)
                    and abs(vn - vp) <= self.limit(tn - tp, False))
                    or abs(vc - chord) > abs(vn - vp) + self.tolerance):
                self._reject(tc, vc, f"{'rose' if abs(vc) > abs(vp) else 'fell'} {abs(abs(vc) - abs(vp)):.4g} {self.unit} "
                                     f"for one sample")
                return
        change = abs(vc) - abs(vp)
        if change > self.limit(tc - tp) or (not self.falls_freely and -change > self.limit(tc - tp)):
            self._reject(tc, vc, f"{'rose' if change > 0 else 'fell'} {abs(change):.4g} {self.unit} in {tc - tp:.3g} s "
                                 f"(at most {self.limit(tc - tp):.4g} possible)")
            return
        self._accept(tc, vc, out)

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
