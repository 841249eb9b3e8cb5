"""A stepped crosshead reading (10 µm encoder counts spanning many samples) re-read between its
steps, and what it changes on a compression record: the plastic strain no longer runs backwards
within each count."""

import numpy as np
import pytest

from flowcurve.identification.compression.identify import identify_compression
from flowcurve.identification.indicator import interpolate_steps, reread_if_stepped, stepped_fraction

from .toe_records import make_toe_compression

Q = 0.01  # mm, one encoder count


def test_a_steady_motion_is_recovered_between_the_counts():
    t = np.arange(0.0, 100.0, 0.1)
    true = 0.001 * t + 0.0003 * np.sin(t / 7.0)  # 1 µm a sample, slowly varying speed: ~100 samples a count
    reading = np.round(true / Q) * Q
    out = interpolate_steps(t, reading)
    change = np.flatnonzero(np.diff(reading))
    inner = slice(change[0] + 1, change[-1] + 1)  # between the first and the last crossing
    assert stepped_fraction(reading) > 0.9
    assert np.abs(reading - true)[inner].max() == pytest.approx(Q / 2, rel=0.02)  # the reading: up to half a count off
    assert np.abs(out - true)[inner].max() < 0.02 * Q  # re-read: the crossing time is known to half a sample (0.5 µm)
    assert np.all(np.abs(out - reading) <= Q / 2 + 1e-12)  # every value stays in its count's cell


def test_a_turn_a_pause_and_dithering_keep_the_reading():
    t = np.arange(0.0, 60.0, 0.1)
    true = np.where(t < 30.0, 0.002 * t, 0.06 - 0.002 * (t - 30.0))  # up, then back down
    reading = np.round(true / Q) * Q
    out = interpolate_steps(t, reading)
    turn = (t > 27.6) & (t < 32.4)  # between the last crossing up and the first down
    assert np.array_equal(out[turn], reading[turn])
    assert np.abs(out - true)[(t > 3) & (t < 27)].max() < 0.1 * Q and np.abs(out - true)[(t > 33) & (t < 57)].max() < 0.1 * Q
    dither = np.tile([0.0, Q], 50)  # an encoder toggling between two counts at rest
    assert np.array_equal(interpolate_steps(np.arange(100.0), dither), dither)
    assert np.array_equal(interpolate_steps(np.arange(3.0), np.array([0.0, Q, Q])), [0.0, Q, Q])  # one crossing: nothing to interpolate


def test_the_plastic_strain_of_a_10_um_record_rises_with_the_stress():
    record, _ = make_toe_compression(rate_hz=10.0, toe_mm=0.05, handbook_E=True)
    ident = identify_compression(record)
    assert ident.result["indicator"]["crosshead_step_interpolated_mm"] == pytest.approx(Q)
    eps_p = ident.true_curve["true_plastic_strain"].to_numpy()[:200]
    # as read, ε_p fell by up to 3e-4 within each count (the force rises at a fixed reading, the frame
    # correction F/C takes it back); re-read, only the force noise's 20 N/C ≈ 2e-5 is left
    assert (np.maximum.accumulate(eps_p) - eps_p).max() < 5e-5
    # a reading that changes at every sample (no counts to re-read) is used as read
    fine = record.data.assign(crosshead_mm=record.data["crosshead_mm"] + np.arange(len(record.data)) * 1e-9)
    as_read = identify_compression(type(record)(meta=dict(record.meta), data=fine, source=record.source))
    assert as_read.result["indicator"]["crosshead_step_interpolated_mm"] is None


def test_only_a_counted_reading_is_re_read():
    t = np.arange(0.0, 50.0, 0.1)
    analogue = 0.001 * t + np.random.default_rng(1).normal(0.0, 1e-4, t.size)  # noisy, never the same twice
    assert reread_if_stepped(t, analogue)[1] is None
    counted = np.round(0.001 * t / Q) * Q
    counted[100] = np.nan  # a missing sample stays missing, the rest is re-read
    out, step = reread_if_stepped(t, counted)
    assert step == pytest.approx(Q) and np.isnan(out[100]) and np.nanmax(np.abs(out - 0.001 * t)[60:440]) < 0.02 * Q  # between the first and last crossings
    whole = np.round(0.001 * t / Q) * Q  # every sample finite: re-read in place
    out, step = reread_if_stepped(t, whole)
    assert step == pytest.approx(Q) and np.nanmax(np.abs(out - 0.001 * t)[60:440]) < 0.02 * Q
