"""VirtualRig life cycle (ptys and in-process), model clock, amplifier filter and settings
memory, bad input. The pty descriptors opened and closed are part of the real-port path of
the default selection (with EIO on unplug in test_faults.py)."""

import math
import os
import threading

import pytest
import serial

from flowcurve.clock import ModelClock
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


def test_in_process_rig_opens_no_descriptor_and_no_thread_and_unregisters_its_ports():
    fds = len(os.listdir("/proc/self/fd"))
    threads = threading.active_count()
    with VirtualRig(clock=ModelClock(), link="inprocess") as rig:
        url = rig.ports["encoder"]
        assert url.startswith("virtual://")
        with serial.serial_for_url(url, timeout=0.1) as p:
            p.write(b"#020\r")
            assert p.read_until(b"\r").startswith(b">")
        assert threading.active_count() == threads
        assert len(os.listdir("/proc/self/fd")) == fds
    with pytest.raises(serial.SerialException, match="no such virtual device"):
        serial.serial_for_url(url)


def test_a_pty_runs_on_the_wall_clock_only():
    with pytest.raises(ConfigError, match="real time"):
        VirtualRig(clock=ModelClock())


def test_model_time_is_host_time_times_scale(model_time_rig):
    rig = model_time_rig("steel45", time_scale=40.0, speed_mm_per_s=0.01)
    t0 = rig.clock.now()
    m0 = rig.sync().time_s
    rig.start_crosshead()
    rig.clock.advance(0.25)
    m = rig.sync()
    assert m.time_s - m0 == pytest.approx(0.25 * 40.0, rel=1e-12)
    assert m.crosshead_mm == pytest.approx(0.01 * (m.time_s - m0), rel=1e-9)
    assert rig.clock.now() - t0 == pytest.approx(0.25)
    meta = rig.metadata()
    assert meta["specimen.l0_mm"] == "30" and meta["crosshead_speed_mm_per_s"] == "0.01"
    assert meta["specimen.parallel_length_mm"] == "30"  # its own bar: Lc = l0, stated (identification's default otherwise)


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


def test_settings_saved_by_tdd1_come_back_after_res_and_cof128_streams_from_power_on(model_clock):
    dev = AEDAmplifier(lambda: (0.0, 1000.0, True), settings={"asf": 0}, clock=model_clock, link="inprocess").start()
    with serial.serial_for_url(dev.port, timeout=0.3) as p:
        for cmd in (b";ICR3;", b";TDD1;", b";ICR5;"):
            p.write(cmd)
            assert p.read_until(b"\r\n") == b"0\r\n"
        p.write(b";RES;")
        model_clock.sleep(0.05)
        p.write(b";ICR?;")
        assert p.read_until(b"\r\n") == b"3\r\n"
    dev.close()
    dev = AEDAmplifier(lambda: (0.0, 1000.0, True), settings={"asf": 0, "cof": 128 + 3, "icr": 0},
                       clock=model_clock, link="inprocess").start()
    with serial.serial_for_url(dev.port, timeout=0.5) as p:
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
