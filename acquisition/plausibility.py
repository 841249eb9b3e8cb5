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

A spike smaller than ``tolerance`` passes those rules (the force's tolerance is 1 % of the
frame's capacity: a +900 N frame at 100 kN). With ``spike_sigmas`` (force) the guard also judges
each sample by the **signal's own noise**: σ is the median absolute residual of the recent samples
from their neighbours' chord (``noise_window`` of them, robust to the rare spike or yield drop
among them; while the window fills, its newer half, so that the knee's few large residuals on a
sparse record leave it soon; at least ``noise_floor``, the instrument's resolution), and a sample
is a one-sample spike at any size when

* it is out of the band its two neighbours span by more than ``spike_sigmas`` σ (it leaves
  the band and comes back: a knee, a step or a fall stays within it), and
* it lies on no trend that excuses it. For a force (``falls_freely``) a **rise** away from zero
  is excused only by the approach: lying between the sample before it and the approach's trend
  extended to its time — the least-squares line through the last :data:`APPROACH_SAMPLES`
  accepted samples where they lie on one (χ²/dof under :data:`SMOOTH_CHI2`), widened by that
  tolerance × the line's prediction noise in chord residuals (:func:`line_prediction_factor`,
  about 1.1), else the line through the two samples before, widened by twice the tolerance (a
  line extended one step carries about twice the chord's noise). A **fall** toward zero (and
  either change of a channel that does not fall freely) is excused by the two-sample approach or
  by the departure (between the sample after it and the line through the two after it extended
  back, widened alike), and
* for a force, a fall is no dip whose rise back the machine could make in that time
  (``max_rate``): a serration reloading faster than the samples resolve its reload.

