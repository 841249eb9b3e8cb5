"""A small in-process fake rig for procedure tests (the real drivers are tested end to end
in test_end_to_end.py); its force law is known, so the record can be checked against it.
It runs on a model clock unless given the wall clock."""

import threading

import numpy as np
import pytest

from flowcurve.acquisition.sampler import Channel
from flowcurve.clock import ModelClock


class FakeRig:
    """Crosshead x = v·t once started; force = k·x up to x_frac, then 0 (a brittle specimen).

    The furnace heats at ``heat_rate_C_per_s`` while the heater is on and cools otherwise.
    ``die_after_s`` makes the encoder raise from then on (an unplugged box).
    """

    has_furnace = True
    can_drive = True
    frame_stiffness_N_per_um = 136.0
    loadcell_period_s = 0.002

    def __init__(self, *, time_scale=20.0, k_N_per_mm=20000.0, x_frac_mm=1.0, max_temperature_C=900.0,
                 heat_rate_C_per_s=20.0, die_after_s=None, overheat_at_s=None, post=None, timebase=None):
        self.timebase = ModelClock() if timebase is None else timebase
        self.time_scale = time_scale
        self.k = k_N_per_mm
        self.x_frac = x_frac_mm
        self.max_temperature_C = max_temperature_C
        self.heat_rate = heat_rate_C_per_s
        self.die_after_s = die_after_s
        self.overheat_at_s = overheat_at_s
        self.post = post
        self.heater = False
        self.heater_log = []
        self.watchdog_armed = False
        self.tared = False
        self._t_move = None
        self._speed = 0.0
        self._dir = 1
        self._temp = 20.0
        self._t_temp = None
        self.sent_forces = []
        self._lock = threading.Lock()
        self.clock = None

    # physics on the procedure's clock
    def x(self, t):
        return 0.0 if self._t_move is None else self._dir * self._speed * max(t - self._t_move, 0.0)

    def f(self, t):
        x = abs(self.x(t))
        return self._dir * (self.k * x if x < self.x_frac else 0.0)

    def set_clock(self, clock):
        self.clock = clock

    def channels(self, clock, to_clock):

        def force():
            self.timebase.sleep(self.loadcell_period_s / self.time_scale)
            t = clock()
            v = self.f(t)
            self.sent_forces.append(v)
            return [(t, v)]

        def encoder():
            t = clock()
            if self.die_after_s is not None and t > self.die_after_s:
                raise OSError("port /dev/ttyUSB1 disappeared")
            return self.x(t)

        tb = self.timebase
        return {
            "force_N": Channel("loadcell", force, clock, silence_s=2.0, timebase=tb),
            "crosshead_mm": Channel("encoder", encoder, clock, period_s=0.01, timebase=tb),
            "temperature_C": Channel("furnace", self.read_temperature_C, clock, period_s=0.05, timebase=tb),
        }

    def read_temperature_C(self):
        with self._lock:
            t = self.timebase.now() * self.time_scale
            if self._t_temp is not None:
                dt = t - self._t_temp
                self._temp += (self.heat_rate if self.heater else -0.1 * self.heat_rate) * dt
                self._temp = max(self._temp, 20.0)
            self._t_temp = t
            if self.overheat_at_s is not None and self.clock and self.clock() > self.overheat_at_s:
                return self.max_temperature_C + 50.0
            return self._temp

    def hold_temperature(self, setpoint_C):
        temperature_C = self.read_temperature_C()
        self.set_heater(temperature_C < setpoint_C)
        return temperature_C

    def set_heater(self, on):
        if on != self.heater:
            self.heater_log.append(on)
        self.heater = on

    def heater_off(self):
        self.set_heater(False)

    def arm_watchdog(self):
        self.watchdog_armed = True

    def host_ok(self):
        pass

    def tare(self):
        self.tared = True

    def start_crosshead(self, speed, direction):
        self._speed, self._dir = speed, direction
        self._t_move = self.clock()

    def stop_crosshead(self):
        t = self.clock()
        if self._t_move is not None:
            frozen = self.x(t)
            self.x = lambda t, frozen=frozen: frozen

    def post_test_measurements(self):
        return self.post


@pytest.fixture
def fake_rig():
    return FakeRig


def run_logged(tmp_path, monkeypatch, argv, *, initial_temperature_C=None, config_overrides=None):
    """``flowcurve run *argv --out tmp_path/r.csv`` on the in-process virtual rig on model time; (exit code, what the
    operator saw, the record, the virtual rig, readings) with readings the furnace driver's every ``temperature_C`` as
    (model s, °C, heater commanded on) — a crossing is the model's, not the check's."""
    import contextlib
    import io

    import flowcurve.acquisition.session as session
    from flowcurve.cli import main
    from flowcurve.record.format import read_record
    from flowcurve.rig.furnace import Furnace

    rigs, readings = [], []
    real_run, real_read = session.run_virtual_test, Furnace.temperature_C

    def on_model_time(*args, **kwargs):
        return real_run(*args, clock=ModelClock(), link="inprocess", rig_setup=rigs.append,
                        initial_temperature_C=initial_temperature_C, config_overrides=config_overrides, **kwargs)

    def logged(furnace):
        value = real_read(furnace)
        readings.append((rigs[0].now(), value, furnace.heater_is_on))
        return value

    monkeypatch.setattr(session, "run_virtual_test", on_model_time)
    monkeypatch.setattr(Furnace, "temperature_C", logged)
    out, err = io.StringIO(), io.StringIO()
    record = tmp_path / "r.csv"
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["run", *map(str, argv), "--out", str(record)])
    return code, out.getvalue() + err.getvalue(), read_record(record), rigs[0], readings
