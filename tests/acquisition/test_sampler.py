"""Synchronized sampling with fake devices on model time: nothing lost, nothing duplicated,
correct merge."""

import itertools
import threading

import numpy as np
import pytest

from flowcurve.acquisition.sampler import Channel, Sampler, interpolate_at, merge_block, releasable
from flowcurve.clock import ModelClock


@pytest.fixture
def tb():
    """The channels' host time; the samples are stamped with ``tb.now`` (test seconds). A
    short stall rule: one test has a driver hang outside the clock."""
    return ModelClock(stall_s=0.01)


def counter_read(n_max, period_s, tb):
    """A fake load cell: sends 0, 1, 2, ... n_max-1 then nothing (returns None)."""
    it = iter(range(n_max))

    def read():
        tb.sleep(period_s)
        return next(it, None)

    return read


def test_merge_block_interpolates_linear_streams_exactly():
    ft = np.array([0.05, 0.15, 0.25, 0.35])
    ts = np.array([0.0, 0.1, 0.2, 0.3, 0.4])
    rows = merge_block(ft, np.arange(4.0), [(ts, 2.0 * ts + 1.0)])
    # a linear law is reproduced exactly by linear interpolation
    np.testing.assert_allclose(rows[:, 2], 2.0 * ft + 1.0, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(rows[:, 1], np.arange(4.0))


def test_releasable_waits_for_the_slowest_stream():
    ft = np.array([0.1, 0.2, 0.3, 0.4])
    assert releasable(ft, [0.25, 0.5], final=False) == 2
    assert releasable(ft, [0.25, -np.inf], final=False) == 0
    assert releasable(ft, [0.25, -np.inf], final=True) == 4


def test_interpolate_holds_ends_and_nan_when_empty():
    out = interpolate_at(np.array([-1.0, 5.0]), np.array([0.0, 1.0]), np.array([3.0, 4.0]))
    np.testing.assert_array_equal(out, [3.0, 4.0])
    assert np.isnan(interpolate_at(np.array([1.0]), np.array([]), np.array([]))).all()


def test_a_stream_that_stopped_answering_leaves_the_rows_after_it_unread():
    """A furnace polled every 0.5 s that fell silent at 2 s: a row 1 s later (a poll due, within 3 × the
    interval) still holds its last reading, a row 5 s later has none — never the last value repeated."""
    ts = np.arange(0.0, 2.01, 0.5)
    vs = 600.0 - ts
    out = interpolate_at(np.array([-0.5, 1.25, 3.0, 7.0, -2.0]), ts, vs)
    np.testing.assert_allclose(out[:3], [600.0, 598.75, 598.0])
    assert np.isnan(out[3]) and np.isnan(out[4])


def test_every_force_sample_appears_exactly_once_and_in_order(tb):
    clock = tb.now
    n = 600
    speed = 0.5  # mm/s, the fake crosshead position is speed * t on the same clock
    force = Channel("loadcell", counter_read(n, 0.0005, tb), clock, silence_s=5, timebase=tb)
    enc = Channel("encoder", lambda: speed * clock(), clock, period_s=0.01, timebase=tb)
    temp = Channel("furnace", lambda: 20.0 + clock(), clock, period_s=0.03, timebase=tb)
    sampler = Sampler({"force_N": force, "crosshead_mm": enc, "temperature_C": temp}).start()
    blocks = []
    while len(force.stream) < n:
        blocks.append(sampler.take_rows())
        tb.sleep(0.01)
    blocks.append(sampler.finish())
    rows = np.vstack(blocks)
    np.testing.assert_array_equal(rows[:, 1], np.arange(n))  # each sent value once, in order
    assert np.all(np.diff(rows[:, 0]) >= 0)
    # interpolated channels follow their laws at the force times (inside their streams)
    ts_enc, _ = enc.stream.snapshot()
    inside = (rows[:, 0] >= ts_enc[0]) & (rows[:, 0] <= ts_enc[-1])
    assert inside.sum() > n // 2
    np.testing.assert_allclose(rows[inside, 2], speed * rows[inside, 0], atol=2e-4)
    ts_t, _ = temp.stream.snapshot()
    inside_t = (rows[:, 0] >= ts_t[0]) & (rows[:, 0] <= ts_t[-1])
    np.testing.assert_allclose(rows[inside_t, 3], 20.0 + rows[inside_t, 0], atol=2e-3)


def test_streamed_blocks_are_stamped_and_kept(tb):
    clock = tb.now
    counter = itertools.count()
    sent = []

    def block_read():
        tb.sleep(0.005)
        if len(sent) >= 500:
            return []
        vals = [next(counter) for _ in range(5)]
        sent.extend(vals)
        return vals

    force = Channel("loadcell", block_read, clock, spacing_s=0.001, silence_s=5, timebase=tb)
    enc = Channel("encoder", lambda: clock(), clock, period_s=0.005, timebase=tb)
    sampler = Sampler({"force_N": force, "crosshead_mm": enc}).start()
    got = []
    while len(force.stream) < 500:
        got.append(sampler.take_rows())
        tb.sleep(0.005)
    got.append(sampler.finish())
    rows = np.vstack(got)
    np.testing.assert_array_equal(rows[:, 1], np.array(sent, dtype=float))
    assert np.all(np.diff(rows[:, 0]) >= 0)


def test_failing_device_is_named_and_recorded_samples_kept(tb):
    clock = tb.now
    calls = itertools.count()

    def dying_encoder():
        if next(calls) > 20:
            raise OSError("device reports readiness to read but returned no data")
        return 1.0

    force = Channel("loadcell", lambda: (tb.sleep(0.002), 5.0)[1], clock, timebase=tb)
    enc = Channel("encoder", dying_encoder, clock, period_s=0.002, max_failures=3, timebase=tb)
    sampler = Sampler({"force_N": force, "crosshead_mm": enc}).start()
    deadline = tb.now() + 5
    while sampler.fault is None and tb.now() < deadline:
        tb.sleep(0.01)
    rows = sampler.finish()
    assert sampler.fault is not None
    assert str(sampler.fault).startswith("encoder: ")
    assert "returned no data" in str(sampler.fault)
    crosshead = rows[:, 2]
    read = np.isfinite(crosshead)  # an encoder that is not a standing stream: rows after it died (beyond 3 intervals) carry none
    assert len(rows) > 0 and read[0] and np.all(crosshead[read] == 1.0) and np.all(np.diff(read.astype(int)) <= 0)


def test_silent_device_returning_nothing_is_a_fault(tb):
    force = Channel("loadcell", lambda: (tb.sleep(0.01), None)[1], tb.now, silence_s=0.2, timebase=tb)
    sampler = Sampler({"force_N": force}).start()
    with tb.idle():  # this thread waits for the channel, which waits on the clock
        force.join(3)
    sampler.stop()
    assert sampler.fault is not None and "loadcell" in str(sampler.fault) and "no data" in str(sampler.fault)


def test_hanging_read_is_caught_by_check_silence(tb):
    clock = tb.now
    release = threading.Event()
    force = Channel("loadcell", lambda: 1.0, clock, period_s=0.05, timebase=tb)
    # a driver stuck outside the clock: time moves on only by the clock's stall rule
    enc = Channel("encoder", lambda: (release.wait(5), 0.0)[1], clock, silence_s=0.1, timebase=tb)
    sampler = Sampler({"force_N": force, "crosshead_mm": enc}).start()
    tb.sleep(0.3)
    fault = sampler.check_silence()
    release.set()
    sampler.finish()
    assert fault is not None and str(fault).startswith("encoder: no answer")


# -- a gap in the crosshead's readings (a retried encoder read) --------------------------------
COUNT_MM = 0.01  # one encoder count


def _crosshead(t, speed=0.5, t_stop=np.inf):
    """The true crosshead: runs at ``speed`` until ``t_stop``, then stands."""
    return speed * np.minimum(t, t_stop)


def _polled(t_stop=np.inf, gap=(4.0, 5.26), end_s=6.0, period_s=0.04):
    """Encoder readings every ``period_s`` (whole counts, truncated as the counter does), none
    inside ``gap``: the dropped reply and the wait for its late reply before the retry."""
    ts = np.arange(0.0, end_s, period_s)
    ts = ts[(ts <= gap[0]) | (ts >= gap[1])]
    return ts, np.floor(_crosshead(ts, t_stop=t_stop) / COUNT_MM + 1e-9) * COUNT_MM


def test_rows_crosshead_stands_after_a_stop_inside_a_gap_of_its_readings():
    ts, xs = _polled(t_stop=4.3)  # the fracture stops the crosshead 0.3 s into a 1.26 s gap
    ft = np.arange(0.01, 6.0, 0.02)
    x = merge_block(ft, np.zeros(ft.size), [(ts, xs)], stands=[True])[:, 2]
    # within one count of the truth everywhere (a straight line across the gap was 0.11 mm short at the stop)
    np.testing.assert_array_less(np.abs(x - _crosshead(ft, t_stop=4.3)), COUNT_MM + 1e-9)
    after = ft > 4.3 + 0.1
    assert np.ptp(x[after]) == 0.0, "after the stop the rows' crosshead stands"
    # the temperature (no flag) is still a straight line across a gap
    np.testing.assert_allclose(merge_block(ft, np.zeros(ft.size), [(ts, xs)])[:, 2], np.interp(ft, ts, xs))


def test_rows_crosshead_crosses_a_gap_in_steady_motion_on_its_line():
    ts, xs = _polled()
    ft = np.arange(0.01, 5.95, 0.02)  # within the readings (the last one is held after them)
    x = merge_block(ft, np.zeros(ft.size), [(ts, xs)], stands=[True])[:, 2]
    np.testing.assert_array_less(np.abs(x - _crosshead(ft)), COUNT_MM + 1e-9)
    inside = (ft > 4.0) & (ft < 5.26)
    assert np.all(np.diff(x[inside]) > 0), "no stand invented inside a gap the crosshead ran through"


def test_sampler_keeps_the_readings_before_a_gap_that_give_the_speed(tb):
    """Rows taken block by block (as the procedure does): the readings before a gap are still
    there when the reading after it comes, so the stop inside it is found."""
    ts, xs = _polled(t_stop=4.3)
    ft = np.arange(0.01, 6.0, 0.02)
    force = Channel("loadcell", lambda: None, tb.now, timebase=tb)
    enc = Channel("encoder", lambda: None, tb.now, timebase=tb, stands=True)
    sampler = Sampler({"force_N": force, "crosshead_mm": enc})
    rows = []
    for lo in np.arange(0.0, 6.0, 0.2):  # 0.2 s of samples arrive between two take_rows
        f = (ft >= lo) & (ft < lo + 0.2)
        e = (ts >= lo) & (ts < lo + 0.2)
        force.stream.extend(ft[f], np.zeros(f.sum()))
        enc.stream.extend(ts[e], xs[e])
        rows.append(sampler.take_rows())
    rows.append(sampler.take_rows(final=True))
    rows = np.vstack(rows)
    np.testing.assert_array_equal(rows[:, 0], ft)
    np.testing.assert_array_less(np.abs(rows[:, 2] - _crosshead(ft, t_stop=4.3)), COUNT_MM + 1e-9)
