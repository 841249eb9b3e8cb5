"""The test procedure on a fake rig (on model time): phases, stop criteria, record contents,
heater state; the 'q' typed on a real terminal in real time."""

import numpy as np
import pytest

from flowcurve.acquisition.procedure import Procedure, ProcedureError, TestSpec, heating_progress
from flowcurve.acquisition.stopping import StopCriteria, StopState, stop_reason
from flowcurve.record.format import read_record
from flowcurve.errors import DeviceError, SafetyError


def rows_from(force, x=None):
    force = np.asarray(force, dtype=float)
    x = np.zeros_like(force) if x is None else np.asarray(x, dtype=float)
    return np.column_stack([np.arange(force.size), force, x])


def test_stop_reason_fracture_needs_a_drop_after_a_real_maximum():
    crit = StopCriteria(fracture_drop_fraction=0.2, fracture_min_force_N=500)
    st = StopState()
    assert stop_reason(rows_from([0, 10, 100, 50, 5]), st, crit) is None  # toe: max < 500 N
    assert stop_reason(rows_from([1000, 5000, 9000]), st, crit) is None
    assert stop_reason(rows_from([8000, 1900]), st, crit) is None  # 1900 > 0.2 * 9000: not yet
    st = StopState()
    assert stop_reason(rows_from([1000, 9000, 6000]), st, crit) is None
    assert "fracture" in stop_reason(rows_from([1700]), st, crit)  # 1700 < 0.2 * 9000


def test_stop_reason_limits_and_compression_signs():
    st = StopState()
    assert "force limit" in stop_reason(rows_from([-100, -60000]), st, StopCriteria(force_limit_N=50000))
    assert "target displacement" in stop_reason(rows_from([-100, -200], [-1.0, -3.0]), StopState(), StopCriteria(target_displacement_mm=3.0))


def test_heating_progress():
    assert heating_progress(20, 310, 600) == pytest.approx(0.5)
    assert heating_progress(20, 700, 600) == 1.0


def spec(test="tension", **kw):
    geo = {"d0_mm": 6.0, "l0_mm": 30.0} if test == "tension" else {"d0_mm": 10.0, "h0_mm": 15.0}
    return TestSpec(test=test, material="fake", geometry_mm=geo, speed_mm_per_s=0.05, **kw)


def test_tension_to_fracture_records_the_known_law(tmp_path, fake_rig):
    rig = fake_rig(x_frac_mm=1.0, post={"post.lu_mm": 31.0, "post.dk_mm": 4.0})
    out = Procedure(rig, spec(post={"post.du_mm": 5.5}), tmp_path / "t.csv").run()
    assert out.status == "complete" and "fracture" in out.reason
    rec = read_record(out.path)
    assert not rec.truncated and rec.meta["status"] == "complete"
    assert rec.meta["post.lu_mm"] == "31.0" and rec.meta["post.du_mm"] == "5.5"
    assert rec.meta["stop_reason"].startswith("fracture")
    x, f = rec.column("crosshead_mm"), rec.column("force_N")
    before = x < 0.98  # rows before fracture follow F = k x (x interpolated on the force clock)
    np.testing.assert_allclose(f[before], rig.k * x[before], atol=0.01 * rig.k)
    assert f.max() > 0.95 * rig.k * rig.x_frac
    # each force the fake load cell sent is in the record once, in order
    assert len(rec.data) == len(rig.sent_forces)
    np.testing.assert_allclose(f, rig.sent_forces, atol=1e-6)
    names = [e.name for e in rec.events]
    assert names[:2] == ["tare", "start"] and "stop" in names and "heater_off" in names
    assert rig.tared and rig.watchdog_armed and not rig.heater


def test_heating_soak_then_compression_to_target(tmp_path, fake_rig):
    rig = fake_rig(x_frac_mm=1e9, heat_rate_C_per_s=4.0)
    s = spec("compression", temperature_C=120.0, soak_s=5.0, soak_band_C=8.0)
    s.stop = StopCriteria(target_displacement_mm=0.5)
    out = Procedure(rig, s, tmp_path / "c.csv").run()
    rec = read_record(out.path)
    assert "target displacement" in out.reason
    names = [e.name for e in rec.events]
    assert names.index("heater_on") < names.index("soak_reached") < names.index("start")
    assert rec.meta["nominal_temperature_C"] == "120.0"
    assert abs(np.median(rec.column("temperature_C")) - 120.0) < 15
    # stopped at the target; the overshoot is what the crosshead runs in one loop tick or two
    assert -0.5 - 3 * 0.05 * 0.05 * rig.time_scale <= rec.column("crosshead_mm").min() <= -0.5
    assert True in rig.heater_log and not rig.heater


def test_unplugged_encoder_stops_the_test_and_keeps_the_record(tmp_path, fake_rig):
    rig = fake_rig(x_frac_mm=1e9, die_after_s=4.0)
    out = Procedure(rig, spec(), tmp_path / "u.csv").run()
    assert out.status == "aborted" and isinstance(out.error, DeviceError)
    assert out.reason.startswith("encoder") or "disappeared" in out.reason
    rec = read_record(out.path)
    assert rec.meta["status"] == "aborted" and "disappeared" in rec.meta["abort_reason"]
    assert rec.column("time_s").max() > 3.0  # the samples before the fault are kept
    assert "fault" in [e.name for e in rec.events]
    assert not rig.heater


