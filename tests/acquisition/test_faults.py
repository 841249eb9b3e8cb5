"""Faults on the virtual rig, through the real drivers: each stops the test with a message
naming the device, the record on disk stays readable with every sample written before the
fault, and the heater ends off (read from the virtual DCON module's digital outputs).

The device faults run in-process on model time (on ptys in real time with ``-m pty``); the
acquisition process interrupted
(SIGINT, SIGTERM, kill -9) runs for real: ``flowcurve run`` in a process of its own against
the virtual devices on ptys, in real time.
"""

import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from flowcurve.acquisition.procedure import TestSpec
from flowcurve.acquisition.stopping import StopCriteria
from flowcurve.record.format import read_record
from flowcurve.acquisition.session import run_virtual_test
from flowcurve.clock import WALL
from flowcurve.errors import DeviceError, SafetyError

MATERIAL = "steel45"


def samples_on_disk(path):
    """(number of sample rows, last time_s) as the file is on disk now; (0, nan) if none."""
    try:
        text = open(path, encoding="utf-8").read()
    except FileNotFoundError:
        return 0, float("nan")
    rows = [l for l in text.split("\n") if l and not l.startswith("#")][1:]  # skip the column row
    rows = [r for r in rows if r.count(",") >= 2]
    if len(rows) < 2:
        return 0, float("nan")
    return len(rows) - 1, float(rows[-2].split(",")[0])  # the last complete line


def wait_for(predicate, timeout_s=20.0, step_s=0.02, clock=WALL):
    """Poll ``predicate`` every ``step_s`` on ``clock`` (host seconds) until it is true."""
    deadline = clock.now() + timeout_s
    while clock.now() < deadline:
        value = predicate()
        if value:
            return value
        clock.sleep(step_s)
    raise AssertionError("timed out waiting")


def wait_for_samples(path, n, timeout_s=20.0, clock=WALL):
    """Wait until ``n`` samples are on disk; the time_s of the last one."""
    def enough():
        count, last = samples_on_disk(path)
        return last if count >= n else None
    return wait_for(enough, timeout_s, clock=clock)


def heated_spec(test="tension", speed=0.02):
    geo = {"d0_mm": 6.0, "l0_mm": 30.0} if test == "tension" else {"d0_mm": 5.989, "h0_mm": 6.982}
    return TestSpec(test, material=MATERIAL, geometry_mm=geo, speed_mm_per_s=speed, temperature_C=60.0, soak_s=5.0, soak_band_C=3.0)


def run_with_fault(tmp_path, link, device, fault, *, spec=None, after_samples=40, time_scale=100.0, overrides=None, **fault_kw):
    """Run a heated virtual test on ``link`` (the ``device_link`` fixture) and inject ``fault``
    once ``after_samples`` are on disk (``fault`` may be a function of the virtual rig instead
    of a fault name)."""
    path = tmp_path / "rec.csv"
    seen = {}
    clock = link["clock"]

    def setup(vr):
        seen["vr"] = vr

        def inject():
            seen["t_on_disk"] = wait_for_samples(path, after_samples, clock=clock)
            if callable(fault):
                fault(vr)
            else:
                vr.inject(device, fault, **fault_kw)

        injector = threading.Thread(target=inject, daemon=True)
        clock.enlist(threading.current_thread())  # time waits for the test to run ...
        clock.enlist(injector)  # ... and for the polls: neither runs ahead of the other
        injector.start()

    run = run_virtual_test(spec or heated_spec(), path, material=MATERIAL, time_scale=time_scale, rig_setup=setup,
                           config_overrides=overrides, **link)
    return run, seen


def check_kept_and_heater_off(run, seen):
    rec = read_record(run.outcome.path)
    assert rec.meta["status"] == "aborted"
    assert rec.column("time_s")[-1] >= seen["t_on_disk"]  # nothing on disk before the fault is lost
    names = [e.name for e in rec.events]
    texts = " ".join(e.text for e in rec.events)
    # heater-off acknowledged, or (silent module) reported as handed to the module watchdog
    assert "fault" in names and ("heater_off" in names or "module watchdog will switch it off" in texts)
    assert names.index("heater_on") < names.index("soak_reached") < names.index("fault")
    vr = seen["vr"]
    assert vr.devices["furnace"].do == 0  # the module's heater output is off
    return rec


