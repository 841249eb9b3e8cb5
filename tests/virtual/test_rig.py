"""VirtualRig life cycle, model clock, amplifier filter and settings memory, bad input."""

import math
import os
import threading
import time

import pytest
import serial

from flowcurve.errors import ConfigError, FlowcurveError
from flowcurve.rig.virtual.materials import get_material
from flowcurve.rig.virtual.aed import AEDAmplifier
from flowcurve.rig.virtual.rig import VirtualRig


def test_no_leaked_descriptors_or_threads():
    fds = len(os.listdir("/proc/self/fd"))
    threads = threading.active_count()
    for _ in range(3):
        with VirtualRig() as rig:
            with serial.Serial(rig.ports["encoder"], timeout=0.1) as p:
                p.write(b"#020\r")
                assert p.read_until(b"\r").startswith(b">")
            rig.inject("loadcell", "unplug")
    assert threading.active_count() == threads
    assert len(os.listdir("/proc/self/fd")) == fds


def test_model_time_is_wall_time_times_scale():
    with VirtualRig("steel45", time_scale=40.0, speed_mm_per_s=0.01) as rig:
        t0 = time.monotonic()
        m0 = rig.sync().time_s
        rig.start_crosshead()
        time.sleep(0.25)
        m = rig.sync()
        elapsed = time.monotonic() - t0
        assert m.time_s - m0 == pytest.approx(elapsed * 40.0, rel=0.2)
        assert m.crosshead_mm == pytest.approx(0.01 * (m.time_s - m0), rel=0.2)
        meta = rig.metadata()
        assert meta["specimen.l0_mm"] == "30" and meta["crosshead_speed_mm_per_s"] == "0.01"


def test_asf_filter_is_first_order_at_its_cutoff_in_model_time():
    clock = {"t": 0.0, "F": 0.0}
    dev = AEDAmplifier(lambda: (clock["t"], clock["F"], True), settings={"asf": 3, "cof": 3})
    dev.measured_frame()  # settle at 0
    clock["F"], fc = 10_000.0, 1.5  # ASF3: -3 dB at 1.5 Hz with FMD0
    tau = 1.0 / (2 * math.pi * fc)
    clock["t"] += tau
    value = int(dev.measured_frame()) / 1e6 * 100e3
    assert value == pytest.approx(10_000.0 * (1 - math.exp(-1)), abs=0.2)
    dev.close()


def test_settings_saved_by_tdd1_come_back_after_res_and_cof128_streams_from_power_on():
    dev = AEDAmplifier(lambda: (0.0, 1000.0, True), settings={"asf": 0}).start()
    with serial.Serial(dev.port, timeout=0.3) as p:
        for cmd in (b";ICR3;", b";TDD1;", b";ICR5;"):
            p.write(cmd)
            assert p.read_until(b"\r\n") == b"0\r\n"
        p.write(b";RES;")
        time.sleep(0.05)
        p.write(b";ICR?;")
        assert p.read_until(b"\r\n") == b"3\r\n"
    dev.close()
    dev = AEDAmplifier(lambda: (0.0, 1000.0, True), settings={"asf": 0, "cof": 128 + 3, "icr": 0}).start()
    with serial.Serial(dev.port, timeout=0.5) as p:
        data = p.read(50)
        assert data[:10] == b"+0010000\r\n" and len(data) == 50
        p.write(b";STP;")
    dev.close()


def test_bad_input_is_a_one_line_flowcurve_error():
    with pytest.raises(ConfigError, match="unknown virtual material 'unobtainium'"):
        get_material("unobtainium")
    with pytest.raises(FlowcurveError, match="time_scale"):
        VirtualRig(time_scale=0)
    with VirtualRig() as rig:
        with pytest.raises(ConfigError, match="unknown fault 'melt'"):
            rig.inject("furnace", "melt")
        with pytest.raises(ConfigError, match="unknown virtual device"):
            rig.inject("motor", "silence")
        with pytest.raises(ConfigError, match="fraction"):
            rig.inject("encoder", "drop", fraction=2)