def test_over_temperature_while_recording_stops_heating(tmp_path, fake_rig):
    rig = fake_rig(x_frac_mm=1e9, max_temperature_C=200.0, heat_rate_C_per_s=8.0, overheat_at_s=None)
    s = spec(temperature_C=150.0, soak_s=2.0, soak_band_C=10.0)
    proc = Procedure(rig, s, tmp_path / "o.csv")
    rig.overheat_at_s = 1e9
    orig_tare = rig.tare

    def tare_then_arm_overheat():
        orig_tare()
        rig.overheat_at_s = rig.clock() + 3.0

    rig.tare = tare_then_arm_overheat
    rig.clock = proc.clock
    out = proc.run()
    assert out.status == "aborted" and isinstance(out.error, SafetyError)
    assert "over-temperature" in out.reason
    assert not rig.heater
    rec = read_record(out.path)
    assert "over-temperature" in rec.meta["abort_reason"]


def test_bad_spec_is_refused_in_one_line(tmp_path, fake_rig):
    with pytest.raises(ProcedureError, match="l0_mm"):
        Procedure(fake_rig(), TestSpec("tension", geometry_mm={"d0_mm": 6.0}), tmp_path / "x.csv")
    with pytest.raises(ProcedureError, match="is not below the configured maximum"):
        Procedure(fake_rig(max_temperature_C=500.0), spec(temperature_C=600.0), tmp_path / "x.csv")


def test_a_parallel_length_is_optional_at_least_l0_and_tension_only(tmp_path, fake_rig):
    with pytest.raises(ProcedureError, match="parallel length 29 mm must be at least l0 30 mm"):
        Procedure(fake_rig(), TestSpec("tension", geometry_mm={"d0_mm": 6.0, "l0_mm": 30.0, "parallel_length_mm": 29.0}), tmp_path / "x.csv")
    with pytest.raises(ProcedureError, match="parallel_length_mm: not a compression specimen's"):
        Procedure(fake_rig(), TestSpec("compression", geometry_mm={"d0_mm": 10.0, "h0_mm": 15.0, "parallel_length_mm": 20.0}), tmp_path / "x.csv")


@pytest.mark.parametrize("lc", [None, 42.0])
def test_a_rigs_record_states_the_parallel_length_only_when_given(tmp_path, fake_rig, lc):
    """The real rig does not know its specimen: Lc is the operator's (--lc), never a guess."""
    test = spec()
    if lc is not None:
        test.geometry_mm["parallel_length_mm"] = lc
    rec = read_record(Procedure(fake_rig(), test, tmp_path / "t.csv").run().path)
    assert rec.meta.get("specimen.parallel_length_mm") == (None if lc is None else "42.0")


def test_set_point_at_the_maximum_is_refused(tmp_path, fake_rig):
    with pytest.raises(ProcedureError, match="not below the configured maximum 500"):
        Procedure(fake_rig(max_temperature_C=500.0), spec(temperature_C=500.0), tmp_path / "x.csv")


def test_post_test_measurements_are_prompted_when_interactive(tmp_path, fake_rig):
    answers = iter(["36.5", "", "not-a-number", "5.1"])
    asked = []

    def prompt(text):
        asked.append(text)
        return next(answers)

    rig = fake_rig(x_frac_mm=0.5, post=None)  # a real rig: nothing measured for us
    out = Procedure(rig, spec(), tmp_path / "p.csv", interactive=True, prompt=prompt).run()
    assert len(asked) == 4 and "lu" in asked[0] and "neck" in asked[3]
    rec = read_record(out.path)
    assert rec.meta["post.lu_mm"] == "36.5" and rec.meta["post.neck_radius_mm"] == "5.1"
    assert "post.dk_mm" not in rec.meta and "post.du_mm" not in rec.meta  # skipped, not invented


def test_q_on_the_terminal_stops_the_test(tmp_path, fake_rig, monkeypatch):
    import os
    import sys
    import threading

    from flowcurve.clock import WALL

    master, slave = os.openpty()
    term = os.fdopen(slave, "r")
    monkeypatch.setattr(sys, "stdin", term)
    rig = fake_rig(x_frac_mm=1e9, timebase=WALL)  # a key typed on a real terminal, in real time
    timer = threading.Timer(0.5, lambda: os.write(master, b"xq"))
    timer.start()
    try:
        out = Procedure(rig, spec(post={"post.lu_mm": 31.0, "post.dk_mm": 5.0, "post.du_mm": 5.8, "post.neck_radius_mm": 4.0}), tmp_path / "q.csv", interactive=True).run()
    finally:
        timer.cancel()
        term.close()
        os.close(master)
    assert out.status == "complete" and out.reason == "operator stop (q)"
    assert read_record(out.path).meta["stop_reason"] == "operator stop (q)"


