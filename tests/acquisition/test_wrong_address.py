"""A reply from a wrong address in a whole test, in process on model time (issue 42).

One furnace reply ``!03`` instead of ``!01`` to ``@01DO01`` during a heated test: the old code
ended it with exit 0 and nothing anywhere (the reading channel retried the failed step). Now the
test stops as ``furnace:wrong_address`` does — exit 3, the heater left to the module's watchdog,
the operator told — with a ``wrong_address`` event naming the device, the command and the address
that answered. A wrong address on a reading is an event; the reading is asked again, not taken.
"""

from __future__ import annotations

import pytest

from flowcurve.identification.identify import FAULT_EVENTS
from flowcurve.rig.virtual.dcon import I7011
from flowcurve.rig.virtual.rig import VirtualRig
from tests.acquisition.conftest import run_logged

UNHEATED = ["tension", "--target", "2", "--time-scale", "3", "--quiet"]
HEATED = [*UNHEATED, "--temperature", "60", "--soak", "5"]


def one_stray_reply(monkeypatch, lead: str, body: str, *, loading: bool = True):
    """The virtual furnace module answers the first ``lead``+``body`` (after the crosshead starts,
    with ``loading``) as module 03 would — having done what it was told, as module 01."""
    armed, sent = [not loading], []
    real_command, real_start = I7011.command, VirtualRig.start_crosshead

    def start(rig):
        real_start(rig)
        armed[0] = True

    def command(module, lead_, body_):
        reply = real_command(module, lead_, body_)
        if armed[0] and not sent and (lead_, body_) == (lead, body) and reply and reply[:1] in "!?":
            sent.append(module.clock.now())
            return reply[0] + "03" + reply[3:]
        return reply

    monkeypatch.setattr(VirtualRig, "start_crosshead", start)
    monkeypatch.setattr(I7011, "command", command)
    return sent


def test_one_heater_command_answered_by_another_module_stops_the_test(tmp_path, monkeypatch):
    sent = one_stray_reply(monkeypatch, "@", "DO01")
    code, said, rec, vr, _ = run_logged(tmp_path, monkeypatch, HEATED)
    assert sent, "the heater was never switched on while loading"
    assert code == 3, said
    assert rec.meta["status"] == "aborted" and "reply to '@01DO01' from address 03, not 01" in rec.meta["stop_reason"]
    events = [e.text for e in rec.events if e.name == "wrong_address"]
    assert len(events) == 1 and events[0].startswith("furnace: reply to '@01DO01' from address 03, not 01")
    assert "left to the module's watchdog" in events[0]
    # the operator told: the error line, and that the module's watchdog switches the heater off
    assert "flowcurve: error: furnace: reply to '@01DO01' from address 03" in said
    assert "heater-off not confirmed" in said and "watchdog switches" in said
    assert "heater off; watching that it cools" not in said  # issue 42's message fix: it was not confirmed
    module = vr.devices["furnace"]
    assert module.do == 0  # the heater-off was sent (and module 01 did switch)
    assert module.watchdog_enabled  # ... but not believed: the watchdog was left armed


def test_a_reading_answered_by_another_module_is_named_and_not_taken(tmp_path, monkeypatch):
    """``@01DI`` (the outputs read back every second while the furnace is only read) answered once by
    03: asked again, the test goes on."""
    sent = one_stray_reply(monkeypatch, "@", "DI")
    code, said, rec, vr, _ = run_logged(tmp_path, monkeypatch, UNHEATED)
    assert sent
    assert code == 0 and rec.meta["status"] == "complete", said
    events = [e.text for e in rec.events if e.name == "wrong_address"]
    assert events == ["furnace: reply to '@01DI' from address 03, not 01 — not taken; asked again"]
    retry = [e.text for e in rec.events if e.name == "retry"]
    assert retry and "the readings were taken on the retry" in retry[0]


def test_wrong_address_is_one_of_identifys_fault_events():
    assert "wrong_address" in FAULT_EVENTS


@pytest.mark.parametrize("fault", ["furnace:wrong_address:3@5"])
def test_the_drill_names_the_address_in_the_events_too(tmp_path, monkeypatch, fault):
    code, said, rec, _, _ = run_logged(tmp_path, monkeypatch, [*HEATED, "--fault", fault])
    assert code == 3
    events = [e.text for e in rec.events if e.name == "wrong_address"]
    assert events and all("from address 03, not 01" in t for t in events)
    assert "heater off; watching that it cools" not in said
    # the @01DI read back failed on every retry too: the retry event no longer says the readings were taken
    retry = [e.text for e in rec.events if e.name == "retry"]
    assert retry and all("the readings were taken on the retry" not in t for t in retry)
    assert any("failed on every retry too" in t for t in retry)
