"""The displacement target while the encoder retries a lost reply (issue 42): its last reading goes
stale, and the stop waited for the next one — 0.5 mm past a 3 mm target in the matrix's compression
cells with encoder:drop. A reading older than the stale limit is carried on at the speed. These
fail on the old ``target_reached`` (no ``now_s``/``speed_mm_per_s``)."""

from flowcurve.acquisition.stopping import StopCriteria, target_reached
CRIT = StopCriteria(target_displacement_mm=3.0)
SPEED = 0.05  # mm/s


def test_a_stale_reading_is_carried_on_to_the_target():
    reading = (50.0, -2.82)  # compression: downwards; 2.82 mm read at 50 s
    assert target_reached(reading, CRIT, now_s=53.0, speed_mm_per_s=SPEED, stale_s=1.0) is None  # 2.97 mm
    reason = target_reached(reading, CRIT, now_s=53.7, speed_mm_per_s=SPEED, stale_s=1.0)  # 3.005 mm
    assert reason is not None and "carried on" in reason


def test_a_fresh_reading_is_never_carried_on():
    # within the stale limit the reading itself decides, however near: no stop on a guess
    assert target_reached((50.0, 2.99), CRIT, now_s=50.9, speed_mm_per_s=SPEED, stale_s=1.0) is None
    assert target_reached((50.0, 2.99), CRIT, now_s=60.0, speed_mm_per_s=0.0, stale_s=1.0) is None  # no motion: none
    assert target_reached((50.0, 3.0), CRIT, now_s=50.0) == "target displacement 3 mm reached"


def test_a_silent_encoder_is_never_carried_on_to_the_target():
    # 0.96 mm read 60 s before: carried on it would reach 3 mm, but that is a silence, not a retry
    assert target_reached((0.0, -0.96), CRIT, now_s=60.0, speed_mm_per_s=SPEED, stale_s=1.0, carry_max_s=20.0) is None
