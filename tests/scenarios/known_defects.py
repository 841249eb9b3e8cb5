"""Cells of the scenario matrix that fail for a known rig or acquisition defect (issue 29, and
the ones the matrix found in acquisition/ and rig/, which this harness does not change): expected to
fail (``xfail(strict=False)``) until they are fixed. One line per defect; the reason names it."""

from __future__ import annotations

from .matrix import Cell

TRANSPARENT = ("drop", "garble", "delay")  # wire faults a driver rides out by retrying or restarting


def _furnace_channel_period_s(cell: Cell) -> float:
    """acquisition/session.py's furnace polling period (host s): a quarter control period (2 s) on
    the time-scaled test clock, within FURNACE_MIN_PERIOD_S–FURNACE_PERIOD_S."""
    return max(0.02, min(0.25, 2.0 / 4.0 / cell.time_scale))


def _fault(cell: Cell, device: str | None, *kinds: str) -> bool:
    return (device is None or cell.fault.device == device) and cell.fault.kind in kinds


KNOWN: list[tuple[str, object]] = [
    ("issue 29 #1: load-cell stream restarts and frames lost to a drop are counted, never written to the record's events "
     "(no event, nothing on the screen, samples lost undeclared)",
     lambda c: _fault(c, "loadcell", "drop", "garble")),
    ("issue 29 #1/#3 class: a retried or late encoder/furnace reply leaves no event and nothing on the screen; a late one "
     "is accepted (the crosshead lags: flow curve off)",
     lambda c: _fault(c, "encoder", *TRANSPARENT) or _fault(c, "furnace", *TRANSPARENT)),
    ("issue 29 #3 class on the load cell: a stream 0.5 s late is accepted without a word (the force lags the crosshead, "
     "the frames in flight at the stop are lost)",
     lambda c: _fault(c, "loadcell", "delay")),
    ("issue 29 #6: the in-process furnace module keeps its heater output on when its port is unplugged (no watchdog)",
     lambda c: _fault(c, "furnace", "unplug")),
    ("issue 29 #13: a stuck heater relay is not detected within the test (the stuck-relay check needs 30 s)",
     lambda c: _fault(c, "furnace", "relay_stuck")),
    ("new (the matrix): acquisition/session.py DriverRig.channels reuses the name `period` for the furnace channel "
     "(line 145) after read_force's closure took it for the stream (line 120): the load-cell stamps step by the furnace "
     "period, so below its rate the record's force is paired with the wrong crosshead (a 2 Hz stream on the real rig: "
     "stamps 0.25 s apart, a 0.5 mm target overshot to ~1 mm; flow curves up to 112 % off)",
     lambda c: 1.0 / c.rate_Hz > _furnace_channel_period_s(c) * 1.0001),
    ("issue 29 #11 class: at a time scale of 20 or more the furnace controller does not hold 850 C from a hot start "
     "(805 C at 20, 773 C at 50): the test ends before loading",
     lambda c: c.temperature_C >= 850.0 and c.time_scale >= 20.0),
]


def known_defect(cell: Cell) -> str | None:
    """The reason ``cell`` is expected to fail, or None."""
    reasons = [reason for reason, applies in KNOWN if applies(cell)]
    return "; ".join(reasons) or None
