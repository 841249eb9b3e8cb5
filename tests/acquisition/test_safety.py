"""Heater safety: off on every exit path; temperature rule."""

import os
import signal
import subprocess
import sys
import textwrap

import pytest

from flowcurve.acquisition.safety import HeaterSafety, Interrupted, check_temperature
from flowcurve.errors import SafetyError


class FakeHeater:
    def __init__(self, fail_times=0):
        self.on = True
        self.fail_times = fail_times
        self.off_calls = 0
        self.watchdog_armed = False

    def off(self):
        self.off_calls += 1
        if self.fail_times > 0:
            self.fail_times -= 1
            raise OSError("no reply")
        self.on = False

    def arm(self):
        self.watchdog_armed = True


def test_normal_exit_switches_off_and_arms_watchdog():
    h = FakeHeater()
    events = []
    with HeaterSafety(h.off, arm_watchdog=h.arm, log=lambda n, t: events.append((n, t))):
        assert h.watchdog_armed and h.on
    assert not h.on
    assert events == [("heater_off", "end of test")]


def test_exception_switches_off_and_propagates():
    h = FakeHeater()
    with pytest.raises(RuntimeError):
        with HeaterSafety(h.off):
            raise RuntimeError("boom")
    assert not h.on


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_signals_raise_in_main_thread_and_switch_off(sig):
    h = FakeHeater()
    before = signal.getsignal(sig)
    with pytest.raises(Interrupted) as info:
        with HeaterSafety(h.off):
            os.kill(os.getpid(), sig)
            signal.sigtimedwait([], 0.5) if hasattr(signal, "sigtimedwait") else None
            for _ in range(1000):  # the handler runs between bytecodes
                pass
    assert info.value.signame == signal.Signals(sig).name
    assert not h.on
    assert signal.getsignal(sig) == before  # handlers restored


def test_heater_off_is_retried():
    h = FakeHeater(fail_times=2)
    with HeaterSafety(h.off, retries=3) as s:
        pass
    assert not h.on and h.off_calls == 3 and s.off_confirmed


def test_heater_off_failing_everywhere_is_reported_not_raised():
    h = FakeHeater(fail_times=10)
    events = []
    with HeaterSafety(h.off, retries=2, log=lambda n, t: events.append(n)) as s:
        pass
    assert h.on and not s.off_confirmed and "no reply" in s.off_error
    assert events == ["fault"]


def test_atexit_switches_off_when_the_block_is_never_left(tmp_path):
    flag = tmp_path / "heater"
    code = textwrap.dedent(f"""
        from pathlib import Path
        from flowcurve.acquisition.safety import HeaterSafety
        flag = Path({str(flag)!r})
        flag.write_text("on")
        HeaterSafety(lambda: flag.write_text("off")).__enter__()
        # interpreter exits without leaving the context
    """)
    subprocess.run([sys.executable, "-c", code], check=True, timeout=30)
    assert flag.read_text() == "off"


def test_check_temperature():
    assert check_temperature(600.0, 900.0) == 600.0
    with pytest.raises(SafetyError, match="over-temperature"):
        check_temperature(905.0, 900.0)
    for bad in (9999.0, float("nan"), None):
        with pytest.raises(SafetyError, match="thermocouple open"):
            check_temperature(bad, 900.0)