@pytest.mark.parametrize("device,fault,named", [
    ("loadcell", "silence", "load cell"),
    ("encoder", "unplug", "crosshead encoder"),
    ("loadcell", "garble", "load cell"),
    ("furnace", "silence", "furnace"),
])
def test_device_faults_stop_the_test_naming_the_device(tmp_path, device_link, device, fault, named):
    # short DCON time-outs keep the silent-furnace case quick (heater-off is retried on it)
    run, seen = run_with_fault(tmp_path, device_link, device, fault, overrides={"furnace_timeout_s": 0.1})
    out = run.outcome
    assert out.status == "aborted" and isinstance(out.error, DeviceError)
    assert named in str(out.error), str(out.error)
    rec = check_kept_and_heater_off(run, seen)
    assert named in rec.meta["abort_reason"]


def test_open_thermocouple_stops_heating(tmp_path, device_link):
    run, seen = run_with_fault(tmp_path, device_link, "furnace", "open_thermocouple")
    out = run.outcome
    assert isinstance(out.error, SafetyError) and "thermocouple" in str(out.error)
    check_kept_and_heater_off(run, seen)
    assert not seen["vr"].model.furnace.relay_on


def test_over_temperature_stops_heating(tmp_path, device_link):
    def overheat(vr):  # the furnace runs away (e.g. a second heat source): 90 C > max 75 C
        with vr.lock:
            vr.sync().furnace.temperature_C = 90.0

    run, seen = run_with_fault(tmp_path, device_link, "furnace", overheat, overrides={"furnace_max_temperature_C": 75.0})
    out = run.outcome
    assert isinstance(out.error, SafetyError) and "over-temperature" in str(out.error)
    check_kept_and_heater_off(run, seen)


def test_stuck_heater_relay_stops_the_test(tmp_path, device_link):
    # a relay stuck on heats whatever the output says: the host must stop and report it,
    # either as the controller's stuck-relay diagnosis or as over-temperature, whichever first
    run, seen = run_with_fault(tmp_path, device_link, "furnace", "relay_stuck", overrides={"furnace_max_temperature_C": 75.0})
    out = run.outcome
    assert isinstance(out.error, SafetyError)
    assert "over-temperature" in str(out.error) or "relay stuck" in str(out.error)
    rec = check_kept_and_heater_off(run, seen)
    assert np.nanmax(rec.column("temperature_C")) <= 75.0 + 15.0  # stopped soon after crossing


# -- the acquisition process itself interrupted: a subprocess against a virtual rig here ----------


def start_run_process(tmp_path, vr, *, watchdog_s=1.0, speed=0.02, time_scale=100.0):
    from flowcurve.rig.config import to_toml, virtual_config

    cfg = tmp_path / "rig.toml"
    cfg.write_text(to_toml(virtual_config(**vr.config_kwargs(), furnace_watchdog_timeout_s=watchdog_s)))
    rec = tmp_path / "rec.csv"
    cmd = [sys.executable, "-m", "flowcurve", "run", "tension", "--config", str(cfg), "--quiet",
           "--time-scale", str(time_scale), "--out", str(rec), "--material", MATERIAL, "--d0", "6",
           "--l0", "30", "--speed", str(speed), "--temperature", "60", "--soak", "5"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True)
    try:
        # the operator starts the machine once the procedure has tared
        wait_for(lambda: rec.exists() and "tare" in rec.read_text(), 30)
        vr.start_crosshead()
        t_on_disk = wait_for_samples(rec, 50)
    except BaseException:
        proc.kill()
        proc.wait(10)
        raise
    return proc, rec, t_on_disk


@pytest.fixture
def virtual_rig():
    from flowcurve.rig.virtual.rig import VirtualRig

    with VirtualRig(MATERIAL, test="tension", speed_mm_per_s=0.02, time_scale=100.0, temperature_C=57.0) as vr:
        yield vr


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_signal_ends_the_test_cleanly(tmp_path, virtual_rig, sig):
    proc, rec_path, t_on_disk = start_run_process(tmp_path, virtual_rig)
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=20)
    rec = read_record(rec_path)
    assert rec.column("time_s")[-1] >= t_on_disk
    assert "heater_off" in [e.name for e in rec.events]
    assert virtual_rig.devices["furnace"].do == 0
    assert "Traceback" not in stderr
    if sig == signal.SIGINT:  # Ctrl-C is the operator's stop: a good record
        assert proc.returncode == 0 and rec.meta["status"] == "complete"
        assert "operator stop" in rec.meta["stop_reason"]
    else:
        assert proc.returncode != 0 and rec.meta["status"] == "aborted"
        assert "SIGTERM" in rec.meta["abort_reason"]


