"""Issue 42: the speed a test asks for is the speed the virtual crosshead runs at, and the record
tells the speed it measured from the encoder; a crosshead at another speed than commanded is an
event, the operator's warning and identify's warning. In-process on model time."""

from dataclasses import replace

import pytest

from flowcurve.acquisition.stopping import StopCriteria
from flowcurve.acquisition.session import run_virtual_test
from flowcurve.clock import ModelClock
from flowcurve.demo import demo_specs
from flowcurve.identification.identify import identify
from flowcurve.record.format import read_record

MATERIAL = "steel45"


def compression_to(target_mm: float, speed_mm_per_s: float):
    return replace(demo_specs(MATERIAL)[1], speed_mm_per_s=speed_mm_per_s, stop=StopCriteria(target_displacement_mm=target_mm))


def twin_at(speed_mm_per_s: float, *, deaf: bool = False):
    """rig_setup: the twin's motor set to another speed (as 'rig virtual' starts at its own
    0.01 mm/s); ``deaf``: its motor ignores the speed it is sent (a machine set by hand)."""
    def setup(vr):
        vr.model.speed_mm_per_s = speed_mm_per_s
        if deaf:
            start = vr.start_crosshead
            vr.start_crosshead = lambda *a, **k: start()
    return setup


def test_the_twin_runs_at_the_commanded_speed_and_the_record_says_the_measured_one(tmp_path):
    """Failed on the old code: DriverRig.start_crosshead sent no speed, the twin ran at its own
    0.01 mm/s, and the header had no measured speed."""
    run = run_virtual_test(compression_to(1.5, 0.1), tmp_path / "c.csv", material=MATERIAL, time_scale=15.0,
                           clock=ModelClock(), link="inprocess", compression_response="slab", rig_setup=twin_at(0.01))
    rec = read_record(run.outcome.path)
    assert float(rec.meta["crosshead_speed_mm_per_s"]) == 0.1
    assert float(rec.meta["crosshead_speed_measured_mm_per_s"]) == pytest.approx(0.1, rel=0.02)
    assert not [e for e in rec.events if e.name == "speed_mismatch"]
    assert not [w for w in identify(rec).result["warnings"] if "commanded" in w]


def test_a_crosshead_at_another_speed_is_an_event_and_a_warning(tmp_path):
    run = run_virtual_test(compression_to(1.5, 0.05), tmp_path / "c.csv", material=MATERIAL, time_scale=15.0,
                           clock=ModelClock(), link="inprocess", compression_response="slab", rig_setup=twin_at(0.02, deaf=True))
    rec = read_record(run.outcome.path)
    measured = float(rec.meta["crosshead_speed_measured_mm_per_s"])
    assert measured == pytest.approx(0.02, rel=0.02)
    events = [e.text for e in rec.events if e.name == "speed_mismatch"]
    assert len(events) == 1 and f"ran at {rec.meta['crosshead_speed_measured_mm_per_s']} mm/s" in events[0] and "commanded 0.05 mm/s" in events[0] and "-60 %" in events[0]
    result = identify(rec).result
    assert any("not the commanded 0.05 mm/s" in w for w in result["warnings"])
    assert result["record"]["strain_rate_per_s"] == pytest.approx(measured / float(rec.meta["specimen.h0_mm"]), rel=0.1)  # the rate it ran at, not 0.05 / h0


def test_the_speed_meter_leaves_out_the_rest_before_and_the_still_tail_after():
    """Closed form: 1 s at rest, 0.1 mm/s for 20 s on a 0.01 mm encoder, then 5 s still."""
    import numpy as np

    from flowcurve.acquisition.stopping import SpeedMeter
    t = np.arange(0.0, 26.0, 0.05)
    x = np.floor(np.clip(t - 1.0, 0.0, 20.0) * 0.1 / 0.01 + 1e-9) * 0.01  # whole counts passed
    rows = np.column_stack([t, np.zeros_like(t), x])
    meter = SpeedMeter()
    for block in np.array_split(rows, 7):
        meter.update(block)
    assert meter.speed_mm_per_s() == pytest.approx(0.1, rel=0.01)
    short = SpeedMeter()
    short.update(rows[:200])  # 0.9 mm of travel: too short to tell
    assert short.speed_mm_per_s() is None
