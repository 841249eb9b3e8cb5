"""A driver bug (a TypeError, say) is not a device failure: it is not retried, it stops the
test with the heater off, and it is reported as an internal error."""

import itertools
import time

from flowcurve.acquisition.procedure import Procedure, TestSpec
from flowcurve.acquisition.sampler import Channel, Sampler
from flowcurve.errors import DeviceError, InternalError
from flowcurve.record.format import read_record


def _wait_for_fault(sampler, seconds=5.0):
    deadline = time.monotonic() + seconds
    while sampler.fault is None and time.monotonic() < deadline:
        time.sleep(0.01)


def test_a_bug_in_a_read_faults_at_once_as_an_internal_error():
    calls = itertools.count(1)

    def buggy():
        next(calls)
        return None + 1.0  # TypeError

    start = time.monotonic()
    channel = Channel("encoder", buggy, lambda: time.monotonic() - start, max_failures=50)
    sampler = Sampler({"crosshead_mm": channel}).start()
    _wait_for_fault(sampler)
    sampler.stop()
    assert isinstance(sampler.fault, InternalError) and not isinstance(sampler.fault, DeviceError)
    assert "TypeError" in str(sampler.fault) and "encoder" in str(sampler.fault)
    assert next(calls) == 2  # read once: a bug is not retried like a flaky device


def test_device_errors_are_retried_and_a_recovered_device_goes_on():
    calls = itertools.count(1)

    def flaky():
        n = next(calls)
        if n in (3, 4):  # two failures in a row, fewer than max_failures
            raise DeviceError("encoder", "no reply to '#020'")
        if n == 6:
            raise OSError(5, "Input/output error")
        return float(n)

    start = time.monotonic()
    channel = Channel("encoder", flaky, lambda: time.monotonic() - start, period_s=0.002, max_failures=3)
    sampler = Sampler({"crosshead_mm": channel}).start()
    while len(channel.stream) < 10 and time.monotonic() - start < 5:
        time.sleep(0.01)
    sampler.stop()
    assert sampler.fault is None and len(channel.stream) >= 10


def test_a_bug_while_recording_stops_the_test_with_the_heater_off(tmp_path, fake_rig):
    rig = fake_rig(x_frac_mm=1e9)
    channels = rig.channels

    def channels_with_a_bug(clock, to_clock):
        made = channels(clock, to_clock)
        read = made["crosshead_mm"].read

        def buggy_encoder():
            if rig._t_move is not None and clock() - rig._t_move > 2.0:  # loading for 2 s
                return {"counts": 1}["count"]  # KeyError: a bug, not a device failure
            return read()

        made["crosshead_mm"].read = buggy_encoder
        return made

    rig.channels = channels_with_a_bug
    spec = TestSpec(test="tension", material="steel", geometry_mm={"d0_mm": 6.0, "l0_mm": 30.0},
                    speed_mm_per_s=0.05, temperature_C=60.0, soak_s=1.0, soak_band_C=10.0)
    out = Procedure(rig, spec, tmp_path / "bug.csv").run()
    assert out.status == "aborted" and isinstance(out.error, InternalError)
    assert "KeyError" in out.reason and "internal error" in out.reason
    assert True in rig.heater_log and not rig.heater  # heated, then off
    rec = read_record(out.path)
    assert rec.meta["status"] == "aborted" and "KeyError" in rec.meta["abort_reason"]
    assert len(rec.data) > 0
