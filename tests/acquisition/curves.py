"""Comparing what two virtual tests recorded: force against crosshead, Fm, the last crosshead
(issue 42). Reusable by any fault case (a lost frame, a garbled one, a spike): run the test
fault-free and with the fault, then ``compare_curves(fault_free, faulty)``."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

GRID_MM = (0.5, 2.9)  # crosshead positions compared (past the toe and the yield, before a 3 mm target)


def force_at(record, positions_mm: np.ndarray) -> np.ndarray:
    """The record's force interpolated at crosshead positions (the crosshead's running maximum,
    so the curve is a function of position; samples where it stood still count once)."""
    x = np.maximum.accumulate(np.asarray(record.column("crosshead_mm"), dtype=float))
    f = np.asarray(record.column("force_N"), dtype=float)
    keep = np.r_[True, np.diff(x) > 0]
    return np.interp(positions_mm, x[keep], f[keep])


@dataclass(frozen=True)
class CurveDifference:
    """How a record differs from a reference record of the same test."""

    worst_force: float  # largest |F / F_ref − 1| over the grid
    worst_at_mm: float  # where it is
    last_crosshead_mm: float  # last crosshead − the reference's
    fm: float  # Fm / Fm_ref − 1

    def __str__(self) -> str:
        return (f"force {100 * self.worst_force:.2f} % off at {self.worst_at_mm:.2f} mm, last crosshead "
                f"{self.last_crosshead_mm:+.3f} mm, Fm {100 * self.fm:+.2f} %")


def compare_curves(reference, record, grid_mm=GRID_MM, points: int = 241) -> CurveDifference:
    """Force against crosshead, the last crosshead and Fm of ``record`` against ``reference``."""
    grid = np.linspace(grid_mm[0], grid_mm[1], points)
    ref, got = force_at(reference, grid), force_at(record, grid)
    err = np.abs(got / ref - 1.0)
    i = int(np.argmax(err))
    last = float(record.column("crosshead_mm")[-1] - reference.column("crosshead_mm")[-1])
    fm = float(np.max(record.column("force_N")) / np.max(reference.column("force_N")) - 1.0)
    return CurveDifference(float(err[i]), float(grid[i]), last, fm)
