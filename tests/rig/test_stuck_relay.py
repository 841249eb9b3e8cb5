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
