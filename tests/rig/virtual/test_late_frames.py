"""The AED twin held up by the host's CPU (issue 42): it keeps the amplifier's own rhythm. Each late
stream frame carries the force at its due time and leaves late, in one write with the others;
only frames further back than the twin remembers are skipped. Before, a late twin sampled the model
at its wake time for every catch-up frame and skipped all but two, so the force sat up to 20 ms of
host time away from its stamp (busy time scale 15: 28-71 frames skipped a run, force 0.7-1.5 % off)."""

import pytest

from flowcurve.clock import ModelClock
from flowcurve.rig.virtual.aed import CATCH_UP_S, AEDAmplifier
from flowcurve.rig.virtual.physics import RigModel
from flowcurve.rig.virtual.rig import VirtualRig

PERIOD_S = 0.01  # ICR0: 100 frames/s
RAMP_N_PER_S = 1000.0


def late_twin():
    """An amplifier whose input ramps at RAMP_N_PER_S of clock time; its writes recorded."""
    clock = ModelClock(auto=False)
    dev = AEDAmplifier(lambda: (clock.now(), RAMP_N_PER_S * clock.now(), False),
                       source_at=lambda t: (t, RAMP_N_PER_S * t, False),
                       settings={"asf": 0, "cof": 3, "icr": 0}, clock=clock, link="inprocess")
    writes = []
    dev.send = lambda *frames: writes.append([int(f) / 1e6 * dev.nominal_load_N for f in frames])
    dev.on_bytes(b"MSV?0;")  # the first frame at 0
    return clock, dev, writes


def test_late_frames_carry_the_force_at_their_due_time_in_one_write():
    clock, dev, writes = late_twin()
    clock.advance(0.055)  # the twin wakes 45 ms late: frames due at 0.01 ... 0.05
    dev.on_tick(clock.now())
    assert writes[0] == [0.0]
    assert writes[1] == pytest.approx([RAMP_N_PER_S * PERIOD_S * k for k in range(1, 6)], abs=0.1)
    assert dev.frames_skipped == 0 and dev.next_deadline() == pytest.approx(0.06)


def test_frames_beyond_the_catch_up_are_skipped_and_counted():
    clock, dev, writes = late_twin()
    clock.advance(3.0)
    dev.on_tick(clock.now())
    sent = writes[1]
    assert len(sent) + dev.frames_skipped == round(3.0 / PERIOD_S)  # every frame due is sent or skipped
    assert len(sent) == pytest.approx(CATCH_UP_S / PERIOD_S, abs=1)
    assert sent[0] == pytest.approx(RAMP_N_PER_S * (3.0 - CATCH_UP_S), abs=RAMP_N_PER_S * PERIOD_S)
    assert sent[-1] == pytest.approx(RAMP_N_PER_S * 3.0, abs=0.1)


def test_a_frame_due_before_the_model_ran_on_reads_the_force_of_its_time():
    """The rig's ``source_at`` for a time the model has already passed (another device read it
    later) against a second model advanced straight to that time (the truth)."""
    scale = 15.0
    clock = ModelClock(auto=False)
    with VirtualRig("12Kh18N12M3TL", speed_mm_per_s=0.05, time_scale=scale, force_noise_N=0.0,
                    clock=clock, link="inprocess") as rig:
        rig.start_crosshead()
        host0 = clock.now()
        for _ in range(150):  # 1.5 s host (22.5 s model: elastic, yield, hardening), synced every 10 ms
            clock.advance(0.01)
            rig.sync()
        truth = RigModel("12Kh18N12M3TL", speed_mm_per_s=0.05, force_noise_N=0.0)
        truth.start_crosshead()
        for back_s in (1.2, 0.9, 0.5, 0.2, 0.013):  # host seconds before now, oldest first
            host_t = clock.now() - back_s
            t, force_N, standstill = rig._loadcell_sample_at(host_t)
            truth.advance_to((host_t - host0) * scale)
            assert t == pytest.approx(truth.time_s) and not standstill
            assert force_N == pytest.approx(truth.force_N, rel=2e-3), back_s
        assert rig._loadcell_sample_at(clock.now() - 1e3) is None  # further back than remembered
