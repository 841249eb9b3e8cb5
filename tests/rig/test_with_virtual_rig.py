"""The drivers against the virtual-rig engineer's twins, opened in-process on model time.

Only what checks the two sides agree on a protocol reading (binary frames, watchdog safe
value, Gray check); the twins' own behaviour is tested in their folder. The drivers over
real pseudo-terminals: tests/acquisition/test_faults.py (a separate process) and
tests/rig/test_cli.py.
"""

import pytest

from flowcurve.errors import DeviceError


@pytest.fixture
def rig(rig_factory):
    return rig_factory(time_scale=1.0)


@pytest.mark.parametrize("cof", [8, 12, 2, 9, 0 + 32])
def test_loadcell_stream_in_each_format(rig, cof):
    cell = rig.config().loadcell.create()
    with cell:
        cell.configure(rate_code=0, filter=0, fmt=cof)  # 100 values/s
        idle = cell.read()
        cell.start_stream()
        got = []
        deadline = rig.clock.now() + 2.0
        while len(got) < 30 and rig.clock.now() < deadline:
            got += cell.read_stream(30 - len(got), timeout=0.5)
        cell.stop_stream()
        after = cell.read()  # the line is clean again after STP
    assert len(got) == 30
    span = got[-1].t_monotonic_s - got[1].t_monotonic_s  # 28 intervals at 100 values/s
    if rig.link == "inprocess":  # model time: exactly (the first frame also waits for its command)
        assert span == pytest.approx(0.28, abs=1e-9)
    else:  # a pty in real time (loose: a loaded machine)
        assert 0.15 < span < 1.0
    # idle machine: force noise of a few newtons around zero, in every format's scale
    for s in [idle, after] + got:
        assert abs(s.force_N) < 50.0 + 100e3 / 20_000 and not s.overload


def test_tare_zeroes_a_held_load(rig_factory):
    rig = rig_factory(speed_mm_per_s=0.1)
    with rig.config().loadcell.create() as cell:
        cell.configure(filter=0)
        rig.start_crosshead()
        rig.clock.sleep(0.3)  # 30 um of crosshead travel: kilonewtons in the elastic range
        rig.stop_crosshead()
        rig.clock.sleep(0.05)
        loaded = cell.read().force_N
        cell.tare()
        tared = cell.read().force_N
    assert abs(loaded) > 500.0
    assert abs(tared) < 30.0


def test_encoder_follows_the_crosshead(rig):
    with rig.config().encoder.create() as enc:
        enc.zero()
        assert enc.read_counts() == 0 and enc.gray_check()
        rig.start_crosshead()
        rig.clock.sleep(0.3)
        rig.stop_crosshead()
        mm = enc.position_mm()
    assert mm == pytest.approx(rig.model.crosshead_mm, abs=0.011)  # one count is 10 um


def test_watchdog_switches_the_heater_off_when_the_host_goes_quiet(rig):
    with rig.config().furnace.create() as furnace:
        furnace.heater(True)
        assert rig.model.furnace.commanded_on
        furnace.arm_watchdog(0.3)
        rig.clock.sleep(0.7)  # the host says nothing
        assert not rig.model.furnace.commanded_on
        assert furnace.watchdog_status() == 0x04
        with pytest.raises(DeviceError, match="outputs locked: the host watchdog timed out"):
            furnace.heater(True)
        assert furnace.heater_off() is True  # refused, but the output reads off
        furnace.clear_watchdog()
        assert furnace.watchdog_status() == 0
        furnace.heater(True)  # usable again
        assert rig.model.furnace.commanded_on


def test_unplugged_furnace_is_reported_and_heater_off_does_not_raise(rig):
    furnace = rig.config().furnace.create()
    furnace.open()
    rig.inject("furnace", "unplug")
    with pytest.raises(DeviceError, match=r"^furnace: "):
        furnace.temperature_C()
    assert furnace.heater_off() is False
    furnace.close()


def test_two_threads_share_one_port_without_mixing_replies(rig):
    """The acquisition reads the temperature in one thread while the controller switches the
    heater in another: the port lock keeps every command with its own reply."""
    import threading

    errors, readings, switches = [], [], []
    with rig.config().furnace.create() as furnace:

        def read_loop():
            try:
                for _ in range(150):
                    readings.append(furnace.temperature_C())
            except Exception as exc:  # noqa: BLE001 - reported below
                errors.append(exc)

        def switch_loop():
            try:
                for i in range(150):
                    furnace.heater(i % 2 == 0)
                    switches.append(furnace.digital_io()["outputs"] & 1)
            except Exception as exc:  # noqa: BLE001
                errors.append(exc)

        threads = [threading.Thread(target=read_loop), threading.Thread(target=switch_loop)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(timeout=30)
    assert not errors, errors
    assert len(readings) == 150 and all(15.0 < r < 40.0 for r in readings)
    assert switches == [1 - i % 2 for i in range(150)]  # each @AADI saw the output just set
    assert not rig.model.furnace.commanded_on  # closing switched it off


def test_stream_survives_garbled_frames(rig):
    rig.inject("loadcell", "garble", fraction=0.05)
    with rig.config().loadcell.create() as cell:
        cell.configure(rate_code=0, filter=0, fmt=3)
        cell.start_stream()
        got, deadline = [], rig.clock.now() + 10.0
        while len(got) < 100 and rig.clock.now() < deadline:
            got += cell.read_stream(100 - len(got), timeout=0.5)
        cell.stop_stream()
    assert len(got) == 100
    # some frames were garbled: each cost that frame, the stream realigned on the next (issue 42) ...
    assert cell.frames_garbled >= 1 and cell.stream_resyncs == 0
    assert cell.frames_lost >= cell.frames_garbled - 1  # (one garbled in the read-ahead past the last frame taken)
    assert all(abs(s.force_N) < 100.0 for s in got)  # ... and none was decoded shifted


@pytest.mark.parametrize("data_format", [0, 1, 2])  # engineering, % of range, hex
def test_furnace_reading_in_each_data_format(rig, data_format):
    rig.devices["furnace"].data_format = data_format
    with rig.config().furnace.create() as furnace:
        reading = furnace.temperature_C()
        assert furnace.data_format == data_format  # learnt from $AA2
    assert reading == pytest.approx(rig.model.furnace.temperature_C, abs=1.0)  # noise + 1370/32767