class _RowsView:
    """A live view that keeps every row the procedure's snapshots carry (as the console does)."""

    def __init__(self):
        self.rows = []

    def show(self, snapshot, force=False):
        if snapshot.rows is not None and len(snapshot.rows):
            self.rows.append(np.asarray(snapshot.rows))

    def say(self, text):
        pass

    def close(self):
        pass


def test_live_rows_reach_the_view_up_to_the_fracture(tmp_path, fake_rig):
    """Every recorded row reaches the live view once, the batch that ended the test included
    (the console's plot stopped short of the fracture drop before)."""
    rig = fake_rig(x_frac_mm=1.0)
    view = _RowsView()
    out = Procedure(rig, spec(), tmp_path / "t.csv", view=view).run()
    rec = read_record(out.path)
    shown = np.concatenate(view.rows)
    assert len(shown) == len(rec.data)
    np.testing.assert_allclose(shown[:, 1], rec.column("force_N"), atol=1e-6)


@pytest.mark.parametrize("seed_delay_s", [0.01, 0.02, 0.03, 0.04])
def test_a_control_step_in_flight_at_the_fault_does_not_leave_the_heater_on(tmp_path, fake_rig, seed_delay_s):
    """Issue 31 (a): the furnace channel's control step reads, then commands the relay a little
    later (a DCON exchange); a fault elsewhere switched the heater off in between. The step that
    was in flight must not switch it back on (the matrix saw a 35 s 'stuck relay' made so)."""
    rig = fake_rig(x_frac_mm=1e9, die_after_s=6.0, heat_rate_C_per_s=4.0)
    hold = rig.hold_temperature
    loading = []

    def slow_hold(setpoint_C):
        if not loading:
            return hold(setpoint_C)
        temperature_C = rig.read_temperature_C()
        rig.timebase.sleep(seed_delay_s)  # the command's exchange: the main thread may switch off meanwhile
        rig.set_heater(True)  # below the set-point: heat
        return temperature_C

    start = rig.start_crosshead

    def start_and_load(speed, direction):
        loading.append(True)
        start(speed, direction)

    switched = []  # every command after the first heater-off
    heater_off, set_heater = rig.heater_off, rig.set_heater

    def noted_off():
        switched.append("off")
        heater_off()

    def noted_set(on):
        if switched:
            switched.append(on)
        set_heater(on)

    watched = []  # the heater as the after-stop watch for a stuck relay finds it

    def watch_heater_off(seconds, **_):
        watched.append(rig.heater)

    rig.hold_temperature, rig.start_crosshead, rig.heater_off, rig.set_heater = slow_hold, start_and_load, noted_off, noted_set
    rig.watch_heater_off = watch_heater_off
    out = Procedure(rig, spec(temperature_C=60.0, soak_s=1.0, soak_band_C=30.0), tmp_path / "r.csv").run()
    assert out.status == "aborted" and isinstance(out.error, DeviceError)
    assert watched == [False], f"the stuck-relay watch began with the heater on again: {switched}"
    assert switched.count(True) <= 1 and not rig.heater  # at most the one step in flight, switched off again


def test_a_relay_found_stuck_after_a_lost_device_keeps_the_lost_devices_own_message(tmp_path, fake_rig):
    """Issue 31 (a): the watch after the abort finds a stuck relay; the operator gets both."""
    rig = fake_rig(x_frac_mm=1e9, die_after_s=6.0, heat_rate_C_per_s=4.0)

    def watch_heater_off(seconds, **_):
        raise SafetyError("furnace", "heater does not switch off (relay stuck?): 6.0 C rise with the heater off for 35 s")

    rig.watch_heater_off = watch_heater_off
    out = Procedure(rig, spec(temperature_C=60.0, soak_s=1.0, soak_band_C=30.0), tmp_path / "r.csv").run()
    assert isinstance(out.error, SafetyError) and out.error.exit_code == 4
    for text in (str(out.error), out.reason, read_record(out.path).meta["abort_reason"]):
        assert text.startswith("furnace: heater does not switch off") and "disappeared" in text and "encoder" in text, text


def test_a_watch_extended_while_the_furnace_still_rises_is_told_and_recorded(tmp_path, fake_rig, capsys):
    """Issue 31 (the relay stuck near 850 C): the watch's 'watching on' reaches the operator (stderr when quiet) and the record."""
    rig = fake_rig(x_frac_mm=3.0, heat_rate_C_per_s=4.0)
    asked = {}

    def watch_heater_off(seconds, longest_s=None, on_extend=None, **_):
        asked.update(seconds=seconds, longest_s=longest_s)
        on_extend("still rising (+3.9 C in the last 5 s) after 45 s with the heater off: watching on, up to 120 s")
        return 47.0

    rig.watch_heater_off = watch_heater_off
    out = Procedure(rig, spec(temperature_C=60.0, soak_s=1.0, soak_band_C=30.0), tmp_path / "r.csv").run()
    assert asked["longest_s"] > asked["seconds"]
    assert "furnace: still rising" in capsys.readouterr().err
    events = {e.name: e.text for e in read_record(out.path).events}
    assert "watching on" in events.get("watch_extended", ""), events
