"""The stuck-relay check against a thermal lag (issue 31, defect a): furnace curves built here,
independently of the check — a lag that rises to its peak after the heater went off, and the
virtual furnace's own physics with the relay welded shut."""

import numpy as np
import pytest

from flowcurve.errors import SafetyError
from flowcurve.rig.furnace import StuckRelayCheck
from flowcurve.rig.virtual.physics import Furnace, FurnaceParams

WATCH_S = 45.0  # acquisition.procedure.WATCH_COOLING_S


def first_alarm(curve, step_s=0.5, **kw):
    """Feed ``curve(t)`` (heater off from t = 0) to a check every ``step_s``; the alarm's time or None."""
    check = StuckRelayCheck(**kw)
    for t in np.arange(0.0, WATCH_S + 1e-9, step_s):
        try:
            check.update(float(curve(t)), float(t), False)
        except SafetyError:
            return float(t)
    return None


def lagging_furnace(t):
    """600 C, cooling 0.05 K/s, and the elements' stored heat arriving late: +7 C from 30 s on with a 2 s time constant."""
    bump = 7.0 * (1.0 - np.exp(-(t - 30.0) / 2.0)) if t > 30.0 else 0.0
    return 600.0 - 0.05 * t + bump


def test_a_lag_that_peaks_is_no_stuck_relay():
    assert first_alarm(lagging_furnace) is None
    # the rule before issue 31 (any 5 C rise after 30 s) read this lag as a stuck relay
    assert first_alarm(lagging_furnace, confirm_s=0.0, confirm_rise_C=0.0) is not None


@pytest.mark.parametrize("held_C", [300.0, 600.0, 850.0])
def test_a_welded_relay_is_caught_within_the_watch_at_every_matrix_temperature(held_C):
    """The virtual furnace's own model, held at ``held_C`` and then its relay stuck on."""
    p = FurnaceParams()
    furnace = Furnace(p, initial_C=held_C)
    furnace.set_heater(False)
    furnace.set_relay_stuck(True)
    temps = {}
    for t in np.arange(0.0, WATCH_S + 1e-9, 0.5):
        temps[round(float(t), 1)] = furnace.temperature_C
        furnace.step(0.5)
    alarm = first_alarm(lambda t: temps[round(float(t), 1)])
    assert alarm is not None and alarm <= WATCH_S


def test_a_cooling_furnace_never_alarms():
    assert first_alarm(lambda t: 850.0 * np.exp(-t / 600.0) + 0.1 * np.sin(7 * t)) is None


# -- over the maximum with the heater off (the watch's 912 C on a 900 C furnace) --------------------------------------

MAX_C = 900.0


def virtual_curve(held_C, *, stuck, on_before_s=0.0, seconds=120.0, step_s=0.5):
    """The virtual furnace's own physics from ``held_C``: heater on for ``on_before_s`` (its stored heat), then
    commanded off at t = 0, the relay stuck on or not; the readings every ``step_s`` as {t: T}."""
    furnace = Furnace(FurnaceParams(), initial_C=held_C)
    furnace.set_heater(on_before_s > 0)
    furnace.step(on_before_s)
    furnace.set_heater(False)
    furnace.set_relay_stuck(stuck)
    temps = {}
    for t in np.arange(0.0, seconds + 1e-9, step_s):
        temps[round(float(t), 1)] = furnace.temperature_C
        furnace.step(step_s)
    return temps


def first_alarm_of(temps, **kw):
    """(time, message) of the check's first alarm over the readings ``temps``, or (None, None)."""
    check = StuckRelayCheck(**kw)
    for t, temp in temps.items():
        try:
            check.update(temp, t, False)
        except SafetyError as exc:
            return t, str(exc)
    return None, None


def test_a_stuck_relay_crossing_the_maximum_is_named_at_the_first_reading_above_it():
    """Held at 890 C, relay welded: the physics crosses 900 C at 27 s, before the rise check may speak (30 s + 5 s)."""
    temps = virtual_curve(890.0, stuck=True)
    crossing = min(t for t, temp in temps.items() if temp > MAX_C)  # from the model's readings, not from the check
    at, said = first_alarm_of(temps, max_temperature_C=MAX_C)
    assert at == crossing, (at, crossing)
    assert f"{temps[at]:.1f} C, above the maximum 900 C" in said
    assert "the heater is commanded off and the furnace still heats" in said and "mains power" in said
    later, _ = first_alarm_of(temps)  # without the maximum: only the rise check, later and hotter
    assert later is not None and later > crossing + 10.0 and temps[later] > MAX_C + 10.0, (later, temps[later])


@pytest.mark.parametrize("held_C", [600.0, 850.0, 880.0])
def test_a_healthy_furnace_with_its_stored_heat_is_not_named(held_C):
    """Switched off after 10 s on (the dead time's 5 s of full power still to come: +4 C): cools, never named."""
    temps = virtual_curve(held_C, stuck=False, on_before_s=10.0)
    assert max(temps.values()) > temps[0.0] + 2.0  # the stored heat's rise after the switch-off
    assert max(temps.values()) < MAX_C
    assert first_alarm_of(temps, max_temperature_C=MAX_C) == (None, None)


def test_a_furnace_already_over_the_maximum_when_switched_off_is_not_named_while_it_cools():
    """An over-temperature stop at 905 C with the heater on till then: its stored heat takes it higher, then it cools."""
    temps = virtual_curve(903.0, stuck=False, on_before_s=10.0)
    assert temps[0.0] > MAX_C and max(temps.values()) > temps[0.0]  # the stored heat's rise above the maximum
    assert first_alarm_of(temps, max_temperature_C=MAX_C) == (None, None)


def test_a_furnace_that_falls_below_the_maximum_and_crosses_it_again_is_named():
    curve = {0.0: 910.0, 1.0: 905.0, 2.0: 899.0, 3.0: 899.5, 4.0: 900.4}
    at, said = first_alarm_of(curve, max_temperature_C=MAX_C)
    assert at == 4.0 and "900.4 C" in said


def test_a_reading_at_the_maximum_is_not_over_it():
    """The same comparison as the heated path's over-temperature (acquisition.safety.check_temperature: above, not at)."""
    assert first_alarm_of({0.0: 899.0, 1.0: 900.0, 2.0: 900.0}, max_temperature_C=MAX_C) == (None, None)


def test_one_reading_jumping_over_the_maximum_is_no_heating_but_a_furnace_that_stays_there_is_named():
    """A corrupt reading (+200 C, the virtual rig's drill) is no crossing by heating: left to the over-temperature
    rule, which names it as the reading it is; two readings over the maximum in a row are a furnace that hot."""
    spike = {0.0: 850.0, 0.5: 850.1, 1.0: 1050.1, 1.5: 850.2, 2.0: 850.1}
    assert first_alarm_of(spike, max_temperature_C=MAX_C) == (None, None)
    stays = {0.0: 850.0, 0.5: 850.1, 1.0: 1050.1, 1.5: 1050.3}
    assert first_alarm_of(stays, max_temperature_C=MAX_C)[0] == 1.5