def test_kill_9_leaves_a_readable_record_and_the_watchdog_switches_the_heater_off(tmp_path, virtual_rig):
    proc, rec_path, t_on_disk = start_run_process(tmp_path, virtual_rig, watchdog_s=1.0)
    furnace = virtual_rig.devices["furnace"]
    assert furnace.watchdog_enabled
    proc.kill()  # SIGKILL: no handler, no finally, no atexit
    proc.wait(10)
    rec = read_record(rec_path)
    assert rec.truncated and rec.meta["status"] == "recording"
    assert rec.column("time_s")[-1] >= t_on_disk
    # the module switches the heater off by itself once the host is silent for its time-out
    wait_for(lambda: furnace.watchdog_status == 0x04, 10)
    assert furnace.do == 0 and not virtual_rig.model.furnace.relay_on
    # and the record can be completed
    from flowcurve.cli import main

    assert main(["recover", str(rec_path)]) == 0
    again = read_record(rec_path)
    assert again.meta["status"] == "aborted" and not again.truncated
    assert len(again.data) == len(rec.data)


@pytest.mark.parametrize("at_s", [0.0, 3.0])
def test_a_relay_that_sticks_in_a_short_unheated_test_is_caught(tmp_path, device_link, at_s):
    """Issue 31 (c): a room-temperature compression of a few seconds; the relay welds shut at
    the start (caught while loading: the heater was never on, so any warming is the relay) or
    just before the end (caught by the watch after the test). Named, heater-off tried, record kept."""
    from flowcurve.rig.virtual.fault_spec import FaultSpec

    spec = TestSpec("compression", material=MATERIAL, geometry_mm={"d0_mm": 5.989, "h0_mm": 6.982}, speed_mm_per_s=0.5,
                    stop=StopCriteria(target_displacement_mm=2.0))
    run = run_virtual_test(spec, tmp_path / "r.csv", material=MATERIAL, time_scale=20.0, compression_response="slab",
                           faults=(FaultSpec("furnace", "relay_stuck", None, at_s),), **device_link)
    out = run.outcome
    assert isinstance(out.error, SafetyError) and "furnace" in str(out.error) and "relay stuck" in str(out.error)
    rec = read_record(out.path)
    assert len(rec.data) > 10 and rec.meta["status"] in ("complete", "aborted")
    texts = [f"{e.name} {e.text}" for e in rec.events]
    assert any(t.startswith("fault furnace: heater does not switch off") for t in texts)
    assert any(t.startswith("heater_off") for t in texts)  # heater-off was tried


def test_three_frames_lost_from_the_load_cells_stream_are_named(tmp_path, device_link):
    """Issue 31 (d): a loss too small for the data-loss limit (3 frames of hundreds) is still
    named in the record's events and in identify's warnings, and the operator hears of it."""
    from flowcurve.identification.identify import fault_warnings

    spec = TestSpec("compression", material=MATERIAL, geometry_mm={"d0_mm": 5.989, "h0_mm": 6.982}, speed_mm_per_s=0.5,
                    stop=StopCriteria(target_displacement_mm=2.0))
    lost = []

    def drop_three_frames(vr):
        aed = vr.devices["loadcell"]
        apply, seen = aed.faults.apply, []

        def dropping(reply):
            if len(reply) == aed_frame_length(aed):
                seen.append(reply)
                if 40 <= len(seen) < 43:  # mid-test (the record has about 100 rows)
                    lost.append(reply)
                    return None
            return apply(reply)

        aed.faults.apply = dropping

    run = run_virtual_test(spec, tmp_path / "r.csv", material=MATERIAL, time_scale=5.0, compression_response="slab",
                           rig_setup=drop_three_frames, **device_link)
    assert len(lost) == 3 and run.outcome.status == "complete"
    rec = read_record(run.outcome.path)
    named = [e.text for e in rec.events if e.name == "frames_missing"]
    assert named and all(t.startswith("load cell: ") for t in named)
    assert 1 <= sum(int(t.split()[2]) for t in named) <= 6  # an estimate from the stream's timing (3 when the clock is exact)
    warnings, _doubtful = fault_warnings(rec)
    assert any("frames_missing" in w and "load cell" in w for w in warnings)


def aed_frame_length(aed) -> int:
    """The length of one stream frame in the virtual amplifier's present output format."""
    from flowcurve.rig.codecs.aed import output_format

    return output_format(int(aed.s["cof"])).frame_length
