"""acquisition.plausibility.RateGuard against hand-made series whose answer is known."""

import numpy as np
import pytest

from flowcurve.acquisition.plausibility import ImplausibleReadings, RateGuard


def force_guard(**kw):
    # 136 N/µm × 0.01 mm/s × 2 = 2720 N/s; 1 kN tolerance; stamps uncertain by 3 s
    return RateGuard("load cell", max_rate=2720.0, tolerance=1000.0, unit="N", falls_freely=True, time_slack=3.0, **kw)


def feed_all(guard, t, v):
    return guard.feed(list(zip(t, v))) + guard.flush()


def test_one_corrupt_frame_is_rejected_even_when_the_stamps_are_uncertain():
    t = np.arange(0, 10, 0.01)
    f = 1000.0 * t  # 1 kN/s loading
    f[500] += 20_000.0  # the corrupt frame (below what 3 s of slack would allow as a lasting rise)
    g = force_guard()
    kept = feed_all(g, t, f)
    assert len(kept) == t.size - 1 and max(v for _, v in kept) < 11_000
    assert len(g.rejected) == 1 and g.rejected[0][0] == t[500] and "one sample" in g.rejected[0][2]


def test_a_fracture_is_a_lasting_fall_and_passes():
    t = np.arange(0, 2, 0.01)
    f = np.where(t < 1.0, 12_000.0, 50.0)
    g = force_guard()
    assert len(feed_all(g, t, f)) == t.size and not g.rejected


def test_a_lasting_impossible_rise_stops_the_channel():
    t = np.arange(0, 1, 0.01)
    f = np.where(t < 0.5, 100.0, 60_000.0)
    with pytest.raises(ImplausibleReadings, match="load cell: 5 readings in a row physically impossible"):
        feed_all(force_guard(), t, f)


def test_a_counter_step_is_rejected_then_stops_the_channel():
    g = RateGuard("crosshead encoder", max_rate=0.02, tolerance=0.05, unit="mm", time_slack=1.0)
    t = np.arange(0, 2, 0.02)
    x = 0.01 * t + np.where(t > 1.0, 50.0, 0.0)
    with pytest.raises(ImplausibleReadings, match="crosshead encoder"):
        feed_all(g, t, x)
    assert len(g.rejected) == 5 and all(v > 50 for _, v, _ in g.rejected)


def test_noise_within_the_tolerance_passes():
    rng = np.random.default_rng(0)
    t = np.arange(0, 5, 0.01)
    f = 2000.0 * t + rng.normal(0, 30, t.size)
    g = force_guard()
    assert len(feed_all(g, t, f)) == t.size and not g.rejected


def _sparse_tension(dt_s: float = 0.4):
    """A tension curve sampled every ``dt_s`` (a fast virtual time scale): 68 kN/s elastic
    (136 N/µm × 0.5 mm/s) to 10 kN, a knee, hardening to 13 kN, a fracture to 50 N."""
    t = np.arange(0, 12, dt_s)
    f = np.minimum(68_000.0 * t, 10_000.0 + 3_000.0 * (1.0 - np.exp(-(t - 10_000.0 / 68_000.0) / 2.0)))
    f[t > 10.0] = 50.0
    return t, f


def test_a_spike_is_rejected_where_the_samples_are_too_sparse_for_the_rate_to_tell():
    """Issue 31: on a fast time scale at 0.5 mm/s, 0.4 s between samples lets the stiff frame's
    rate allow 27 kN; a +20 kN reading was taken as the maximum force. Off the chord of its
    neighbours by more than they differ, it is rejected; the knee and the fracture pass."""
    t, f = _sparse_tension()
    g = RateGuard("load cell", max_rate=68_000.0 * 1.5, tolerance=1000.0, unit="N", falls_freely=True, time_slack=1.0)
    assert len(feed_all(g, t, f)) == t.size and not g.rejected  # the clean curve: every sample kept
    spiked = f.copy()
    spiked[10] += 20_000.0
    g = RateGuard("load cell", max_rate=68_000.0 * 1.5, tolerance=1000.0, unit="N", falls_freely=True, time_slack=1.0)
    kept = feed_all(g, t, spiked)
    assert len(kept) == t.size - 1 and max(v for _, v in kept) < 13_100.0
    assert [r[0] for r in g.rejected] == [t[10]]
