"""A furnace past its configured maximum while the heater is commanded off, end to end: ``flowcurve run compression
--temperature 850`` on the in-process virtual rig on model time (the scenario matrix's 850 C relay cell), a relay that
welds shut while loading and carries the furnace over 900 C in the watch after the test. Every reading the furnace
driver takes is logged here, so the crossing is the model's, not the check's."""

from __future__ import annotations

import pytest

from tests.acquisition.conftest import run_logged as run_cli_logged

MAX_C = 900.0
HELD_C = 850.0
ARGS = ["compression", "--quiet", "--speed", "0.05", "--target", "3", "--time-scale", "50", "--temperature", f"{HELD_C:g}",
        "--soak", "5", "--material", "steel45"]


def run_logged(tmp_path, monkeypatch, *extra):
    """The 850 C compression test from a furnace already at 850 C, under a 900 C maximum (conftest.run_logged)."""
    return run_cli_logged(tmp_path, monkeypatch, [*ARGS, *extra], initial_temperature_C=HELD_C,
                          config_overrides={"furnace_max_temperature_C": MAX_C})


def test_a_relay_stuck_near_the_maximum_is_named_when_the_furnace_crosses_it(tmp_path, monkeypatch):
    code, said, rec, vr, readings = run_logged(tmp_path, monkeypatch, "--fault", "furnace:relay_stuck@20")
    last_on = max(i for i, (_, _, on) in enumerate(readings) if on)
    off = readings[last_on + 1:]  # from the last reading with the heater commanded on: the heater off since
    crossing = next(i for i, (_, value, _) in enumerate(off) if value > MAX_C)
    named_at, named_C, _ = off[crossing]
    assert code == 4, said[-600:]
    line = f"furnace: heater does not switch off (relay stuck?): {named_C:.1f} C, above the maximum {MAX_C:g} C"
    assert line in said and "the heater is commanded off and the furnace still heats" in said and "mains power" in said
    assert len(off) - crossing <= 2, f"{len(off) - crossing - 1} readings taken after the crossing: {off[crossing:]}"
    faults = [e for e in rec.events if e.name == "fault"]
    assert faults and faults[-1].text.startswith(line), [e.text for e in faults]
    heater_off = next(e.time_s for e in rec.events if e.name == "heater_off")
    assert heater_off < faults[-1].time_s <= heater_off + 120.0  # in the watch after the test, not while loading
    assert vr.devices["furnace"].do == 0 and vr.model.furnace.relay_on  # the output off; only the mains can stop it
    assert max(value for _, value, _ in readings) < MAX_C + 2.0  # stopped at the crossing: was 913.7 C at the watch's end


def test_a_healthy_850_C_test_under_a_900_C_maximum_is_not_named(tmp_path, monkeypatch):
    code, said, rec, vr, readings = run_logged(tmp_path, monkeypatch)
    assert code == 0, said[-600:]
    assert "relay stuck" not in said and not [e for e in rec.events if e.name == "fault"]
    assert max(value for _, value, _ in readings) < MAX_C and vr.devices["furnace"].do == 0
