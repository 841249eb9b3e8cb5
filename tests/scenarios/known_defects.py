"""Cells of the scenario matrix that fail for a known rig or acquisition defect (issue 29, and
the ones the matrix found in acquisition/ and rig/, which this harness does not change): expected to
fail (``xfail(strict=False)``) until they are fixed. One line per defect; the reason names it."""

from __future__ import annotations

from .matrix import FAULT_AT_MM, Cell

TRANSPARENT = ("drop", "garble", "delay")  # wire faults a driver rides out by retrying or restarting


def _fault(cell: Cell, device: str | None, *kinds: str) -> bool:
    return (device is None or cell.fault.device == device) and cell.fault.kind in kinds


KNOWN: list[tuple[str, object]] = [
    # not a matrix cell (the matrix injects at 1 mm of travel, where the stall as the stream falls behind is named as frames
    # missing); kept because it cannot be fixed in principle (README's fault table says so)
    ("load cell delay within the driver's time-out present from the stream's first frame: not detectable — the frames "
     "arrive at their rate, only late, and the force's lag behind the crosshead at the start of loading cannot be told "
     "from the specimen's seating slack (a longer one delays the set-up replies: named, exit 3)",
     lambda c: _fault(c, "loadcell", "delay") and FAULT_AT_MM == 0.0),
    # cannot be fixed in principle either (acquisition/plausibility.py says what no rule can tell); at 50 and 100 Hz
    # every spike cell names it, at 12 Hz 42 of 54, at 2 Hz 2 of 72 (issue 42)
    ("a +900 N one-sample spike (under the rate rules' 1 % of the frame's capacity) in a record of 2 or 12 samples per mm "
     "of crosshead: judged by the signal's own noise, which a dozen samples before the 1 mm injection do not yet give (2 Hz), "
     "and which cannot tell a spike smaller than the force's climb between two samples from a knee (compression at 12 Hz: "
     "it stays within its neighbours' band) — there only a spike beyond 1 % of the capacity is rejected",
     lambda c: _fault(c, "loadcell", "spike") and c.rate_Hz <= 12.0),
]


# strict (xfail strict=True): a fix turns the cell red, so the entry is removed with the fix (issue 42)
STRICT: list[tuple[str, object]] = []
# the 2 Hz delay, partly fixed (rig/loadcell.py gap_after_verdict decides a gap with 1-3 frames before it on the 3 frames
# after it: 10 of 25 cells measured pass); not strict, the cells split by the frames around 1 mm
KNOWN.append(("load cell delayed 0.5 s mid-test at 2 Hz (one output period, 2-3 frames before it): where the frame "
              "before the gap is still the elastic start, or the frames after it bend at Fm, neither latency nor one "
              "lost frame puts the frames on one smooth curve — the gap is named undecided (stream_gap_undecided, "
              "data_loss, run exit 5) and stamped as a loss, so the forces after it stay one period off",
              lambda c: _fault(c, "loadcell", "delay") and c.rate_Hz == 2.0))


def is_strict(cell: Cell) -> bool:
    """Whether ``cell``'s known defect is held strictly (its fix must remove the entry)."""
    return any(applies(cell) for _, applies in STRICT)


def known_defect(cell: Cell) -> str | None:
    """The reason ``cell`` is expected to fail, or None."""
    reasons = [reason for reason, applies in KNOWN if applies(cell)]
    return "; ".join(reasons) or None
