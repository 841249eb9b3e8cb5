"""The load cell's stream stamped on its own rhythm (issue 42): ``stream_stamps`` against known
send times. A lost frame leaves a gap and never moves a later stamp; a burst read at once gets
its spacing back; one late frame heals at the next; a crystal off its nominal rate within the
margin keeps the stamps between the send and the arrival. The old rule (j_k = 1 always) left
every stamp after a loss the lost periods too early: these tests fail on it."""

import numpy as np
import pytest

from flowcurve.rig.loadcell import PERIOD_MARGIN, stream_stamps

T = 0.01  # ICR0: 100 values/s
LATENCY = 0.0012  # the line's time for a frame and the host's wake-up


def sent_times(n, period=T, lost=()):
    """Send times of frames 0..n-1 at ``period`` without those in ``lost``."""
    keep = np.array([k for k in range(n) if k not in set(lost)])
    return keep * period, keep


def old_rule(arrival, period):
    """The stamping before the fix: stamp_k = min(arrival_k, stamp_(k-1) + period·margin)."""
    out = np.empty(len(arrival))
    for k, a in enumerate(arrival):
        out[k] = a if k == 0 else min(a, out[k - 1] + period * PERIOD_MARGIN)
    return out


def test_lost_frames_leave_a_gap_and_move_no_later_stamp():
    sent, index = sent_times(400, lost=set(range(50, 400, 5)) | {120, 121, 122, 123})  # 20 % and a run of 4
    arrival = sent + LATENCY
    stamps, spans = stream_stamps(arrival, T)
    assert np.max(np.abs(stamps - sent)) <= LATENCY + 1e-12  # never beyond the latency, however many were lost
    np.testing.assert_array_equal(spans[1:], np.diff(index))  # each gap counted in periods
    assert spans.sum() - spans.size == (index[-1] - index[0] + 1) - index.size
    # the old rule: every stamp after the first loss stays the lost periods too early
    assert np.max(sent - old_rule(arrival, T)) > 60 * T


def test_a_burst_read_at_once_gets_its_spacing_back():
    sent, _ = sent_times(60)
    # the host stalled: frames 10..29 are read at once, each back-dated by the frames behind it
    read_at = sent[29] + LATENCY
    arrival = sent + LATENCY
    arrival[10:30] = read_at - (29 - np.arange(10, 30)) * T
    arrival[10:30] += 0.0004  # the host's read comes a little after the last one's arrival
    stamps, spans = stream_stamps(arrival, T)
    assert np.all(spans == 1)
    assert np.max(np.abs(stamps - sent)) <= LATENCY + 0.0004 + 1e-12
    # continuing from a previous block gives the same stamps
    more, _ = stream_stamps(arrival[25:], T, last=stamps[24])
    np.testing.assert_allclose(more, stamps[25:], atol=1e-12)


@pytest.mark.parametrize("late", [0.4 * T, 0.6 * T, 0.95 * T])
def test_one_late_frame_heals_at_the_next(late):
    sent, _ = sent_times(40)
    arrival = sent + LATENCY
    arrival[20] += late  # one frame held up on its way (arrivals stay in order)
    stamps, spans = stream_stamps(arrival, T)
    assert stamps[20] <= arrival[20] + 1e-12 and stamps[20] - sent[20] <= LATENCY + late + 1e-12
    np.testing.assert_allclose(stamps[21:], sent[21:] + LATENCY, atol=1e-9)  # healed at the next frame
    assert np.all(np.diff(stamps) > 0)


@pytest.mark.parametrize("drift", [-0.005, -1e-4, 1e-4, 0.005])  # the crystal's rate off nominal, within the margin
def test_a_crystal_off_nominal_keeps_the_stamps_between_send_and_arrival(drift):
    period = T * (1 + drift)
    sent, index = sent_times(2000, period=period, lost=set(range(100, 2000, 7)))
    rng = np.random.default_rng(3)
    arrival = sent + LATENCY + rng.exponential(0.002, sent.size)  # jitter beyond the least delay
    stamps, spans = stream_stamps(arrival, T)
    assert np.all(stamps <= arrival + 1e-12)
    # a frame over T/2 late just before a loss takes one period from the gap's count: the next
    # stamps are then at most T/2 early, and the margin brings them back within 1/(m − 1) frames
    assert np.min(stamps - sent) >= -0.5 * T
    assert np.mean(np.abs(stamps - sent) > LATENCY + 0.01) < 0.01  # nothing shifted for long
    assert np.median(stamps - sent) < LATENCY + 0.002  # the envelope leans on the least-delayed arrivals
    # the gaps in periods, as the stamps' span counts them
    assert abs(round((stamps[-1] - stamps[0]) / T) - (index[-1] - index[0])) <= abs(drift) * index[-1] + 1


def test_stamps_always_increase_and_never_exceed_the_arrival():
    rng = np.random.default_rng(7)
    sent = np.cumsum(rng.choice([T, 2 * T, 5 * T], size=500, p=[0.8, 0.15, 0.05]))
    arrival = sent + LATENCY + rng.exponential(0.004, sent.size)
    arrival = np.maximum.accumulate(arrival) + np.arange(sent.size) * 1e-7  # in order, as the driver makes them
    stamps, _ = stream_stamps(arrival, T)
    assert np.all(np.diff(stamps) > 0) and np.all(stamps <= arrival + 1e-12)