A physical event does not return, so one of these fails: at a **yield drop**, a **serration**
(Portevin–Le Chatelier) or a **fracture** the sample at the bottom lies on the departure's
trend (the lower yield level, the reloading, the broken specimen's zero) and the peak before
lies on the approach's trend (the elastic or hardening rise, at most up to its extension: a peak
reached between two samples); a step or a fall stays within its neighbours' band. What no rule
can tell: a spike smaller than the signal's climb between two samples (it stays within its
neighbours' band, like a knee: a sparse record of a steep curve), a serration whose rise to its
peak takes a single sample, and (for a force) a dip smaller than ``max_rate`` × the sampling
interval (2 kN at 0.05 mm/s on a 136 N/µm frame and 0.15 s apart, the virtual rig at time scale
15). The guard holds two samples with this rule (one without). Rejections by the noise rule are
named like the others but never stop the channel (``persist`` counts the rules above): they are
single readings judged against the signal, not a broken channel; the noise window takes every
judged sample, rejected or not, so a channel whose noise really grows is followed within half a
window. Before ``noise_min`` residuals (the first samples) only the rules above judge. At the
**end of the stream** (:meth:`RateGuard.flush`) the last two samples lack the samples after them:
a force's rise out of the band (the last sample's band is the sample before it) is judged by the
approach alone (the last sample may also be a reload after a fall: back by at most that fall and
what the machine can make), a fall
toward zero is kept (a fracture, as far as anything can tell) unless it lands beyond zero by more
than ``tolerance`` (a garbled sign: a fracture reads the broken specimen's zero).

Every rejection is kept in :attr:`RateGuard.rejected` (time, value, why) for the record's events.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from flowcurve.errors import DeviceError

NOISE_WINDOW = 200  # residuals from the neighbours' chord the noise σ is the median of
NOISE_MIN = 8  # the noise rule judges once this many residuals are in the window
MAD_TO_SIGMA = 1.0 / 0.6745  # a normal distribution's σ from its median absolute deviation
LINE_NOISE = 2.0  # a line through two samples extended one step: ≈ 2 × the chord's noise (√6 σ against √1.5 σ)
CHORD_VARIANCE = 1.5  # a chord residual's variance in the samples' σ² (1 + 2 × ¼)
APPROACH_SAMPLES = 6  # accepted samples the approach's least-squares line is fitted through
SMOOTH_CHI2 = 4.0  # ... where their residuals' χ² per degree of freedom is under this (else the two-sample line)
EXTEND_AT_MOST = 4.0  # a trend line is extended at most this many of its own steps (a gap of lost frames)


class ImplausibleReadings(DeviceError):
    """A channel whose readings stay physically impossible: the test stops."""


class RateGuard:
    """One channel's plausibility filter (see the module docstring); ``unit`` names values."""

    def __init__(self, device: str, *, max_rate: float, tolerance: float, unit: str, falls_freely: bool = False,
                 persist: int = 5, advice: str = "check the device and its cable", time_slack: float = 0.0,
                 spike_sigmas: float | None = None, noise_floor: float = 0.0, noise_window: int = NOISE_WINDOW,
                 noise_min: int = NOISE_MIN):
        self.device = device
        self.spike_sigmas = spike_sigmas  # None: no judging by the signal's noise (the module docstring)
        self.noise_floor = float(noise_floor)
        self.noise_min = int(noise_min)
        self._residuals: deque[float] = deque(maxlen=int(noise_window))
        self._sigma: float | None = None
        self._before_last: tuple[float, float] | None = None  # the accepted sample before _last (the approach's line)
        self._accepted: deque[tuple[float, float]] = deque(maxlen=APPROACH_SAMPLES)  # the approach's samples
        self.max_rate = float(max_rate)
        self.time_slack = float(time_slack)  # how wrong two time stamps' difference may be
        self.tolerance = float(tolerance)
        self.unit = unit
        self.falls_freely = falls_freely
        self.persist = persist
        self.advice = advice
        self.rejected: list[tuple[float, float, str]] = []
        self._last: tuple[float, float] | None = None  # last accepted (t, v)
        self._held: list[tuple[float, float]] = []  # samples waiting for the next one (two with spike_sigmas)
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
        """At the end: the held samples are judged with what follows them (the last against the
        last accepted one alone)."""
        held, self._held = self._held, []
        out: list[tuple[float, float]] = []
        for i, c in enumerate(held):
            self._judge(c, held[i + 1] if i + 1 < len(held) else None, held[i + 2] if i + 2 < len(held) else None, out)
        return out

    @property
    def noise(self) -> float | None:
        """The σ the noise rule judges with (the chord residual's), None before enough samples."""
        return self._sigma

    def _one(self, t: float, v: float, out: list) -> None:
        if self._last is None:
            self._accept(t, v, out)
            return
        self._held.append((t, v))
        if len(self._held) > (2 if self.spike_sigmas is not None else 1):
            c = self._held.pop(0)
            self._judge(c, self._held[0], self._held[1] if len(self._held) > 1 else None, out)

    def _judge(self, c: tuple[float, float], n: tuple[float, float] | None, nn: tuple[float, float] | None, out: list) -> None:
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
                self._note_residual(vc - chord)
                self._reject(tc, vc, f"{'rose' if abs(vc) > abs(vp) else 'fell'} {abs(abs(vc) - abs(vp)):.4g} {self.unit} "
                                     f"for one sample")
                return
            if self.spike_sigmas is not None:
                spike = self._noise_spike(c, n, nn, chord)
                self._note_residual(vc - chord)
                if spike:
                    self._reject(tc, vc, spike, counts=False)
                    return
        elif self.spike_sigmas is not None:  # the last sample: judged against the trend that led to it alone
            spike = self._noise_spike(c, None, None, vp)
            if spike:
                self._reject(tc, vc, spike, counts=False)
                return
        change = abs(vc) - abs(vp)
        if change > self.limit(tc - tp) or (not self.falls_freely and -change > self.limit(tc - tp)):
            self._reject(tc, vc, f"{'rose' if change > 0 else 'fell'} {abs(change):.4g} {self.unit} in {tc - tp:.3g} s "
                                 f"(at most {self.limit(tc - tp):.4g} possible)")
            return
        self._accept(tc, vc, out)

    def _noise_spike(self, c, n, nn, chord: float) -> str:
        """Why ``c`` is a one-sample spike by the signal's own noise (the module docstring), or ''.
        ``n``/``nn``: the samples after it (None at the end of the stream); ``chord``: the value it is
        measured from (its neighbours' chord, or the last accepted sample without a next one)."""
        sigma = self._sigma
        if sigma is None:
            return ""
        (tp, vp), (tc, vc) = self._last, c
        off, tol = vc - chord, self.spike_sigmas * sigma
        sign = -1.0 if self.falls_freely and vp < 0 else 1.0  # a force rises away from zero, falls toward it
        band = [sign * vp] + ([sign * n[1]] if n is not None else [])
        above, below = sign * vc - max(band), min(band) - sign * vc
        if max(above, below) <= tol:
            return ""  # within the band its neighbours span (a step, a knee, a fall), or not far out of it
        if self.falls_freely and above > tol:  # a rise out of the band: only as the peak of the rise that led to it
            if self._on_approach(tc, vc, tol):
                return ""  # on the rise (or fall) that led to it, not beyond: a peak before a drop, the upper yield point
            fell = sign * (self._before_last[1] - vp) if self._before_last is not None else 0.0
            if n is None and fell > tol and sign * (vc - vp) <= min(fell, self.max_rate * (tc - tp)) + tol:
                return ""  # the last sample: a rise back after a fall, no higher and no faster than the machine (a reload)
            return self._spike_text(off, sigma)
        if nn is None:  # the end of the stream: a fall is a fracture's, down to the broken specimen's zero
            return self._spike_text(off, sigma) if self.falls_freely and sign * vc < -self.tolerance else ""
        tn, vn = n
        line = LINE_NOISE * tol
        approach = _extended(self._before_last, self._last, tc)
        if approach is not None and _between(vc, vp, approach, line):
            return ""  # on the trend that led to it: a fall that had begun before it (any change, without falls_freely)
        departure = _extended(nn, n, tc)
        if departure is not None and _between(vc, vn, departure, line):
            return ""  # on the trend that follows it: the bottom of a yield drop or serration, a fracture
        if self.falls_freely and abs(vc) < min(abs(vp), abs(vn)) and abs(vn) - abs(vc) <= self.max_rate * (tn - tc) + tol:
            return ""  # a fall, then a rise the machine can make: a serration reloading faster than the samples resolve
        return self._spike_text(off, sigma)

    def _spike_text(self, off: float, sigma: float) -> str:
        return (f"a one-sample spike, {off:+.4g} {self.unit} off its neighbours' chord and back at the next sample "
                f"({abs(off) / sigma:.0f} × the signal's noise σ {sigma:.2g} {self.unit})")

    def _on_approach(self, tc: float, vc: float, tol: float) -> bool:
        """``vc`` between the last accepted sample and the approach's trend extended to ``tc``: the least-
        squares line through the last :data:`APPROACH_SAMPLES` accepted samples where they lie on one
        (its prediction noise, :func:`line_prediction_factor`, instead of two samples' 2×), else the line
        through the last two."""
        vp = self._last[1]
        fit = _smooth_line(self._accepted, tc, self._sigma / np.sqrt(CHORD_VARIANCE))
        if fit is not None:
            value, factor = fit
            return _between(vc, vp, value, factor * tol)
        approach = _extended(self._before_last, self._last, tc)
        return approach is not None and _between(vc, vp, approach, LINE_NOISE * tol)

    def _note_residual(self, residual: float) -> None:
        if self.spike_sigmas is None:
            return
        self._residuals.append(abs(residual))
        n = len(self._residuals)
        if n >= self.noise_min:
            # the newer half while the window fills: the first samples' knee (the elastic line bending into
            # flow, a few large residuals where the samples are sparse) leaves the estimate soon
            recent = list(self._residuals)[-max(self.noise_min, n // 2):] if n < self._residuals.maxlen else self._residuals
            self._sigma = max(float(np.median(recent)) * MAD_TO_SIGMA, self.noise_floor, 1e-12)

    def _accept(self, t: float, v: float, out: list) -> None:
        self._before_last, self._last = self._last, (t, v)
        self._accepted.append((t, v))
        self._in_a_row = 0
        out.append((t, v))

    def _reject(self, t: float, v: float, why: str, counts: bool = True) -> None:
        """``counts``: a rejection by the rules that stop a channel which keeps making them."""
        self.rejected.append((t, v, why))
        if not counts:
            return
        self._in_a_row += 1
        if self._in_a_row >= self.persist:
            raise ImplausibleReadings(self.device, f"{self._in_a_row} readings in a row physically impossible "
                                                   f"(last {v:.6g} {self.unit}: {why}) — {self.advice}")


def _between(v: float, a: float, b: float, margin: float) -> bool:
    """``v`` within [a, b] (either order) widened by ``margin``."""
    return min(a, b) - margin <= v <= max(a, b) + margin


def _extended(a: tuple[float, float] | None, b: tuple[float, float] | None, t: float) -> float | None:
    """The line through samples ``a`` and ``b`` at time ``t`` (None without two distinct times)."""
    if a is None or b is None or a[0] == b[0]:
        return None
    (ta, va), (tb, vb) = a, b
    steps = (t - tb) / (tb - ta)
    if abs(steps) > EXTEND_AT_MOST:
        return None
    return vb + (vb - va) * steps


def line_prediction_factor(t: np.ndarray, at: float) -> float:
    """The least-squares line through samples at times ``t``, predicted at ``at``: its error's σ in units
    of a chord residual's σ (each sample's σ² × (1 + 1/k + (at − t̄)²/Sxx), over CHORD_VARIANCE)."""
    mean = t.mean()
    return float(np.sqrt((1.0 + 1.0 / t.size + (at - mean) ** 2 / np.sum((t - mean) ** 2)) / CHORD_VARIANCE))


def _smooth_line(samples, at: float, sample_sigma: float) -> tuple[float, float] | None:
    """(value at ``at``, :func:`line_prediction_factor`) of the least-squares line through ``samples``
    when there are :data:`APPROACH_SAMPLES` of them lying on a line (χ²/dof under :data:`SMOOTH_CHI2`
    with the samples' σ) and ``at`` is at most :data:`EXTEND_AT_MOST` of their steps beyond; else None."""
    if len(samples) < APPROACH_SAMPLES:
        return None
    t, v = np.array(samples, dtype=float).T
    step = (t[-1] - t[0]) / (t.size - 1)
    if step <= 0 or (at - t[-1]) / step > EXTEND_AT_MOST:
        return None
    slope, intercept = np.polyfit(t - t[-1], v, 1)  # (t − t_last) keeps the normal equations well conditioned
    chi2 = np.sum((v - (intercept + slope * (t - t[-1]))) ** 2) / (t.size - 2)
    if chi2 > SMOOTH_CHI2 * sample_sigma ** 2:
        return None
    return float(intercept + slope * (at - t[-1])), line_prediction_factor(t, at)
